"""The measured foot path of a policy rollout: the paper's way of extraction (Section 3, after Figure 6).
Numpy only.

The paper "extracted the simulation data with the minimum energy consumption from the cycle with the optimal
reward function" and recorded the foot's x and z (Figure 7). Replayed as a new target through IK + PID, such a
measured path applies the tracking lag and stance wiggles a second time and loses most of the saving, so the
default extraction is the commanded path (`cyberdog.analysis.extract`, which also holds what both share: the
`Cycle`, `ExtractionError`, the speed band). Here, from the physics-rate traces of one deterministic rollout of
the trained stage-2 policy (`cyberdog.rl.rollout.rollout`):

1. each foot's position relative to its hip joint: forward kinematics of the recorded joint angles in the
   leg frame (`kinematics.foot_position`), x forward and z = foot z + stand height (the trot controller's
   convention: z = 0 is the ground for a body at its nominal height), in the body's axes;
2. the rollout is cut into gait cycles at the reference leg's touch-downs (rising edges of its recorded
   ground contact, runs shorter than `min_run_s` ignored as bounces);
3. each cycle's energy by Eq. (7), E = Σ_ij ∫|τ_ij·θ̇_ij| dt over the cycle (all 12 joints), and its speed,
   the body's forward displacement over the cycle divided by its duration;
4. among the cycles whose speed is within ±`speed_tolerance` (5 %) of the command (and that start after
   `settle_time`, last a plausible time and contain one lift-off), the cheapest one is taken (or the cheapest
   not in `skip_cycles`: evaluation's extraction skips a cycle whose path does not replay in the band);
5. its foot path becomes a `SampledTrajectory`: phase 0 at the recorded lift-off, the end-to-start gap
   spread linearly over the cycle (closing the loop), z shifted so the contact level is 0, resampled at
   `n_points` equal phases. It is normalised by the step length the policy's controller was commanded,
   S = v·stance_time, and by the recorded lift height (the peak of z), so `SampledTrajectory` replays it at
   other S and H; replayed at the recorded S and H it is the recorded path.

`extract_trajectory(traces, ...)` takes plain arrays (no torch), so it can be tested on synthetic traces;
`cyberdog.rl.rollout` produces the real ones.
"""
from __future__ import annotations

from collections.abc import Collection
from dataclasses import dataclass, field

import numpy as np

from cyberdog.analysis.extract import SPEED_TOLERANCE, Cycle, ExtractionError, cycle_speed, rollout_provenance
from cyberdog.config import LEG_NAMES, GaitConfig, RobotConfig
from cyberdog.config.paper import speed_within_band
from cyberdog.core import energy as en
from cyberdog.core import kinematics as kin
from cyberdog.core.trajectories import SampledTrajectory


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

    @property
    def used(self) -> list[int]:
        """Index of the cycle the trajectory was built from (as `CommandedExtraction.used`)."""
        return [self.chosen.index]


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
                       provenance: dict | None = None, skip_cycles: Collection[int] = ()) -> Extraction:
    """The cheapest in-band gait cycle of a rollout as a `SampledTrajectory` (see the module docstring).

    traces: t, q, tau, dq (n, 12), contacts (n, 4), base_position (n, 3) at the physics rate dt (s).
    speed_command: m/s, the speed the policy was commanded. robot, gait: the rollout's robot geometry and
    trot (period, swing time and lift height of the policy's env; defaults: RobotConfig(), GaitConfig()).
    leg: the reference foot (the paper shows LF). provenance: merged into the trajectory's provenance.
    skip_cycles: indices of cycles not to take (ones whose path was replayed and rejected): the cheapest of the
    others is taken. Raises ExtractionError when no cycle qualifies, listing the cycles' speeds.
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
    left = [c for c in usable if c.index not in set(skip_cycles)]
    if not left:
        raise ExtractionError(f"all {len(usable)} gait cycles of {leg} within ±{speed_tolerance:.0%} of "
                              f"{speed_command:g} m/s were replayed and rejected")
    chosen = min(left, key=lambda c: c.energy)
    contacts = debounce(np.asarray(traces["contacts"], dtype=bool)[:, li], max(1, int(round(min_run_s / dt))))
    cp = _cycle_path(foot_paths(traces["q"], robot)[:, li, :], contacts, chosen, n_points)
    phase, x, z, grid, xs, zs = cp["phase"], cp["x"], cp["z"], cp["grid"], cp["xs"], cp["zs"]
    z_ground, gap, swing_share = cp["z_ground"], cp["gap"], cp["swing_share"]
    step_length = speed_command * gait.stance_time  # m, the S the policy's controller was commanded
    lift_height = float(np.max(zs))
    if not lift_height > 1e-3:
        raise ExtractionError(f"the chosen cycle's foot hardly lifts (peak {lift_height * 1e3:.2f} mm)")
    prov = {
        "source": "cyberdog.analysis.extract_measured.extract_trajectory", "leg": leg,
        "speed_command_mps": float(speed_command), "cycle_index": chosen.index,
        "cycle_t_start_s": chosen.t_start, "cycle_duration_s": chosen.duration,
        "cycle_energy_J": chosen.energy, "cycle_speed_mps": chosen.speed,
        "speed_tolerance": float(speed_tolerance), "settle_time_s": float(settle_time),
        "cycles_total": len(cycles), "cycles_in_band": len(usable), "cycles_skipped": sorted(set(skip_cycles)),
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


def extract_from_rollout(rollout, env_config, leg: str = "LF", speed_tolerance: float = SPEED_TOLERANCE,
                         settle_time: float = 1.0, n_points: int = 100, provenance: dict | None = None,
                         skip_cycles: Collection[int] = ()) -> Extraction:
    """`extract_trajectory` on a policy rollout (a WalkResult of `cyberdog.rl.rollout.rollout`) in `env_config`."""
    prov = rollout_provenance(rollout, env_config, provenance)
    return extract_trajectory(rollout.traces, rollout.trace_dt, rollout.speed_command, env_config.walk.robot,
                              env_config.walk.gait, leg, speed_tolerance, settle_time, n_points, provenance=prov,
                              skip_cycles=skip_cycles)


__all__ = ["Extraction", "debounce", "extract_from_rollout", "extract_trajectory", "find_cycles", "foot_paths",
           "resample_closed", "touch_downs"]
