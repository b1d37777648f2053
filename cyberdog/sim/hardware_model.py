"""The one hardware model: what separates the simulated robot from the real one (beyond the paper).

`HardwareConfig` (cyberdog.config) names the effects; this module applies them at the controller rate (joint
friction and motor strength act in the actuator law, at every physics step), for the learning environment and
for the scripted walks alike (`cyberdog.loop.walker.Walker` owns one):

- `hardware_walk_config`: the walk config the simulator must be built with (joint friction on or off);
- `draw_mass_scale`: the mass-scale draw in [1 − u, 1 + u];
- `CommandDelay`: actuation latency, the controller's command held in a FIFO of whole controller periods;
- `HardwareSensing`: what the robot's software reads: noisy joint encoders and the Kalman body velocity
  from a simulated IMU and leg odometry (the estimator pieces of `cyberdog.core.estimator`). The noise is on
  what the locomotion controller reads; the motor drivers close their PD on their own encoders, the true
  joint state, at every physics step (`cyberdog.sim.robot.Robot.drive`);
- `draw_robot`: one robot from the ranges of a `RandomizationConfig` (domain randomisation), a `RobotDraw`
  that `Walker.reset` applies.

Randomness: a scripted walk seeds everything from `HardwareConfig.seed`: one `numpy.random.SeedSequence`
spawns independent streams for the mass draw and the sensors, so that the mass draw does not depend on which
sensors are on (same seed, same robot). The env seeds both per episode from its own generator instead.
"""
from __future__ import annotations

import dataclasses
from collections import deque

import numpy as np

from cyberdog.config import HardwareConfig, RandomizationConfig, WalkConfig
from cyberdog.core.estimator import SimulatedIMU, VelocityEstimator, leg_odometry_velocity

MASS_STREAM, SENSOR_STREAM = 0, 1  # indices of the child seed sequences of HardwareConfig.seed


def seeded_streams(hw: HardwareConfig) -> tuple[np.random.Generator, np.random.Generator]:
    """(mass generator, sensor generator) of a scripted walk, from `hw.seed`."""
    mass, sensor = np.random.SeedSequence(hw.seed).spawn(2)
    return np.random.default_rng(mass), np.random.default_rng(sensor)


def draw_mass_scale(hw: HardwareConfig, rng: np.random.Generator | None = None) -> float:
    """Mass (and inertia) scale of every link: a draw from U(1 − u, 1 + u), u = mass_uncertainty; 1 if u = 0.
    rng: the generator to draw from (default: the mass stream of `hw.seed`)."""
    u = hw.mass_uncertainty
    if u == 0:
        return 1.0
    rng = rng if rng is not None else seeded_streams(hw)[MASS_STREAM]
    return float(rng.uniform(1.0 - u, 1.0 + u))


@dataclasses.dataclass(frozen=True)
class RobotDraw:
    """One robot drawn from a `RandomizationConfig`: the values a walk or an episode is simulated with."""

    joint_friction_scale: float = 1.0  # × ActuatorConfig viscous and dry friction
    latency_periods: int = 0  # controller periods of actuation delay
    mass_scale: float = 1.0  # × every link's mass and inertia
    motor_strength: float = 1.0  # × the torque the motors produce
    kp_factor: float = 1.0  # × the PID's proportional gains
    kd_factor: float = 1.0  # × the PID's derivative gains and the drivers' joint damping (torque mode)
    ground_friction_scale: float = 1.0  # × SimConfig.ground_friction


def draw_robot(ranges: RandomizationConfig, rng: np.random.Generator) -> RobotDraw:
    """One draw of every range of `ranges`, uniformly and in the order of its fields (the same generator state
    gives the same robot); the latency is a whole number of periods, each value of its range equally likely."""
    values = {}
    for name in RandomizationConfig.RANGES:
        lo, hi = getattr(ranges, name)
        if name == "latency_periods":
            values[name] = int(rng.integers(lo, hi + 1))
        else:
            values[name] = float(rng.uniform(lo, hi))
    return RobotDraw(**values)


def resolve_draw(draw: RobotDraw, ranges: RandomizationConfig, latency_periods: int,
                 mass_scale: float | None) -> RobotDraw:
    """The one robot an episode walks, from a randomisation draw and the hardware's own effects, by one rule:
    a range left at its nominal value (no randomisation of that effect) keeps the hardware's value (its
    `latency_periods`; its `mass_scale` draw, None = 1), a range that is set replaces it. A set range that
    does not contain the hardware's value is refused where the config is made (`EnvConfig`), so that no
    effect is dropped without a word."""
    nominal = RandomizationConfig()
    changes = {}
    if ranges.latency_periods == nominal.latency_periods:
        changes["latency_periods"] = latency_periods
    if ranges.mass_scale == nominal.mass_scale and mass_scale is not None:
        changes["mass_scale"] = mass_scale
    return dataclasses.replace(draw, **changes) if changes else draw


def hardware_walk_config(cfg: WalkConfig, hw: HardwareConfig | None) -> WalkConfig:
    """`cfg` with the actuator's joint friction set by `hw.friction` (unchanged when hw is None).

    The energy model then counts friction once: simulated (in the applied torque) when on, added analytically
    to the electrical power when off (cyberdog.core.energy.drive_torque)."""
    if hw is None or cfg.actuator.friction == hw.friction:
        return cfg
    return dataclasses.replace(cfg, actuator=dataclasses.replace(cfg.actuator, friction=hw.friction))


