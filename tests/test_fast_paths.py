"""The 1 kHz fast paths agree with the straightforward array code they replace.

The trot controller, leg odometry, velocity filter, gait clock and trajectories have per-step paths written
in Python floats (numpy's call overhead on (4, 3) arrays dominated the simulation's inner loop). Each test
here runs a plain reference, written with the array functions as the code was before, on random states.
"""
import dataclasses

import numpy as np
import pytest

from cyberdog import config as C
from cyberdog.control.trot import BodyFeedback, TrotController
from cyberdog.core import kinematics as kin
from cyberdog.core.estimator import leg_odometry_velocity
from cyberdog.core.gait import GaitScheduler
from cyberdog.core.pid import JointPID
from cyberdog.core.trajectories import (CompositeCycloid, SampledTrajectory, StraightLine, make_trajectory,
                                        point_evaluator)

import oracles
from conftest import walk_config

ROBOT = C.RobotConfig()
SIDES = (np.array([0, 2]), np.array([1, 3]))


def sampled_trajectory() -> SampledTrajectory:
    phase = np.linspace(0.0, 1.0, 40, endpoint=False)
    x = 0.12 * np.cos(2 * np.pi * phase)
    z = 0.15 * np.maximum(np.sin(2 * np.pi * phase), 0.0) + 0.01 * np.sin(4 * np.pi * phase)
    return SampledTrajectory(phase, x, z, 0.24, 0.15)


class ReferenceTrot:
    """The trot controller as written with the array functions (IK, jacobian + np.linalg.solve, JointPID)."""

    def __init__(self, cfg: C.WalkConfig, trajectory=None):
        self.cfg, self.robot, self.gait = cfg, cfg.robot, cfg.gait
        self.trajectory = trajectory if trajectory is not None else make_trajectory(cfg.gait)
        self.scheduler = GaitScheduler.from_config(cfg.gait)
        self.pid = JointPID.from_config(cfg.pid, cfg.sim.controller_dt, cfg.actuator.torque_limit)
        self.stand_height = self.robot.body_height - self.robot.foot_radius
        self.body_weight = self.robot.carried_mass * cfg.sim.gravity
        self.speed, self.speed_correction = cfg.gait.speed, 0.0

    def step_lengths(self, t, body):
        c = self.cfg.controller
        ramp = c.speed_ramp_time
        v = self.speed if ramp <= 0 else self.speed * min(1.0, t / ramp)
        if body.forward_speed is not None and c.speed_gain > 0:
            limit = c.max_speed_correction * v
            self.speed_correction = float(np.clip(
                self.speed_correction + c.speed_gain * (v - body.forward_speed) * self.cfg.sim.controller_dt,
                -limit, limit))
        S = (v + self.speed_correction) * self.gait.stance_time
        skew = np.clip(c.heading_gain * (body.yaw + c.lateral_gain * body.lateral_offset), -0.5, 0.5)
        return np.maximum(S * (1.0 + skew * kin.LEFT_RIGHT), 0.0)

    def targets(self, t, body):
        g, c = self.gait, self.cfg.controller
        phases = self.scheduler.leg_phases(t)
        S = self.step_lengths(t, body)
        xz, vxz = np.empty((4, 2)), np.empty((4, 2))
        for legs in SIDES:
            xz[legs], vxz[legs] = self.trajectory.position_velocity(phases[legs], S[legs[0]], g.lift_height,
                                                                    g.swing_time, g.stance_time)
        dy = float(np.clip(c.lateral_placement_gain * body.lateral_speed, -0.03, 0.03))
        foot = np.stack([xz[:, 0], kin.LEFT_RIGHT * self.robot.l1 + dy, xz[:, 1] - self.stand_height], axis=-1)
        foot_vel = np.stack([vxz[:, 0], np.zeros(4), vxz[:, 1]], axis=-1)
        q = kin.inverse_kinematics(foot, self.robot)
        dq = (np.linalg.solve(kin.jacobian(q, self.robot), foot_vel[..., None])[..., 0]
              if c.velocity_feedforward else np.zeros((4, 3)))
        return foot, foot_vel, q.ravel(), dq.ravel(), self.scheduler.in_swing(t)

    def torque(self, t, q, dq, body):
        _, _, q_t, dq_t, in_swing = self.targets(t, body)
        tau = self.pid.torque(q_t, q, dq_t, dq)
        stance = ~in_swing
        n = int(np.count_nonzero(stance))
        if self.cfg.controller.gravity_compensation and n:
            J = kin.jacobian(np.reshape(q, (4, 3)), self.robot)
            tau = tau + (J[:, 2, :] * (-self.body_weight / n * stance)[:, None]).ravel()
        return tau


