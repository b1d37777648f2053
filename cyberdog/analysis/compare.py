"""The trajectory comparison of the paper's Section 4.1 and its Table 5.

For each speed (1.0, 1.2, 1.4 m/s) the learned trajectory (one per policy seed) and the two common ones are
replayed by the same IK + PID diagonal trot (`cyberdog.analysis.walk.walk`) with the same gait period and step
length S = v·stance_time, for `duration` s (the paper's 10 s). Each walk reports E by Eq. (7), energy per
100 m, cost of transport and mean speed; the learned walks also D_t by Eq. (12) against the cheaper baseline
of the same set.

Two sets of baselines, because the lift height H alone changes the energy a lot:
- "paper": the baselines at the paper's H (`cfg.gait.lift_height`, 0.15 m): Table 5 proper;
- "same_lift": the baselines at the learned trajectory's own recorded H (a control: what is left of the
  saving when only the shape differs).
The learned trajectory is always replayed at its own recorded H (its provenance says which).

The learned paths come as a `LearnedSet` (`cyberdog.core.learned_set`): per label (the policy's seed) a
commanded path per speed, replayed only at its speed with no policy in the loop, or one sampled x-z path
replayed at every speed; `LearnedSet.at(v)` picks each label's path at speed v by the set's one rule, and a
path's "own H" is its `lift_height`.

A reference row (optional, `reference`): the best hand-designed shape that the project's direct search finds
at the learned paths' lift height (`tools/optimize_trajectory.py`, a `SampledTrajectory`), walked once per
speed at its own H in the "same_lift" set. It is not one of Eq. (12)'s baselines: the learned walks get
D_ref, Eq. (12)'s formula with the reference as E_min (negative: the learned path costs more), so that the
common trajectories are not the only yardstick.

Every walk also reports what Eq. (7) does not see: the electrical energy (copper loss, friction, driver
efficiency; `cyberdog.core.energy`), the positive mechanical work, and the foot slip per cycle; the learned
walks get D_t on the electrical energy too.

A walk that falls, or whose mean speed over its last half misses the command by more than 5 %, is reported
with its status and left out of D_t and of the across-seed means (mean and 95 % Student-t interval,
`cyberdog.analysis.stats.mean_ci`). Walks run in parallel processes (spawn; one PyBullet client each).
"""
from __future__ import annotations

import dataclasses
import math
import time
from dataclasses import dataclass

from cyberdog.analysis.comparison_sets import BASELINES, LIFT_DECIMALS, REFERENCE, SETS, same_lift
from cyberdog.analysis.parallel import map_in_processes, progress_log
from cyberdog.analysis.stats import mean_ci
from cyberdog.analysis.walk import walk
from cyberdog.config import WalkConfig
from cyberdog.config.paper import PAPER_SPEEDS, PAPER_WALK_DURATION
from cyberdog.core import energy as en
from cyberdog.core.foot_offsets import FootOffsetPath
from cyberdog.core.learned_set import LearnedPath, LearnedSet
from cyberdog.core.trajectories import FootTrajectory, SampledTrajectory

COLUMNS = ["set", "trajectory", "seed", "lift_height_m", "speed_command_mps", "mean_speed_mps", "status",
           "energy_kJ", "energy_per_100m_kJ", "cost_of_transport", "electrical_energy_J", "positive_work_J",
           "foot_slip_mm_per_cycle", "D_t_pct", "D_t_per_100m_pct", "D_t_electrical_pct", "E_min_trajectory",
           "D_ref_pct", "D_ref_electrical_pct"]


@dataclass(frozen=True)
class WalkJob:
    """One replay: a trajectory at one speed and lift height."""

    walk_id: int
    trajectory: str  # "learned", "cycloid", "straight" or REFERENCE
    seed: str  # the learned trajectory's label ("" for the baselines)
    speed: float  # m/s
    lift_height: float  # m
    cfg: WalkConfig
    duration: float  # s
    foot_trajectory: SampledTrajectory | None = None  # a sampled learned or the reference path (None: cfg.gait's)
    foot_offsets: FootOffsetPath | None = None  # a commanded learned path's shift of the foot targets
    learned: LearnedPath | None = None  # the learned path walked (None for the other rows)


