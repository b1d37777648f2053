#!/usr/bin/env python3
"""The battery policy in closed loop against its replayed path, on the prototype run's hardware-like robots.

What the prototype run walks is the commanded foot path extracted from a policy and replayed with IK + PID,
no policy in the loop. This script asks how much of the policy's own saving that replay keeps: for every
actor given and every speed it serves, on `--draws` hardware-like robots (HARDWARE_LIKE with seed + d, the
prototype's draws; the actor's domain randomisation off), three timed walks of `--duration` s from a stand:

  closed loop   the actor in CyberDog-v0 (cyberdog.rl.rollout), deterministic;
  replay        the learned path of that seed and speed (`--learned`), as the prototype walks it;
  cycloid       the composite cycloid at that path's lift height.

`evaluate.py prototype --closed-loop ACTOR...` walks the policies the prototype's own way (run-up, distance)
as a row of its tables; this script keeps the timed walks from a stand. Printed and written to --out (markdown and JSON): electrical energy per 100 m (what the battery pays; battery
% per 100 m is proportional to it, Eq. 13) and the saving against the cycloid, per actor, speed and draw, and
whether the walk fell or left the ±5 % speed band.

    python notebook/tools/closed_loop_battery.py --actors runs/battery/seed*/stage2_final_actor.pt \\
        --labels seed0 ... --learned notebook/results/learned_battery --speeds 1.0 1.2 --out runs/closed_loop
"""
from __future__ import annotations

import argparse
import dataclasses
import json
import sys
from pathlib import Path

from cyberdog import config as C
from cyberdog.analysis.parallel import map_in_processes, progress_log
from cyberdog.analysis.report import json_safe, markdown_table
from cyberdog.analysis.walk import walk
from cyberdog.config.paper import speed_within_band
from cyberdog.core.learned_set import LearnedSet, LearnedSetError, learned_files


def walk_row(job: tuple) -> dict:
    """One walk → one row (in a worker process). job: (kind, actor file, label, learned path, speed, draw, s)."""
    from cyberdog.rl.rollout import load_actor, rollout

    kind, actor_file, label, path, speed, draw, duration = job
    hw = dataclasses.replace(C.HARDWARE_LIKE, seed=C.HARDWARE_LIKE.seed + draw)
    cfg, trajectory, offsets = path.walk_args(C.WalkConfig(), speed)
    if kind == "closed loop":
        actor = load_actor(actor_file)
        env = dataclasses.replace(actor.config.env, hardware=hw, randomization=C.RandomizationConfig())
        r = rollout(actor, speed, duration, seed=draw, env_config=env, hardware_robot=True)  # the draw's robot
    elif kind == "replay":
        r = walk(cfg, duration, trajectory, hardware=hw, foot_offsets=offsets)
    else:  # the cycloid at the path's own lift height, as the prototype run matches it
        gait = dataclasses.replace(cfg.gait, trajectory="cycloid", lift_height=path.lift_height)
        r = walk(dataclasses.replace(cfg, gait=gait), duration, hardware=hw)
    ok = not r.fell and speed_within_band(r.mean_speed, speed)
    return {"label": label, "speed_mps": speed, "draw": draw, "walk": kind, "fell": r.fell,
            "mean_speed_mps": r.mean_speed, "distance_m": r.distance, "counts": ok,
            "electrical_kJ_per_100m": 100.0 * r.electrical_energy / r.distance / 1e3 if r.distance > 0 else None,
            "lift_height_m": path.lift_height}


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--actors", type=Path, nargs="+", required=True, help="stage-2 actor files (train.py's)")
    p.add_argument("--labels", nargs="+", required=True, help="each actor's seed label in --learned (seed0 ...)")
    p.add_argument("--learned", type=Path, default=Path("notebook/results/learned_battery"),
                   help="the learned paths (default notebook/results/learned_battery)")
    p.add_argument("--speeds", type=float, nargs="+", default=[1.0, 1.2, 1.4], help="m/s (default 1.0 1.2 1.4)")
    p.add_argument("--draws", type=int, default=2, help="hardware-like robots (default 2, as the prototype run)")
    p.add_argument("--duration", type=float, default=15.0, help="s per walk (default 15)")
    p.add_argument("--workers", type=int, default=None, help="processes (default: the CPUs)")
    p.add_argument("--out", type=Path, required=True, help="folder for closed_loop.md and closed_loop.json")
    args = p.parse_args(argv)
    if len(args.actors) != len(args.labels):
        p.error(f"--actors and --labels must pair up: {len(args.actors)} actors, {len(args.labels)} labels")
    missing = [a for a in args.actors if not a.is_file()]
    if missing:
        p.error(f"no actor file {missing[0]}")
    try:
        learned = LearnedSet.load(learned_files([args.learned]))
        jobs = [(kind, str(a), label, learned.path(label, v), v, d, args.duration)
                for a, label in zip(args.actors, args.labels) for v in args.speeds if learned.covers(v)
                for d in range(args.draws) for kind in ("closed loop", "replay", "cycloid")]
    except LearnedSetError as err:  # a label or speed without a path, an unreadable file: before any walk
        p.error(str(err))
    print(f"{len(jobs)} walks of {args.duration:g} s on {args.draws} hardware-like robot(s)", flush=True)
    def line(r: dict) -> str:
        return (f"{r['label']} {r['speed_mps']:g} m/s draw {r['draw']} {r['walk']:11s} "
                f"{r['mean_speed_mps']:.3f} m/s fell={r['fell']}")

    rows = map_in_processes(walk_row, jobs, args.workers, on_result=progress_log(len(jobs), line))
    table = []
    for i in range(0, len(rows), 3):
        closed, replay, cycloid = rows[i:i + 3]
        base = cycloid["electrical_kJ_per_100m"] if cycloid["counts"] else None

        def cell(r):
            e = r["electrical_kJ_per_100m"]
            if not r["counts"] or e is None:
                return "fell" if r["fell"] else f"off band ({r['mean_speed_mps']:.2f} m/s)"
            return f"{e:.2f}" + (f" ({100 * (1 - e / base):+.1f} %)" if base else "")
        table.append({"seed": closed["label"], "v (m/s)": f"{closed['speed_mps']:g}", "draw": closed["draw"],
                      "closed loop, kJ/100 m (saving)": cell(closed), "replay": cell(replay),
                      "cycloid at the path's lift": cell(cycloid)})
    md = markdown_table(table)
    print(md)
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "closed_loop.md").write_text(md)
    (args.out / "closed_loop.json").write_text(json.dumps(json_safe(rows), indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