def random_states(seed, n):
    """n random (t, q, dq, BodyFeedback) around the standing pose, times over several gait cycles; every 11th
    with a yaw error of several rad (the heading skew at its bound)."""
    rng = np.random.default_rng(seed)
    q_stand = kin.standing_joint_angles(ROBOT).ravel()
    for k in range(n):
        t = 0.0 if k == 0 else float(rng.uniform(0.0, 3.0))
        q, dq, yaw = q_stand + rng.normal(0.0, 0.15, 12), rng.normal(0.0, 4.0, 12), rng.normal(0, 0.1)
        yield (t, q, dq, BodyFeedback(yaw=yaw * 30 if k % 11 == 5 else yaw, lateral_offset=rng.normal(0, 0.05),
                                      forward_speed=None if k % 7 == 3 else float(rng.uniform(0.0, 1.6)),
                                      lateral_speed=rng.normal(0, 0.3)))


@pytest.mark.parametrize("trajectory, shape, options", [
    ("cycloid", "rectangle", {}),
    ("straight", "rectangle", {}), ("straight", "trapezoid", {}), ("straight", "triangle", {}),
    ("sampled", "rectangle", {}),
    ("cycloid", "rectangle", {"velocity_feedforward": False, "gravity_compensation": False}),
    ("cycloid", "rectangle", {"speed_ramp_time": 0.0, "speed_gain": 0.0}),
])
def test_controller_torque_and_targets_match_the_array_reference(trajectory, shape, options):
    cfg = walk_config("cycloid" if trajectory == "sampled" else trajectory, speed=1.2, straight_shape=shape,
                      **options)
    traj = sampled_trajectory() if trajectory == "sampled" else None
    fast, ref = TrotController(cfg, traj), ReferenceTrot(cfg, traj)
    for t, q, dq, body in random_states(0, 300):
        np.testing.assert_allclose(fast.torque(t, q, dq, body), ref.torque(t, q, dq, body), rtol=1e-9, atol=1e-9)
        assert fast.speed_correction == pytest.approx(ref.speed_correction, rel=1e-12, abs=1e-15)
        tgt = fast.targets(t, body)
        for got, want in zip((tgt.foot_position, tgt.foot_velocity, tgt.joint_angles, tgt.joint_velocities),
                             ref.targets(t, body)[:4]):
            assert got.shape == want.shape
            np.testing.assert_allclose(got, want, rtol=1e-9, atol=1e-12)
        np.testing.assert_array_equal(tgt.in_swing, ref.scheduler.in_swing(t))


