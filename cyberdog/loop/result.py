"""`WalkResult`: the one record of a walk, scripted or a policy's rollout, and how it is computed."""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from cyberdog.config import HardwareConfig
from cyberdog.config.paper import speed_within_band
from cyberdog.core import energy as en

LOOP_NOTE_PCT = 10.0  # % of a walk with the trot's speed loop at its bound from which a report says so


@dataclass
class WalkResult:
    """Metrics of one walk (SI units) and, if recorded, its traces at the controller rate."""

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
    peak_torque: float  # N·m, max |τ| over joints and physics steps
    peak_joint_speed: float  # rad/s, max |Δq / physics_dt| over joints and physics steps
    non_foot_contacts: list  # link names other than feet that touched the ground
    traces: dict = field(default_factory=dict)  # t, tau, dq, q, power, base_position, contacts
    target_distance: float | None = None  # m, the walk's distance goal (None: a timed walk)
    mass_scale: float = 1.0  # link mass scale the robot walked with (hardware-like: a ±u draw)
    mass_kg: float = float("nan")  # kg, what the robot weighed in this walk (the payload's and the mass draw's body)
    hardware: HardwareConfig | None = None  # the hardware-like effects, None = the ideal robot
    score: float | None = None  # sum of the env's rewards, for a policy rollout (None for a scripted walk)
    dropped_shifts: int = 0  # leg-periods in which a shifted foot target was out of reach and the unshifted
    #                          one was sent instead (a learned path's or a policy's shift the robot never got)
    speed_loop_share: float = float("nan")  # the trot's speed integral, mean over the walk, / the command: what
    #                          the speed loop added to the stride (+0.25: strides 25 % longer than v·stance time)
    speed_loop_at_limit: float = float("nan")  # share of the walk's periods with the integral at its bound
    #                          (ControllerConfig.max_speed_correction): a walk that needs more falls behind

    @property
    def reached(self) -> bool:
        """The distance goal was reached without falling (a timed walk: it did not fall)."""
        return not self.fell and (self.target_distance is None or self.distance >= self.target_distance)

    @property
    def energy_per_100m(self) -> float:
        """J per 100 m of forward travel."""
        return en.energy_per_100m(self.energy, self.distance) if self.distance > 0 else float("nan")

    @property
    def energy_per_metre(self) -> float:
        """J/m of forward travel; nan without forward travel."""
        return self.energy / self.distance if self.distance > 0 else float("nan")

    @property
    def trace_dt(self) -> float:
        """s between trace samples: the controller period (`SimConfig.controller_dt`)."""
        t = self.traces.get("t")
        return float(t[1] - t[0]) if t is not None and len(t) > 1 else float("nan")

    @property
    def speed_ok(self) -> bool:
        """Mean speed within the acceptance band (±5 %) of the command."""
        return speed_within_band(self.mean_speed, self.speed_command)

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
        } | ({} if self.score is None else {"score": self.score, "energy_per_m_J": self.energy_per_metre})


def walk_result(walker, speed_command: float, fell: bool, target_distance: float | None = None,
                score: float | None = None, since: int = 0, since_x: float | None = None) -> WalkResult:
    """The metrics of what `walker` (a `cyberdog.loop.walker.Walker`) stepped since its reset, or from controller
    period `since` on (a run-up left out: time, distance, energies, speed, posture, slip and peaks count from
    there, the body then at forward position `since_x`, m); `fell`, the lateral drift (from the path's start)
    and the non-foot contacts are of the whole walk, and the traces are all of it."""
    cfg, dt = walker.cfg, walker.dt
    tr = walker.traces()
    if not walker.body_trace:
        raise ValueError("walk_result needs the walker's body trace: build the Walker with body_trace=True")
    if not 0 <= since <= len(tr["tau"]) or (since > 0) != (since_x is not None):
        raise ValueError(f"since must be a period in [0, {len(tr['tau'])}] given with since_x (the body's x "
                         f"then, m), got {since!r}, {since_x!r}")
    n = len(tr["tau"]) - since
    physics = walker.physics_traces(since)  # the torque and speed of every physics step: what Eq. (7) integrates
    body = walker.body.view(since)
    vx, rpy, z = body[:, 0], body[:, 1:4], body[:, 4]
    start, end = walker.start, walker.state.base_position
    e_joint = walker.energy_per_joint(since)
    travelled = float(end[0] - (start[0] if since_x is None else since_x))  # m, forward
    mass = cfg.robot.carried_mass * walker.robot.mass_scale  # kg, what the robot weighed in this walk
    cycles = n * dt / cfg.gait.period
    slip = float("nan")
    first_sample = -(-since // walker.slip_sample_every)  # the slip samples taken from period `since` on
    if walker.gait_metrics and cycles > 0 and walker.slip_xy[first_sample:]:
        slip = float(en.foot_slip(np.reshape(walker.slip_xy[first_sample:], (-1, 4, 2)),
                                  np.reshape(walker.slip_contacts[first_sample:], (-1, 4))).mean() / cycles)
    loop = walker.speed_loop.view(since)  # (correction, bound) per driven period, m/s; none in torque mode
    at_limit = (np.abs(loop[:, 0]) >= loop[:, 1] - 1e-9) & (loop[:, 1] > 0) if len(loop) else None
    return WalkResult(
        speed_loop_share=float(loop[:, 0].mean() / speed_command) if len(loop) and speed_command > 0 else float("nan"),
        speed_loop_at_limit=float(at_limit.mean()) if at_limit is not None else float("nan"),
        speed_command=float(speed_command), duration=n * dt, fell=bool(fell),
        mean_speed=float(np.mean(vx[n // 2:])) if n else 0.0,
        lateral_drift=float(abs(end[1] - start[1])),
        height_min=float(z.min()) if n else float("nan"), height_max=float(z.max()) if n else float("nan"),
        max_roll=float(np.max(np.abs(rpy[:, 0]))) if n else float("nan"),
        max_pitch=float(np.max(np.abs(rpy[:, 1]))) if n else float("nan"),
        distance=travelled, energy=float(e_joint.sum()), energy_per_joint=e_joint,
        electrical_energy=walker.electrical_energy(since), positive_work=walker.positive_work(since),
        foot_slip_per_cycle=slip,
        cost_of_transport=(en.cost_of_transport(float(e_joint.sum()), mass, cfg.sim.gravity, travelled)
                           if travelled > 0 else float("nan")),  # undefined without forward travel
        peak_torque=float(np.max(np.abs(physics["tau"]))) if n else 0.0,
        peak_joint_speed=float(np.max(np.abs(physics["dq"]))) if n else 0.0,
        non_foot_contacts=sorted(walker.non_foot_contacts), target_distance=target_distance,
        mass_scale=walker.robot.mass_scale, mass_kg=mass, hardware=walker.hardware, score=score, traces=tr,
        dropped_shifts=int(walker.controller.dropped_shifts))
