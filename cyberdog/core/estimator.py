"""State estimation as on the hardware: a simulated MEMS IMU, leg odometry, and a velocity Kalman filter.

Beyond the paper (which reads the simulator's true states). The real CyberDog knows its body velocity only
from an IMU and its joint encoders; this module lets the environment observe the same estimate.

- `SimulatedIMU`: accelerometer (specific force: measures a − g, so +9.81 m/s² up at rest) and gyroscope
  readings in the body frame, with white noise and a turn-on + random-walk bias, all drawn from an explicit
  `numpy.random.Generator`.
- `leg_odometry_velocity`: the body velocity implied by the stance feet staying still on the ground.
- `VelocityEstimator`: a `filterpy` Kalman filter over the body's world-frame linear velocity, predicted
  with the accelerometer rotated to the world with gravity removed, corrected with leg odometry.

Frames: world x forward (at start), y left, z up; body frame as the URDF base. `rotation_matrix` R maps
body-frame vectors to the world (v_world = R v_body). The body's orientation is taken as known (on the robot
it comes from the IMU's attitude filter); the gyroscope reading is not used by the velocity filter.
"""
from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from filterpy.kalman import KalmanFilter

from cyberdog.config import EstimatorConfig, RobotConfig
from cyberdog.core.kinematics import FRONT_REAR, LEFT_RIGHT

STANDARD_GRAVITY = 9.81  # m/s², default; pass SimConfig.gravity where it differs
_LEG_SIDE = tuple(LEFT_RIGHT.tolist())  # +1 left, −1 right (Python floats for the per-leg loop)
_LEG_END = tuple(FRONT_REAR.tolist())  # +1 front, −1 hind


class ImuReading(NamedTuple):
    accelerometer: np.ndarray  # (3,) m/s², specific force in the body frame
    gyroscope: np.ndarray  # (3,) rad/s, angular velocity in the body frame


class SimulatedIMU:
    """MEMS IMU on the body: true motion in, noisy body-frame readings out.

    reading = truth + bias + white noise, each axis independent; bias = turn-on bias (drawn at `reset`,
    std `*_bias_std`) + random walk (std `*_bias_walk`·√dt per sample). With `noise` False the readings are
    exact and the generator is never used.
    """

    def __init__(self, cfg: EstimatorConfig, rng: np.random.Generator, dt: float,
                 gravity: float = STANDARD_GRAVITY, noise: bool = False) -> None:
        if not (dt > 0 and np.isfinite(dt)):
            raise ValueError(f"SimulatedIMU dt must be > 0 s and finite, got {dt!r}")
        if not isinstance(rng, np.random.Generator):
            raise TypeError(f"rng must be a numpy.random.Generator, got {type(rng).__name__}")
        self.cfg, self.rng, self.dt, self.noise = cfg, rng, float(dt), bool(noise)
        self.gravity = np.array([0.0, 0.0, -float(gravity)])  # m/s², world frame
        self.reset()

    def reset(self) -> None:
        """Draw new turn-on biases (zero when noise is off)."""
        c = self.cfg
        if self.noise:
            self.accelerometer_bias = self.rng.normal(0.0, c.accelerometer_bias_std, 3)
            self.gyroscope_bias = self.rng.normal(0.0, c.gyroscope_bias_std, 3)
        else:
            self.accelerometer_bias = np.zeros(3)
            self.gyroscope_bias = np.zeros(3)

    def measure(self, linear_acceleration: np.ndarray, angular_velocity: np.ndarray,
                rotation_matrix: np.ndarray, frame: str = "world") -> ImuReading:
        """One sample from the body's linear acceleration (m/s², e.g. the world velocity difference / dt) and
        angular velocity (rad/s), both given in `frame` ("world", as PyBullet reports them, or "body")."""
        R = np.asarray(rotation_matrix, dtype=float).reshape(3, 3)
        a = np.asarray(linear_acceleration, dtype=float).reshape(3)
        w = np.asarray(angular_velocity, dtype=float).reshape(3)
        if frame == "world":
            f_body = R.T @ (a - self.gravity)
            w_body = R.T @ w
        elif frame == "body":
            f_body = a - R.T @ self.gravity
            w_body = w
        else:
            raise ValueError(f"frame must be 'world' or 'body', got {frame!r}")
        c = self.cfg
        if not self.noise:
            return ImuReading(f_body, w_body)
        sqrt_dt = np.sqrt(self.dt)
        self.accelerometer_bias = self.accelerometer_bias + self.rng.normal(0.0, c.accelerometer_bias_walk * sqrt_dt, 3)
        self.gyroscope_bias = self.gyroscope_bias + self.rng.normal(0.0, c.gyroscope_bias_walk * sqrt_dt, 3)
        accelerometer = f_body + self.accelerometer_bias + self.rng.normal(0.0, c.accelerometer_noise_std, 3)
        gyroscope = w_body + self.gyroscope_bias + self.rng.normal(0.0, c.gyroscope_noise_std, 3)
        return ImuReading(accelerometer, gyroscope)


