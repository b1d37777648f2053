"""The joint controller's rate apart from the physics rate: PyBullet's substeps hold the torque, and the
energy the walker books for a held torque is the one the joints received at every physics step."""
import numpy as np
import pybullet
import pytest

from cyberdog import config as C
from cyberdog.loop.walker import Walker
from cyberdog.sim.robot import Robot


def _held_torque_walk(robot: Robot, torque: np.ndarray, periods: int, substeps_in_cpp: bool) -> np.ndarray:
    """Joint angles after `periods` controller periods of one constant torque, the substeps run by PyBullet
    (numSubSteps) or one stepSimulation per physics step re-applying the torque."""
    c, sim = robot.client, robot.sim_config
    n = sim.physics_substeps
    if substeps_in_cpp:
        c.setPhysicsEngineParameter(fixedTimeStep=sim.controller_dt, numSubSteps=n)
    else:
        c.setPhysicsEngineParameter(fixedTimeStep=sim.physics_dt, numSubSteps=0)
    robot.reset()
    for _ in range(periods * (1 if substeps_in_cpp else n)):
        c.setJointMotorControlArray(robot.body_id, robot.joint_ids, pybullet.TORQUE_CONTROL, forces=torque.tolist())
        c.stepSimulation()
    robot._joint_cache = None
    return robot.joint_angles()


@pytest.mark.parametrize("physics_dt, controller_dt", [(0.00125, 0.0025), (0.0005, 0.0025), (0.001, 0.005)])
def test_substeps_hold_the_torque_over_the_controller_period(physics_dt, controller_dt):
    cfg = C.WalkConfig(sim=C.SimConfig(physics_dt=physics_dt, controller_dt=controller_dt))
    torque = np.tile([0.5, -2.0, 3.0], 4)
    with Robot(cfg.robot, cfg.actuator, cfg.sim) as robot:
        in_cpp = _held_torque_walk(robot, torque, 40, substeps_in_cpp=True)
        by_hand = _held_torque_walk(robot, torque, 40, substeps_in_cpp=False)
    assert np.abs(in_cpp - robot_rest_angles(cfg)).max() > 0.05  # the torque did move the joints
    np.testing.assert_array_equal(in_cpp, by_hand)


def robot_rest_angles(cfg: C.WalkConfig) -> np.ndarray:
    from cyberdog.core.kinematics import standing_joint_angles
    return standing_joint_angles(cfg.robot).ravel()


def test_walker_energy_agrees_with_the_physics_rate_integral_of_what_pybullet_received():
    """Replay the walker's applied torques at every physics step in a second world, with the joint speeds
    PyBullet reports at each physics step: Σ|τ·ω|·physics_dt agrees with the walker's Σ|τ·Δq| within 1 %."""
    cfg = C.WalkConfig()
    sim = cfg.sim
    with Walker(cfg) as w:
        for _ in range(int(round(2.0 / w.dt))):  # 2 s of the trot at 1 m/s
            w.step()
        tau, booked = w.traces()["tau"], w.energy()
    with Robot(cfg.robot, cfg.actuator, sim) as robot:
        c = robot.client
        c.setPhysicsEngineParameter(fixedTimeStep=sim.physics_dt, numSubSteps=0)
        robot.reset()
        integral = 0.0
        for torque in tau:  # friction is off on the ideal robot: the motor torque is what the joint received
            forces = torque.tolist()
            for _ in range(sim.physics_substeps):
                omega = np.array([s[1] for s in c.getJointStates(robot.body_id, robot.joint_ids)])
                integral += float(np.abs(torque * omega).sum()) * sim.physics_dt
                c.setJointMotorControlArray(robot.body_id, robot.joint_ids, pybullet.TORQUE_CONTROL, forces=forces)
                c.stepSimulation()
    assert booked > 100.0  # the robot walked
    assert booked == pytest.approx(integral, rel=0.01)


def test_rates_are_validated_with_the_fields_named():
    with pytest.raises(ValueError, match="controller_dt.*whole multiple of physics_dt"):
        C.SimConfig(physics_dt=0.001, controller_dt=0.0025)
    with pytest.raises(ValueError, match="controller_dt"):
        C.SimConfig(physics_dt=0.001, controller_dt=0.0005)  # faster than the physics
    with pytest.raises(ValueError, match="control_dt.*controller_dt"):
        C.EnvConfig(control_dt=0.026)
    with pytest.raises(ValueError, match="latency_s.*controller_dt"):
        C.EnvConfig(hardware=C.HardwareConfig(latency_s=0.003))
    assert C.SimConfig().physics_substeps == 2 and C.EnvConfig().decimation == 10


def test_a_config_written_before_the_controller_rate_loads_only_with_it_named():
    """Old configs give the physics step alone: the default controller period does not divide it, and the
    error says what to add."""
    with pytest.raises(ValueError, match="give it controller_dt = physics_dt"):
        C.from_dict(C.WalkConfig, {"sim": {"physics_dt": 0.001}})
    old = C.from_dict(C.WalkConfig, {"sim": {"physics_dt": 0.001, "controller_dt": 0.001}})
    assert old.sim.physics_substeps == 1
