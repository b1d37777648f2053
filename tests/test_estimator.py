"""State estimation with synthetic data (no simulator): simulated IMU, leg odometry, velocity Kalman filter."""
import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from cyberdog.config import EstimatorConfig, RobotConfig
from cyberdog.core.estimator import ImuReading, SimulatedIMU, VelocityEstimator, leg_odometry_velocity
from cyberdog.core.kinematics import abad_offsets, foot_position, jacobian, standing_joint_angles

DT = 0.001  # s, 1 kHz IMU and filter
NOISY = EstimatorConfig()  # with the IMU's noise switched on (`noise=True` below)


def body_motion(duration=4.0):
    """Known trot-like motion: world velocity, acceleration (analytic) and body rotation matrices."""
    t = np.arange(0.0, duration, DT)
    w1, w2, w3 = 2 * np.pi * 2.5, 2 * np.pi * 0.5, 2 * np.pi * 5.0
    v = np.stack([1 + 0.2 * np.sin(w1 * t), 0.05 * np.sin(w2 * t), 0.02 * np.sin(w3 * t)], axis=1)
    a = np.stack([0.2 * w1 * np.cos(w1 * t), 0.05 * w2 * np.cos(w2 * t), 0.02 * w3 * np.cos(w3 * t)], axis=1)
    rpy = np.stack([0.03 * np.sin(w1 * t), 0.02 * np.sin(w3 * t + 0.3), 0.1 * t], axis=1)
    R = Rotation.from_euler("xyz", rpy).as_matrix()
    # world angular velocity from dR/dt · Rᵀ (only feeds the gyro, which the velocity filter does not use)
    dR = np.gradient(R, DT, axis=0)
    S = dR @ np.transpose(R, (0, 2, 1))
    omega = np.stack([S[:, 2, 1], S[:, 0, 2], S[:, 1, 0]], axis=1)
    return t, v, a, R, omega


def run_filter(seed, cfg=NOISY, duration=4.0):
    """Returns truth, filter estimate and leg-odometry measurements (NaN rows where dropped)."""
    rng = np.random.default_rng(seed)
    t, v, a, R, omega = body_motion(duration)
    imu = SimulatedIMU(cfg, rng, DT, noise=True)
    est = VelocityEstimator(cfg, DT)
    est.reset(v[0])  # the robot starts from a known state (standing still on the real robot)
    estimates = np.empty_like(v)
    legs = np.full_like(v, np.nan)
    for k in range(len(t)):
        reading = imu.measure(a[k], omega[k], R[k])
        # leg odometry: truth + 0.1 m/s noise, lost around each touchdown (15 ms every 0.2 s) and 5 % at random
        touchdown = (t[k] % 0.2) < 0.015
        if not touchdown and rng.random() > 0.05:
            legs[k] = R[k] @ (R[k].T @ v[k] + rng.normal(0.0, 0.1, 3))  # world frame, for the error
            leg_body = R[k].T @ legs[k]
        else:
            leg_body = None
        estimates[k] = est.update(reading, leg_body, R[k])
    return v, estimates, legs


def rms(err):
    return float(np.sqrt(np.mean(np.sum(err ** 2, axis=-1))))


def test_filter_beats_leg_odometry_and_meets_accuracy():
    v, estimates, legs = run_filter(seed=7)
    ok = np.all(np.isfinite(legs), axis=1)
    assert 0.7 < ok.mean() < 0.9  # dropouts happened
    rms_filter = rms(estimates - v)
    rms_legs = rms(legs[ok] - v[ok])
    print(f"RMS velocity error: filter {rms_filter:.4f} m/s, raw leg odometry {rms_legs:.4f} m/s")
    assert rms_filter < 0.05
    assert rms_filter < rms_legs
    assert rms(estimates[:, 0:1] - v[:, 0:1]) < 0.05  # forward speed alone, the one the reward uses


def test_reproducible_with_a_fixed_seed():
    _, e1, l1 = run_filter(seed=3, duration=0.5)
    _, e2, l2 = run_filter(seed=3, duration=0.5)
    _, e3, _ = run_filter(seed=4, duration=0.5)
    np.testing.assert_array_equal(e1, e2)
    np.testing.assert_array_equal(l1, l2)
    assert not np.array_equal(e1, e3)


def test_imu_without_noise_is_exact():
    imu = SimulatedIMU(EstimatorConfig(), np.random.default_rng(0), DT)
    R = Rotation.from_euler("xyz", [0.1, -0.2, 0.7]).as_matrix()
    at_rest = imu.measure(np.zeros(3), np.zeros(3), np.eye(3))
    np.testing.assert_allclose(at_rest.accelerometer, [0.0, 0.0, 9.81])
    a_w, w_w = np.array([0.5, -0.2, 1.0]), np.array([0.1, 0.2, -0.3])
    world = imu.measure(a_w, w_w, R)
    body = imu.measure(R.T @ a_w, R.T @ w_w, R, frame="body")
    np.testing.assert_allclose(world.accelerometer, R.T @ (a_w + [0, 0, 9.81]))
    np.testing.assert_allclose(world.gyroscope, R.T @ w_w)
    np.testing.assert_allclose(body.accelerometer, world.accelerometer)
    np.testing.assert_allclose(body.gyroscope, world.gyroscope)
    with pytest.raises(ValueError, match="frame"):
        imu.measure(a_w, w_w, R, frame="leg")