def leg_odometry_velocity(q: np.ndarray, dq: np.ndarray, contacts: np.ndarray,
                          body_angular_velocity: np.ndarray, robot_cfg: RobotConfig,
                          rolling: bool = True) -> np.ndarray:
    """(3,) body-frame linear velocity of the body from the stance legs, m/s; NaN when no foot is in contact.

    A stance foot stands still in the world: 0 = v_body + ω × p_foot + J(q)·dq (all in the body frame, p_foot
    from the body centre), so each stance foot gives v_body = −(J(q)·dq + ω × p_foot); the estimates of the
    feet in contact are averaged. q, dq: (12,) or (4, 3) joint angles (rad) and speeds (rad/s) in the order
    LF, RF, LH, RH × (abad, hip, knee); contacts: (4,) bool; body_angular_velocity: (3,) rad/s, body frame.
    With `rolling` (default) the foot sphere rolls on the ground instead of standing still: its centre moves
    at ω_foot × (0, 0, r) = (ω_foot,y·r, 0, 0), with ω_foot,y = body pitch rate + hip + knee speeds. Ignoring
    it biased the forward estimate by about −6 % in a 1 m/s trot (r = 18 mm, ω_foot ≈ −3 rad/s).
    """
    q = np.asarray(q, dtype=float).reshape(12).tolist()
    dq = np.asarray(dq, dtype=float).reshape(12).tolist()
    contacts = np.asarray(contacts, dtype=bool).reshape(4).tolist()
    wx, wy, wz = np.asarray(body_angular_velocity, dtype=float).reshape(3).tolist()
    if not any(contacts):
        return np.full(3, np.nan)
    # leg by leg in Python floats (this runs at the estimator rate inside the env): the formulas of
    # abad_offsets + foot_position and jacobian(q) · dq, for the legs in contact only
    l1, l2, l3 = robot_cfg.l1, robot_cfg.l2, robot_cfg.l3
    total = [0.0, 0.0, 0.0]
    for leg in range(4):
        if not contacts[leg]:
            continue
        abad, hip, knee = q[3 * leg:3 * leg + 3]
        d_abad, d_hip, d_knee = dq[3 * leg:3 * leg + 3]
        c1, s1 = math.cos(abad), math.sin(abad)
        s_h, c_h, s_hk, c_hk = math.sin(hip), math.cos(hip), math.sin(hip + knee), math.cos(hip + knee)
        x, z_leg = -l2 * s_h - l3 * s_hk, -l2 * c_h - l3 * c_hk  # sagittal_foot_position
        y_leg = _LEG_SIDE[leg] * l1
        # foot in the body frame: abad offset + abad rotation of (x, y_leg, z_leg)
        px = _LEG_END[leg] * robot_cfg.abad_offset_x + x
        py = _LEG_SIDE[leg] * robot_cfg.abad_offset_y + (c1 * y_leg - s1 * z_leg)
        pz = s1 * y_leg + c1 * z_leg
        # foot velocity relative to the body, J(q)·dq (rows of `jacobian`)
        dz_dhip, dz_dknee = l2 * s_h + l3 * s_hk, l3 * s_hk
        vx = (-l2 * c_h - l3 * c_hk) * d_hip + (-l3 * c_hk) * d_knee
        vy = (-s1 * y_leg - c1 * z_leg) * d_abad + (-s1 * dz_dhip) * d_hip + (-s1 * dz_dknee) * d_knee
        vz = (c1 * y_leg - s1 * z_leg) * d_abad + (c1 * dz_dhip) * d_hip + (c1 * dz_dknee) * d_knee
        # v_body = −(v_foot_rel + ω × p_foot)
        v = [-(vx + (wy * pz - wz * py)), -(vy + (wz * px - wx * pz)), -(vz + (wx * py - wy * px))]
        if rolling:
            v[0] += (wy + d_hip + d_knee) * robot_cfg.foot_radius
        total = [a + b for a, b in zip(total, v)]
    n = sum(contacts)
    return np.array([a / n for a in total])