def test_controller_with_integral_gain_matches_reference():
    cfg = walk_config(speed=1.2)
    cfg = dataclasses.replace(cfg, pid=dataclasses.replace(cfg.pid, ki=(50.0, 80.0, 80.0)))
    fast, ref = TrotController(cfg), ReferenceTrot(cfg)
    for t, q, dq, body in random_states(1, 200):
        np.testing.assert_allclose(fast.torque(t, q, dq, body), ref.torque(t, q, dq, body), rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(fast.pid.integral, ref.pid.integral, rtol=1e-9, atol=1e-12)
    assert np.any(fast.pid.integral != 0)


def test_controller_errors_are_those_of_the_array_code():
    ctrl = TrotController(walk_config(speed=1.2))
    with pytest.raises(ValueError, match="shape"):
        ctrl.torque(0.1, np.zeros(11), np.zeros(12))
    with pytest.raises(ValueError, match="finite"):
        ctrl.torque(float("nan"), np.zeros(12), np.zeros(12))
    tall = dataclasses.replace(walk_config(speed=1.2), robot=dataclasses.replace(ROBOT, body_height=0.5))
    with pytest.raises(ValueError, match="unreachable foot target"):
        TrotController(tall).torque(0.1, np.zeros(12), np.zeros(12))


def test_scalar_leg_kinematics_match_the_array_functions():
    rng = np.random.default_rng(2)
    l1, l2, l3 = ROBOT.l1, ROBOT.l2, ROBOT.l3
    for _ in range(200):
        feet = np.stack([rng.uniform(-0.15, 0.15, 4), kin.LEFT_RIGHT * l1 + rng.uniform(-0.03, 0.03, 4),
                         rng.uniform(-0.34, -0.12, 4)], axis=-1)
        q = kin.inverse_kinematics(feet, ROBOT)
        J = kin.jacobian(q, ROBOT)
        v = rng.normal(0.0, 1.0, (4, 3))
        dq = np.linalg.solve(J, v[..., None])[..., 0]
        for leg, side in enumerate(kin.LEFT_RIGHT.tolist()):
            q_leg = kin.leg_inverse_kinematics(*feet[leg].tolist(), side, l1, l2, l3)
            np.testing.assert_allclose(q_leg, q[leg], rtol=0, atol=1e-12)
            np.testing.assert_allclose(kin.leg_joint_velocity(*q[leg].tolist(), side, *v[leg].tolist(), l1, l2, l3),
                                       dq[leg], rtol=1e-9, atol=1e-12)
            np.testing.assert_allclose(kin.leg_jacobian_z_row(*q[leg].tolist(), side, l1, l2, l3), J[leg, 2],
                                       rtol=1e-12, atol=1e-15)
    with pytest.raises(ValueError, match="unreachable"):
        kin.leg_inverse_kinematics(0.0, 0.0, -0.5, 1.0, l1, l2, l3)
    with pytest.raises(ValueError, match="unreachable"):
        kin.leg_inverse_kinematics(0.0, 0.01, 0.0, 1.0, l1, l2, l3)
    with pytest.raises(np.linalg.LinAlgError):  # straight knee: J is singular, as np.linalg.solve says
        kin.leg_joint_velocity(0.0, 0.3, 0.0, 1.0, 0.1, 0.0, 0.1, l1, l2, l3)


def test_gait_phases_equal_the_array_law_exactly():
    sched = GaitScheduler.from_config(C.GaitConfig())
    rng = np.random.default_rng(3)
    times = np.concatenate([np.arange(0.0, 4.0, 0.001), rng.uniform(-50, 50, 2000), 0.2 * np.arange(100),
                            [0.0, -0.0, 1e-17, -1e-17]])
    for t in times:
        assert sched.phases_at(float(t)) == oracles.leg_phases(sched, t).tolist()
    np.testing.assert_array_equal(sched.leg_phases(times), oracles.leg_phases(sched, times))
    with pytest.raises(ValueError, match="finite"):
        sched.phases_at(float("inf"))


@pytest.mark.parametrize("trajectory", [CompositeCycloid(), StraightLine("rectangle"), StraightLine("trapezoid"),
                                        StraightLine("triangle")], ids=lambda t: getattr(t, "shape", t.name))
def test_trajectory_foot_point_equals_position_velocity(trajectory):
    rng = np.random.default_rng(4)
    point, point_at = trajectory.foot_point, point_evaluator(trajectory)
    for _ in range(500):
        S = 0.0 if rng.random() < 0.1 else float(rng.uniform(0.0, 0.4))
        H, swing, stance = float(rng.uniform(0.02, 0.2)), float(rng.uniform(0.05, 0.4)), float(rng.uniform(0.05, 0.4))
        phase = float(rng.choice([rng.uniform(-1.0, 2.0), 0.0, swing / (swing + stance)]))
        pos, vel = trajectory.position_velocity(phase, S, H, swing, stance)
        np.testing.assert_allclose(point(phase, S, H, swing, stance), np.concatenate([pos, vel]),
                                   rtol=1e-12, atol=1e-14)
        # the controller's unchecked form, at the wrapped phase and the swing fraction
        assert point_at(phase % 1.0, swing / (swing + stance), S, H, swing, stance) == point(phase, S, H, swing,
                                                                                             stance)
    with pytest.raises(ValueError, match="step_length"):
        point(0.1, -0.1, 0.1, 0.2, 0.2)
    with pytest.raises(ValueError, match="phase"):
        point(float("nan"), 0.1, 0.1, 0.2, 0.2)


def test_point_evaluator_only_for_trajectories_it_reproduces():
    class Lower(CompositeCycloid):
        def swing_path(self, tau, step_length, lift_height):
            x, z, dx, dz = super().swing_path(tau, step_length, lift_height)
            return x, 0.5 * z, dx, 0.5 * dz

    assert point_evaluator(CompositeCycloid()) is not None
    assert point_evaluator(Lower()) is None
    assert point_evaluator(sampled_trajectory()) is None
    # the controller falls back to the array method for such a trajectory
    cfg = walk_config(speed=1.2)
    fast, ref = TrotController(cfg, Lower()), ReferenceTrot(cfg, Lower())
    for t, q, dq, body in random_states(5, 50):
        np.testing.assert_allclose(fast.torque(t, q, dq, body), ref.torque(t, q, dq, body), rtol=1e-9, atol=1e-9)


def test_pid_fast_path_equals_full_update():
    rng = np.random.default_rng(6)
    fast = JointPID(60.0, 0.0, 2.0, 2.0, 0.001, 25.0)
    for _ in range(200):
        args = [rng.normal(0.0, 0.5, 12) for _ in range(4)]
        e, r = args[0] - args[1], args[2] - args[3]
        np.testing.assert_array_equal(fast.torque(*args), np.clip(60.0 * e + 2.0 * r + 0.0, -25.0, 25.0))
        np.testing.assert_array_equal(fast.integral, 0.0)
    # a non-finite error poisons the integral as the full update always did
    bad = np.zeros(12)
    bad[4] = np.nan
    fast.torque(bad, np.zeros(12), np.zeros(12), np.zeros(12))
    assert np.isnan(fast.integral[4])


def reference_leg_odometry(q, dq, contacts, w, robot, rolling=True):
    q, dq = np.reshape(q, (4, 3)), np.reshape(dq, (4, 3))
    p_foot = kin.abad_offsets(robot) + kin.foot_position(q, robot)
    v_body = -(np.einsum("lij,lj->li", kin.jacobian(q, robot), dq) + np.cross(w, p_foot))
    if rolling:
        v_body[:, 0] += (w[1] + dq[:, 1] + dq[:, 2]) * robot.foot_radius
    return v_body[contacts].mean(axis=0)


def test_leg_odometry_matches_the_array_formula():
    rng = np.random.default_rng(7)
    q_stand = kin.standing_joint_angles(ROBOT).ravel()
    for k in range(300):
        q, dq, w = q_stand + rng.normal(0, 0.2, 12), rng.normal(0, 5, 12), rng.normal(0, 1, 3)
        contacts = rng.random(4) < 0.6
        if not contacts.any():
            assert np.all(np.isnan(leg_odometry_velocity(q, dq, contacts, w, ROBOT)))
            continue
        for rolling in (True, False):
            np.testing.assert_allclose(leg_odometry_velocity(q, dq, contacts, w, ROBOT, rolling),
                                       reference_leg_odometry(q, dq, contacts, w, ROBOT, rolling),
                                       rtol=1e-12, atol=1e-13)


# ---------------------------------------------------------------------------------------------------------
# simulator side: Robot.read_state and the env's inner loop
# ---------------------------------------------------------------------------------------------------------

def reference_state(robot):
    """The state as read_state computed it eagerly before (every field from PyBullet, link frame)."""
    c, body = robot.client, robot.body_id
    states = c.getJointStates(body, robot.joint_ids)
    com_pos, com_quat = c.getBasePositionAndOrientation(body)
    pos, quat = c.multiplyTransforms(com_pos, com_quat, *c.invertTransform(*c.getDynamicsInfo(body, -1)[3:5]))
    lin_com, ang = c.getBaseVelocity(body)
    rot = np.array(c.getMatrixFromQuaternion(quat)).reshape(3, 3)
    lin = np.array(lin_com) + np.cross(ang, np.array(pos) - np.array(com_pos))
    return {"q": np.array([s[0] for s in states]), "dq": np.array([s[1] for s in states]),
            "base_position": np.array(pos), "base_quaternion": np.array(quat),
            "base_rpy": np.array(c.getEulerFromQuaternion(quat)), "base_linear_velocity_world": lin,
            "base_angular_velocity_world": np.array(ang), "base_linear_velocity_body": lin @ rot,
            "base_angular_velocity_body": np.array(ang) @ rot, "rotation_matrix": rot}


def test_read_state_equals_the_eager_reference():
    from cyberdog.sim.robot import Robot
    cfg = C.WalkConfig()
    rng = np.random.default_rng(9)
    with Robot(cfg.robot, cfg.actuator, cfg.sim) as robot:
        robot.reset(base_position=(0.0, 0.0, 0.6), base_yaw=0.4)
        for k in range(60):
            robot.step(rng.uniform(-5, 5, 12))  # tumble in the air: every field non-trivial
            if k % 20 == 19:
                state, want = robot.read_state(), reference_state(robot)
                assert state.time == pytest.approx((k + 1) * cfg.sim.controller_dt)
                for name, value in want.items():
                    np.testing.assert_allclose(getattr(state, name), value, rtol=1e-12, atol=1e-12, err_msg=name)
                assert state.lateral_velocity_body == pytest.approx(want["base_linear_velocity_body"][1],
                                                                    rel=1e-12, abs=1e-12)
            if k % 20 == 9:  # the per-period read in floats: the reference's numbers, and the snapshot's to the bit
                reading, want, state = robot.read(), reference_state(robot), robot.read_state()
                for name, value in want.items():
                    if name in reading._fields:
                        np.testing.assert_allclose(getattr(reading, name), value, rtol=1e-12, atol=1e-12, err_msg=name)
                        assert np.array_equal(np.array(getattr(reading, name)), getattr(state, name)), name
                assert reading.time == state.time
        state = robot.read_state()
        with pytest.raises(dataclasses.FrozenInstanceError):
            state.q = np.zeros(12)
        state.q[0] = 123.0  # a caller's copy: the robot's own joint cache is unchanged
        assert robot.read_state().q[0] != 123.0
        assert robot.read().q[0] != 123.0


def test_joint_stop_is_off_inside_the_range_and_a_spring_damper_outside():
    from cyberdog.control.joint_stop import JointStop
    from cyberdog.core import kinematics as kin
    cfg = C.EnvConfig()
    robot = cfg.walk.robot
    stop = JointStop(robot, np.deg2rad(cfg.joint_range_deg), cfg.joint_stop_stiffness, cfg.joint_stop_damping)
    q_stand = kin.standing_joint_angles(robot).ravel()
    assert stop.torque(q_stand, np.ones(12)) is None
    q = q_stand.copy()
    q[1], q[5] = stop.q_high[1] + 0.1, stop.q_low[5] - 0.2
    dq = np.arange(12.0)
    tau = stop.torque(q, dq)
    np.testing.assert_array_equal(stop.torque(q.tolist(), dq.tolist()), tau)  # the walker passes floats
    assert stop.torque(q_stand.tolist(), dq.tolist()) is None
    k, c = cfg.joint_stop_stiffness, cfg.joint_stop_damping
    assert tau[1] == pytest.approx(-k * 0.1 - c * dq[1]) and tau[5] == pytest.approx(k * 0.2 - c * dq[5])
    assert np.count_nonzero(tau) == 2


@pytest.mark.parametrize("friction", [False, True])
@pytest.mark.parametrize("curve", [False, True])
def test_actuator_law_in_floats_equals_the_array_law(friction, curve):
    """The robot's per-period actuator path (floats) is the array law joint by joint: clip, torque–speed
    envelope while motoring, friction; over commands beyond the limit and speeds beyond both corner speeds."""
    from cyberdog.core.actuator import ActuatorModel
    model = ActuatorModel(C.ActuatorConfig(friction=friction, torque_speed_curve=curve))
    rng = np.random.default_rng(3)
    for _ in range(200):
        command, omega = rng.uniform(-40, 40, 12), rng.uniform(-25, 25, 12)
        omega[:3] = [0.0, 1e-4, -11.4145]  # at rest, inside the dry-friction smoothing, at the corner speed
        motor, joint = oracles.joint_torque(model, command, omega)
        motor_list, joint_list = model.joint_torque(command.tolist(), omega.tolist())
        np.testing.assert_allclose(motor_list, motor, rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(joint_list, joint, rtol=1e-12, atol=1e-12)
