"""Settings of the robot beyond the paper's ideal one: the IMU and velocity filter, the hardware model (latency,
friction, sensor noise, mass) and the ranges that domain randomisation draws robots from."""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Tuple

from cyberdog.config._validate import _check, _non_negative, _positive


@dataclass(frozen=True)
class EstimatorConfig:
    """Simulated IMU and the body-velocity Kalman filter (beyond the paper, which reads true states).

    Sensor numbers are assumptions [G] typical of a MEMS IMU such as the Bosch BMI088 sampled at 1 kHz
    (accelerometer noise density ≈ 160 µg/√Hz, gyroscope ≈ 0.014 °/s/√Hz, times √(500 Hz bandwidth)), with
    the turn-on bias left after a standstill calibration; `HardwareConfig.imu_noise` switches them on.
    """

    accelerometer_noise_std: float = 0.05  # m/s², white noise per sample [G: ≈ 0.035 for a BMI088]
    gyroscope_noise_std: float = 0.005  # rad/s, white noise per sample [G: ≈ 0.0055 for a BMI088]
    accelerometer_bias_std: float = 0.05  # m/s², constant bias drawn at each reset [G: after calibration]
    accelerometer_bias_walk: float = 0.001  # m/s² per √s, bias random walk [G]
    gyroscope_bias_std: float = 0.002  # rad/s, constant bias drawn at each reset [G: after calibration]
    gyroscope_bias_walk: float = 1e-4  # rad/s per √s, bias random walk [G]
    leg_velocity_noise_std: float = 0.1  # m/s, leg-odometry velocity error (slip, contact timing): filter R [G]
    process_noise_std: float = 0.5  # m/s², acceleration error per predict (noise, bias, attitude): filter Q [G]
    initial_velocity_std: float = 0.1  # m/s, filter's initial uncertainty after reset [G]

    def __post_init__(self) -> None:
        _non_negative(self, "accelerometer_noise_std", "gyroscope_noise_std", "accelerometer_bias_std",
                      "accelerometer_bias_walk", "gyroscope_bias_std", "gyroscope_bias_walk")
        _positive(self, "leg_velocity_noise_std", "process_noise_std", "initial_velocity_std")