class VelocityEstimator:
    """Kalman filter (filterpy) over the body's linear velocity in the world frame, x = [vx, vy, vz] (m/s).

    predict:  v ← v + (R·f_accelerometer + g)·dt,   process noise Q = (process_noise_std·dt)² I
    update:   z = R·v_leg (leg odometry rotated to the world),   measurement noise R = leg_velocity_noise_std² I
    The update is skipped when no foot is in contact (leg velocity None or not finite). The accelerometer
    bias is not a state: a constant bias b leaves a lag of about b·τ with τ the filter's time constant
    (≈ 0.2 s with the defaults at 1 kHz, so 0.05 m/s² → 0.01 m/s).
    """

    def __init__(self, cfg: EstimatorConfig, dt: float, gravity: float = STANDARD_GRAVITY) -> None:
        if not (dt > 0 and np.isfinite(dt)):
            raise ValueError(f"VelocityEstimator dt must be > 0 s and finite, got {dt!r}")
        self.cfg, self.dt = cfg, float(dt)
        self.gravity = np.array([0.0, 0.0, -float(gravity)])
        self.kf = KalmanFilter(dim_x=3, dim_z=3, dim_u=3)
        self.kf.F = np.eye(3)
        self.kf.H = np.eye(3)
        self.kf.R = np.eye(3) * cfg.leg_velocity_noise_std ** 2
        self.kf.B, self.kf.Q = self._input_matrices(self.dt)
        self.reset()

    def _input_matrices(self, dt: float) -> tuple[np.ndarray, np.ndarray]:
        """B = dt·I (the acceleration integrated over dt) and Q = (process_noise_std·dt)²·I for a step of dt s."""
        return np.eye(3) * dt, np.eye(3) * (self.cfg.process_noise_std * dt) ** 2

    def reset(self, v0: np.ndarray | None = None) -> None:
        """Start from world velocity v0 (m/s; zeros if None) with the configured initial uncertainty."""
        v0 = np.zeros(3) if v0 is None else np.asarray(v0, dtype=float).reshape(3)
        self.kf.x = v0.reshape(3, 1).copy()
        self.kf.P = np.eye(3) * self.cfg.initial_velocity_std ** 2

    @property
    def velocity(self) -> np.ndarray:
        """(3,) estimated world-frame velocity, m/s."""
        return self.kf.x.reshape(3).copy()

    @property
    def covariance(self) -> np.ndarray:
        return self.kf.P.copy()

    def update(self, imu: ImuReading | np.ndarray, leg_velocity: np.ndarray | None,
               rotation_matrix: np.ndarray, dt: float | None = None) -> np.ndarray:
        """One filter step: predict with the accelerometer over dt (s; default the constructor's), then correct
        with the body-frame leg-odometry velocity if there is one. Returns the world-frame estimate (3,)."""
        dt = self.dt if dt is None else float(dt)
        if not (dt > 0 and np.isfinite(dt)):
            raise ValueError(f"dt must be > 0 s and finite, got {dt!r}")
        R = np.asarray(rotation_matrix, dtype=float).reshape(3, 3)
        f_body = np.asarray(imu.accelerometer if isinstance(imu, ImuReading) else imu, dtype=float).reshape(3)
        a_world = R @ f_body + self.gravity
        z = None
        if leg_velocity is not None:
            v_leg = np.asarray(leg_velocity, dtype=float).reshape(3)
            if np.all(np.isfinite(v_leg)):
                z = R @ v_leg
        B, Q = (None, None) if dt == self.dt else self._input_matrices(dt)  # None: the filter's own, for self.dt
        self.kf.predict(u=a_world.reshape(3, 1), B=B, Q=Q)
        if z is not None:
            self.kf.update(z.reshape(3, 1))
        return self.velocity
