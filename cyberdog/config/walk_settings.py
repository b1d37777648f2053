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
    """Geometry and mass of the first-generation CyberDog (docs/robot.md, tags [X]). The geometry and total_mass
    state the URDF's (the trot's kinematics and weight feed-forward read them; a robot built from a URDF that
    disagrees is refused); `payload` changes the simulated body."""

    urdf: str = "urdf/cyberdog.urdf"  # absolute, or relative: the package's shipped file, else the repository root
    abad_offset_x: float = 0.23035  # m, body centre → abad joint, forward (±x per leg)
    abad_offset_y: float = 0.05  # m, body centre → abad joint, sideways (±y per leg)
    l1: float = 0.105076  # m, abad → hip joint along y (the paper's l1)
    l2: float = 0.200  # m, thigh: hip → knee (the paper's l2)
    l3: float = 0.200  # m, calf: knee → foot-sphere centre (the paper's l3)
    foot_radius: float = 0.018  # m
    total_mass: float = 13.573  # kg, the URDF's links (body + 4 legs incl. rotors); checked against it at load
    # kg carried on the body at its centre of mass, spread as the body's own mass is (its inertia scales with it):
    # the simulated body weighs this much more, and the trot's weight feed-forward counts it (a known load)
    payload: float = 0.0
    body_height: float = 0.30  # m, nominal standing height of the body centre (Xiaomi's des height)
    abad_limit: float = 0.76096355387  # rad, symmetric ±
    hip_limit: Tuple[float, float] = (-1.88495559215, 3.76991118431)  # rad
    knee_limit: Tuple[float, float] = (-2.49582083035, -0.717155789644)  # rad
    reflected_rotor_inertia: float = 0.00721  # kg·m², rotor 8.9031e-5 × gear 9², added about each joint axis

    @property
    def carried_mass(self) -> float:
        """kg, the robot as it walks: the URDF's links and the payload."""
        return self.total_mass + self.payload

    def __post_init__(self) -> None:
        _positive(self, "l1", "l2", "l3", "foot_radius", "total_mass", "body_height", "abad_limit")
        _non_negative(self, "reflected_rotor_inertia")
        _check(math.isfinite(self.payload) and 0.0 <= self.payload <= self.total_mass, "RobotConfig.payload",
               f"kg in [0, total_mass = {self.total_mass}]", self.payload)
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


ENGINES = ("pybullet", "mujoco")  # the physics engines a robot can be built in (the first is the default)


@dataclass(frozen=True)
class SimConfig:
    """PyBullet world and the two rates of the simulated robot.

    The locomotion controller (trot scheduler, IK, the PID's integral, feedforward, the sensed state) runs once
    every `controller_dt` and sends the motor drivers a command (targets, target speeds, gains, feed-forward)
    that they hold over that period; the drivers close their PD on the joint state at every physics step
    `physics_dt` = `controller_dt / n`, where the actuator envelope applies and the energy is integrated
    (`cyberdog.core.drivers`; their rate's convergence: docs/design.md). A walk whose PD gains are stiffer or
    more damped than the default halves `physics_dt` until the PD converges (`cyberdog.loop.walker.
    driver_rate_config`: kd 4 or kp 120 walk at 1.6 kHz); the configured step is the coarsest. The real
    CyberDog runs its locomotion controller at 500 Hz; 400 Hz is the nearest rate that divides the agent's
    Ts = 25 ms. The defaults were chosen by the convergence study of docs/design.md (control 1000 / 400 /
    200 Hz x physics 0.5 / 1 / 1.25 ms against a 2 kHz reference).
    """

    physics_dt: float = 0.00125  # s, contact solver step (800 Hz; docs/robot.md: at 240 Hz the abad joints chatter)
    controller_dt: float = 0.0025  # s, joint controller period (400 Hz), a whole multiple of physics_dt
    gravity: float = 9.81  # m/s²
    ground_friction: float = 0.8  # lateral friction coefficient of foot on ground [G]
    solver_iterations: int = 50  # PyBullet numSolverIterations
    engine: str = "pybullet"  # one of ENGINES: the physics engine (cyberdog.sim.make_robot; docs/design.md)

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
        _check(self.engine in ENGINES, "SimConfig.engine", f"one of {', '.join(ENGINES)}", self.engine)


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
    """Per-joint PID gains (abad, hip, knee): the PD closed by the motor drivers at every physics step, the
    integral term (ki) by the controller at every controller period (SimConfig), sent with its command."""

    kp: Tuple[float, float, float] = (60.0, 60.0, 60.0)  # N·m/rad
    ki: Tuple[float, float, float] = (0.0, 0.0, 0.0)  # N·m/(rad·s)
    kd: Tuple[float, float, float] = (2.0, 2.0, 2.0)  # N·m·s/rad
    integral_limit: float = 2.0  # N·m, anti-windup clamp on the integral term's torque

    def __post_init__(self) -> None:
        for n in ("kp", "ki", "kd"):
            v = getattr(self, n)
            _check(len(v) == 3 and all(g >= 0 for g in v), f"PIDConfig.{n}", "3 non-negative gains", v)
        _non_negative(self, "integral_limit")

    def stiffness_scaled(self, factor: float) -> "PIDConfig":
        """The PD `factor` times as stiff: kp × factor and kd × √factor, so that each joint's damping ratio
        ζ = kd / (2·√(kp·J)) stays what it was (J the joint's reflected inertia); ki × factor keeps the integral's
        share of the proportional action. The stiffness a user may set, as one number (0.7 = 30 % softer)."""
        _check(isinstance(factor, (int, float)) and math.isfinite(factor) and factor > 0, "PD stiffness factor",
               "a finite number > 0", factor)
        root = math.sqrt(factor)
        return PIDConfig(kp=tuple(g * factor for g in self.kp), ki=tuple(g * factor for g in self.ki),
                         kd=tuple(g * root for g in self.kd), integral_limit=self.integral_limit)


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
    sagittal_placement_gain: float = 0.0  # s, touchdown x shift per m/s of forward speed above the command
    #                                       (Raibert 1986's foot placement; 0 = off, the paper's trot)
    speed_ramp_time: float = 1.0  # s, the commanded speed rises linearly from 0 over this time after a reset

    def __post_init__(self) -> None:
        _non_negative(self, "heading_gain", "lateral_gain", "speed_gain", "max_speed_correction",
                      "lateral_placement_gain", "sagittal_placement_gain", "speed_ramp_time")


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
