"""The joint controller's rate apart from the physics rate: a torque held by hand over the physics steps of a
period is what PyBullet's substeps hold (`Robot.step`), and the rates are validated. The drivers at the
physics rate and the energy of what PyBullet received: tests/test_drivers.py."""
import numpy as np
import pybullet
import pytest

from cyberdog import config as C
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
        robot.client.setPhysicsEngineParameter(fixedTimeStep=physics_dt, numSubSteps=1)  # the robot's own setting
        robot.reset()
        for _ in range(40):
            robot.step(torque)  # the robot's hold: one physics step at a time
        held = robot.joint_angles()
    assert np.abs(in_cpp - robot_rest_angles(cfg)).max() > 0.05  # the torque did move the joints
    np.testing.assert_array_equal(in_cpp, by_hand)
    np.testing.assert_array_equal(held, by_hand)


def robot_rest_angles(cfg: C.WalkConfig) -> np.ndarray:
    from cyberdog.core.kinematics import standing_joint_angles
    return standing_joint_angles(cfg.robot).ravel()


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
