#!/usr/bin/env python3
"""Evaluate foot trajectories on the simulated CyberDog (paper Sections 3 and 4).

Sub-commands (default: all):
  all         compare + prototype + figures (+ a video with --video), on the learned trajectories
              (default results/learned/: one commanded path per seed and speed; --learned FILE|DIR..., or
              --policies/--sweep to extract first)
  baselines   walk 10 s at 1.0, 1.2 and 1.4 m/s with the composite cycloid and straight-line trajectories and
              print speed, drift, posture, energy (Eq. 7), energy per 100 m, CoT, peak torque and speed
  extract     roll out trained stage-2 policies (--policy/--policies PATH, --sweep DIR) at each speed (a policy
              trained over a speed range: each of --speeds) and save the learned path (learned/<label>_<v>mps.json)
              and every cycle (learned/<label>_<v>mps_cycles.csv): the commanded foot path (trot path + the
              policy's per-leg shift, mean of the settled cycles within ±5 % of the command) for foot-mode
              policies, or with --path measured the paper's way (the measured foot path of the cheapest cycle)
  compare     Section 4.1: replay the learned, cycloid and straight-line trajectories with the IK + PID trot for
              --duration s at each speed; Table 5 (the headline: baselines at the learned path's own lift
              height; and the paper's protocol: baselines at 0.15 m), D_t by Eq. (12) on Eq. (7) and on the
              electrical energy, positive work and foot slip; Figures 10 and 13
  prototype   Section 4.2 in simulation: walks of --prototype-distance m (default 20; the paper's 100) on the
              ideal and a hardware-like robot, battery use (Eq. 13), range, sim-to-real gap
  figures     Figures 4, 6, 7, 10, 13 from saved results (--from DIR: a folder written by `all` or `compare`)
  video       a GIF (or MP4) of the trot with one trajectory (--video-trajectory, --video-speed)

Outputs go to --out (default runs/evaluate-<time>/), never over inputs; a folder that already holds results is
refused unless --force (which first removes the files earlier runs recorded in its outputs.json); every file this
run writes is listed at the end and recorded in outputs.json:
  table5.md                     Table 5: matched-lift and paper-protocol summaries (mean ± 95 % CI over seeds),
                                then every walk
  table5_summary.{csv,json}     the summaries, machine-readable
  table5.{csv,json}             every walk's E (kJ) and D_t by Eq. 12, both sets
  comparison.{md,csv,json}      every walk: E, energy per 100 m, CoT, mean speed, status, D_t (also per 100 m)
  learned_mean_ci.*             across seeds: mean and 95 % CI of E and D_t (with several learned trajectories)
  walks.json, power_traces.npz  per walk metadata and total joint power Σ|τ·θ̇| at the physics rate (Figure 10)
  prototype.{md,csv,json}, prototype_gaps.*   the prototype experiment
  figure{4,6,7,10,13}_*.{png,pdf}             the paper's figures
  learned/<label>.json          the learned trajectories used (extracted ones with <label>_cycles.*)
"""
from __future__ import annotations

import argparse
import json
import math
import sys
import time
from pathlib import Path

import numpy as np

from cyberdog import config as C
from cyberdog.analysis import compare as cmp
from cyberdog.analysis import figures as figs
from cyberdog.analysis.baselines import BASELINES, PAPER_SPEEDS, baseline_rows
from cyberdog.analysis import table5 as t5
from cyberdog.analysis.extract import (CYCLE_CHOICES, SPEED_TOLERANCE, ExtractionError, commanded_from_rollout,
                                       cycle_rows, extract_from_rollout)
from cyberdog.analysis.report import markdown_table, write_rows
from cyberdog.core.commanded_path import CommandedPath, load_foot_path
from cyberdog.core.trajectories import SampledTrajectory
from cyberdog.output_folder import OutputFolder, OutputFolderError