def walk_config(base: WalkConfig, trajectory: str, speed: float, lift_height: float) -> WalkConfig:
    gait = dataclasses.replace(base.gait, speed=float(speed), lift_height=float(lift_height),
                               trajectory=trajectory if trajectory in BASELINES else base.gait.trajectory)
    return dataclasses.replace(base, gait=gait)


def comparison_jobs(cfg: WalkConfig, learned: LearnedSet, speeds=PAPER_SPEEDS,
                    duration: float = PAPER_WALK_DURATION, same_lift: bool = True,
                    reference: SampledTrajectory | None = None, skip_missing: bool = False) -> list[WalkJob]:
    """Every walk of the comparison: each label's learned path at each speed (`LearnedSet.at`: an error if a
    label has none there; with `skip_missing`, the labels that have one, an error only where none has), each
    baseline walk once per speed and distinct lift height, and the `reference` shape (if given, with
    `same_lift`) once per speed at its own lift height."""
    if not isinstance(learned, LearnedSet):
        raise TypeError(f"learned must be a LearnedSet, got {type(learned).__name__}")
    if reference is not None and not isinstance(reference, FootTrajectory):
        raise TypeError(f"reference must be a foot trajectory (a saved SampledTrajectory) or None, got "
                        f"{type(reference).__name__}")
    jobs: list[WalkJob] = []
    for v in speeds:
        # with skip_missing, the labels that have a path at v; where none has, at() raises naming them
        here = learned.at(v) if not skip_missing else \
            {label: learned.path(label, v) for label in learned.labels if learned.has(label, v)} or learned.at(v)
        lifts = [round(cfg.gait.lift_height, LIFT_DECIMALS)]
        if same_lift:
            lifts += [round(p.lift_height, LIFT_DECIMALS) for p in here.values()]
        lifts = list(dict.fromkeys(lifts))
        for label, path in here.items():
            job_cfg, foot_trajectory, offsets = path.walk_args(cfg, v)
            jobs.append(WalkJob(len(jobs), "learned", label, float(v), path.lift_height, job_cfg, duration,
                                foot_trajectory, offsets, path))
        for name in BASELINES:
            for h in lifts:
                jobs.append(WalkJob(len(jobs), name, "", float(v), h, walk_config(cfg, name, v, h), duration))
        if reference is not None and same_lift:
            h = float(reference.lift_height)
            jobs.append(WalkJob(len(jobs), REFERENCE, "", float(v), h, walk_config(cfg, REFERENCE, v, h), duration,
                                reference))
    return jobs


def run_walk_job(job: WalkJob) -> dict:
    """One walk → a row with its metrics and total joint power trace (runs in a worker process)."""
    t0 = time.perf_counter()
    r = walk(job.cfg, job.duration, job.foot_trajectory, record=True, foot_offsets=job.foot_offsets)
    total_power = r.traces["power"].sum(axis=1)  # W, Σ_ij |τ_ij·θ̇_ij|, Eq. (7)'s integrand
    if r.fell:
        status = f"fell at {r.duration:.2f} s"
    elif not r.speed_ok:
        status = f"speed miss ({r.mean_speed:.3f} m/s)"
    else:
        status = "ok"
    label = {"straight": f"straight ({job.cfg.gait.straight_shape})",
             REFERENCE: "searched shape"}.get(job.trajectory, job.trajectory)
    return {
        "walk_id": job.walk_id, "trajectory": job.trajectory, "label": label, "seed": job.seed,
        "lift_height_m": job.lift_height, "speed_command_mps": job.speed, "period_s": job.cfg.gait.period,
        "step_length_m": job.cfg.gait.step_length, "mean_speed_mps": r.mean_speed, "fell": r.fell,
        "speed_ok": r.speed_ok, "valid": (not r.fell) and r.speed_ok, "status": status,
        "duration_s": r.duration, "distance_m": r.distance, "energy_J": r.energy,
        "energy_kJ": r.energy / 1e3, "energy_per_100m_kJ": r.energy_per_100m / 1e3,
        "cost_of_transport": r.cost_of_transport, "electrical_energy_J": r.electrical_energy,
        "positive_work_J": r.positive_work, "foot_slip_mm_per_cycle": 1e3 * r.foot_slip_per_cycle,
        "peak_torque_Nm": r.peak_torque, "lateral_drift_m": r.lateral_drift,
        "controller_dt_s": job.cfg.sim.controller_dt, "wall_s": time.perf_counter() - t0,
        "power_W": total_power,
    }


