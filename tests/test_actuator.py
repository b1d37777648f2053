"""Actuator model (torque clip, torque–speed envelope, friction) and the torque path of Robot.step."""
import numpy as np
import pytest

from cyberdog.config import ActuatorConfig, RobotConfig, SimConfig
from cyberdog.core.actuator import ActuatorModel
from oracles import torque_envelope

CFG = ActuatorConfig()  # 25 N·m, full torque to 11.4145 rad/s, zero at 20.9136 rad/s
N1, N2, LIMIT = CFG.full_torque_speed, CFG.zero_torque_speed, CFG.torque_limit


def motor(model: ActuatorModel, command, omega) -> np.ndarray:
    """The motor torque of the model's law (12 floats) as an array."""
    return np.array(model.joint_torque(command, omega)[0])


def friction(model: ActuatorModel, omega) -> np.ndarray:
    """What the joints feel beyond the motor torque: the friction of the model's law."""
    m, joint = model.joint_torque(np.zeros(12), omega)
    return np.subtract(joint, m)


def test_clip_to_torque_limit():
    model = ActuatorModel(CFG)
    cmd = np.array([100.0, -100.0, 24.0, -24.0, 0.0, 25.0, -25.0, 30.0, -1e6, 1e6, 3.0, -3.0])
    tau = motor(model, cmd, np.zeros(12))
    assert tau.shape == (12,)
    np.testing.assert_allclose(tau, [25, -25, 24, -24, 0, 25, -25, 25, -25, 25, 3, -3])
    assert cmd[0] == 100.0  # input untouched


@pytest.mark.parametrize("sign", [1.0, -1.0])
@pytest.mark.parametrize("speed, available", [
    (0.0, LIMIT), (5.0, LIMIT), (N1 - 1e-9, LIMIT), (N1, LIMIT),
    ((N1 + N2) / 2, LIMIT / 2), (N2, 0.0), (N2 + 0.01, 0.0), (30.0, 0.0),
])
def test_torque_speed_envelope_when_motoring(speed, available, sign):
    model = ActuatorModel(CFG)
    omega = np.full(12, sign * speed)
    tau = motor(model, np.full(12, sign * 100.0), omega)  # torque along the motion: motoring
    np.testing.assert_allclose(tau, sign * available, atol=1e-9)
    np.testing.assert_allclose(torque_envelope(model, omega), available, atol=1e-9)  # the tests' oracle


@pytest.mark.parametrize("speed", [5.0, (N1 + N2) / 2, N2, 30.0])
def test_braking_torque_is_only_clipped(speed):
    model = ActuatorModel(CFG)
    omega = np.array([speed, -speed] * 6)
    cmd = np.array([-100.0, 100.0, -10.0, 10.0] * 3)  # every torque opposes its joint's motion
    np.testing.assert_allclose(motor(model, cmd, omega), [-25.0, 25.0, -10.0, 10.0] * 3)


def test_envelope_off_only_clips():
    model = ActuatorModel(ActuatorConfig(torque_speed_curve=False))
    np.testing.assert_allclose(motor(model, np.full(12, 100.0), np.full(12, 30.0)), 25.0)


def test_friction_off_is_zero():
    model = ActuatorModel(ActuatorConfig(friction=False))
    np.testing.assert_array_equal(friction(model, np.linspace(-20, 20, 12)), np.zeros(12))


def test_friction_on_opposes_motion():
    model = ActuatorModel(ActuatorConfig(friction=True))
    omega = np.array([0.0, 1.0, -1.0, 10.0, -10.0, 0.001, -0.001, 20.0, 0.5, -0.5, 2.0, -2.0])
    tau = friction(model, omega)
    expected = -(CFG.viscous_damping * omega + CFG.dry_friction * np.tanh(omega / 0.01))
    np.testing.assert_allclose(tau, expected)
    assert tau[0] == 0.0
    assert np.all(tau[1:] * omega[1:] < 0)  # dissipative
    np.testing.assert_allclose(tau[1], -(0.01 + 0.246), atol=1e-6)  # ω = 1 rad/s: viscous + full Coulomb
    m, total = model.joint_torque(np.full(12, 5.0), omega)
    np.testing.assert_allclose(np.subtract(total, m), tau)


@pytest.fixture(scope="module")
def robot():
    from cyberdog.sim import Robot

    r = Robot(RobotConfig(), ActuatorConfig(friction=True), SimConfig())
    yield r
    r.close()


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_robot_step_rejects_non_finite(robot, bad):
    cmd = np.zeros(12)
    cmd[4] = bad
    steps = robot.physics_steps
    with pytest.raises(ValueError, match="finite"):
        robot.step(cmd)
    assert robot.physics_steps == steps  # nothing was simulated


def test_robot_step_rejects_wrong_shape(robot):
    with pytest.raises(ValueError, match="shape"):
        robot.step(np.zeros(11))
    with pytest.raises(ValueError, match="12 numbers"):
        robot.step([0.0] * 11)


def test_robot_step_returns_clipped_motor_torque_without_friction(robot):
    robot.reset()
    cmd = np.array([100.0, -100.0, 3.0] * 4)
    applied = robot.step(cmd)  # at rest: only the clip acts, and friction is not part of the motor torque
    np.testing.assert_allclose(applied, [25.0, -25.0, 3.0] * 4)