BASELINE_COLUMNS = ["trajectory", "speed_command_mps", "mean_speed_mps", "lateral_drift_m", "height_min_m",
                    "height_max_m", "max_roll_rad", "max_pitch_rad", "fell", "energy_J", "energy_per_100m_kJ",
                    "cost_of_transport", "peak_torque_Nm", "peak_joint_speed_radps"]
COMMANDS = ("all", "baselines", "extract", "compare", "prototype", "figures", "video")
ROOT = Path(__file__).resolve().parent
DEFAULT_LEARNED = ROOT / "results" / "learned"  # the shipped learned paths: one JSON per seed and speed
DEFAULT_METRICS = ROOT / "results" / "policy_speeds" / "metrics.csv"  # the shipped policy's training log
DEFAULT_PROTOTYPE_DISTANCE = 20.0  # m per prototype walk in the default run (paper: 100 m, `--prototype-distance 100`)
# preference order: the shipped name, then the actor at the end of stage 2 (fixed in advance), then the one of
# its best-scoring episode (chosen on a noisy score)
STAGE2_ACTORS = ("stage2_actor.pt", "stage2_final_actor.pt", "stage2_best_actor.pt")


class UsageError(Exception):
    """Bad or missing input, reported before any long work starts."""


def parse_args(argv=None):
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("command", nargs="?", default="all", choices=COMMANDS, help="which part to run (default: all)")
    g = p.add_argument_group("walks")
    g.add_argument("--config", type=Path, default=None,
                   help="YAML walk config (WalkConfig sections: robot, actuator, sim, gait, pid, controller, "
                        "energy); default: the built-in defaults (paper lift height 0.15 m)")
    g.add_argument("--set", nargs="*", default=[], metavar="SECTION.FIELD=VALUE",
                   help="config overrides, e.g. gait.lift_height=0.1 gait.straight_shape=trapezoid")
    g.add_argument("--speeds", type=float, nargs="+", default=list(PAPER_SPEEDS), help="m/s (default 1.0 1.2 1.4)")
    g.add_argument("--trajectories", nargs="+", default=list(BASELINES), choices=list(BASELINES),
                   help="baselines: which common trajectories to walk")
    g.add_argument("--duration", type=float, default=10.0, help="s per comparison walk (default 10, the paper's)")
    g.add_argument("--workers", type=int, default=None, help="parallel walk processes (default: CPU count)")
    g.add_argument("--no-same-lift", action="store_true",
                   help="compare: skip the control set of baselines at the learned trajectory's lift height")
    g.add_argument("--out", type=Path, default=None, help="output folder (default runs/evaluate-<time>)")
    g.add_argument("--force", action="store_true",
                   help="write into an --out folder that already holds results: the files earlier evaluate.py runs "
                        "recorded there (outputs.json) are removed first; without --force such a folder is refused")
    g = p.add_argument_group("learned trajectory")
    g.add_argument("--learned", type=Path, nargs="+", default=None, metavar="FILE",
                   help="extracted trajectories (JSON/CSV files, or folders of JSON files): commanded paths (one "
                        "per seed and speed) or sampled x-z paths (one per seed, rescaled to every speed); "
                        f"default {DEFAULT_LEARNED}/")
    g.add_argument("--policies", "--policy", dest="policies", type=Path, nargs="+", default=None, metavar="PATH",
                   help="stage-2 actor files or training run folders: extract their trajectories first")
    g.add_argument("--sweep", type=Path, default=None, metavar="DIR",
                   help="a folder of training runs (one per seed): extract each run's trajectory first")
    g.add_argument("--policy-speed", type=float, default=None,
                   help="m/s commanded in the extraction rollout (default: each of --speeds for a policy trained "
                        "over a speed range, else the policy's training speed)")
    g.add_argument("--path", dest="path_kind", default="auto", choices=("auto", "commanded", "measured"),
                   help="extraction: 'commanded' (the foot targets the policy commanded: trot path + its per-leg "
                        "shift), 'measured' (the paper's: forward kinematics of the joint angles, one leg), or "
                        "'auto' (default): commanded for foot-mode policies, else measured")
    g.add_argument("--cycle", default="mean", choices=CYCLE_CHOICES,
                   help="commanded extraction: average the settled in-band cycles (default) or take the cheapest")
    g.add_argument("--rollout-duration", type=float, default=10.0, help="s of each extraction rollout")
    g.add_argument("--rollout-seed", type=int, default=0, help="env seed of the extraction rollout")
    g.add_argument("--speed-tolerance", type=float, default=SPEED_TOLERANCE,
                   help="extraction: cycles within this share of the command qualify (default 0.05)")
    g.add_argument("--leg", default="LF", choices=C.LEG_NAMES, help="extraction: the reference foot")
    g = p.add_argument_group("prototype experiment (Section 4.2)")
    g.add_argument("--prototype-distance", type=float, default=DEFAULT_PROTOTYPE_DISTANCE,
                   help=f"m per walk (default {DEFAULT_PROTOTYPE_DISTANCE:g}, so that the default run stays under "
                        "5 min on 2 cores; the paper's is 100: about 5x the prototype's time). Battery use and "
                        "range are also reported per 100 m")
    g.add_argument("--prototype-modes", nargs="+", default=["ideal", "hardware"], choices=["ideal", "hardware"])
    g.add_argument("--no-prototype", action="store_true", help="all: skip the prototype experiment")
    g = p.add_argument_group("figures")
    g.add_argument("--metrics", type=Path, nargs="+", default=None, metavar="CSV",
                   help=f"training logs for Figure 6 (default: the policies' metrics.csv, else {DEFAULT_METRICS})")
    g.add_argument("--from", dest="from_dir", type=Path, default=None, metavar="DIR",
                   help="figures: the results folder to draw from (default: --out)")
    g = p.add_argument_group("video")
    g.add_argument("--video", action="store_true", help="all: also write a video")
    g.add_argument("--video-trajectory", default="learned", choices=["learned", "cycloid", "straight"])
    g.add_argument("--video-speed", type=float, default=1.0, help="m/s")
    g.add_argument("--video-duration", type=float, default=4.0, help="s of simulated walking")
    g.add_argument("--video-format", default="gif", choices=["gif", "mp4"])
    args = p.parse_args(argv)
    if any(not (math.isfinite(v) and v > 0) for v in args.speeds) and args.command != "baselines":
        p.error(f"--speeds must be > 0 m/s, got {args.speeds}")
    if any(v < 0 for v in args.speeds):
        p.error(f"--speeds must be >= 0 m/s, got {args.speeds}")
    for name in ("duration", "rollout_duration", "prototype_distance", "video_duration", "video_speed"):
        if not getattr(args, name) > 0:
            p.error(f"--{name.replace('_', '-')} must be > 0, got {getattr(args, name)}")
    if args.policy_speed is not None and not args.policy_speed > 0:
        p.error(f"--policy-speed must be > 0 m/s, got {args.policy_speed}")
    if not 0 < args.speed_tolerance < 1:
        p.error(f"--speed-tolerance must be in (0, 1), got {args.speed_tolerance}")
    if args.workers is not None and args.workers < 1:
        p.error(f"--workers must be >= 1, got {args.workers}")
    return args


