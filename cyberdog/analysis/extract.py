"""Extraction of the learned foot trajectory from a policy rollout (paper Section 3, after Figure 6). Numpy only.

Two ways, reported side by side:

- **commanded** (`extract_commanded`, the default for foot-mode policies): the trot controller's foot targets
  are what the policy changed, and the rollout records them at the physics rate (the base trot path plus the
  policy's shift of each foot). The rollout is cut into gait-clock cycles (each leg's phase runs once; the
  cycle opens at LF's lift-off); the settled cycles within ±5 % of the command are kept, and the shift of
  each leg over its phase is averaged over them (`cycle="mean"`, the default) or taken from the cheapest one
  (`cycle="cheapest"`, the paper's choice). The result, a `CommandedPath`, replays through IK + PID with no
  policy in the loop. Each leg keeps its own path: the policy shifts the four feet differently.
  Measured on the shipped 1.0 m/s policy (10 s rollout): settled cycles cost 39.81 J on average (cheapest
  39.28 J); replaying the mean path costs 39.98 J per cycle (+0.4 %), the cheapest cycle's path 39.94 J
  (+1.7 % over that cycle): the cheapest cycle is cheap by noise, not by a better path, hence the default.
- **measured** (`extract_trajectory`, the paper's way, below): the feet's measured path, forward kinematics
  of the recorded joint angles, of the cheapest cycle. Replayed as a new target through IK + PID it applies
  the tracking lag and stance wiggles a second time, and loses most of the saving.

The measured way, in detail: the paper "extracted the simulation data with the minimum energy consumption from the cycle with the optimal
reward function" and recorded the foot's x and z (Figure 7). Here, from the physics-rate traces of one
deterministic rollout of the trained stage-2 policy (`cyberdog.rl.rollout.rollout`):

1. each foot's position relative to its hip joint: forward kinematics of the recorded joint angles in the
   leg frame (`kinematics.foot_position`), x forward and z = foot z + stand height (the trot controller's
   convention: z = 0 is the ground for a body at its nominal height), in the body's axes;
2. the rollout is cut into gait cycles at the reference leg's touch-downs (rising edges of its recorded
   ground contact, runs shorter than `min_run_s` ignored as bounces);
3. each cycle's energy by Eq. (7), E = Σ_ij ∫|τ_ij·θ̇_ij| dt over the cycle (all 12 joints), and its speed,
   the body's forward displacement over the cycle divided by its duration;
4. among the cycles whose speed is within ±`speed_tolerance` (5 %) of the command (and that start after
   `settle_time`, last a plausible time and contain one lift-off), the cheapest one is taken;
5. its foot path becomes a `SampledTrajectory`: phase 0 at the recorded lift-off, the end-to-start gap
   spread linearly over the cycle (closing the loop), z shifted so the contact level is 0, resampled at
   `n_points` equal phases. It is normalised by the step length the policy's controller was commanded,
   S = v·stance_time, and by the recorded lift height (the peak of z), so `SampledTrajectory` replays it at
   other S and H; replayed at the recorded S and H it is the recorded path.

`extract_trajectory(traces, ...)` takes plain arrays (no torch), so it can be tested on synthetic traces;
`cyberdog.rl.rollout` produces the real ones.
"""
from __future__ import annotations

from dataclasses import asdict, dataclass, field

import numpy as np

from cyberdog.config import LEG_NAMES, GaitConfig, RobotConfig
from cyberdog.config.paper import SPEED_BAND, speed_within_band
from cyberdog.core import energy as en
from cyberdog.core import kinematics as kin
from cyberdog.core.commanded_path import CommandedPath
from cyberdog.core.foot_offsets import FootOffsetPath
from cyberdog.core.gait import GaitScheduler
from cyberdog.core.trajectories import SampledTrajectory

SPEED_TOLERANCE = SPEED_BAND  # ± share of the command (the acceptance band of every walk); the CLIs' default
CYCLE_CHOICES = ("mean", "cheapest")  # how extract_commanded builds the path from the in-band cycles


class ExtractionError(ValueError):
    """No gait cycle of the rollout qualifies (too short, fell, no cycle in the speed band, ...)."""


