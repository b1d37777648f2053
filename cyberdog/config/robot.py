"""Settings of one scripted walk: robot, actuator, simulator, gait, PID, trot controller, energy and battery."""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Tuple

from cyberdog.config._validate import _check, _non_negative, _positive

LEG_NAMES = ("LF", "RF", "LH", "RH")  # order used for every per-leg array in the project
JOINT_NAMES = ("abad", "hip", "knee")  # per leg; joint index = 3 * leg + joint


@dataclass(frozen=True)
class RobotConfig:
    """Geometry and mass of the first-generation CyberDog (parameter file, tags [X])."""

    urdf: str = "urdf/cyberdog.urdf"  # absolute, or relative: the package's shipped file, else the repository root
    abad_offset_x: float = 0.23035  # m, body centre → abad joint, forward (±x per leg)
    abad_offset_y: float = 0.05  # m, body centre → abad joint, sideways (±y per leg)
    l1: float = 0.105076  # m, abad → hip joint along y (the paper's l1)
    l2: float = 0.200  # m, thigh: hip → knee (the paper's l2)
    l3: float = 0.200  # m, calf: knee → foot-sphere centre (the paper's l3)
    foot_radius: float = 0.018  # m
    total_mass: float = 13.573  # kg, model total (body + 4 legs incl. rotors)
    body_height: float = 0.30  # m, nominal standing height of the body centre (Xiaomi's des height)
    abad_limit: float = 0.76096355387  # rad, symmetric ±
    hip_limit: Tuple[float, float] = (-1.88495559215, 3.76991118431)  # rad
    knee_limit: Tuple[float, float] = (-2.49582083035, -0.717155789644)  # rad
    reflected_rotor_inertia: float = 0.00721  # kg·m², rotor 8.9031e-5 × gear 9², added about each joint axis

    def __post_init__(self) -> None:
        _positive(self, "l1", "l2", "l3", "foot_radius", "total_mass", "body_height", "abad_limit")
        _non_negative(self, "reflected_rotor_inertia")
        for n in ("hip_limit", "knee_limit"):
            lo, hi = getattr(self, n)
            _check(lo < hi, f"RobotConfig.{n}", "(lower, upper) with lower < upper", (lo, hi))


@dataclass(frozen=True)
class ActuatorConfig:
    """Joint actuator model applied in our code (PyBullet does not enforce limits under torque control)."""

    torque_limit: float = 25.0  # N·m, command clip (paper Table 4)
    torque_speed_curve: bool = True  # limit torque with joint speed (Xiaomi's n1/n2 model)
    full_torque_speed: float = 11.4145  # rad/s, full torque available up to this joint speed [X]
    zero_torque_speed: float = 20.9136  # rad/s, torque falls linearly to zero here [X]
    viscous_damping: float = 0.01  # N·m·s/rad, joint viscous friction [X]
    dry_friction: float = 0.246  # N·m, joint Coulomb friction [X]
    friction: bool = False  # apply viscous + dry joint friction in simulation (paper ignores it, Section 2)
    gear_ratio: float = 9.0  # [X]
    motor_kt: float = 0.05  # N·m/A, motor torque constant [X, low confidence: Mini Cheetah value]
    motor_resistance: float = 0.173  # Ω, winding resistance [X, low confidence: Mini Cheetah value]

    def __post_init__(self) -> None:
        _positive(self, "torque_limit", "full_torque_speed", "zero_torque_speed", "gear_ratio", "motor_kt")
        _non_negative(self, "viscous_damping", "dry_friction", "motor_resistance")
        _check(self.zero_torque_speed > self.full_torque_speed, "ActuatorConfig.zero_torque_speed",
               f"> full_torque_speed ({self.full_torque_speed})", self.zero_torque_speed)


@dataclass(frozen=True)
class SimConfig:
    """PyBullet world and the two rates of the simulated robot.

    The joint controller (trot scheduler, IK, PID, feedforward, the hardware model, the actuator envelope and
    the energy bookkeeping) runs once every `controller_dt`; its torque is held constant over that period, as
    the robot's motor drivers hold the last command between two controller cycles. PyBullet's contact solver
    steps `physics_dt` = `controller_dt / n` underneath, the n substeps in C++ (`numSubSteps`). The real
    CyberDog runs its locomotion controller at 500 Hz; 400 Hz is the nearest rate that divides the agent's
    Ts = 25 ms. The defaults were chosen by the convergence study of docs/design.md (control 1000 / 400 /
    200 Hz x physics 0.5 / 1 / 1.25 ms against a 2 kHz reference).
    """

    physics_dt: float = 0.00125  # s, contact solver step (800 Hz; NOTES: 240 Hz makes the abad joints chatter)
    controller_dt: float = 0.0025  # s, joint controller period (400 Hz), a whole multiple of physics_dt
    gravity: float = 9.81  # m/s²
    ground_friction: float = 0.8  # lateral friction coefficient of foot on ground [G]
    solver_iterations: int = 50  # PyBullet numSolverIterations

    @property
    def physics_substeps(self) -> int:
        """Solver steps per controller period."""
        return int(round(self.controller_dt / self.physics_dt))

    def __post_init__(self) -> None:
        _positive(self, "physics_dt", "controller_dt", "gravity", "ground_friction")
        _check(self.physics_dt <= 0.005, "SimConfig.physics_dt", "<= 0.005 s", self.physics_dt)
        _check(self.controller_dt <= 0.01, "SimConfig.controller_dt", "<= 0.01 s (100 Hz)", self.controller_dt)
        ratio = self.controller_dt / self.physics_dt
        _check(ratio >= 1 - 1e-9 and abs(ratio - round(ratio)) < 1e-6, "SimConfig.controller_dt",
               f"a whole multiple of physics_dt ({self.physics_dt} s); a config written when the controller ran "
               f"at every physics step has no controller_dt: give it controller_dt = physics_dt",
               self.controller_dt)
        _check(self.solver_iterations >= 1, "SimConfig.solver_iterations", ">= 1", self.solver_iterations)


