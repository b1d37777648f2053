"""The paper's prototype experiment (Section 4.2) in simulation: walk a distance (the paper's 100 m) with each
trajectory at each speed, on the ideal robot and on hardware-like ones, and report the battery drain by Eq. (13).

The paper walked the real CyberDog 100 m at 1.0, 1.2 and 1.4 m/s with three foot trajectories and read the
drop of the battery charge (Eq. 13, P_C = E_f − E_n, starting from E_f = 95 %). It reports ranges on a full
charge at 1 m/s of 3,600 m (composite cycloid) and 3,924 m (learned trajectory), and a 3 % gap between the
energy reduction measured in simulation (12 %, Eq. 7 and Eq. 12) and on the robot (9 %, battery).

Here each walk is one `cyberdog.analysis.walk.walk(..., distance=distance_m)`:
- "ideal": the Section 4.1 simulation (true states, no joint friction in the physics, nominal mass);
- "hardware": `HardwareConfig` effects on (by default `HARDWARE_LIKE`: joint friction, 2.5 ms latency, encoder
  noise, Kalman speed with a noisy IMU, a ±5 % mass draw); each draw walks every trajectory, as in the paper.
Both report Eq. (7) mechanical energy and the electrical energy drawn from the pack (copper loss, joint friction,
driver efficiency; `cyberdog.core.energy`). Battery (EnergyConfig; ASSUMPTION [G] except where noted):
pack energy `battery_capacity_wh` (default 8 Ah × 25.2 V = 201.6 Wh [G]), charged to 25 V (paper), the walk
starting at E_f = 95 % (paper), motor drivers 95 % efficient [G], no electronics load (idle_power = 0 W:
legs only, so ranges are upper bounds). Battery % used = 100·E_el / pack energy (= Eq. 13's E_f − E_n);
range = distance × 95 / battery % used (the walk's rate until the usable 95 % is spent).

Walks run in parallel processes (spawn; each its own PyBullet client); `evaluate.py prototype` writes the tables.
"""
from __future__ import annotations

import dataclasses
import math
import pickle
import time
from pathlib import Path

from cyberdog.analysis.parallel import map_in_processes, progress_log
from cyberdog.analysis.pd_match_recording import pd_matched_foot_offsets
from cyberdog.analysis.prototype_gaps import add_gaps, gap_rows
from cyberdog.analysis.prototype_summary import summary_markdown, summary_rows
from cyberdog.analysis.report import markdown_table, write_rows
from cyberdog.analysis.walk import walk
from cyberdog.config import (HARDWARE_LIKE, TRAJECTORY_NAMES, HardwareConfig, PIDConfig, RandomizationConfig,
                             WalkConfig)
from cyberdog.config.paper import (PAPER_RANGE_1MPS_M, PAPER_SIM_TO_REAL_GAP_PP, PAPER_SPEEDS, PROTOTYPE_DISTANCE_M,
                                   PROTOTYPE_DRAWS, PROTOTYPE_RUN_UP_S)
from cyberdog.core import energy as en
from cyberdog.core.foot_offsets import FootOffsetPath
from cyberdog.core.learned_set import LearnedSet, LearnedSetError
from cyberdog.core.trajectories import FootTrajectory

MODES = ("ideal", "hardware")
POLICY = "policy"  # the row of a policy walking closed loop (`run_prototype(policies=...)`)
TIME_CAP_MARGIN_S = 10.0  # s added to 1.5 × distance / speed (+ the start-up ramp) before a walk is abandoned

# the Markdown table's columns (rows carry more: J, wall time, peak torque, lateral drift, battery E_f, E_n)
TABLE_COLUMNS = ["trajectory", "seed", "draw", "speed_mps", "robot", "lift_height_m", "fell", "reached", "mass_scale",
                 "mass_kg", "mean_speed_mps",
                 "distance_m", "time_s", "energy_kJ", "electrical_energy_kJ", "battery_used_pct",
                 "range_full_charge_m", "electrical_gap_pct"]