@dataclass
class Cycle:
    """One gait cycle of the reference leg: touch-down to the next touch-down."""

    index: int  # 0, 1, ... in time order
    start: int  # sample index of the touch-down that opens it
    end: int  # sample index of the next touch-down (exclusive)
    lift_off: int  # sample index of the lift-off inside the cycle, -1 if none
    t_start: float  # s
    duration: float  # s
    energy: float  # J, Eq. (7) over all 12 joints
    speed: float  # m/s, forward body displacement / duration
    speed_ok: bool  # within the tolerance of the command
    valid: bool  # usable: settled, one lift-off, plausible duration
    reason: str = ""  # why not valid ("" when valid)

    def row(self) -> dict:
        return {"cycle": self.index, "t_start_s": self.t_start, "duration_s": self.duration,
                "energy_J": self.energy, "speed_mps": self.speed, "speed_ok": self.speed_ok,
                "valid": self.valid, "reason": self.reason}


@dataclass
class Extraction:
    """What `extract_trajectory` found: every cycle, the chosen one and the trajectory built from it."""

    trajectory: SampledTrajectory
    cycles: list[Cycle]
    chosen: Cycle
    raw_phase: np.ndarray  # phase of each raw sample of the chosen cycle (0 = lift-off)
    raw_x: np.ndarray  # m, raw foot x of the chosen cycle (before closing and resampling)
    raw_z: np.ndarray  # m, raw foot z (contact level shifted to 0)
    provenance: dict = field(default_factory=dict)


# ---------------------------------------------------------------------------------------------------------
# pieces
# ---------------------------------------------------------------------------------------------------------

def foot_paths(q: np.ndarray, robot: RobotConfig) -> np.ndarray:
    """(n, 4, 2) foot (x, z), m, of joint angles q (n, 12): x forward from the hip joint and z + stand height
    (the controller's trajectory frame: z = 0 at the ground for a body at its nominal height)."""
    q = np.asarray(q, dtype=float).reshape(-1, 4, 3)
    p = kin.foot_position(q, robot, np.broadcast_to(kin.LEFT_RIGHT, q.shape[:2]))
    stand_height = robot.body_height - robot.foot_radius
    return np.stack([p[..., 0], p[..., 2] + stand_height], axis=-1)


def debounce(flags: np.ndarray, min_run: int) -> np.ndarray:
    """Boolean series with every run shorter than `min_run` samples merged into its neighbours.

    Runs are removed shortest first, so a contact bounce inside a swing (or a blip of lift inside a stance)
    disappears while the long runs stay.
    """
    f = np.asarray(flags, dtype=bool).copy()
    if min_run <= 1 or f.size == 0:
        return f
    while True:
        edges = np.flatnonzero(np.diff(f.astype(np.int8))) + 1
        starts = np.concatenate([[0], edges])
        ends = np.concatenate([edges, [f.size]])
        lengths = ends - starts
        inner = np.arange(len(lengths))
        short = [(lengths[i], i) for i in inner if lengths[i] < min_run]
        if not short or len(lengths) == 1:
            return f
        _, i = min(short)
        f[starts[i]:ends[i]] = not f[starts[i]]


def touch_downs(contact: np.ndarray, min_run: int = 1) -> np.ndarray:
    """Sample indices where the (debounced) contact switches from off to on."""
    c = debounce(contact, min_run).astype(np.int8)
    return np.flatnonzero(np.diff(c) == 1) + 1


def cycle_speed(base_x: np.ndarray, start: int, end: int, dt: float) -> float:
    """m/s, forward displacement of the body from sample `start` to sample `end` over (end − start)·dt.
    `end` may be one past the last sample (then the last one is used: the rollout's end)."""
    end_x = base_x[min(end, len(base_x) - 1)]
    n = min(end, len(base_x) - 1) - start
    return float(end_x - base_x[start]) / (n * dt) if n > 0 else float("nan")


def resample_closed(phase: np.ndarray, values: np.ndarray, n_points: int) -> tuple[np.ndarray, np.ndarray]:
    """Values of a periodic curve sampled at increasing `phase` ∈ [0, 1), linearly interpolated at
    `n_points` equal phases k / n_points."""
    grid = np.arange(n_points) / n_points
    p = np.concatenate([phase[-1:] - 1.0, phase, phase[:1] + 1.0])
    v = np.concatenate([values[-1:], values, values[:1]])
    return grid, np.interp(grid, p, v)


