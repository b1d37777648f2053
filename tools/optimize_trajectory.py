#!/usr/bin/env python
"""Optimise the foot path's SHAPE for energy at a fixed lift height and gait timing, then replay it.

    python tools/optimize_trajectory.py --lift-height 0.10 --max-evals 100 --workers 2
    python tools/optimize_trajectory.py --lift-height 0.085 --objective electrical --robot hardware   # battery
    python tools/optimize_trajectory.py --lift-height 0.085 --objective electrical --robot hardware --gains 1:1 0.5:1 1:2

Beyond the paper (`cyberdog.core.path_shape`, the search in `cyberdog.analysis.shape_search`): a
5-parameter periodic foot path (swing x timing law and skew, apex timing and fullness with the apex exactly at
H, stance timing law), started from the composite cycloid and improved with bounded Nelder–Mead on the mean
energy (Eq. 7, or with `--objective electrical` what the battery pays) of `--duration`-s walks (measured from
`--measure-from` s on) at each of `--speeds`, with the same simulator and IK + PID trot as Table 5, on the
ideal robot or with `--robot hardware` the prototype run's hardware-like one. Falls and speed misses beyond
5 % are penalised.

Then the optimised path, the start point replayed through the same spline ("cycloid (sampled)", a control
for the spline's rounding), the composite cycloid and the straight line (rectangle) walk `--replay-duration`
s (Table 5's 10 s) at each speed at the same H; printed table: E (J), energy per 100 m, mean speed, fell,
status, D_t by Eq. (12) against the cheaper valid baseline (cycloid, straight) and against the cycloid.

Writes the optimised path to --result (default results/searched_shapes/optimized_trajectory_H<H>.json; SampledTrajectory
JSON with provenance: parameters, objective, H, speeds, evaluations, git commit) and into --out (default
runs/optimize-<time>/): optimized_trajectory.json, history.csv (every evaluation), table.{md,csv},
summary.json. `--replay-only FILE` skips the optimisation and replays a saved path.

`--gains KP:KD ...` walks each shape at each speed under each of these (kp, kd) factors of the joint PD (the gains a
user may set; the drivers step at the physics rate each needs), and the objective is the mean over them all: the
shape cheapest over those gains, not at the default alone (the file's name ends in `_gains`).

`--foot-inset D` searches the shape with every foot D m nearer the body's midline (a stance width; the file carries
it, and whatever walks the shape walks it so; the name ends in `_inset<mm>`); the replay's common paths keep theirs.

`--set SECTION.FIELD=VALUE` changes the walk config of every walk, search and replay alike (e.g. the trot with
sagittal foot placement, `--set controller.sagittal_placement_gain=0.1`, so that the shape is searched under the
trot the learned paths it is compared with walk under); the overrides are recorded in the path's provenance, and
with any the path is written only into --out unless --result names a file.
"""
from __future__ import annotations

import argparse
import csv
import json
import math
import sys
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))  # run as a script from anywhere

from cyberdog.core import path_shape as so  # noqa: E402
from cyberdog.analysis import shape_search  # noqa: E402
from cyberdog.analysis.compare import WalkJob, reduction, run_jobs, walk_config  # noqa: E402
from cyberdog.analysis.report import json_safe  # noqa: E402
from cyberdog.config import HARDWARE_LIKE, GaitConfig, WalkConfig, add_override_option, override  # noqa: E402
from cyberdog.core.trajectories import SampledTrajectory  # noqa: E402
from cyberdog.provenance import code_state, portable_command, portable_path  # noqa: E402

TABLE_COLUMNS = ["speed_command_mps", "trajectory", "energy_J", "energy_per_100m_kJ", "mean_speed_mps", "fell",
                 "status", "D_t_pct", "E_min_trajectory", "D_t_vs_cycloid_pct", "electrical_energy_J",
                 "D_el_vs_cycloid_pct", "peak_torque_Nm"]