def whole_steps(duration_s: float, dt: float, name: str) -> int:
    """`duration_s` in controller periods of `dt`; ValueError unless it is a whole multiple (0 allowed)."""
    n = int(round(duration_s / dt))
    if abs(duration_s / dt - n) > 1e-6:
        raise ValueError(f"{name} must be a whole multiple of SimConfig.controller_dt ({dt} s), got {duration_s!r}")
    return n


class CommandDelay:
    """Actuation latency: `push(x)` returns what was pushed `steps` calls before (None at first: no command
    has arrived yet). With steps = 0 it returns its input.

    The walker pushes the controller's command to the motor drivers (joint targets, target speeds, gains,
    feedforward and any torque added to it), and the drivers then close their PD on it at every physics step,
    on the joint state then: the latency sits on the command bus, not inside the PD loop, as on CyberDog, whose
    drivers take (q_des, qd_des, kp, kd, tau_des) and compute τ from their own encoders (MiRoboticsLab
    cyberdog_motor_sdk)."""

    def __init__(self, steps: int) -> None:
        self.reset(steps)

    def reset(self, steps: int | None = None) -> None:
        """Empty the queue, with a new delay of `steps` periods if given."""
        if steps is not None:
            if not (isinstance(steps, int) and steps >= 0):
                raise ValueError(f"latency steps must be an integer >= 0, got {steps!r}")
            self.steps = steps
        self._queue: deque = deque([None] * self.steps)

    def push(self, command):
        if self.steps == 0:
            return command
        self._queue.append(command)
        return self._queue.popleft()


class HardwareSensing:
    """What the robot's software measures, once per controller period.

    `read(k, state, contacts)` → (q, dq, v_world): encoder readings with white noise, and the Kalman estimate
    of the body velocity (world frame) when `estimated_velocity`, else None (the simulator's truth is used).
    The filter runs every `estimator_dt` (predict with the IMU, correct with leg odometry of the feet in
    contact); `contacts` is called only then.
    """

    def __init__(self, hw: HardwareConfig, cfg: WalkConfig, rng: np.random.Generator) -> None:
        self.hw, self.cfg, self.rng = hw, cfg, rng
        dt = cfg.sim.controller_dt
        self.estimator_every = whole_steps(hw.estimator_dt, dt, "HardwareConfig.estimator_dt")
        if self.estimator_every < 1:
            raise ValueError(f"HardwareConfig.estimator_dt must be >= SimConfig.controller_dt ({dt} s), "
                             f"got {hw.estimator_dt!r}")
        est = hw.estimator
        self.imu = SimulatedIMU(est, rng, hw.estimator_dt, cfg.sim.gravity, noise=hw.imu_noise)
        self.estimator = VelocityEstimator(est, hw.estimator_dt, cfg.sim.gravity)
        self.noisy = hw.joint_angle_noise_std > 0 or hw.joint_velocity_noise_std > 0
        self._prev_velocity_world = np.zeros(3)

    def reset(self, state) -> None:
        """Start at rest in `state` (a RobotState): the filter starts from the true (zero) velocity."""
        self.imu.reset()
        self.estimator.reset(state.base_linear_velocity_world)
        self._prev_velocity_world = state.base_linear_velocity_world.copy()

    @property
    def velocity_estimate_world(self) -> np.ndarray:
        """(3,) current Kalman estimate of the body velocity, world frame, m/s."""
        return self.estimator.velocity

    def joints(self, q: np.ndarray, dq: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Encoder readings of the true (q, dq): white noise of the configured std (none when 0)."""
        hw = self.hw
        if hw.joint_angle_noise_std > 0:
            q = q + self.rng.normal(0.0, hw.joint_angle_noise_std, q.shape)
        if hw.joint_velocity_noise_std > 0:
            dq = dq + self.rng.normal(0.0, hw.joint_velocity_noise_std, dq.shape)
        return q, dq

    def update_estimator(self, state, contacts) -> None:
        """One run of the velocity filter on the state read now (a period where `estimator_due`): `read` runs it
        for the trot controller; a walker with no controller (a torque policy) calls it itself."""
        dt = self.hw.estimator_dt
        R = state.rotation_matrix
        v_world = state.base_linear_velocity_world
        accel_world = (v_world - self._prev_velocity_world) / dt  # mean acceleration over the filter period
        self._prev_velocity_world = v_world.copy()
        imu = self.imu.measure(accel_world, state.base_angular_velocity_world, R, frame="world")
        q, dq = self.joints(state.q, state.dq)  # the encoders feed leg odometry too
        leg_v = leg_odometry_velocity(q, dq, contacts(), imu.gyroscope, self.cfg.robot)
        self.estimator.update(imu, leg_v, R)

    def estimator_due(self, k: int) -> bool:
        """The velocity filter runs at controller period k (every `estimator_every` periods after the first)."""
        return self.hw.estimated_velocity and k > 0 and k % self.estimator_every == 0

    def read(self, k: int, state, contacts) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
        """Sensor readings at controller period k (state read after period k − 1); `contacts()` → (4,) bool."""
        if self.estimator_due(k):
            self.update_estimator(state, contacts)
        q, dq = self.joints(state.q, state.dq)
        return q, dq, (self.estimator.velocity if self.hw.estimated_velocity else None)


__all__ = ["CommandDelay", "HardwareSensing", "RobotDraw", "draw_mass_scale", "draw_robot", "resolve_draw",
           "hardware_walk_config",
           "seeded_streams", "whole_steps"]