# ---------------------------------------------------------------------------------------------------------
# the extraction
# ---------------------------------------------------------------------------------------------------------

def find_cycles(traces: dict, dt: float, speed_command: float, leg: int = 0, speed_tolerance: float =
                SPEED_TOLERANCE, settle_time: float = 1.0, period: float | None = None,
                min_run_s: float = 0.01) -> list[Cycle]:
    """Gait cycles of leg `leg` (0 = LF) in `traces` (t, tau, dq (n, 12), contacts (n, 4),
    base_position (n, 3)), each with its Eq. (7) energy and speed. A cycle is valid when it starts at or after
    `settle_time` s, has one lift-off, and (if `period` is given) lasts 0.75–1.25 periods."""
    contacts = np.asarray(traces["contacts"], dtype=bool)[:, leg]
    min_run = max(1, int(round(min_run_s / dt)))
    clean = debounce(contacts, min_run)
    tds = np.flatnonzero(np.diff(clean.astype(np.int8)) == 1) + 1
    power = en.mechanical_power(traces["tau"], traces["dq"]).sum(axis=1)  # W, Eq. (7) integrand
    base_x = np.asarray(traces["base_position"], dtype=float)[:, 0]
    cycles = []
    for i, (a, b) in enumerate(zip(tds[:-1], tds[1:])):
        lift = np.flatnonzero(np.diff(clean[a:b].astype(np.int8)) == -1)
        duration = (b - a) * dt
        speed = cycle_speed(base_x, a, b, dt)
        reasons = []
        if a * dt < settle_time - 1e-9:
            reasons.append(f"before settle time {settle_time:g} s")
        if len(lift) != 1:
            reasons.append(f"{len(lift)} lift-offs")
        if period is not None and not 0.75 * period <= duration <= 1.25 * period:
            reasons.append(f"duration {duration:.3f} s not within 25 % of the period {period:g} s")
        cycles.append(Cycle(
            index=i, start=int(a), end=int(b), lift_off=int(a + lift[0] + 1) if len(lift) else -1,
            t_start=float(a * dt), duration=float(duration), energy=float(power[a:b].sum() * dt), speed=speed,
            speed_ok=speed_within_band(speed, speed_command, speed_tolerance),
            valid=not reasons, reason="; ".join(reasons)))
    return cycles


def _check_extraction_args(leg: str, speed_command: float, speed_tolerance: float, n_points: int) -> None:
    if leg not in LEG_NAMES:
        raise ValueError(f"leg must be one of {LEG_NAMES}, got {leg!r}")
    if not (np.isfinite(speed_command) and speed_command > 0):
        raise ValueError(f"speed_command must be > 0 m/s, got {speed_command!r}")
    if not 0 < speed_tolerance < 1:
        raise ValueError(f"speed_tolerance must be in (0, 1), got {speed_tolerance!r}")
    if n_points < SampledTrajectory.MIN_POINTS:
        raise ValueError(f"n_points must be >= {SampledTrajectory.MIN_POINTS}, got {n_points!r}")


def _cycle_path(xz: np.ndarray, contacts: np.ndarray, chosen: Cycle, n_points: int) -> dict:
    """One leg's foot path (xz (n, 2), m; debounced contacts (n,)) over the chosen cycle, re-ordered to start
    at its lift-off, the contact level at z = 0 and the loop closed; resampled onto `n_points` phases.
    Keys: phase, x, z (the cycle's own samples), grid, xs, zs (resampled), z_ground, gap, swing_share."""
    n = len(xz)
    a, b, lo = chosen.start, chosen.end, chosen.lift_off
    stance = contacts[a:b]
    z_ground = float(np.median(xz[a:b, 1][stance])) if stance.any() else 0.0
    # the cycle's own samples re-ordered to start at its lift-off: the swing [lo, b) first, then the stance
    # [a, lo) placed after it (as the next cycle's stance would be), phases 0 … 1 over the cycle's length
    idx = np.concatenate([np.arange(lo, b), np.arange(a, lo)])
    length = b - a
    phase = np.concatenate([np.arange(b - lo), np.arange(lo - a) + (b - lo)]) / length
    x = xz[idx, 0]
    z = xz[idx, 1] - z_ground
    # close the loop: the foot at the next touch-down (sample b) should equal the one at this touch-down (a);
    # the gap (drift, slip) is spread linearly over the samples from touch-down a onward in time order
    gap = xz[min(b, n - 1)] - xz[a]
    t_from_a = (idx - a) / length  # 0 at touch-down a, → 1 at touch-down b
    grid, xs = resample_closed(phase, x - gap[0] * t_from_a, n_points)
    _, zs = resample_closed(phase, z - gap[1] * t_from_a, n_points)
    return {"phase": phase, "x": x, "z": z, "grid": grid, "xs": xs, "zs": zs, "z_ground": z_ground, "gap": gap,
            "swing_share": float(np.count_nonzero(~stance) / length)}