# ---------------------------------------------------------------------------------------------------------
# learned trajectories: load, or extract from policies
# ---------------------------------------------------------------------------------------------------------

def policy_file(path: Path) -> Path:
    """An actor file, or the stage-2 actor of a training run folder."""
    if path.is_file():
        return path
    if path.is_dir():
        for name in STAGE2_ACTORS:
            if (path / name).is_file():
                return path / name
        raise UsageError(f"{path} holds no stage-2 actor (looked for {', '.join(STAGE2_ACTORS)})")
    raise UsageError(f"policy {path} does not exist")


def policy_paths(args) -> list[Path]:
    paths = [policy_file(p) for p in (args.policies or [])]
    if args.sweep is not None:
        if not args.sweep.is_dir():
            raise UsageError(f"--sweep {args.sweep} is not a folder")
        runs = sorted(d for d in args.sweep.iterdir()
                      if d.is_dir() and any((d / n).is_file() for n in STAGE2_ACTORS))
        if not runs:
            raise UsageError(f"--sweep {args.sweep} has no run folder with a stage-2 actor "
                             f"({', '.join(STAGE2_ACTORS)})")
        paths += [policy_file(d) for d in runs]
    return paths


def unique_labels(labels: list[str]) -> list[str]:
    out, seen = [], {}
    for lab in labels:
        seen[lab] = seen.get(lab, 0) + 1
        out.append(lab if labels.count(lab) == 1 else f"{lab}-{seen[lab]}")
    return out