@dataclass(frozen=True)
class HardwareConfig:
    """The one hardware model: what separates the simulated robot from the real one, beyond the paper.

    Used by the prototype experiment in simulation (paper Section 4.2, `cyberdog.analysis.walk.walk(...,
    hardware=...)`) and by the learning environment (`EnvConfig.hardware`, so that training can randomise
    over it); applied at the physics rate by `cyberdog.sim.hardware_model` inside `cyberdog.loop.walker.Walker`.
    The defaults are all off: `HardwareConfig()` is the ideal simulated robot of Section 4.1 (true states,
    no friction, no delay, nominal mass). `HARDWARE_LIKE` below turns every effect on. What each does:

    - `friction`: the joints feel viscous + dry friction (ActuatorConfig.viscous_damping 0.01 N·m·s/rad,
      dry_friction 0.246 N·m [X]) in the physics; the motors must overcome it (the paper's suspected cause of
      its 3 % sim-to-real gap). The torque–speed curve and copper loss are on in both cases (ActuatorConfig,
      cyberdog.core.energy).
    - `latency_s`: the controller's command (joint targets, target speeds, feedforward torque) reaches the motor
      drivers this long after it was computed (a FIFO of whole controller periods); the drivers close the
      joint PD on the encoder readings they have then, as CyberDog's do (its motor command is q_des, qd_des,
      kp, kd and tau_des; MiRoboticsLab cyberdog_motor_sdk). 2.5 ms [G]: one 400 Hz controller cycle, about
      one 500 Hz cycle of Xiaomi's locomotion controller plus the motor bus. (A delay inside the PD loop, the
      model before, made the PD fight itself: +40 % Eq. 7 on the hardware-like robot, docs/results.md.)
    - `joint_angle_noise_std`, `joint_velocity_noise_std`: white encoder noise on the q, q̇ the controller
      reads (the energy is computed from the true values) [G, as EnvConfig's defaults].
    - `estimated_velocity`: the controller's speed feedback is the Kalman estimate (simulated IMU + leg
      odometry, cyberdog.core.estimator) instead of the simulator's true body velocity; `imu_noise` adds the
      IMU's noise and bias (EstimatorConfig's [G] BMI088-like values).
    - `mass_uncertainty`: every link's mass and inertia are scaled by one draw from U(1 − u, 1 + u), from
      `seed` (±5 % in the preset [G]: the model's 13.57 kg against the spec's "about 14 kg", +3 %). The
      controller keeps the nominal mass: it does not know the draw.
    - `seed`: one seed for the mass draw and every sensor-noise generator (same seed, same walk).
    """

    friction: bool = False  # joint viscous + dry friction in the physics (values from ActuatorConfig [X])
    latency_s: float = 0.0  # s, command delay to the drivers, a whole multiple of SimConfig.controller_dt [G: 0.0025]
    joint_angle_noise_std: float = 0.0  # rad, encoder noise on the controller's q [G: 0.002]
    joint_velocity_noise_std: float = 0.0  # rad/s, noise on the controller's q̇ [G: 0.05]
    estimated_velocity: bool = False  # speed feedback from the IMU + leg-odometry Kalman filter, not the truth
    imu_noise: bool = False  # simulated IMU noise and bias (`estimator`'s values), with estimated_velocity
    estimator_dt: float = 0.005  # s, Kalman filter period, a whole multiple of SimConfig.controller_dt
    mass_uncertainty: float = 0.0  # ± fraction; mass scale drawn from U(1 − u, 1 + u) [G: 0.05]
    seed: int = 0  # seeds the mass draw and the sensor noise (scripted walks; the env seeds per episode)
    # the IMU's noise and bias values and the Kalman filter's tuning; `imu_noise` switches the noise on
    estimator: EstimatorConfig = field(default_factory=EstimatorConfig)

    @property
    def ideal(self) -> bool:
        """True when no effect is on (the ideal robot, whatever the seed)."""
        return not (self.friction or self.latency_s > 0 or self.joint_angle_noise_std > 0
                    or self.joint_velocity_noise_std > 0 or self.estimated_velocity or self.mass_uncertainty > 0)

    def __post_init__(self) -> None:
        _non_negative(self, "latency_s", "joint_angle_noise_std", "joint_velocity_noise_std", "mass_uncertainty")
        _positive(self, "estimator_dt")
        _check(self.latency_s <= 0.1, "HardwareConfig.latency_s", "in [0, 0.1] s", self.latency_s)
        _check(self.mass_uncertainty <= 0.5, "HardwareConfig.mass_uncertainty", "in [0, 0.5]",
               self.mass_uncertainty)
        _check(isinstance(self.seed, int) and not isinstance(self.seed, bool) and self.seed >= 0,
               "HardwareConfig.seed", "an integer >= 0", self.seed)
        _check(not self.imu_noise or self.estimated_velocity, "HardwareConfig.imu_noise",
               "False unless estimated_velocity is True (the IMU only feeds the estimator)", self.imu_noise)


# the prototype experiment's robot: every effect of HardwareConfig on ([G] values, see its docstring)
HARDWARE_LIKE = HardwareConfig(friction=True, latency_s=0.0025, joint_angle_noise_std=0.002,
                               joint_velocity_noise_std=0.05, estimated_velocity=True, imu_noise=True,
                               mass_uncertainty=0.05)


def check_controller_periods(hardware: HardwareConfig, controller_dt: float, where: str, dt_name: str) -> None:
    """ValueError unless `hardware`'s latency_s and estimator_dt are whole controller periods (`controller_dt` s,
    named `dt_name`; the filter at least one): the command FIFO and the Kalman filter step with the controller.
    `where`: the model's name in the error ("EnvConfig.hardware", or "hardware" as --set names it)."""
    for name, least in (("latency_s", 0.0), ("estimator_dt", controller_dt)):
        value = getattr(hardware, name)
        _check(abs(value / controller_dt - round(value / controller_dt)) < 1e-6 and value >= least - 1e-12,
               f"{where}.{name}", f"a whole multiple of {dt_name} ({controller_dt} s)", value)