def extract_trajectory(traces: dict, dt: float, speed_command: float, robot: RobotConfig | None = None,
                       gait: GaitConfig | None = None, leg: str = "LF", speed_tolerance: float = SPEED_TOLERANCE,
                       settle_time: float = 1.0, n_points: int = 100, min_run_s: float = 0.01,
                       provenance: dict | None = None) -> Extraction:
    """The cheapest in-band gait cycle of a rollout as a `SampledTrajectory` (see the module docstring).

    traces: t, q, tau, dq (n, 12), contacts (n, 4), base_position (n, 3) at the physics rate dt (s).
    speed_command: m/s, the speed the policy was commanded. robot, gait: the rollout's robot geometry and
    trot (period, swing time and lift height of the policy's env; defaults: RobotConfig(), GaitConfig()).
    leg: the reference foot (the paper shows LF). provenance: merged into the trajectory's provenance.
    Raises ExtractionError when no cycle qualifies, listing the cycles' speeds.
    """
    robot = robot or RobotConfig()
    gait = gait or GaitConfig()
    _check_extraction_args(leg, speed_command, speed_tolerance, n_points)
    n = len(traces["tau"])
    if n < 2:
        raise ExtractionError(f"the rollout has {n} samples: nothing to extract")
    li = LEG_NAMES.index(leg)
    cycles = find_cycles(traces, dt, speed_command, li, speed_tolerance, settle_time, gait.period, min_run_s)
    usable = [c for c in cycles if c.valid and c.speed_ok]
    if not usable:
        valid = [c for c in cycles if c.valid]
        speeds = ", ".join(f"{c.speed:.3f}" for c in valid[:20]) or "none"
        raise ExtractionError(
            f"no gait cycle of {leg} within ±{speed_tolerance:.0%} of {speed_command:g} m/s: {len(cycles)} cycles "
            f"in {n * dt:.2f} s, {len(valid)} valid (after {settle_time:g} s, one lift-off, plausible duration); "
            f"their speeds (m/s): {speeds}")
    chosen = min(usable, key=lambda c: c.energy)
    contacts = debounce(np.asarray(traces["contacts"], dtype=bool)[:, li], max(1, int(round(min_run_s / dt))))
    cp = _cycle_path(foot_paths(traces["q"], robot)[:, li, :], contacts, chosen, n_points)
    phase, x, z, grid, xs, zs = cp["phase"], cp["x"], cp["z"], cp["grid"], cp["xs"], cp["zs"]
    z_ground, gap, swing_share = cp["z_ground"], cp["gap"], cp["swing_share"]
    step_length = speed_command * gait.stance_time  # m, the S the policy's controller was commanded
    lift_height = float(np.max(zs))
    if not lift_height > 1e-3:
        raise ExtractionError(f"the chosen cycle's foot hardly lifts (peak {lift_height * 1e3:.2f} mm)")
    prov = {
        "source": "cyberdog.analysis.extract.extract_trajectory", "leg": leg,
        "speed_command_mps": float(speed_command), "cycle_index": chosen.index,
        "cycle_t_start_s": chosen.t_start, "cycle_duration_s": chosen.duration,
        "cycle_energy_J": chosen.energy, "cycle_speed_mps": chosen.speed,
        "speed_tolerance": float(speed_tolerance), "settle_time_s": float(settle_time),
        "cycles_total": len(cycles), "cycles_in_band": len(usable),
        "period_s": gait.period, "swing_time_s": gait.swing_time, "controller_lift_height_m": gait.lift_height,
        "step_length_basis": "commanded: speed_command * stance_time", "step_length_m": step_length,
        "measured_x_range_m": float(np.ptp(xs)), "measured_lift_height_m": lift_height,
        "measured_swing_share": swing_share, "contact_level_shift_m": z_ground,
        "loop_closure_gap_m": [float(gap[0]), float(gap[1])], "controller_dt_s": float(dt),
    }
    prov.update(provenance or {})
    traj = SampledTrajectory.from_points(grid, xs, zs, step_length, lift_height, prov)
    return Extraction(trajectory=traj, cycles=cycles, chosen=chosen, raw_phase=phase, raw_x=x, raw_z=z,
                      provenance=prov)