def run_jobs(jobs: list[WalkJob], workers: int | None = None, log=print, every_walk: bool = True) -> list[dict]:
    """Run the walks (in `workers` spawned processes; None: one per walk, at most the CPUs; 1 = in this
    process); rows in job order. A line per walk, or with `every_walk=False` one per quarter of them."""
    def line(row: dict) -> str:
        seed = f" [{row['seed']}]" if row["seed"] else ""
        return (f"{row['label'] + seed:24s} H={row['lift_height_m']:.3f} m v={row['speed_command_mps']:.1f} m/s  "
                f"mean {row['mean_speed_mps']:.3f} m/s  E={row['energy_J']:7.1f} J  {row['status']}")

    return map_in_processes(run_walk_job, jobs, workers, on_result=progress_log(len(jobs), line, log, every_walk), describe=_describe_job)


def _describe_job(job: WalkJob) -> str:
    return (f"walk {job.walk_id}: {job.trajectory}{f' [{job.seed}]' if job.seed else ''} at {job.speed:g} m/s, "
            f"H = {job.lift_height:.3f} m, {job.duration:g} s")


# ---------------------------------------------------------------------------------------------------------
# Eq. (12) and the table
# ---------------------------------------------------------------------------------------------------------

def reduction(e_min: float, e_s: float) -> float:
    """Eq. (12) in %, nan where it is undefined (no valid baseline or learned walk)."""
    if not (math.isfinite(e_min) and e_min > 0 and math.isfinite(e_s)):
        return float("nan")
    return 100.0 * en.energy_reduction(e_min, e_s)


def comparison_rows(walks: list[dict], paper_lift: float) -> list[dict]:
    """The walks arranged in sets ("paper": baselines at `paper_lift`; "same_lift": at each learned
    trajectory's own H), with D_t (Eq. 12, %) on E and on energy per 100 m for every learned walk, against the
    cheaper valid baseline of its set at its speed. The learned walk appears in both sets. In "same_lift", the
    reference walks (if any) are rows too, and each learned walk gets D_ref (Eq. 12's formula against the
    valid reference walk at its speed, on E and on the electrical energy; nan without one)."""
    out = []
    learned = [w for w in walks if w["trajectory"] == "learned"]
    seeds = list(dict.fromkeys(w["seed"] for w in learned))
    speeds = list(dict.fromkeys(w["speed_command_mps"] for w in walks))
    for set_name in SETS:
        for seed in seeds:
            for v in speeds:
                mine = [w for w in learned if w["seed"] == seed and w["speed_command_mps"] == v]
                if not mine:
                    continue
                lw = mine[0]
                lift = paper_lift if set_name == "paper" else lw["lift_height_m"]
                base = [w for w in walks if w["trajectory"] in BASELINES and w["speed_command_mps"] == v
                        and same_lift(w["lift_height_m"], lift)]
                if not base:
                    continue
                valid = [w for w in base if w["valid"]]
                cheap = min(valid, key=lambda w: w["energy_J"]) if valid else None
                cheap100 = min(valid, key=lambda w: w["energy_per_100m_kJ"]) if valid else None
                d = reduction(cheap["energy_J"], lw["energy_J"]) if cheap and lw["valid"] else float("nan")
                d100 = (reduction(cheap100["energy_per_100m_kJ"], lw["energy_per_100m_kJ"])
                        if cheap100 and lw["valid"] else float("nan"))
                cheap_el = min(valid, key=lambda w: w["electrical_energy_J"]) if valid else None
                d_el = (reduction(cheap_el["electrical_energy_J"], lw["electrical_energy_J"])
                        if cheap_el and lw["valid"] else float("nan"))
                ref = next((w for w in walks if w["trajectory"] == REFERENCE and w["speed_command_mps"] == v),
                           None) if set_name == "same_lift" else None
                both = bool(ref and ref["valid"] and lw["valid"])
                d_ref = reduction(ref["energy_J"], lw["energy_J"]) if both else float("nan")
                d_ref_el = reduction(ref["electrical_energy_J"], lw["electrical_energy_J"]) if both else float("nan")
                out.append({**_public(lw), "set": set_name, "D_t_pct": d, "D_t_per_100m_pct": d100,
                            "D_t_electrical_pct": d_el, "D_ref_pct": d_ref, "D_ref_electrical_pct": d_ref_el,
                            "E_min_trajectory": cheap["label"] if cheap else "",
                            "E_min_kJ": cheap["energy_kJ"] if cheap else float("nan")})
                for w in base + ([ref] if ref else []):
                    if not any(o["set"] == set_name and o["walk_id"] == w["walk_id"] for o in out):
                        out.append({**_public(w), "set": set_name, **dict.fromkeys(NO_D, float("nan")),
                                    "E_min_trajectory": ""})
    order = {"learned": 0, "cycloid": 1, "straight": 2, REFERENCE: 3}
    out.sort(key=lambda r: (SETS.index(r["set"]),
                            round(r["lift_height_m"], LIFT_DECIMALS) if r["set"] == "same_lift" else 0,
                            order[r["trajectory"]], r["seed"], r["speed_command_mps"]))
    return out