@dataclasses.dataclass(frozen=True)
class _Job:
    trajectory_name: str
    trajectory: FootTrajectory | None
    speed: float
    mode: str
    cfg: WalkConfig
    hardware: HardwareConfig
    distance_m: float
    foot_offsets: FootOffsetPath | None = None  # a commanded path's shift of the foot targets
    seed: str = ""  # the learned path's label this walk belongs to (a baseline: the one whose lift it matches)
    draw: int = 0  # which hardware-like robot: HardwareConfig.seed + draw (0 on the ideal robot)
    run_up_s: float = 0.0  # s walked before the measured distance (see `run_prototype`)
    lift_height: float | None = None  # m, the path's own lift (a learned path); None: the config's trajectory's
    policy: str | None = None  # an actor file: the policy itself walks (closed loop, `cyberdog.rl.rollout`)
    pd_scale: float = 1.0  # the joint PD's stiffness in `cfg.pid`, × the base config's (PIDConfig.stiffness_scaled)
    pd_matched_from: PIDConfig | None = None  # the path's own PD: its command re-solved for `cfg.pid` (pd_matched)


def time_cap(distance_m: float, speed: float, cfg: WalkConfig, run_up_s: float = 0.0) -> float:
    """s: a walk slower than 2/3 of the command is abandoned (and reported as not reached)."""
    return run_up_s + 1.5 * distance_m / speed + cfg.controller.speed_ramp_time + TIME_CAP_MARGIN_S


def _job_config(base: WalkConfig, name: str, trajectory: FootTrajectory | None, speed: float) -> WalkConfig:
    gait = dataclasses.replace(base.gait, speed=float(speed))
    if trajectory is None and name in TRAJECTORY_NAMES and name != "sampled":
        gait = dataclasses.replace(gait, trajectory=name)  # "cycloid" / "straight" by name
    return dataclasses.replace(base, gait=gait)


def _policy_walk(job: _Job, hardware: HardwareConfig | None, cap: float):
    """The actor of `job.policy` walks the protocol in its own env (its observation, its trot under the action),
    on the same robot, in the same physics engine and with the same joint PD as the paths: `job.cfg.robot` (its
    payload), `job.cfg.pid`,
    `job.cfg.sim.engine`, the hardware draw's mass and sensor streams (`hardware_robot`), the domain
    randomisation off."""
    from cyberdog.rl.rollout import load_actor, rollout  # torch: only in the processes that walk a policy

    actor = load_actor(job.policy)
    env = actor.config.env
    sim = dataclasses.replace(env.walk.sim, engine=job.cfg.sim.engine)
    env = dataclasses.replace(env, walk=dataclasses.replace(env.walk, robot=job.cfg.robot, pid=job.cfg.pid, sim=sim),
                              hardware=hardware or HardwareConfig(), randomization=RandomizationConfig())
    return rollout(actor, job.speed, cap, seed=job.draw, env_config=env, distance=job.distance_m,
                   run_up=job.run_up_s, hardware_robot=True)