def learned_files(paths: list[Path]) -> list[Path]:
    """The trajectory files named: files as given, folders expanded to their JSON files (no *_cycles)."""
    files = []
    for p in paths:
        if p.is_dir():
            found = sorted(f for f in p.glob("*.json") if not f.stem.endswith("_cycles"))
            if not found:
                raise UsageError(f"learned trajectory folder {p} holds no JSON file")
            files += found
        else:
            files.append(p)
    return files


def load_learned(paths: list[Path]) -> dict:
    """Learned trajectories by label (the provenance's seed, else the file name): a commanded path per seed
    and speed is grouped as {speed: path}; a sampled trajectory stands alone (replayed at every speed)."""
    learned: dict = {}
    for f in learned_files(paths):
        if not f.is_file():
            hint = ("" if f != DEFAULT_LEARNED else
                    " (train policies with train.py, then `evaluate.py extract --sweep RUNS` and pass its "
                    "<out>/learned/ folder with --learned)")
            raise UsageError(f"learned trajectory {f} does not exist{hint}")
        try:
            t = load_foot_path(f)
        except (ValueError, KeyError, json.JSONDecodeError) as err:
            raise UsageError(f"learned trajectory {f} is unreadable: {err}") from None
        seed = t.provenance.get("seed")
        label = f"seed{seed}" if seed is not None else f.stem
        if isinstance(t, CommandedPath):
            group = learned.setdefault(label, {})
            if not isinstance(group, dict) or t.speed in group:
                raise UsageError(f"two learned trajectories for {label} at {t.speed:g} m/s ({f})")
            group[t.speed] = t
        else:
            learned[unique_labels(list(learned) + [label])[-1]] = t
    return learned


def flat_learned(learned: dict, speed: float = 1.0) -> dict[str, SampledTrajectory]:
    """One x-z path per label for the figures: a commanded path's reference leg (LF) at `speed` (or its
    nearest speed), a sampled trajectory as it is."""
    out = {}
    for label, entry in learned.items():
        if isinstance(entry, dict):
            v = min(entry, key=lambda s: abs(s - speed))
            out[label] = entry[v].as_sampled("LF")
        else:
            out[label] = entry
    return out


def extraction_speeds(env: C.EnvConfig, args) -> list[float]:
    """Speeds at which a policy is rolled out for extraction (see --policy-speed)."""
    if args.policy_speed is not None:
        return [args.policy_speed]
    if env.target_speed_range:
        lo, hi = env.target_speed_range
        outside = [v for v in args.speeds if not lo - 1e-9 <= v <= hi + 1e-9]
        if outside:
            raise UsageError(f"--speeds {outside} lie outside the policy's training range {lo:g}-{hi:g} m/s")
        return list(args.speeds)
    return [env.target_speed]