def test_imu_noise_statistics():
    cfg = EstimatorConfig(accelerometer_bias_walk=0.0, gyroscope_bias_walk=0.0)
    imu = SimulatedIMU(cfg, np.random.default_rng(1), DT, noise=True)
    readings = [imu.measure(np.zeros(3), np.zeros(3), np.eye(3)) for _ in range(5000)]
    acc = np.array([r.accelerometer for r in readings])
    gyr = np.array([r.gyroscope for r in readings])
    np.testing.assert_allclose(acc.mean(axis=0), imu.accelerometer_bias + [0, 0, 9.81], atol=0.005)
    np.testing.assert_allclose(acc.std(axis=0), cfg.accelerometer_noise_std, rtol=0.05)
    np.testing.assert_allclose(gyr.std(axis=0), cfg.gyroscope_noise_std, rtol=0.05)


def test_filter_integrates_accelerometer_when_no_foot_touches():
    est = VelocityEstimator(EstimatorConfig(), DT)
    est.reset([1.0, 0.0, 0.0])
    P0 = est.covariance
    R = Rotation.from_euler("z", 0.5).as_matrix()
    a_world = np.array([0.3, -0.1, 0.2])
    f_body = R.T @ (a_world + [0, 0, 9.81])
    for _ in range(100):
        v = est.update(ImuReading(f_body, np.zeros(3)), np.full(3, np.nan), R)
    np.testing.assert_allclose(v, [1.0, 0.0, 0.0] + a_world * 0.1, atol=1e-12)
    assert np.all(np.diag(est.covariance) > np.diag(P0))
    with pytest.raises(ValueError, match="dt"):
        est.update(f_body, None, R, dt=0.0)


@pytest.mark.parametrize("contacts", [[True, False, False, True], [False, True, True, False], [True] * 4,
                                      [True, False, False, False]])
def test_leg_odometry_recovers_body_velocity(contacts):
    robot = RobotConfig()
    rng = np.random.default_rng(2)
    q = standing_joint_angles(robot) + rng.normal(0.0, 0.1, (4, 3))
    v_body, omega = np.array([0.9, -0.05, 0.02]), np.array([0.1, -0.2, 0.3])
    p_foot = abad_offsets(robot) + foot_position(q, robot)
    J = jacobian(q, robot)
    dq = rng.normal(0.0, 3.0, (4, 3))  # swing legs move freely
    for leg in np.flatnonzero(contacts):  # stance feet fixed in the world: J dq = −(v + ω × p)
        dq[leg] = np.linalg.solve(J[leg], -(v_body + np.cross(omega, p_foot[leg])))
    v = leg_odometry_velocity(q.ravel(), dq.ravel(), np.array(contacts), omega, robot, rolling=False)
    np.testing.assert_allclose(v, v_body, atol=1e-10)


def test_leg_odometry_without_contact_is_nan_and_skipped():
    robot = RobotConfig()
    q = standing_joint_angles(robot)
    v = leg_odometry_velocity(q, np.ones((4, 3)), np.zeros(4, bool), np.zeros(3), robot)
    assert v.shape == (3,) and np.all(np.isnan(v))
    est = VelocityEstimator(EstimatorConfig(), DT)
    out = est.update(np.array([0.0, 0.0, 9.81]), v, np.eye(3))
    np.testing.assert_allclose(out, 0.0, atol=1e-12)


@pytest.mark.parametrize("field,value", [("leg_velocity_noise_std", 0.0), ("process_noise_std", -1.0),
                                         ("accelerometer_noise_std", -0.1), ("gyroscope_bias_walk", np.inf)])
def test_bad_config_raises_naming_the_field(field, value):
    with pytest.raises(ValueError, match=f"EstimatorConfig.{field}"):
        EstimatorConfig(**{field: value})


def test_bad_arguments_raise():
    with pytest.raises(ValueError, match="dt"):
        SimulatedIMU(EstimatorConfig(), np.random.default_rng(0), dt=0.0)
    with pytest.raises(TypeError, match="Generator"):
        SimulatedIMU(EstimatorConfig(), 0, dt=DT)
    with pytest.raises(ValueError, match="dt"):
        VelocityEstimator(EstimatorConfig(), dt=-1.0)


def test_velocity_filter_is_the_kalman_filter_of_its_docstring():
    """The estimator (filterpy's KalmanFilter) against the docstring's model written out as three independent
    scalar filters (F = H = I, diagonal P, Q, R): predict v += a·dt, P += (σ_q·dt)²; update with the leg
    velocity when there is one (Joseph form). Steps of two lengths, some without a foot on the ground."""
    cfg = EstimatorConfig()
    rng = np.random.default_rng(8)
    est = VelocityEstimator(cfg, 0.005)
    v0 = rng.normal(0, 1, 3)
    est.reset(v0)
    x, p = v0.tolist(), [cfg.initial_velocity_std ** 2] * 3
    r, gravity = cfg.leg_velocity_noise_std ** 2, np.array([0.0, 0.0, -9.81])
    for k in range(2000):
        R = np.linalg.qr(rng.normal(size=(3, 3)))[0]
        f = rng.normal(0, 5, 3) + [0.0, 0.0, 9.81]
        leg = None if k % 5 == 0 else rng.normal(0, 1, 3)
        dt = 0.005 if k % 11 else 0.002
        got = est.update(f, leg, R, dt)
        a = R @ f + gravity
        x = [xi + dt * ai for xi, ai in zip(x, a)]
        p = [pi + (cfg.process_noise_std * dt) ** 2 for pi in p]
        if leg is not None:
            z = R @ leg
            for i in range(3):
                gain = p[i] / (p[i] + r)
                x[i] += gain * (z[i] - x[i])
                p[i] = (1 - gain) ** 2 * p[i] + gain ** 2 * r
        np.testing.assert_allclose(got, x, rtol=1e-10, atol=1e-12)
        np.testing.assert_allclose(est.covariance, np.diag(p), rtol=1e-10, atol=1e-15)