def _run_job(job: _Job) -> dict:
    """One walk → one row (runs in a worker process)."""
    t0 = time.perf_counter()
    hw = job.hardware if job.mode == "hardware" else None
    cap = time_cap(job.distance_m, job.speed, job.cfg, job.run_up_s)
    if job.policy is not None:
        r = _policy_walk(job, hw, cap)
    else:
        offsets = job.foot_offsets
        if job.pd_matched_from is not None:  # the path's executed motion kept, its command solved for this PD
            offsets = pd_matched_foot_offsets(dataclasses.replace(job.cfg, pid=job.pd_matched_from), job.trajectory,
                                              offsets, job.cfg.pid)
        r = walk(job.cfg, cap, job.trajectory, hardware=hw, distance=job.distance_m, foot_offsets=offsets,
                 run_up=job.run_up_s)
    e_cfg = job.cfg.energy
    ok = r.distance > 0 and r.electrical_energy > 0
    pct = en.battery_percent_used(r.electrical_energy, e_cfg)
    start_pct = 100.0 * e_cfg.usable_fraction
    return {
        "trajectory": job.trajectory_name, "seed": job.seed, "draw": job.draw, "speed_mps": job.speed,
        "robot": job.mode, "pd_scale": job.pd_scale, "pd_matched": job.pd_matched_from is not None, "fell": r.fell,
        "reached": r.reached, "mass_scale": r.mass_scale,
        "mass_kg": r.mass_kg,  # the payload's and the mass draw's body
        # one meaning in every row: the lift height of the foot path walked (a learned path's own); the trot a
        # commanded path shifts has its own, under its own name
        "lift_height_m": (math.nan if job.policy is not None  # a policy's own foot lift is not an input
                          else job.cfg.gait.lift_height if job.lift_height is None else job.lift_height),
        "trot_lift_height_m": job.cfg.gait.lift_height if job.foot_offsets is not None else None,
        "mean_speed_mps": r.mean_speed,  # last half of the walk
        "average_speed_mps": r.distance / r.duration if r.duration > 0 else float("nan"),
        "run_up_s": job.run_up_s, "distance_m": r.distance, "time_s": r.duration, "lateral_drift_m": r.lateral_drift,
        "energy_J": r.energy,  # Eq. (7)
        "electrical_energy_J": r.electrical_energy,
        "electrical_cost_of_transport": (en.cost_of_transport(r.electrical_energy, r.mass_kg,
                                                              job.cfg.sim.gravity, r.distance) if ok else float("nan")),
        "battery_start_pct": start_pct,  # E_f
        "battery_end_pct": en.remaining_percent(r.electrical_energy, e_cfg),  # E_n
        "battery_used_pct": en.power_consumption(start_pct, en.remaining_percent(r.electrical_energy, e_cfg)),
        "range_full_charge_m": en.range_from_percent(r.distance, pct, e_cfg) if ok else float("nan"),
        "peak_torque_Nm": r.peak_torque, "wall_s": time.perf_counter() - t0,
        # how much the body rocked: a gait that keeps its speed and one that falls into a rocking, slower orbit
        # differ here first (|roll| 0.05 against 0.25 rad)
        "max_roll_rad": r.max_roll, "max_pitch_rad": r.max_pitch,
        # the trot's speed loop: the mean stride it added (% of the command) and the share of the walk it ran at its
        # bound (ControllerConfig.max_speed_correction; a walk that needs more than the bound falls behind)
        "speed_loop_pct": 100.0 * r.speed_loop_share, "speed_loop_at_limit_pct": 100.0 * r.speed_loop_at_limit,
    }


def _check_picklable(name: str, trajectory) -> None:
    try:
        pickle.dumps(trajectory)
    except Exception as err:  # noqa: BLE001 - any pickling failure means the worker cannot receive it
        raise ValueError(f"trajectory {name!r} cannot be sent to a worker process ({err}); pass a "
                         "SampledTrajectory or a name in TRAJECTORY_NAMES") from None