def extract_policies(paths: list[Path], args, out: Path, log=print) -> dict:
    """Roll out each policy at each of its speeds, extract its learned path (commanded or measured, see
    --path) and save it under out/learned/ with every cycle in <label>_cycles.csv."""
    from cyberdog.rl.rollout import load_actor, rollout  # torch: only here, only when asked

    results, labels = [], []
    for path in paths:
        actor = load_actor(path)
        env = actor.config.env
        kind = args.path_kind if args.path_kind != "auto" else ("commanded" if env.action_mode == "foot"
                                                                  else "measured")
        if kind == "commanded" and env.action_mode != "foot":
            raise UsageError(f"{path}: a policy of action_mode {env.action_mode!r} commands no foot path; use "
                             "--path measured")
        seed = actor.config.train.seed
        found = {}
        for speed in extraction_speeds(env, args):
            t0 = time.perf_counter()
            r = rollout(actor, speed=speed, duration=args.rollout_duration, seed=args.rollout_seed,
                        env_config=env)
            prov = {"policy": str(path), "seed": seed, "policy_meta": actor.meta, "rollout_seed": args.rollout_seed}
            log(f"rollout {path} at {speed:g} m/s: {r.duration:.1f} s, mean {r.mean_speed:.3f} m/s, "
                f"E={r.energy:.0f} J, fell={r.fell} ({time.perf_counter() - t0:.0f} s)")
            try:
                if kind == "commanded":
                    found[speed] = commanded_from_rollout(r, env, args.cycle, args.speed_tolerance, provenance=prov)
                else:
                    found[speed] = extract_from_rollout(r, env, args.leg, args.speed_tolerance, provenance=prov)
            except ExtractionError as err:
                raise UsageError(f"extraction from {path} at {speed:g} m/s failed: {err} (try --speed-tolerance "
                                 "or --policy-speed)") from None
        results.append((kind, found))
        labels.append(f"seed{seed}")
    if len(set(labels)) < len(labels):  # runs trained with the same seed: name them by their folders
        labels = [p.parent.name or lab for p, lab in zip(paths, labels)]
    learned: dict = {}
    for label, (kind, found) in zip(unique_labels(labels), results):
        for speed, ex in found.items():
            name = f"{label}_{speed:g}mps"
            traj = ex.path if kind == "commanded" else ex.trajectory
            path = traj.save(out / "learned" / f"{name}.json")
            write_rows(cycle_rows(ex), out / "learned", f"{name}_cycles")
            if kind == "commanded":
                log(f"{name}: commanded path from {len(ex.used)} of {len(ex.cycles)} cycles ({args.cycle}), "
                    f"{ex.energy:.1f} J per cycle, own H = {traj.own_lift_height():.4f} m -> {path}")
                learned.setdefault(label, {})[speed] = traj
            else:
                c = ex.chosen
                log(f"{name}: measured path of cycle {c.index} of {len(ex.cycles)} (t = {c.t_start:.2f} s), "
                    f"{c.energy:.1f} J, {c.speed:.3f} m/s, H = {traj.lift_height:.3f} m -> {path}")
                learned.setdefault(label, traj)  # a measured path is rescaled to every speed: the first one
    return learned


def learned_trajectories(args, out: Path, log=print) -> dict:
    paths = policy_paths(args)
    if paths:
        return extract_policies(paths, args, out, log)
    return load_learned(args.learned or [DEFAULT_LEARNED])


def metrics_files(args) -> dict[str, Path]:
    if args.metrics:
        missing = [m for m in args.metrics if not m.is_file()]
        if missing:
            raise UsageError(f"--metrics file(s) do not exist: {', '.join(map(str, missing))}")
        return dict(zip(unique_labels([m.parent.name or m.stem for m in args.metrics]), args.metrics))
    found = [p.parent / "metrics.csv" for p in policy_paths(args) if (p.parent / "metrics.csv").is_file()]
    if not found and DEFAULT_METRICS.is_file():
        found = [DEFAULT_METRICS]
    return dict(zip(unique_labels([m.parent.name for m in found]), found))


# ---------------------------------------------------------------------------------------------------------
# the parts
# ---------------------------------------------------------------------------------------------------------