NO_D = ("D_t_pct", "D_t_per_100m_pct", "D_t_electrical_pct", "D_ref_pct", "D_ref_electrical_pct", "E_min_kJ")


def _public(w: dict) -> dict:
    return {k: v for k, v in w.items() if k != "power_W"}


def seed_means(rows: list[dict]) -> list[dict]:
    """Per set and speed, across the learned seeds: mean and 95 % CI half-width of E (kJ) and D_t (%),
    over the valid walks only (`n_valid` of `n_seeds`)."""
    out = []
    learned = [r for r in rows if r["trajectory"] == "learned"]
    for set_name in SETS:
        for v in dict.fromkeys(r["speed_command_mps"] for r in learned):
            group = [r for r in learned if r["set"] == set_name and r["speed_command_mps"] == v]
            if not group:
                continue
            ok = [r for r in group if r["valid"]]
            e, e_ci = mean_ci([r["energy_kJ"] for r in ok])
            d, d_ci = mean_ci([r["D_t_pct"] for r in ok])
            d100, d100_ci = mean_ci([r["D_t_per_100m_pct"] for r in ok])
            d_el, d_el_ci = mean_ci([r["D_t_electrical_pct"] for r in ok])
            h, h_ci = mean_ci([r["lift_height_m"] for r in ok])
            slip, slip_ci = mean_ci([r["foot_slip_mm_per_cycle"] for r in ok])
            out.append({"set": set_name, "speed_command_mps": v, "n_seeds": len(group), "n_valid": len(ok),
                        "energy_kJ_mean": e, "energy_kJ_ci95": e_ci, "D_t_pct_mean": d, "D_t_pct_ci95": d_ci,
                        "D_t_per_100m_pct_mean": d100, "D_t_per_100m_pct_ci95": d100_ci,
                        "D_t_electrical_pct_mean": d_el, "D_t_electrical_pct_ci95": d_el_ci,
                        "lift_height_m_mean": h, "lift_height_m_ci95": h_ci,
                        "foot_slip_mm_per_cycle_mean": slip, "foot_slip_mm_per_cycle_ci95": slip_ci})
    return out


__all__ = ["BASELINES", "COLUMNS", "REFERENCE", "PAPER_SPEEDS", "SETS", "WalkJob", "comparison_jobs",
           "comparison_rows", "reduction", "run_jobs",
           "run_walk_job", "seed_means", "walk_config"]