@dataclass(frozen=True)
class RandomizationConfig:
    """Domain randomisation: the ranges the robot of each training episode is drawn from (beyond the paper).

    A policy trained on one simulated robot learns that robot's quirks (its saving may rest on how the ideal
    PID tracks a path, docs/results.md); drawn anew each episode from ranges around the real robot's
    uncertain values, it must find what works on all of them, as legged_gym and walk-these-ways train
    (their ranges, for robots of similar size, in brackets). Each range is (low, high), drawn uniformly
    and independently per episode from the env's generator (`cyberdog.sim.hardware_model.draw_robot`); a range
    with low = high is that value, and the defaults are the nominal robot (no randomisation). It acts on top
    of `HardwareConfig`, which says which effects exist, by one rule (`cyberdog.sim.hardware_model.resolve_draw`): the
    friction scale needs `friction` on; a mass or latency range left at its default keeps the hardware's
    `mass_uncertainty` draw and `latency_s`, and a range that is set replaces them and must contain them
    (`EnvConfig` refuses one that does not, naming both fields).

    [G] marks a guess for this robot; every range of `configs/battery.yaml` contains the
    prototype's hardware-like robot (`HARDWARE_LIKE`: scales 1, one period of latency, mass within ±5 %).
    """

    joint_friction_scale: Tuple[float, float] = (1.0, 1.0)  # × ActuatorConfig viscous and dry friction [G]
    latency_periods: Tuple[int, int] = (0, 0)  # controller periods of actuation delay, each whole value equally likely
    mass_scale: Tuple[float, float] = (1.0, 1.0)  # × every link's mass and inertia [legged_gym: −1..+3 kg on 13 kg]
    motor_strength: Tuple[float, float] = (1.0, 1.0)  # × the torque the motors produce [walk-these-ways: 0.9..1.1]
    kp_factor: Tuple[float, float] = (1.0, 1.0)  # × the PID's proportional gains [walk-these-ways: 0.8..1.3]
    kd_factor: Tuple[float, float] = (1.0, 1.0)  # × the PID's kd, torque mode's damping [walk-these-ways: 0.5..1.5]
    ground_friction_scale: Tuple[float, float] = (1.0, 1.0)  # × SimConfig.ground_friction [legged_gym: 0.5..1.25 absolute]
    # True: each drawn robot's physics step is the one its drawn gains need (`driver_physics_dt`, as for a
    # configured robot with those gains); False: every draw steps at the configured robot's
    drivers_rate_per_robot: bool = False

    RANGES = ("joint_friction_scale", "latency_periods", "mass_scale", "motor_strength", "kp_factor", "kd_factor",
              "ground_friction_scale")

    @property
    def enabled(self) -> bool:
        """True unless every range is the nominal robot's value."""
        return self != RandomizationConfig()

    def __post_init__(self) -> None:
        for name in self.RANGES:
            lo, hi = getattr(self, name)
            _check(lo <= hi and all(math.isfinite(v) for v in (lo, hi)), f"RandomizationConfig.{name}",
                   "(low, high) with low <= high, finite", (lo, hi))
        lo, hi = self.latency_periods
        _check(isinstance(lo, int) and isinstance(hi, int) and 0 <= lo and hi <= 40,
               "RandomizationConfig.latency_periods", "(low, high) whole controller periods in [0, 40]", (lo, hi))
        _check(self.joint_friction_scale[0] >= 0, "RandomizationConfig.joint_friction_scale", ">= 0",
               self.joint_friction_scale)
        for name, low, high in (("mass_scale", 0.5, 2.0), ("motor_strength", 0.1, 2.0), ("kp_factor", 0.1, 3.0),
                                ("kd_factor", 0.1, 3.0), ("ground_friction_scale", 0.05, 5.0)):
            lo, hi = getattr(self, name)
            _check(low <= lo and hi <= high, f"RandomizationConfig.{name}", f"within [{low}, {high}]", (lo, hi))
        _check(not self.drivers_rate_per_robot or self.kp_factor != (1.0, 1.0) or self.kd_factor != (1.0, 1.0),
               "RandomizationConfig.drivers_rate_per_robot", "False unless kp_factor or kd_factor is drawn (it "
               "changes the step only for drawn gains)", self.drivers_rate_per_robot)