TRAJECTORY_NAMES = ("cycloid", "straight", "sampled")
STRAIGHT_SHAPES = ("rectangle", "trapezoid", "triangle")


@dataclass(frozen=True)
class GaitConfig:
    """Diagonal trot (paper Figure 9) and its foot trajectory (Section 2.3).

    The paper states both T = 0.8 s and Tm = 0.2 s with v = S/Tm; Figure 10 shows 0.4 s cycles, so the
    default is a 0.4 s cycle of 0.2 s swing + 0.2 s stance and step length S = v · swing_time.
    """

    speed: float = 1.0  # m/s, commanded forward speed v
    period: float = 0.4  # s, gait cycle T (one swing + one stance of each leg)
    swing_time: float = 0.2  # s, swing duration Tm; stance = period − swing_time
    lift_height: float = 0.15  # m, foot lift H (paper Section 2.3)
    trajectory: str = "cycloid"  # one of TRAJECTORY_NAMES
    straight_shape: str = "rectangle"  # one of STRAIGHT_SHAPES (the paper's Figure 4b is a rectangle-like path)
    trapezoid_fraction: float = 0.25  # share of S covered while lifting (and while lowering) in "trapezoid"
    sampled_file: str = ""  # CSV/JSON of a sampled trajectory, for trajectory="sampled"
    phase_offsets: Tuple[float, float, float, float] = (0.0, 0.5, 0.5, 0.0)  # LF, RF, LH, RH: diagonal pairs

    @property
    def stance_time(self) -> float:
        return self.period - self.swing_time

    @property
    def step_length(self) -> float:
        """S = v · Tm (paper, after Figure 8): the foot travels S back during stance at speed v."""
        return self.speed * self.stance_time

    def __post_init__(self) -> None:
        _non_negative(self, "speed")
        _positive(self, "period", "swing_time", "lift_height")
        _check(self.swing_time < self.period, "GaitConfig.swing_time", f"< period ({self.period} s)",
               self.swing_time)
        _check(self.trajectory in TRAJECTORY_NAMES, "GaitConfig.trajectory", f"one of {TRAJECTORY_NAMES}",
               self.trajectory)
        _check(self.straight_shape in STRAIGHT_SHAPES, "GaitConfig.straight_shape",
               f"one of {STRAIGHT_SHAPES}", self.straight_shape)
        _check(0 < self.trapezoid_fraction < 0.5, "GaitConfig.trapezoid_fraction", "in (0, 0.5)",
               self.trapezoid_fraction)
        _check(len(self.phase_offsets) == 4, "GaitConfig.phase_offsets", "4 values (LF, RF, LH, RH)",
               self.phase_offsets)


@dataclass(frozen=True)
class PIDConfig:
    """Per-joint PID gains (abad, hip, knee), run at every controller period (SimConfig.controller_dt)."""

    kp: Tuple[float, float, float] = (60.0, 60.0, 60.0)  # N·m/rad
    ki: Tuple[float, float, float] = (0.0, 0.0, 0.0)  # N·m/(rad·s)
    kd: Tuple[float, float, float] = (2.0, 2.0, 2.0)  # N·m·s/rad
    integral_limit: float = 2.0  # N·m, anti-windup clamp on the integral term's torque

    def __post_init__(self) -> None:
        for n in ("kp", "ki", "kd"):
            v = getattr(self, n)
            _check(len(v) == 3 and all(g >= 0 for g in v), f"PIDConfig.{n}", "3 non-negative gains", v)
        _non_negative(self, "integral_limit")