def run_prototype(trajectories: dict | None = None,
                  speeds=PAPER_SPEEDS, distance_m: float = PROTOTYPE_DISTANCE_M, modes=MODES,
                  hardware: HardwareConfig = HARDWARE_LIKE, workers: int | None = None,
                  base_cfg: WalkConfig | None = None, lift_heights: dict | None = None, log=print,
                  every_walk: bool = True, learned: LearnedSet | None = None, draws: int = PROTOTYPE_DRAWS,
                  run_up_s: float = PROTOTYPE_RUN_UP_S, policies: dict | None = None, pd_scale: float = 1.0,
                  pd_matched: bool = False, own_trot: dict | None = None, skip_missing: bool = False,
                  pd_matched_from: PIDConfig | None = None) -> list[dict]:
    """Walk `distance_m` with every trajectory at every speed on the robots in `modes`; one row per walk. The
    defaults (distance, draws, run-up) are the prototype run's, `cyberdog.config.paper`'s, as `evaluate.py`'s.

    trajectories: name → FootTrajectory, or None for the trajectory of that name in TRAJECTORY_NAMES
        ("cycloid", "straight") or, for any other name, `base_cfg.gait`'s own. Default: cycloid and straight.
    learned: learned paths (a `LearnedSet`); per label, its path at each speed (the set's rule) walks first as
        "learned", then the named trajectories at that path's lift height (matched; rows carry the label as
        `seed`), unless `lift_heights` says otherwise.
    lift_heights: {speed: m}, the lift height of the named walks at that speed; default: the learned path's
        own, else `base_cfg.gait.lift_height`.
    draws: hardware-like robots per walk: `hardware` with seed `hardware.seed + d` for d < draws (its mass
        draw and sensor noise), the same robots for every trajectory; the ideal robot is walked once.
    modes: any of "ideal" (the Section 4.1 simulation) and "hardware" (`hardware`'s effects on).
    run_up_s: s walked from the stand before `distance_m` is measured (`walk(run_up=...)`): the start-up is left
        out, as of a range on a full charge, where it happens once in kilometres; 0 = the paper's walk from a stand.
    policies: {label of `learned`: actor file}: that seed's policy walks too, closed loop, as the row "policy"
        (same robots, PD, run-up and distance as its replayed path; its saving is against the same baselines).
    pd_scale: every walk with the joint PD this many times as stiff as `base_cfg.pid` (kp × s, kd × √s:
        `PIDConfig.stiffness_scaled`); rows carry it as `pd_scale`.
    pd_matched: at a `pd_scale` other than 1, every path and trajectory (not a policy) walks with its command
        re-solved for the scaled PD so that it executes the motion it executes under `base_cfg.pid`
        (`cyberdog.analysis.pd_match_recording`); rows carry `pd_matched` (True where a command was re-solved).
    own_trot: {trajectory name: ControllerConfig}, trajectories that walk under their own trot controller (a
        searched shape under the one it was searched under) instead of `base_cfg.controller`.
    pd_matched_from: the PD the paths and trajectories were made under, where `base_cfg.pid` is another (a
        user's gains): every walk but a policy's has its command re-solved from it to `base_cfg.pid`, as
        `pd_matched` does for a `pd_scale` (rows carry `pd_matched`); None: each walks its command as it is.
    skip_missing: a label of `learned` without a path at a speed (its extraction found none there) walks nothing
        at that speed, neither its path nor the common trajectories at its lift, so that speed's rows are over
        the labels that have one; every speed needs at least one. False: every label must have every speed.
    workers: processes (default: one per walk, at most the CPU count); 1 runs in this process.
    every_walk: a progress line per walk (False: one per quarter of them). Rows come back in (trajectory, speed,
    mode) order with the ideal-vs-hardware gaps filled in (`add_gaps`); the battery: the module docstring.
    """
    base_cfg = base_cfg or WalkConfig()
    trajectories = {"cycloid": None, "straight": None} if trajectories is None else dict(trajectories)
    speeds, modes, policies = _checked_inputs(trajectories, speeds, distance_m, modes, hardware, learned, draws,
                                              run_up_s, policies, skip_missing)
    base_cfg, own_pid = _walked_pd(base_cfg, pd_scale, pd_matched, pd_matched_from)
    robots = [(mode, d) for mode in modes for d in (range(draws) if mode == "hardware" else (0,))]
    jobs = _walk_jobs(trajectories, speeds, base_cfg, robots, hardware, float(distance_m), float(run_up_s), learned,
                      lift_heights, policies, pd_scale, own_pid, own_trot or {}, skip_missing)
    rows = map_in_processes(_run_job, jobs, workers, on_result=progress_log(len(jobs), _walk_line, log, every_walk),
                            describe=lambda j: f"{j.trajectory_name} at {j.speed:g} m/s, {j.mode}, {j.distance_m:g} m")
    return add_gaps(rows)


def _walked_pd(base_cfg: WalkConfig, pd_scale: float, pd_matched: bool,
               pd_matched_from: PIDConfig | None) -> tuple[WalkConfig, PIDConfig | None]:
    """`base_cfg` with its PD scaled by `pd_scale`, and the PD the walks' commands are re-solved from (None: each
    walks its command as it is): `run_prototype`'s `pd_matched` and `pd_matched_from`."""
    if pd_matched_from is not None and (pd_matched or pd_scale != 1.0):
        raise ValueError("pd_matched_from re-commands for base_cfg.pid itself: give it with pd_scale 1 and no "
                         "pd_matched")
    own_pid = base_cfg.pid if pd_matched and pd_scale != 1.0 else None  # the PD the paths were made under
    if pd_matched_from is not None and pd_matched_from != base_cfg.pid:
        own_pid = pd_matched_from
    return dataclasses.replace(base_cfg, pid=base_cfg.pid.stiffness_scaled(pd_scale)), own_pid


