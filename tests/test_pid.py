"""Joint PID: closed-form P and D terms, integral clamp, no windup while saturated, bad inputs."""
import numpy as np
import pytest

from cyberdog.config import PIDConfig
from cyberdog.core.pid import JointPID, per_joint

DT = 0.001  # s


def test_gains_tiled_per_joint_type():
    pid = JointPID.from_config(PIDConfig(kp=(10.0, 20.0, 30.0), kd=(1.0, 2.0, 3.0)), DT, 25.0)
    np.testing.assert_array_equal(pid.kp, [10, 20, 30] * 4)
    np.testing.assert_array_equal(pid.kd, [1, 2, 3] * 4)
    np.testing.assert_array_equal(per_joint(np.arange(12.0)), np.arange(12.0))


def test_pd_terms_closed_form():
    rng = np.random.default_rng(1)
    kp, kd = rng.uniform(10, 80, 12), rng.uniform(0.5, 3, 12)
    pid = JointPID(kp, 0.0, kd, integral_limit=2.0, dt=DT, torque_limit=np.inf)
    for _ in range(5):
        q_t, q, dq_t, dq = rng.normal(size=(4, 12))
        np.testing.assert_allclose(pid.torque(q_t, q, dq_t, dq), kp * (q_t - q) + kd * (dq_t - dq), rtol=1e-12)
    np.testing.assert_array_equal(pid.integral, 0.0)


def test_output_clipped_to_torque_limit():
    pid = JointPID(100.0, 0.0, 0.0, 0.0, DT, torque_limit=25.0)
    tau = pid.torque(np.linspace(-1, 1, 12), np.zeros(12), np.zeros(12), np.zeros(12))
    np.testing.assert_allclose(tau, np.clip(100 * np.linspace(-1, 1, 12), -25, 25))


def test_integral_accumulates_then_clamps():
    ki, e, limit = 50.0, 0.2, 2.0  # integral grows by ki·e·dt = 0.01 N·m per step
    pid = JointPID(0.0, ki, 0.0, integral_limit=limit, dt=DT, torque_limit=25.0)
    zeros = np.zeros(12)
    for _ in range(100):
        tau = pid.torque(np.full(12, e), zeros, zeros, zeros)
    np.testing.assert_allclose(tau, 100 * ki * e * DT)
    for _ in range(1000):
        tau = pid.torque(np.full(12, -e), zeros, zeros, zeros)
    np.testing.assert_allclose(tau, -limit)
    pid.reset()
    np.testing.assert_array_equal(pid.torque(zeros, zeros, zeros, zeros), 0.0)


def test_no_windup_under_saturation():
    kp, ki, limit = 100.0, 100.0, 25.0
    pid = JointPID(kp, ki, 0.0, integral_limit=20.0, dt=DT, torque_limit=limit)
    zeros = np.zeros(12)
    for _ in range(2000):  # error 1 rad → P alone is 100 N·m, far past the 25 N·m limit
        tau = pid.torque(np.ones(12), zeros, zeros, zeros)
    np.testing.assert_allclose(tau, limit)
    np.testing.assert_array_equal(pid.integral, 0.0)  # nothing stored while saturated
    small = 0.05  # back inside the linear range: the output is the P term alone, no stored torque
    np.testing.assert_allclose(pid.torque(np.full(12, small), zeros, zeros, zeros), kp * small + ki * small * DT)
    # a windup-prone PID (plain integration with the same clamp) would hold +20 N·m here instead


def test_integrates_when_saturated_against_the_error():
    # large D term drives the output to −limit while the position error is positive: integration continues
    pid = JointPID(1.0, 10.0, 100.0, integral_limit=5.0, dt=DT, torque_limit=25.0)
    zeros = np.zeros(12)
    tau = pid.torque(np.full(12, 0.1), zeros, zeros, np.ones(12))
    np.testing.assert_allclose(tau, -25.0)
    np.testing.assert_allclose(pid.integral, 10.0 * 0.1 * DT)


@pytest.mark.parametrize("kwargs, match", [
    ({"kp": -1.0}, "kp"),
    ({"kd": (1.0, 2.0)}, "kd"),
    ({"dt": 0.0}, "dt"),
    ({"torque_limit": 0.0}, "torque_limit"),
    ({"integral_limit": -1.0}, "integral_limit"),
])
def test_bad_arguments_raise(kwargs, match):
    args = {"kp": 60.0, "ki": 0.0, "kd": 2.0, "integral_limit": 2.0, "dt": DT, "torque_limit": 25.0} | kwargs
    with pytest.raises(ValueError, match=match):
        JointPID(**args)


def test_bad_shape_raises():
    pid = JointPID(60.0, 0.0, 2.0, 2.0, DT, 25.0)
    with pytest.raises(ValueError, match="q_target"):
        pid.torque(np.zeros(3), np.zeros(12), np.zeros(12), np.zeros(12))
