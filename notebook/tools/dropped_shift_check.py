#!/usr/bin/env python3
"""Did any learned path ask for a foot target out of the leg's reach? Counted on the walks that use it.

A foot shift that puts a target out of reach is dropped for that controller period (the unshifted target is
sent, and the record says so: `TrotController.dropped_shifts`, `WalkResult.dropped_shifts`). This replays
every learned path given (the folders of `evaluate.py extract`, e.g. results/table5/paths notebook/results/learned_battery)
at the speed it serves for `--duration` s on the ideal robot and on the hardware-like one, and with
`--policies`, rolls out foot-mode actors (whose traced offsets a commanded path averages) at each path speed,
and prints the dropped leg-periods of each walk. Nonzero means a path or a rollout held shifts the robot
never got.

    python notebook/tools/dropped_shift_check.py --learned results/table5/paths notebook/results/learned_battery \\
        --policies results/table5/policy/seed0/stage2_actor.pt notebook/results/policy_battery/stage2_actor.pt
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

from cyberdog.analysis.parallel import map_in_processes, progress_log


def check(job: tuple) -> dict:
    """One walk: ("path", file, label, speed, robot, duration) or ("policy", file, "", speed, "ideal", duration)."""
    from cyberdog.config import HARDWARE_LIKE

    kind, file, label, speed, robot, duration = job
    if kind == "path":
        from cyberdog.analysis.replay_check import replay_walk
        from cyberdog.core.learned_set import LearnedSet
        path = LearnedSet.load([file]).at(speed)[label]
        r = replay_walk(path, speed, duration=duration, hardware=HARDWARE_LIKE if robot == "hardware" else None)
    else:
        from cyberdog.rl.rollout import load_actor, rollout
        r = rollout(load_actor(file), speed=speed, duration=duration)
    return {"kind": kind, "file": file, "speed": speed, "robot": robot, "dropped_shifts": r.dropped_shifts,
            "fell": r.fell}


def main(argv=None) -> int:
    from cyberdog.core.learned_set import LearnedSet, LearnedSetError, learned_files

    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--learned", type=Path, nargs="+", default=[], help="folders or files of learned paths")
    p.add_argument("--policies", type=Path, nargs="*", default=[], help="foot-mode actor files to roll out")
    p.add_argument("--speeds", type=float, nargs="+", default=[1.0, 1.2, 1.4], help="policy speeds (m/s)")
    p.add_argument("--duration", type=float, default=10.0, help="s per walk (default 10)")
    p.add_argument("--workers", type=int, default=None, help="processes (default: the CPUs)")
    args = p.parse_args(argv)
    jobs = []
    try:
        for file in learned_files(args.learned):
            learned = LearnedSet.load([file])
            for path in learned.paths():
                for robot in ("ideal", "hardware"):
                    jobs.append(("path", str(file), path.label, path.speed or 1.0, robot, args.duration))
    except LearnedSetError as err:
        p.error(str(err))
    jobs += [("policy", str(f), "", v, "ideal", args.duration) for f in args.policies for v in args.speeds]
    if not jobs:
        p.error("nothing to check: give --learned and/or --policies")
    rows = map_in_processes(check, jobs, args.workers, on_result=progress_log(
        len(jobs), lambda r: f"{r['file']} {r['speed']:g} m/s {r['robot']}: {r['dropped_shifts']} dropped"))
    dropped = [r for r in rows if r["dropped_shifts"]]
    print(f"{len(rows)} walks, {len(dropped)} with dropped foot shifts"
          + "".join(f"\n  {r['file']} at {r['speed']:g} m/s ({r['robot']}): {r['dropped_shifts']}" for r in dropped))
    return 1 if dropped else 0


if __name__ == "__main__":
    sys.exit(main())