def run_compare(cfg: C.WalkConfig, learned: dict, args, out: Path, log=print) -> tuple[list, list, dict]:
    """Comparison walks → comparison.*, table5.*, walks.json, power_traces.npz; returns (rows, walks, power)."""
    for label, entry in learned.items():
        for t in (entry.values() if isinstance(entry, dict) else [entry]):
            period = t.gait.period if isinstance(t, CommandedPath) else t.provenance.get("period_s")
            if period is not None and abs(period - cfg.gait.period) > 1e-9:
                log(f"warning: {label} was recorded with a {period} s gait period; the baselines walk "
                    f"{cfg.gait.period} s")
    jobs = cmp.comparison_jobs(cfg, learned, args.speeds, args.duration, same_lift=not args.no_same_lift)
    log(f"comparison: {len(jobs)} walks of {args.duration:g} s")
    walks = cmp.run_jobs(jobs, args.workers, log)
    power = {w["walk_id"]: w.pop("power_W") for w in walks}
    rows = cmp.comparison_rows(walks, cfg.gait.lift_height)
    means = cmp.seed_means(rows)
    write_rows(rows, out, "comparison")
    (out / "comparison.md").write_text(markdown_table(rows, cmp.COLUMNS) + "\n")
    write_rows(t5.table5_rows(rows), out, "table5")
    # every walk of the paper's set, per seed (the matched-lift walks, one baseline pair per seed and lift
    # height, are in comparison.md; the summaries above average them)
    table5 = t5.table5_markdown([r for r in rows if r["set"] == "paper"], means)
    summary = t5.summary_rows(rows)
    write_rows(summary, out, "table5_summary")
    headline = "\n\n".join(
        f"{title}\n\n{t5.summary_markdown(summary, set_name)}"
        for set_name, title in (("same_lift", "Matched conditions: the baselines at the learned path's own lift "
                                              "height, same step length and period (the headline)"),
                                ("paper", "The paper's protocol: the baselines at H = "
                                          f"{cfg.gait.lift_height:g} m"))
        if t5.summary_markdown(summary, set_name))
    (out / "table5.md").write_text("Table 5: energy consumption of the foot trajectories at each speed\n\n"
                                   + headline + "\n\nEvery walk of the paper's protocol (E in kJ over the walk; the "
                                   "matched-lift walks are in comparison.md)\n\n" + table5 + "\n")
    if len(learned) > 1:
        write_rows(means, out, "learned_mean_ci")
    (out / "walks.json").write_text(json.dumps(walks, indent=1))
    np.savez_compressed(out / "power_traces.npz", **{f"walk_{i}": p for i, p in power.items()})
    print("\nTable 5: energy consumption of the foot trajectories over the walk\n")
    print(headline)
    print("\nEvery walk of the paper's protocol (E in kJ over the walk; matched-lift walks: comparison.md)\n")
    print(table5)
    print("\nAll walks (energy per 100 m, cost of transport, mean speed over the last half):\n")
    print(markdown_table(rows, cmp.COLUMNS))
    return rows, walks, power


def run_prototype_part(cfg: C.WalkConfig, learned: dict, args, out: Path, log=print) -> list[dict]:
    from cyberdog.analysis.prototype import prototype_table, run_prototype, write_prototype

    label, entry = next(iter(learned.items()))
    lifts = None
    if isinstance(entry, dict):  # commanded paths: the baselines at each speed's own lift height (matched)
        missing = [v for v in args.speeds if not any(abs(v - u) < 1e-6 for u in entry)]
        if missing:
            raise UsageError(f"prototype: the learned {label} has no path at {missing} m/s")
        lifts = {v: t.own_lift_height() for v in args.speeds for u, t in entry.items() if abs(v - u) < 1e-6}
        trajectories = {"learned": entry, "cycloid": None, "straight": None}
    else:
        trajectories = {"learned": cmp.pinned_lift(entry, cfg.gait.lift_height), "cycloid": None, "straight": None}
    log(f"prototype: {len(trajectories) * len(args.speeds) * len(args.prototype_modes)} walks of "
        f"{args.prototype_distance:g} m (learned = {label}"
        + (", baselines at its own lift height)" if lifts else ")"))
    rows = run_prototype(trajectories, speeds=args.speeds, distance_m=args.prototype_distance,
                         modes=args.prototype_modes, workers=args.workers, base_cfg=cfg, lift_heights=lifts,
                         log=log)
    write_prototype(rows, out)
    print(f"\nPrototype experiment (Section 4.2) in simulation: {args.prototype_distance:g} m walks "
          f"(paper: 100 m); learned = {label}\n")
    print(prototype_table(rows))
    return rows