def rollout_provenance(rollout, env_config, provenance: dict | None = None) -> dict:
    """What an extracted trajectory records of the rollout it came from: its walk, the trot controller it walked
    under (`controller`, e.g. with foot placement) and a warning if it fell."""
    prov = {"rollout_mean_speed_mps": rollout.mean_speed, "rollout_fell": bool(rollout.fell),
            "rollout_duration_s": rollout.duration, "rollout_energy_J": rollout.energy,
            "action_mode": env_config.action_mode, "controller": asdict(env_config.walk.controller),
            **(provenance or {})}
    if rollout.fell:
        prov["warning"] = f"the rollout fell after {rollout.duration:.2f} s"
    return prov


def extract_from_rollout(rollout, env_config, leg: str = "LF", speed_tolerance: float = SPEED_TOLERANCE,
                         settle_time: float = 1.0, n_points: int = 100, provenance: dict | None = None
                         ) -> Extraction:
    """`extract_trajectory` on a policy rollout (a WalkResult of `cyberdog.rl.rollout.rollout`) in `env_config`."""
    prov = rollout_provenance(rollout, env_config, provenance)
    return extract_trajectory(rollout.traces, rollout.trace_dt, rollout.speed_command, env_config.walk.robot,
                              env_config.walk.gait, leg, speed_tolerance, settle_time, n_points, provenance=prov)


@dataclass
class CommandedExtraction:
    """What `extract_commanded` found: every gait-clock cycle, those used, and the path built from them."""

    path: CommandedPath
    cycles: list[Cycle]
    used: list[int]  # indices of the cycles the path was built from
    energy: float  # J, the mean Eq. (7) energy of the used cycles (the closed-loop figure to reproduce)