def _walk_line(row: dict) -> str:
    """One walk's progress line."""
    return (f"{row['trajectory']:10s} {row['speed_mps']:.1f} m/s {row['robot']:8s} {row['distance_m']:6.1f} m "
            f"in {row['time_s']:6.1f} s  E={row['energy_J'] / 1e3:6.2f} kJ  "
            f"E_el={row['electrical_energy_J'] / 1e3:6.2f} kJ  battery {row['battery_used_pct']:.2f} %  "
            f"fell={row['fell']}")


def _walk_jobs(trajectories: dict, speeds, base_cfg: WalkConfig, robots: list, hardware: HardwareConfig,
               distance_m: float, run_up_s: float, learned, lift_heights, policies: dict, pd_scale: float,
               own_pid, own_trot: dict, skip_missing: bool = False) -> list[_Job]:
    """`run_prototype`'s walks, per learned label: its paths (and policy) on every robot, then the trajectories
    (with `skip_missing`, only at the speeds the label has a path at)."""
    jobs = []
    for label in learned.labels if learned is not None else [""]:
        paths = ({v: learned.path(label, v) for v in speeds if not skip_missing or learned.has(label, v)}
                 if learned is not None else {})
        lifts = dict(lift_heights) if lift_heights is not None else {v: p.lift_height for v, p in paths.items()}
        for v, path in paths.items():
            cfg, foot_trajectory, offsets = path.walk_args(base_cfg, v)
            jobs += [_Job("learned", foot_trajectory, v, mode, cfg, _draw(hardware, d), distance_m, offsets, label, d,
                          run_up_s, float(path.lift_height), pd_scale=pd_scale, pd_matched_from=own_pid)
                     for mode, d in robots]
            if label in policies:
                jobs += [_Job(POLICY, None, v, mode, cfg, _draw(hardware, d), distance_m, None, label, d, run_up_s,
                              policy=str(policies[label]), pd_scale=pd_scale) for mode, d in robots]
        for name, traj in trajectories.items():
            for v in (speeds if learned is None else paths):
                cfg = _job_config(base_cfg, name, traj, v)
                if name in own_trot:
                    cfg = dataclasses.replace(cfg, controller=own_trot[name])
                if v in lifts:
                    cfg = dataclasses.replace(cfg, gait=dataclasses.replace(cfg.gait, lift_height=float(lifts[v])))
                jobs += [_Job(name, traj, v, mode, cfg, _draw(hardware, d), distance_m, None, label, d, run_up_s,
                              pd_scale=pd_scale, pd_matched_from=own_pid) for mode, d in robots]
    return jobs


def _draw(hardware: HardwareConfig, d: int) -> HardwareConfig:
    """The hardware-like robot of draw d: its own mass draw and sensor noise (seed + d)."""
    return hardware if d == 0 else dataclasses.replace(hardware, seed=hardware.seed + d)