def run_figures(cfg: C.WalkConfig, learned: dict | None, metrics: dict, out: Path, rows=None, walks=None,
                power=None, prototype_rows=None) -> list[Path]:
    g = cfg.gait
    paths = figs.figure4(out, 0.2, g.lift_height, g.straight_shape, g.swing_time, g.stance_time)
    if metrics:
        paths += figs.figure6(metrics, out)
    else:
        print(f"Figure 6 skipped: no training log ({DEFAULT_METRICS} missing; pass --metrics CSV)")
    if learned:
        paths += figs.figure7(flat_learned(learned), out, g.straight_shape, g.lift_height, g.swing_time,
                              g.stance_time)
    if walks and power:
        paths += figs.figure10(walks, power, out, g.lift_height)
    if rows:
        paths += figs.figure13(rows, out, prototype_rows)
    return paths


def load_saved(folder: Path) -> tuple:
    """(rows, walks, power, prototype_rows, learned) saved by `compare`/`all` in `folder` (None where absent)."""
    rows = walks = power = proto = None
    if (folder / "comparison.json").is_file():
        rows = json.loads((folder / "comparison.json").read_text())
    if (folder / "walks.json").is_file() and (folder / "power_traces.npz").is_file():
        walks = json.loads((folder / "walks.json").read_text())
        with np.load(folder / "power_traces.npz") as z:
            power = {int(k.split("_")[1]): z[k] for k in z.files}
    if (folder / "prototype.json").is_file():
        proto = json.loads((folder / "prototype.json").read_text())
    learned_files = sorted((folder / "learned").glob("*.json")) if (folder / "learned").is_dir() else []
    learned_files = [f for f in learned_files if not f.stem.endswith("_cycles")]
    learned = load_learned(learned_files) if learned_files else None
    return rows, walks, power, proto, learned


def run_video(cfg: C.WalkConfig, learned: dict | None, args, out: Path) -> Path:
    from cyberdog.analysis.video import record_video

    name = args.video_trajectory
    traj = None
    lift = cfg.gait.lift_height
    if name == "learned":  # a commanded path is shown as its LF leg's x-z path on all four legs
        label, traj = next(iter(flat_learned(learned, args.video_speed).items()))
        lift = cmp.learned_lift_height(traj)
    vcfg = cmp.walk_config(cfg, name, args.video_speed, lift)
    path = out / f"trot_{name}_{args.video_speed:g}mps.{args.video_format}"
    return record_video(vcfg, traj, path, args.video_duration, label=name)


# ---------------------------------------------------------------------------------------------------------

_OUTPUT: dict = {}  # this run's OutputFolder, for _finish


