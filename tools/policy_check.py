#!/usr/bin/env python3
"""Do trained policies walk, alone, at the paper's speeds, and does stage 2 spend less Eq. 7 energy than stage 1?

For each run folder given (train.py's), its `stage1_final_actor.pt` and `stage2_final_actor.pt` (whichever
exist) walk `--duration` s from the stand at each `--speeds`, deterministically, on the ideal robot, with no
trot prior (a torque policy is judged alone: `cyberdog.rl.rollout`). A walk *walks* if it does not fall and its
mean speed over the last half is within ±5 % of the command. Printed and written to --out (policy_check.md,
policy_check.json): every walk, and per run and speed the Eq. 7 reduction of stage 2 against stage 1.

    python tools/policy_check.py --runs runs/torque_s0 runs/torque_s1 --out runs/policy_check
"""
from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from cyberdog.analysis.parallel import map_in_processes, progress_log
from cyberdog.analysis.policy_check import COLUMNS, check_actor, check_jobs, check_trot, stage_reductions
from cyberdog.analysis.report import json_safe, markdown_table
from cyberdog.config import ExperimentConfig, load


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--runs", type=Path, nargs="+", required=True, help="run folders of train.py (label: the name)")
    p.add_argument("--speeds", type=float, nargs="+", default=[1.0, 1.2, 1.4], help="m/s (default 1.0 1.2 1.4)")
    p.add_argument("--duration", type=float, default=10.0, help="s per walk (default 10, the paper's)")
    p.add_argument("--actor", choices=["final", "best"], default="final",
                   help="stage<N>_final_actor.pt (default) or stage<N>_best_actor.pt")
    p.add_argument("--trot", action="store_true",
                   help="also walk the trot controller itself at each speed (label trot, stage 0): the reference, "
                        "with the first run's env.walk (its trajectory and lift height)")
    p.add_argument("--workers", type=int, default=None, help="processes (default: the CPUs)")
    p.add_argument("--out", type=Path, required=True, help="folder for policy_check.md and policy_check.json")
    args = p.parse_args(argv)
    actors = {}
    for run in args.runs:
        stages = {s: run / f"stage{s}_{args.actor}_actor.pt" for s in (1, 2)}
        stages = {s: f for s, f in stages.items() if f.is_file()}
        if not stages:
            p.error(f"{run}: no stage1_{args.actor}_actor.pt or stage2_{args.actor}_actor.pt")
        actors[run.name] = stages
    try:
        jobs = check_jobs(actors, args.speeds, args.duration)
    except (ValueError, FileNotFoundError) as err:
        p.error(str(err))
    print(f"{len(jobs)} walks of {args.duration:g} s on the ideal robot, the policies alone", flush=True)

    def line(r: dict) -> str:
        return (f"{r['label']} stage {r['stage']} {r['speed_command_mps']:g} m/s: {r['mean_speed_mps']:.3f} m/s, "
                f"{'fell' if r['fell'] else 'walks' if r['walks'] else 'off the band'}, {r['energy_J']:.0f} J")

    rows = map_in_processes(check_actor, jobs, args.workers, on_result=progress_log(len(jobs), line))
    if args.trot:  # the reference: the trot controller's own walks, as the first run's env has it
        config = args.runs[0] / "config.yaml"
        walk_cfg = (load(ExperimentConfig, config) if config.is_file() else ExperimentConfig()).env.walk
        rows += map_in_processes(check_trot, [(float(v), args.duration, walk_cfg) for v in args.speeds], args.workers,
                                 on_result=progress_log(len(args.speeds), line))
    reductions = stage_reductions(rows)
    md = ("## Every walk\n\n" + markdown_table([{k: r[k] for k in COLUMNS} for r in rows])
          + "\n\n## Stage 2 against stage 1 (Eq. 7, same speed and duration)\n\n" + markdown_table(reductions) + "\n")
    print(md)
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "policy_check.md").write_text(md)
    (args.out / "policy_check.json").write_text(json.dumps(json_safe({"walks": rows, "reductions": reductions}),
                                                           indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