BASELINE_LABELS = ("cycloid", "straight")  # Eq. (12)'s E_s: the cheaper valid one of these at each speed


def parse_args(argv=None) -> argparse.Namespace:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--lift-height", type=float, default=0.10, help="m, fixed lift height H (default 0.10)")
    p.add_argument("--speeds", type=float, nargs="+", default=list(shape_search.PAPER_SPEEDS), help="m/s (default 1.0 1.2 1.4)")
    p.add_argument("--duration", type=float, default=6.0, help="s, each optimisation walk (default 6)")
    p.add_argument("--measure-from", type=float, default=2.0,
                   help="s, energy integrated from here on (skips the 1 s start-up ramp; default 2)")
    p.add_argument("--max-evals", type=int, default=100, help="objective evaluations (default 100)")
    p.add_argument("--objective", choices=shape_search.OBJECTIVES, default="eq7",
                   help="what a walk's energy counts: eq7, the paper's Σ∫|τ·ω|dt, or electrical, what the battery "
                        "pays (default eq7)")
    p.add_argument("--robot", choices=("ideal", "hardware"), default="ideal",
                   help="the robot of the optimisation walks: ideal, or hardware, the prototype run's "
                        "hardware-like robot (HARDWARE_LIKE: friction, latency, sensor noise, Kalman speed, its "
                        "seeded mass draw); the replay table stays on the ideal robot (default ideal)")
    p.add_argument("--gains", type=gain_pair, nargs="+", default=None, metavar="KP:KD",
                   help="the joint PD's kp and kd factors each shape walks under, at each speed: the objective is "
                        "the mean over speeds and gains (e.g. 1:1 0.5:1 1:2, the default gains and the two that cost "
                        "the searched shape most; default 1:1 alone)")
    p.add_argument("--foot-inset", type=float, default=0.0, metavar="M",
                   help="m, every foot this much nearer the body's midline in the search (default 0: below the hips)")
    p.add_argument("--workers", type=int, default=2, help="parallel walk processes (default 2)")
    p.add_argument("--initial-step", type=float, default=0.2,
                   help="initial Nelder–Mead simplex size, share of each parameter's range (default 0.2)")
    p.add_argument("--replay-duration", type=float, default=10.0, help="s, the final comparison walks (default 10)")
    p.add_argument("--out", type=Path, default=None, help="run folder (default runs/optimize-<time>/)")
    p.add_argument("--result", type=Path, default=None,
                   help="optimised path file (default results/searched_shapes/optimized_trajectory_H<H>.json; with another "
                        "--objective or --robot, results/searched_shapes/optimized_trajectory_H<H>_<objective>_<robot>.json)")
    p.add_argument("--replay-only", type=Path, default=None, metavar="FILE",
                   help="skip the optimisation; replay this saved path (its provenance's H must match)")
    add_override_option(p, "controller.sagittal_placement_gain=0.1",
                        "; every walk, search and replay, under it; recorded in the path's provenance")
    args = p.parse_args(argv)
    # every check before any long work starts
    if args.gains is not None and args.replay_only is not None:
        p.error("--gains sets the search's walks; --replay-only runs no search (the replay walks the default gains)")
    if args.foot_inset and args.replay_only is not None:
        p.error("--foot-inset sets the search's walks; --replay-only walks the file's own (its foot_inset_m)")
    if not (math.isfinite(args.foot_inset) and abs(args.foot_inset) < 0.1):
        p.error(f"--foot-inset must be within ±0.1 m, got {args.foot_inset}")
    try:
        shape_search.check_objective_args(args.lift_height, args.speeds, args.duration, args.measure_from,
                                          gains=args.gains or shape_search.DEFAULT_GAINS)
    except ValueError as err:
        p.error(str(err))
    if args.max_evals < 2:
        p.error(f"--max-evals must be >= 2, got {args.max_evals}")
    if args.workers < 1:
        p.error(f"--workers must be >= 1, got {args.workers}")
    if not 0 < args.initial_step <= 0.5:
        p.error(f"--initial-step must be in (0, 0.5], got {args.initial_step}")
    if not (math.isfinite(args.replay_duration) and args.replay_duration > 0):
        p.error(f"--replay-duration must be > 0 s, got {args.replay_duration}")
    if args.replay_only is not None and not args.replay_only.is_file():
        p.error(f"--replay-only file {str(args.replay_only)!r} does not exist")
    try:
        args.base = override(WalkConfig(), args.overrides)
    except ValueError as err:
        p.error(str(err))
    args.out = args.out or REPO / "runs" / time.strftime("optimize-%Y%m%d-%H%M%S")
    if args.overrides and args.result is None:  # a search under another walk config never replaces a shipped path
        args.result = args.out / "optimized_trajectory.json"
    name = (f"optimized_trajectory_H{args.lift_height:.2f}" if (args.objective, args.robot) == ("eq7", "ideal")
            else f"optimized_trajectory_H{args.lift_height:.3f}_{args.objective}_{args.robot}")
    name += "_gains" if args.gains else ""
    name += f"_inset{1e3 * args.foot_inset:.0f}" if args.foot_inset else ""
    args.result = args.result or REPO / "results" / "searched_shapes" / f"{name}.json"
    return args