def clock_cycles(traces: dict, dt: float, speed_command: float, period: float, speed_tolerance: float =
                 SPEED_TOLERANCE, settle_time: float = 2.0) -> list[Cycle]:
    """The rollout cut into whole gait-clock cycles [k·T, (k+1)·T) (LF lifts off at each start), each with its
    Eq. (7) energy and speed; valid after `settle_time` s (the 1 s speed ramp and the controller's speed
    integral settle first)."""
    per = int(round(period / dt))
    n = len(traces["tau"])
    power = en.mechanical_power(traces["tau"], traces["dq"]).sum(axis=1)
    base_x = np.asarray(traces["base_position"], dtype=float)[:, 0]
    cycles = []
    for k in range(n // per):
        a, b = k * per, (k + 1) * per
        speed = cycle_speed(base_x, a, b, dt)
        settled = a * dt >= settle_time - 1e-9
        cycles.append(Cycle(index=k, start=a, end=b, lift_off=a, t_start=a * dt, duration=per * dt,
                            energy=float(power[a:b].sum() * dt), speed=speed,
                            speed_ok=speed_within_band(speed, speed_command, speed_tolerance),
                            valid=settled, reason="" if settled else f"before settle time {settle_time:g} s"))
    return cycles


def extract_commanded(traces: dict, dt: float, speed_command: float, gait: GaitConfig, cycle: str = "mean",
                      speed_tolerance: float = SPEED_TOLERANCE, settle_time: float = 2.0,
                      provenance: dict | None = None) -> CommandedExtraction:
    """The policy's commanded foot path (see the module docstring) from a rollout's traces: t, tau, dq
    (n, 12), base_position (n, 3) and foot_offsets (n, 4, 3) m at the physics rate dt (s), with the trot the
    policy's controller ran (`gait`: base trajectory, period, swing time, lift height). The offset table has
    one sample per controller period of a cycle. Raises ExtractionError when no settled cycle is in the band."""
    if cycle not in CYCLE_CHOICES:
        raise ValueError(f"cycle must be one of {CYCLE_CHOICES}, got {cycle!r}")
    if not (np.isfinite(speed_command) and speed_command > 0):
        raise ValueError(f"speed_command must be > 0 m/s, got {speed_command!r}")
    if "foot_offsets" not in traces:
        raise ExtractionError("the rollout has no recorded foot targets (foot_offsets): roll it out with "
                              "cyberdog.rl.rollout.rollout")
    offsets = np.asarray(traces["foot_offsets"], dtype=float)
    if not np.all(np.isfinite(offsets)):
        raise ExtractionError("the recorded foot offsets are not finite (a torque-mode policy commands no foot "
                              "path: use the measured-path extraction)")
    cycles = clock_cycles(traces, dt, speed_command, gait.period, speed_tolerance, settle_time)
    usable = [c for c in cycles if c.valid and c.speed_ok]
    if not usable:
        speeds = ", ".join(f"{c.speed:.3f}" for c in cycles if c.valid) or "none"
        raise ExtractionError(f"no settled gait cycle within ±{speed_tolerance:.0%} of {speed_command:g} m/s "
                              f"({len(cycles)} cycles; speeds after {settle_time:g} s (m/s): {speeds})")
    used = usable if cycle == "mean" else [min(usable, key=lambda c: c.energy)]
    # the cycles are whole gait-clock periods, so sample j of every cycle is at the same phase of each leg:
    # average them sample by sample, then order each leg's samples by its phase
    per = used[0].end - used[0].start
    mean_offsets = np.mean([offsets[c.start:c.end] for c in used], axis=0)  # (per, 4, 3)
    first = used[0]
    phases = GaitScheduler.from_config(gait).leg_phases(np.asarray(traces["t"], dtype=float)[first.start:first.end])
    table = FootOffsetPath.from_samples(phases, mean_offsets, gait.period, per)
    energy = float(np.mean([c.energy for c in used]))
    prov = {"source": "cyberdog.analysis.extract.extract_commanded", "path": "commanded", "cycle": cycle,
            "speed_command_mps": float(speed_command), "cycles_total": len(cycles),
            "cycles_in_band": len(usable), "cycles_used": [c.index for c in used],
            "cycle_energy_J": energy, "cycle_speed_mps": float(np.mean([c.speed for c in used])),
            "speed_tolerance": float(speed_tolerance), "settle_time_s": float(settle_time),
            "offset_rms_mm": np.round(1e3 * table.rms(), 3).tolist(), "controller_dt_s": float(dt),
            **(provenance or {})}
    path = CommandedPath(float(speed_command), gait, table, prov)
    return CommandedExtraction(path, cycles, [c.index for c in used], energy)


def commanded_from_rollout(rollout, env_config, cycle: str = "mean", speed_tolerance: float = SPEED_TOLERANCE,
                           settle_time: float = 2.0, provenance: dict | None = None) -> CommandedExtraction:
    """`extract_commanded` on a policy rollout (a WalkResult of `cyberdog.rl.rollout.rollout`) in `env_config`."""
    if env_config.action_mode != "foot":
        raise ExtractionError(f"a policy of action_mode {env_config.action_mode!r} commands no foot path; "
                              "use the measured-path extraction")
    prov = rollout_provenance(rollout, env_config, provenance)
    return extract_commanded(rollout.traces, rollout.trace_dt, rollout.speed_command, env_config.walk.gait,
                             cycle, speed_tolerance, settle_time, prov)


def cycle_rows(extraction: Extraction | CommandedExtraction) -> list[dict]:
    """One row per cycle (CSV-ready), the chosen one marked."""
    chosen = extraction.used if isinstance(extraction, CommandedExtraction) else [extraction.chosen.index]
    return [{**c.row(), "chosen": c.index in chosen} for c in extraction.cycles]


__all__ = ["CYCLE_CHOICES", "CommandedExtraction", "Cycle", "Extraction", "ExtractionError", "SPEED_TOLERANCE",
           "clock_cycles", "commanded_from_rollout", "cycle_rows", "debounce", "extract_commanded",
           "extract_from_rollout", "extract_trajectory", "find_cycles", "foot_paths", "resample_closed",
           "touch_downs"]