def main(argv=None) -> int:
    args = parse_args(argv)
    args.argv = list(sys.argv[1:] if argv is None else argv)
    try:
        return _main(args)
    except UsageError as err:
        print(f"evaluate.py: error: {err}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("\nevaluate.py: interrupted", file=sys.stderr)
        return 130


def _open_output(out: Path, args, append: bool = False) -> None:
    """Refuse an --out folder that holds results (unless --force); remember what is there before this run."""
    try:
        _OUTPUT["folder"] = folder = OutputFolder(out, force=args.force, append=append, command=args.command,
                                                  argv=getattr(args, "argv", ()))
    except OutputFolderError as err:
        raise UsageError(str(err)) from None
    for note in folder.notes:
        print(note)


def _new_out() -> Path:
    """runs/evaluate-<time>, with a suffix if a run in the same second took that name."""
    base = Path("runs") / time.strftime("evaluate-%Y%m%d-%H%M%S")
    out, k = base, 1
    while out.exists():
        k += 1
        out = base.with_name(f"{base.name}-{k}")
    return out


def _main(args) -> int:
    _OUTPUT.clear()
    try:
        cfg = C.load(C.WalkConfig, args.config) if args.config else C.WalkConfig()
        cfg = C.override(cfg, args.set)
    except (ValueError, OSError) as err:
        raise UsageError(f"config error: {err}") from None
    t0 = time.perf_counter()
    cmd = args.command
    if cmd == "figures":
        src = args.from_dir or args.out
        if src is None or not src.is_dir():
            raise UsageError("figures needs --from DIR (a folder written by `evaluate.py` all/compare)")
        out = args.out or src
        _open_output(out, args, append=out.resolve() == src.resolve())  # figures beside the results they draw
        rows, walks, power, proto, learned = load_saved(src)
        if learned is None and (args.learned or DEFAULT_LEARNED.is_dir()):
            learned = load_learned(args.learned or [DEFAULT_LEARNED])
        run_figures(cfg, learned, metrics_files(args), out, rows, walks, power, proto)
        return _finish(out, t0)
    if cmd == "extract" and not (args.policies or args.sweep):
        raise UsageError("extract needs --policy PATH (actor file or run folder), --policies ... or --sweep DIR")
    needs_learned = cmd in ("all", "extract", "compare", "prototype") or (
        cmd == "video" and args.video_trajectory == "learned")
    if needs_learned and not policy_paths(args):  # check the inputs before any long work
        load_learned(args.learned or [DEFAULT_LEARNED])
    metrics = metrics_files(args) if cmd == "all" else {}
    out = args.out or _new_out()
    _open_output(out, args)
    out.mkdir(parents=True, exist_ok=True)
    C.save(cfg, out / "config.yaml")
    if cmd == "baselines":
        rows = baseline_rows(cfg, args.speeds, args.trajectories, args.duration)
        write_rows(rows, out, "baselines")
        print(markdown_table(rows, BASELINE_COLUMNS))
        return _finish(out, t0)
    learned = None
    if needs_learned:
        learned = learned_trajectories(args, out)
        for label, entry in learned.items():  # the inputs used, copied beside the results
            for v, t in (entry.items() if isinstance(entry, dict) else [(None, entry)]):
                name = label if v is None else f"{label}_{v:g}mps"
                if not (out / "learned" / f"{name}.json").is_file():
                    t.save(out / "learned" / f"{name}.json")
    if cmd == "extract":
        figs.figure7(flat_learned(learned), out, cfg.gait.straight_shape, cfg.gait.lift_height)
        return _finish(out, t0)
    rows = walks = power = proto = None
    if cmd in ("all", "compare"):
        rows, walks, power = run_compare(cfg, learned, args, out)
    if cmd == "prototype" or (cmd == "all" and not args.no_prototype):
        proto = run_prototype_part(cfg, learned, args, out)
    if cmd == "all":
        run_figures(cfg, learned, metrics, out, rows, walks, power, proto)
    elif cmd == "compare":
        figs.figure10(walks, power, out, cfg.gait.lift_height)
        figs.figure13(rows, out)
    if cmd == "video" or (cmd == "all" and args.video):
        run_video(cfg, learned, args, out)
    return _finish(out, t0)


def _finish(out: Path, t0: float) -> int:
    """List exactly the files this run wrote (also recorded in the folder's outputs.json)."""
    folder = _OUTPUT.pop("folder", None)
    files = folder.finish() if folder is not None else sorted(p for p in out.rglob("*") if p.is_file())
    print(f"\nwrote {len(files)} files in {out}/ ({time.perf_counter() - t0:.1f} s):")
    for p in files:
        print(f"  {p}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