def gain_pair(text: str) -> tuple[float, float]:
    """"0.5:1" → (0.5, 1.0): the joint PD's kp and kd factors (`--gains`)."""
    kp, sep, kd = text.partition(":")
    try:
        if not sep:
            raise ValueError
        return float(kp), float(kd)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected KP:KD factors such as 0.5:1, got {text!r}") from None


def write_csv(path: Path, rows: list[dict]) -> None:
    keys = list(dict.fromkeys(k for r in rows for k in r))
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=keys)
        w.writeheader()
        w.writerows(rows)


def replay_rows(optimized: SampledTrajectory, start: SampledTrajectory, lift_height: float, speeds, duration: float,
                workers: int, base: WalkConfig | None = None) -> list[dict]:
    """The optimised path, the sampled start, the cycloid and the straight line at every speed, each walked
    with `base` (default WalkConfig()) at that speed and H; D_t columns."""
    base = base or WalkConfig()
    jobs = []
    for v in speeds:
        for name, path in (("optimized", optimized), ("cycloid (sampled)", start), ("cycloid", None),
                           ("straight", None)):
            jobs.append(WalkJob(len(jobs), name, "", float(v), lift_height, walk_config(base, name, v, lift_height),
                                duration, path))
    walks = run_jobs(jobs, workers=workers)
    rows = []
    for v in speeds:
        group = [w for w in walks if w["speed_command_mps"] == float(v)]
        valid_base = [w for w in group if w["trajectory"] in BASELINE_LABELS and w["valid"]]
        cheap = min(valid_base, key=lambda w: w["energy_J"]) if valid_base else None
        cyc = next((w for w in group if w["trajectory"] == "cycloid" and w["valid"]), None)
        for w in group:
            mine = w["trajectory"] not in BASELINE_LABELS and w["valid"]
            rows.append({
                "speed_command_mps": w["speed_command_mps"], "trajectory": w["label"], "energy_J": w["energy_J"],
                "energy_per_100m_kJ": w["energy_per_100m_kJ"], "mean_speed_mps": w["mean_speed_mps"],
                "fell": w["fell"], "status": w["status"],
                # Eq. (12) with E_s the cheaper valid baseline: positive = the path saves energy
                "D_t_pct": reduction(cheap["energy_J"], w["energy_J"]) if mine and cheap else float("nan"),
                "E_min_trajectory": cheap["label"] if mine and cheap else "",
                "D_t_vs_cycloid_pct": reduction(cyc["energy_J"], w["energy_J"]) if mine and cyc else float("nan"),
                # a check beyond Eq. (7): the electrical model (copper loss, driver efficiency, braking work not
                # recovered nor charged) weighs the path differently; peak torque shows the clip is reached
                "electrical_energy_J": w["electrical_energy_J"],
                "D_el_vs_cycloid_pct": (reduction(cyc["electrical_energy_J"], w["electrical_energy_J"])
                                        if mine and cyc else float("nan")),
                "peak_torque_Nm": w["peak_torque_Nm"],
            })
    return rows


