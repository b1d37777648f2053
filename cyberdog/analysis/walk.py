"""One scripted walk: the trot controller drives the simulated CyberDog; energy and gait metrics are recorded.

This is the experiment behind `evaluate.py baselines` and the trajectory comparison (paper Section 4.1):
walk `duration` seconds at the commanded speed, integrate Eq. (7) at every physics step, and report speed,
drift, posture and energy.

The prototype experiment (Section 4.2, `cyberdog.analysis.prototype`) adds two options: `distance` ends the
walk after that much forward travel (the paper's 100 m; `duration` is then the time cap), and `hardware`
(a `HardwareConfig`) makes the robot hardware-like: joint friction, actuation latency, encoder noise,
Kalman-estimated speed feedback and a mass-scale draw (`cyberdog.analysis.hardware`). Without them the walk
is exactly the ideal one.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from cyberdog.analysis.hardware import (HardwareSensing, TorqueDelay, draw_mass_scale, hardware_walk_config,
                                        whole_steps)
from cyberdog.config import EnvConfig, HardwareConfig, WalkConfig
from cyberdog.control.trot import BodyFeedback, TrotController
from cyberdog.core import energy as en
from cyberdog.core.foot_offsets import FootOffsetPath
from cyberdog.core.trajectories import FootTrajectory
from cyberdog.sim.robot import Robot

# "fallen" means the same as in the learning environment (EnvConfig's defaults)
FALL_HEIGHT = EnvConfig.fall_height  # m, body centre below this
FALL_TILT = np.deg2rad(EnvConfig.fall_tilt_deg)  # rad, |roll| or |pitch| above this
CONTACT_CHECK_EVERY = 10  # physics steps between checks of which links touch the ground
SLIP_SAMPLE_EVERY = 5  # physics steps between samples of the feet's positions and contacts (foot slip)


@dataclass
class WalkResult:
    """Metrics of one walk (SI units) and, if recorded, its traces at the physics rate."""

    speed_command: float  # m/s
    duration: float  # s walked (shorter than asked if the robot fell)
    fell: bool
    mean_speed: float  # m/s, forward, over the last half of the walk (last 5 s of 10 s)
    lateral_drift: float  # m, |y| at the end
    height_min: float  # m, body centre
    height_max: float  # m
    max_roll: float  # rad, |roll|
    max_pitch: float  # rad, |pitch|
    distance: float  # m, forward displacement
    energy: float  # J, Eq. (7) Σ∫|τ·ω|dt over the walk
    energy_per_joint: np.ndarray  # (12,) J
    electrical_energy: float  # J, with copper loss, friction loss and driver efficiency
    positive_work: float  # J, Σ∫max(τ·ω, 0)dt: the work the motors put in (Eq. 7 also counts braking)
    foot_slip_per_cycle: float  # m, mean distance a foot slides on the ground per gait cycle
    cost_of_transport: float  # E / (m g d); nan when the robot made no forward progress
    peak_torque: float  # N·m, max |τ| over joints and time
    peak_joint_speed: float  # rad/s
    non_foot_contacts: list  # link names other than feet that touched the ground
    traces: dict = field(default_factory=dict)  # t, tau, dq, q, power, base_position, contacts
    target_distance: float | None = None  # m, the walk's distance goal (None: a timed walk)
    mass_scale: float = 1.0  # link mass scale the robot walked with (hardware-like: a ±u draw)
    hardware: HardwareConfig | None = None  # the hardware-like effects, None = the ideal robot

    @property
    def reached(self) -> bool:
        """The distance goal was reached without falling (a timed walk: it did not fall)."""
        return not self.fell and (self.target_distance is None or self.distance >= self.target_distance)

    @property
    def energy_per_100m(self) -> float:
        """J per 100 m of forward travel."""
        return en.energy_per_100m(self.energy, self.distance) if self.distance > 0 else float("nan")

    @property
    def speed_ok(self) -> bool:
        """Mean speed within ±5 % of the command (the issues' acceptance band)."""
        return abs(self.mean_speed - self.speed_command) <= 0.05 * self.speed_command

    def summary(self) -> dict:
        return {
            "speed_command_mps": self.speed_command, "mean_speed_mps": self.mean_speed,
            "lateral_drift_m": self.lateral_drift, "height_min_m": self.height_min,
            "height_max_m": self.height_max, "max_roll_rad": self.max_roll, "max_pitch_rad": self.max_pitch,
            "fell": self.fell, "duration_s": self.duration, "distance_m": self.distance,
            "energy_J": self.energy, "energy_per_100m_kJ": self.energy_per_100m / 1e3,
            "electrical_energy_J": self.electrical_energy, "positive_work_J": self.positive_work,
            "foot_slip_mm_per_cycle": 1e3 * self.foot_slip_per_cycle, "cost_of_transport": self.cost_of_transport,
            "peak_torque_Nm": self.peak_torque, "peak_joint_speed_radps": self.peak_joint_speed,
            "non_foot_contacts": ",".join(self.non_foot_contacts), "speed_ok": self.speed_ok,
        }


def walk(cfg: WalkConfig, duration: float = 10.0, trajectory: FootTrajectory | None = None,
         robot: Robot | None = None, record: bool = False, hardware: HardwareConfig | None = None,
         distance: float | None = None, foot_offsets: FootOffsetPath | None = None) -> WalkResult:
    """Walk at `cfg.gait.speed` with the trot controller; reuse `robot` if given.

    duration: s; the walk's length, or with `distance` its time cap.
    distance: m of forward travel (body x from the start) after which the walk ends; None = a timed walk.
    foot_offsets: a periodic shift of each foot target over its phase (a learned path's, see
        `cyberdog.core.foot_offsets`) added to `trajectory`'s targets; None = the plain trajectory.
    hardware: the hardware-like robot (HardwareConfig; None or HardwareConfig() = ideal). With friction on,
        a given `robot` must have been built with `hardware_walk_config(cfg, hardware).actuator`; its mass is
        set to the hardware's draw for the walk.
    """
    if not (duration > 0 and np.isfinite(duration)):
        raise ValueError(f"duration must be > 0 s and finite, got {duration!r}")
    if distance is not None and not (distance > 0 and np.isfinite(distance)):
        raise ValueError(f"distance must be None or > 0 m and finite, got {distance!r}")
    if hardware is not None and not isinstance(hardware, HardwareConfig):
        raise TypeError(f"hardware must be a HardwareConfig or None, got {type(hardware).__name__}")
    cfg = hardware_walk_config(cfg, hardware)
    if robot is not None and robot.actuator_config != cfg.actuator:
        raise ValueError("robot was built with another ActuatorConfig than the walk needs "
                         f"(friction={cfg.actuator.friction}); build it from hardware_walk_config(cfg, hardware)")
    own_robot = robot is None
    robot = robot or Robot(cfg.robot, cfg.actuator, cfg.sim)
    try:
        if hardware is not None:
            robot.set_mass_scale(draw_mass_scale(hardware))
        return _walk(cfg, duration, TrotController(cfg, trajectory, foot_offsets), robot, record, hardware, distance)
    finally:
        if own_robot:
            robot.close()


def _walk(cfg: WalkConfig, duration: float, ctrl: TrotController, robot: Robot, record: bool,
          hardware: HardwareConfig | None, distance: float | None) -> WalkResult:
    dt = cfg.sim.physics_dt
    n_steps = int(round(duration / dt))
    robot.reset()
    ctrl.reset()
    delay = sensing = None
    if hardware is not None:
        delay = TorqueDelay(whole_steps(hardware.latency_s, dt, "HardwareConfig.latency_s"))
        sensing = HardwareSensing(hardware, cfg)
        sensing.reset(robot.read_state())
    foot_links = set(robot.foot_link_names)
    n_rec = n_steps if record else 0
    tau_log, dq_log = np.zeros((n_steps, 12)), np.zeros((n_steps, 12))
    q_log, pos_log = np.zeros((n_rec, 12)), np.zeros((n_rec, 3))
    contact_log = np.zeros((n_rec, 4), dtype=bool)
    vx_log, rpy_log, z_log = np.zeros(n_steps), np.zeros((n_steps, 3)), np.zeros(n_steps)
    start = robot.read_state().base_position.copy()
    bad_contacts: set[str] = set()
    slip_xy: list[np.ndarray] = []  # (4, 2) m, every SLIP_SAMPLE_EVERY steps
    slip_contacts: list[np.ndarray] = []
    fell = False
    steps_done = 0
    goal_x = None if distance is None else start[0] + distance
    for k in range(n_steps):
        s = robot.read_state()
        if goal_x is not None and s.base_position[0] >= goal_x:
            break  # the energy of exactly the steps that carried the body to the goal
        if sensing is None:  # ideal: the controller reads the simulator's true state
            tau_cmd = ctrl.torque(k * dt, s.q, s.dq, BodyFeedback.from_state(s, start))
        else:
            q, dq, body = sensing.read(k, s, robot, start)
            tau_cmd = delay.push(ctrl.torque(k * dt, q, dq, body))
        tau = robot.step(tau_cmd)
        tau_log[k], dq_log[k] = tau, s.dq
        vx_log[k], rpy_log[k], z_log[k] = s.base_linear_velocity_world[0], s.base_rpy, s.base_position[2]
        if record:
            q_log[k], pos_log[k] = s.q, s.base_position
            contact_log[k] = robot.foot_contacts()
        if k % CONTACT_CHECK_EVERY == 0:
            bad_contacts |= robot.ground_contact_links() - foot_links
        if k % SLIP_SAMPLE_EVERY == 0:
            slip_xy.append(robot.foot_positions_world()[:, :2])
            slip_contacts.append(robot.foot_contacts())
        steps_done = k + 1
        if s.base_position[2] < FALL_HEIGHT or np.max(np.abs(s.base_rpy[:2])) > FALL_TILT:
            fell = True
            break
    end = robot.read_state().base_position
    n = steps_done
    tau_log, dq_log, vx_log, rpy_log, z_log = tau_log[:n], dq_log[:n], vx_log[:n], rpy_log[:n], z_log[:n]
    e_joint = en.joint_energy(tau_log, dq_log, dt)
    travelled = float(end[0] - start[0])  # m, forward
    e_elec = float(np.sum(en.electrical_power(tau_log, dq_log, cfg.actuator, cfg.energy)) * dt)
    mass = cfg.robot.total_mass * robot.mass_scale  # kg, what the robot weighed in this walk
    slip = en.foot_slip(np.reshape(slip_xy, (-1, 4, 2)), np.reshape(slip_contacts, (-1, 4)))
    cycles = n * dt / cfg.gait.period
    result = WalkResult(
        speed_command=ctrl.speed, duration=n * dt, fell=fell,
        mean_speed=float(np.mean(vx_log[n // 2:])) if n else 0.0,
        lateral_drift=float(abs(end[1] - start[1])),
        height_min=float(z_log.min()), height_max=float(z_log.max()),
        max_roll=float(np.max(np.abs(rpy_log[:, 0]))), max_pitch=float(np.max(np.abs(rpy_log[:, 1]))),
        distance=travelled, energy=float(e_joint.sum()), energy_per_joint=e_joint, electrical_energy=e_elec,
        positive_work=en.positive_work(tau_log, dq_log, dt),
        foot_slip_per_cycle=float(slip.mean() / cycles) if cycles > 0 else float("nan"),
        cost_of_transport=(en.cost_of_transport(float(e_joint.sum()), mass, cfg.sim.gravity, travelled)
                           if travelled > 0 else float("nan")),  # undefined without forward travel
        peak_torque=float(np.max(np.abs(tau_log))), peak_joint_speed=float(np.max(np.abs(dq_log))),
        non_foot_contacts=sorted(bad_contacts), target_distance=distance, mass_scale=robot.mass_scale,
        hardware=hardware)
    if record:
        result.traces = {"t": np.arange(n) * dt, "tau": tau_log, "dq": dq_log, "q": q_log[:n],
                         "power": np.abs(tau_log * dq_log), "base_position": pos_log[:n],
                         "contacts": contact_log[:n]}
    return result