@dataclass(frozen=True)
class ControllerConfig:
    """Trot controller: what is added on top of the joint PID to walk straight at the commanded speed."""

    velocity_feedforward: bool = True  # joint velocity target from the trajectory's foot velocity (J⁻¹ v)
    gravity_compensation: bool = True  # stance feedforward τ = Jᵀ f, f = weight shared by stance feet
    heading_gain: float = 0.5  # step-length correction per rad of yaw error (left/right asymmetry)
    lateral_gain: float = 0.5  # rad of heading set-point per m of lateral drift, back toward the path
    speed_gain: float = 1.0  # 1/s, integral gain on the speed error (m/s) that corrects the step length; 0 = open loop
    max_speed_correction: float = 0.3  # share of the commanded speed the speed integral may add or remove
    lateral_placement_gain: float = 0.05  # s, swing-foot y shift per m/s of sideways body speed (Raibert-style)
    speed_ramp_time: float = 1.0  # s, the commanded speed rises linearly from 0 over this time after a reset

    def __post_init__(self) -> None:
        _non_negative(self, "heading_gain", "lateral_gain", "speed_gain", "max_speed_correction",
                      "lateral_placement_gain", "speed_ramp_time")


@dataclass(frozen=True)
class EnergyConfig:
    """Energy and battery model (paper Eq. 7, 13; beyond the paper: copper loss, friction, battery)."""

    battery_voltage: float = 25.0  # V, pack voltage at full charge (paper Section 4.2 measured 25 V)
    battery_capacity_wh: float = 8.0 * 25.2  # Wh, assumption [G]: 8 Ah pack at 25.2 V nominal
    usable_fraction: float = 0.95  # the paper starts every walk at 95 % charge (Eq. 13)
    driver_efficiency: float = 0.95  # motor driver (inverter) efficiency, assumption [G]
    idle_power: float = 0.0  # W, electronics drawn from the battery regardless of gait (0: legs only)
    regeneration: bool = False  # negative electrical power recharges the pack (False: clipped to 0)

    def __post_init__(self) -> None:
        _positive(self, "battery_voltage", "battery_capacity_wh", "usable_fraction", "driver_efficiency")
        _check(self.usable_fraction <= 1, "EnergyConfig.usable_fraction", "in (0, 1]", self.usable_fraction)
        _check(self.driver_efficiency <= 1, "EnergyConfig.driver_efficiency", "in (0, 1]",
               self.driver_efficiency)
        _non_negative(self, "idle_power")


@dataclass(frozen=True)
class WalkConfig:
    """Everything one scripted walk (trot controller in the simulator) needs."""

    robot: RobotConfig = field(default_factory=RobotConfig)
    actuator: ActuatorConfig = field(default_factory=ActuatorConfig)
    sim: SimConfig = field(default_factory=SimConfig)
    gait: GaitConfig = field(default_factory=GaitConfig)
    pid: PIDConfig = field(default_factory=PIDConfig)
    controller: ControllerConfig = field(default_factory=ControllerConfig)
    energy: EnergyConfig = field(default_factory=EnergyConfig)


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
    over it); applied at the physics rate by `cyberdog.sim.hardware` inside `cyberdog.loop.walker.Walker`.
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


@dataclass(frozen=True)
class RandomizationConfig:
    """Domain randomisation: the ranges the robot of each training episode is drawn from (beyond the paper).

    A policy trained on one simulated robot learns that robot's quirks (its saving may rest on how the ideal
    PID tracks a path, docs/results.md); drawn anew each episode from ranges around the real robot's
    uncertain values, it must find what works on all of them, as legged_gym and walk-these-ways train
    (their ranges, for robots of similar size, in brackets). Each range is (low, high), drawn uniformly
    and independently per episode from the env's generator (`cyberdog.sim.hardware.draw_robot`); a range
    with low = high is that value, and the defaults are the nominal robot (no randomisation). It acts on top
    of `HardwareConfig`, which says which effects exist, by one rule (`cyberdog.sim.hardware.resolve_draw`): the
    friction scale needs `friction` on; a mass or latency range left at its default keeps the hardware's
    `mass_uncertainty` draw and `latency_s`, and a range that is set replaces them and must contain them
    (`EnvConfig` refuses one that does not, naming both fields).

    [G] marks a guess for this robot; every range of `configs/quick_speeds_battery.yaml` contains the
    prototype's hardware-like robot (`HARDWARE_LIKE`: scales 1, one period of latency, mass within ±5 %).
    """

    joint_friction_scale: Tuple[float, float] = (1.0, 1.0)  # × ActuatorConfig viscous and dry friction [G]
    latency_periods: Tuple[int, int] = (0, 0)  # controller periods of actuation delay, each whole value equally likely
    mass_scale: Tuple[float, float] = (1.0, 1.0)  # × every link's mass and inertia [legged_gym: −1..+3 kg on 13 kg]
    motor_strength: Tuple[float, float] = (1.0, 1.0)  # × the torque the motors produce [walk-these-ways: 0.9..1.1]
    kp_factor: Tuple[float, float] = (1.0, 1.0)  # × the PID's proportional gains [walk-these-ways: 0.8..1.3]
    kd_factor: Tuple[float, float] = (1.0, 1.0)  # × the PID's derivative gains [walk-these-ways: 0.5..1.5]
    ground_friction_scale: Tuple[float, float] = (1.0, 1.0)  # × SimConfig.ground_friction [legged_gym: 0.5..1.25 absolute]

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