def _fmt(x, spec: str) -> str:
    return "—" if isinstance(x, float) and not math.isfinite(x) else format(x, spec)


def table_markdown(rows: list[dict], lift_height: float, duration: float) -> str:
    lines = [f"Foot-path shapes at H = {lift_height:.3f} m, {duration:g} s walks (Eq. 7 energy); D_t by Eq. (12) "
             "against the cheaper valid baseline (cycloid, straight) and against the cycloid; + = saves energy.",
             "E_el: the electrical model of cyberdog.core.energy (copper loss, 95 % driver, no regeneration); "
             "D_el: Eq. (12) on E_el against the cycloid.",
             "", "| v (m/s) | trajectory | E (J) | E per 100 m (kJ) | mean speed (m/s) | fell | status | D_t (%) "
             "| vs | D_t vs cycloid (%) | E_el (J) | D_el vs cycloid (%) | peak τ (N·m) |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['speed_command_mps']:.1f} | {r['trajectory']} | {r['energy_J']:.1f} | "
                     f"{_fmt(r['energy_per_100m_kJ'], '.3f')} | {r['mean_speed_mps']:.3f} | {r['fell']} | "
                     f"{r['status']} | {_fmt(r['D_t_pct'], '+.2f')} | {r['E_min_trajectory']} | "
                     f"{_fmt(r['D_t_vs_cycloid_pct'], '+.2f')} | {r['electrical_energy_J']:.0f} | "
                     f"{_fmt(r['D_el_vs_cycloid_pct'], '+.2f')} | {r['peak_torque_Nm']:.1f} |")
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    args = parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    gait = GaitConfig(speed=args.speeds[0], lift_height=args.lift_height)
    command = "python tools/optimize_trajectory.py " + portable_command(sys.argv[1:] if argv is None else argv)
    summary: dict = {"command": command, "lift_height_m": args.lift_height, "speeds_mps": args.speeds, **code_state(),
                     "walk_overrides": list(args.overrides)}
    if args.replay_only is not None:
        optimized = SampledTrajectory.load(args.replay_only)
        h = optimized.provenance.get("lift_height_m", optimized.lift_height)
        if abs(h - args.lift_height) > 1e-6:
            sys.exit(f"{args.replay_only} was optimised at H = {h} m, not --lift-height {args.lift_height} m")
        summary.update({"replayed_file": portable_path(args.replay_only), "replayed_provenance": optimized.provenance})
    else:
        print(f"optimising the foot-path shape at H = {args.lift_height} m, speeds {args.speeds} m/s, "
              f"{args.duration} s walks measured from {args.measure_from} s, ≤ {args.max_evals} evaluations, "
              f"{args.workers} worker(s) → {args.out}")
        res = shape_search.optimize_shape(args.lift_height, args.speeds, args.duration, args.measure_from, args.max_evals,
                                args.workers, initial_step=args.initial_step, objective=args.objective,
                                hardware=HARDWARE_LIKE if args.robot == "hardware" else None, base=args.base,
                                gains=args.gains or shape_search.DEFAULT_GAINS, foot_inset=args.foot_inset)
        write_csv(args.out / "history.csv", [e.row() for e in res.history])
        cpu_s = sum(w["cpu_s"] for e in res.history for w in e.walks)
        print(f"done: {len(res.history)} evaluations in {res.wall_s:.0f} s wall ({cpu_s:.0f} s CPU in walks); "
              f"best objective {res.best.objective_J:.1f} J vs start (cycloid) {res.start.objective_J:.1f} J "
              f"({res.saving_pct:+.2f} % saved); {res.message}")
        print("best parameters: " + ", ".join(f"{k}={v:+.4f}" for k, v in res.best.params.as_dict().items()))
        summary.update({
            "objective": (f"mean over speeds{' and the joint PD gains' if args.gains else ''} of "
                          f"{'Eq. (7)' if args.objective == 'eq7' else 'electrical'} energy, J, "
                          f"of a {args.duration} s walk from {args.measure_from} s on, {args.robot} robot; falls and "
                          ">5 % speed misses penalised"),
            "energy_objective": args.objective, "robot": args.robot,
            "pd_gain_factors": [list(g) for g in args.gains or shape_search.DEFAULT_GAINS],  # (kp, kd) ×
            "optimizer": "scipy Nelder-Mead, bounded, unit coordinates, started from the composite cycloid",
            "shape_params": res.best.params.as_dict(), "objective_J": res.best.objective_J,
            "start_objective_J": res.start.objective_J, "objective_saving_pct": res.saving_pct,
            "per_speed_window_energy_J": {shape_search.walk_key(w): w["energy_window_J"] for w in res.best.walks},
            "evaluations": len(res.history), "best_eval": res.best.index, "optimize_wall_s": res.wall_s,
            "optimize_walk_cpu_s": cpu_s, "duration_s": args.duration, "measure_from_s": args.measure_from,
            "optimizer_message": res.message, **({"foot_inset_m": args.foot_inset} if args.foot_inset else {})})
        optimized = so.shape_trajectory(res.best.params, gait, provenance={
            "name": "optimized", "lift_height_m": args.lift_height,
            **{k: v for k, v in summary.items() if k not in ("lift_height_m",)}}, foot_inset=args.foot_inset)
        for path in (args.result, args.out / "optimized_trajectory.json"):
            optimized.save(path)
        print(f"wrote {args.result}")
    if "shape_params" not in optimized.provenance:
        sys.exit(f"{args.replay_only} has no shape_params in its provenance: not written by this tool")
    params = so.ShapeParams(**optimized.provenance["shape_params"])
    start = so.shape_trajectory(so.CYCLOID_PARAMS, gait, provenance={"name": "cycloid (sampled)"})
    if params == so.CYCLOID_PARAMS:
        print("the optimum is the start point (the cycloid)")
    print(f"replaying optimized, cycloid (sampled), cycloid, straight at H = {args.lift_height} m for "
          f"{args.replay_duration} s at {args.speeds} m/s")
    rows = replay_rows(optimized, start, args.lift_height, args.speeds, args.replay_duration, args.workers, args.base)
    md = table_markdown(rows, args.lift_height, args.replay_duration)
    print("\n" + md)
    (args.out / "table.md").write_text(md)
    write_csv(args.out / "table.csv", rows)
    summary["replay"] = [{k: r[k] for k in TABLE_COLUMNS} for r in rows]
    summary["replay_duration_s"] = args.replay_duration
    summary["total_wall_s"] = time.perf_counter() - t0
    (args.out / "summary.json").write_text(json.dumps(summary, indent=1, default=float))
    if args.replay_only is None:  # the shipped file also carries the 10 s comparison it was judged by
        opt = [r for r in rows if r["trajectory"] == "optimized"]
        # nan (an invalid walk) → null: strict JSON
        for key in ("D_t_vs_cycloid_pct", "D_t_pct", "energy_J", "D_el_vs_cycloid_pct"):
            optimized.provenance[f"replay_{key}"] = {f"{r['speed_command_mps']:.2f}": json_safe(float(r[key]))
                                                     for r in opt}
        optimized.provenance["replay_duration_s"] = args.replay_duration
        for path in (args.result, args.out / "optimized_trajectory.json"):
            optimized.save(path)
    print(f"wrote {args.out}/table.md, table.csv, summary.json"
          + ("" if args.replay_only else ", history.csv, optimized_trajectory.json")
          + f"; total {summary['total_wall_s']:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