def _checked_inputs(trajectories: dict, speeds, distance_m: float, modes, hardware, learned, draws: int,
                    run_up_s: float, policies: dict | None, skip_missing: bool = False
                    ) -> tuple[tuple[float, ...], tuple[str, ...], dict]:
    """(speeds, modes) as tuples and the policies as a dict, after checking every argument of `run_prototype`."""
    if not trajectories and learned is None:
        raise ValueError("trajectories must name at least one trajectory")
    speeds = tuple(float(v) for v in speeds)
    if not speeds or not all(math.isfinite(v) and v > 0 for v in speeds):
        raise ValueError(f"speeds must be one or more finite speeds > 0 m/s, got {speeds!r}")
    if not (math.isfinite(distance_m) and distance_m > 0):
        raise ValueError(f"distance_m must be > 0 and finite, got {distance_m!r}")
    modes = tuple(modes)
    if not modes or any(m not in MODES for m in modes) or len(set(modes)) != len(modes):
        raise ValueError(f"modes must be distinct values of {MODES}, got {modes!r}")
    if not isinstance(hardware, HardwareConfig):
        raise TypeError(f"hardware must be a HardwareConfig, got {type(hardware).__name__}")
    if not (isinstance(draws, int) and draws >= 1):
        raise ValueError(f"draws must be an integer >= 1, got {draws!r}")
    if learned is not None:
        if not isinstance(learned, LearnedSet) or not learned:
            raise ValueError(f"learned must be a non-empty LearnedSet, got {learned!r}")
        for v in speeds:
            if not skip_missing:
                learned.at(v)  # LearnedSetError now, before any walk, if a speed has no path
            elif not any(learned.has(label, v) for label in learned.labels):
                raise LearnedSetError(f"no learned path at {v:g} m/s (skip_missing needs one label with a path)")
    for name, traj in trajectories.items():
        if traj is not None and not isinstance(traj, FootTrajectory):
            raise TypeError(f"trajectory {name!r} must be a FootTrajectory or None, got {type(traj).__name__}")
        _check_picklable(name, traj)
    if not (math.isfinite(run_up_s) and run_up_s >= 0):
        raise ValueError(f"run_up_s must be >= 0 s and finite, got {run_up_s!r}")
    unknown = [label for label in policies or {} if learned is None or label not in learned.labels]
    if unknown:
        raise ValueError(f"policies {unknown} have no learned path of the same label (labels: "
                         f"{list(learned.labels) if learned is not None else []})")
    return speeds, modes, dict(policies or {})


def prototype_table(rows: list[dict], energy_cfg=None) -> str:
    """Markdown: per robot the summary across seeds and draws, then the walks and the ideal-vs-hardware gaps,
    with the battery assumption stated."""
    e = energy_cfg or WalkConfig().energy
    note = (f"Battery (ASSUMPTION [G]): {e.battery_capacity_wh:.1f} Wh pack charged to {e.battery_voltage:g} V "
            f"(paper), walks start at E_f = {100 * e.usable_fraction:g} % (paper, Eq. 13), driver efficiency "
            f"{e.driver_efficiency:g} [G], electronics {e.idle_power:g} W. battery_used_pct = E_f − E_n (Eq. 13); "
            f"range_full_charge_m = distance × {100 * e.usable_fraction:g} / battery_used_pct. Paper at 1 m/s: "
            f"{PAPER_RANGE_1MPS_M['cycloid']:.0f} m (cycloid), {PAPER_RANGE_1MPS_M['learned']:.0f} m (learned); "
            f"sim-to-real gap {PAPER_SIM_TO_REAL_GAP_PP:g} percentage points.")
    shown = [{**r, "energy_kJ": r["energy_J"] / 1e3, "electrical_energy_kJ": r["electrical_energy_J"] / 1e3}
             for r in rows]
    summary = summary_rows(rows)
    parts = [f"{title}\n\n{summary_markdown(summary, robot)}\n" for robot, title in (
        ("hardware", "The hardware-like robot (mean ± 95 % CI across seeds; a seed's value is the mean of its draws)"),
        ("ideal", "The ideal robot (Section 4.1's simulation)")) if any(r["robot"] == robot for r in summary)]
    parts += ["Every walk", "", markdown_table(shown, [c for c in TABLE_COLUMNS if c in shown[0]] if shown else None),
              "", note]
    gaps = gap_rows(rows)
    if gaps:
        parts += ["", markdown_table(gaps)]
    return "\n".join(parts)


def write_prototype(rows: list[dict], folder: str | Path) -> None:
    """`prototype.{csv,json,md}` (the walks; the Markdown with every table), `prototype_summary.{csv,json,md}`
    (across seeds and draws) and `prototype_gaps.{csv,json,md}`."""
    folder = Path(folder)
    write_rows(rows, folder, "prototype")
    write_rows(summary_rows(rows), folder, "prototype_summary")
    write_rows(gap_rows(rows), folder, "prototype_gaps")
    (folder / "prototype.md").write_text(prototype_table(rows) + "\n")
