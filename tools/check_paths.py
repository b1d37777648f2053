#!/usr/bin/env python3
"""Walk learned path files through the extraction's replay check, every walk of it: which pass, and by how much.

`evaluate.py extract` stops a candidate's check at its first failing walk and records only that one. This script
walks every walk of `cyberdog.analysis.replay_check.check_walks` (or the parts asked for) for each commanded path
file, under the trot the path was recorded with (as extraction checks it), and prints per walk the mean speed
as a share of the command, a fall, and the electrical energy per metre; then each path's verdict ("ok", or the
walks that failed). Uses: which shipped paths a changed check would reject (their candidates regenerated with
`evaluate.py extract --rollout-seed K --cycle C --no-replay-check`), and how close to the ±5 % band a kept path
walks.

    python tools/check_paths.py results/battery/paths/seed0_1.4mps.json --parts spread
    python tools/check_paths.py runs/cands/*/learned/*mps.json --parts spread --workers 2 --out runs/spread.json
"""
from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from cyberdog.analysis.parallel import map_in_processes
from cyberdog.analysis.replay_check import check_walks, walk_status
from cyberdog.analysis.report import json_safe
from cyberdog.config import WalkConfig
from cyberdog.core.learned_set import LearnedSet, learned_files
from cyberdog.evaluation.trot import with_trot

PARTS = ("ideal", "spread", "hardware")


def path_walks(path, parts) -> tuple[WalkConfig, list]:
    """`path`'s trot (the one it was recorded with) and the check walks of `parts` at its speed."""
    cfg = WalkConfig()
    if path.recorded_controller:
        cfg = with_trot(cfg, path.recorded_controller)
    return cfg, [w for w in check_walks(path.speed, cfg) if w.part in parts]


def walk_job(job: tuple) -> dict:
    """One check walk of one path file: a row (runs in a worker process)."""
    file, index, parts = job
    path = LearnedSet.load([file]).paths()[0]
    cfg, walks = path_walks(path, parts)
    w = walks[index]
    r = w.run(path, path.speed, cfg)
    return {"file": str(file), "speed_mps": path.speed, "walk": w.name, "part": w.part, "pd_scale": w.pd_scale,
            "status": walk_status(r), "fell": r.fell, "speed_share": r.mean_speed / path.speed,
            "electrical_J_per_m": r.electrical_energy / r.distance if r.distance > 0 else float("nan")}


def verdicts(rows: list[dict]) -> dict[str, str]:
    """Per file: "ok" if every walk passed, else its failing walks and why."""
    out: dict[str, list[str]] = {}
    for row in rows:
        failed = out.setdefault(row["file"], [])
        if row["status"] != "ok":
            failed.append(f"{row['walk']}: {row['status']}")
    return {f: "ok" if not failed else "; ".join(failed) for f, failed in out.items()}


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("paths", nargs="+", type=Path, help="commanded path files (JSON) or folders of them")
    p.add_argument("--parts", nargs="+", choices=PARTS, default=list(PARTS),
                   help="the check's parts to walk (default all): the ideal robot's walks, the spread walks at "
                        "the stiffness's ends, the 100 m hardware-like walks")
    p.add_argument("--workers", type=int, default=None, help="walk processes (default: one per CPU)")
    p.add_argument("--out", type=Path, help="JSON file for the rows and verdicts (never overwritten)")
    args = p.parse_args(argv)
    if args.out is not None and args.out.exists():
        p.error(f"--out {args.out} exists: choose a new file")
    try:
        files = learned_files(args.paths)
        paths = [LearnedSet.load([f]).paths()[0] for f in files]
    except (OSError, ValueError) as err:
        p.error(str(err))
    sampled = [str(f) for f, path in zip(files, paths) if not path.commanded]
    if sampled:
        p.error(f"not commanded paths (the check walks a path at the one speed it was recorded at): {sampled}")
    jobs = [(str(f), i, tuple(args.parts)) for f, path in zip(files, paths)
            for i in range(len(path_walks(path, args.parts)[1]))]
    print(f"{len(jobs)} walks of {len(files)} paths ({', '.join(args.parts)})", flush=True)

    def line(row: dict, done: int) -> None:
        print(f"[{done}/{len(jobs)}] {Path(row['file']).name} {row['walk']}: {row['status']}, "
              f"{row['speed_share']:.3f} of the command, {row['electrical_J_per_m']:.1f} J/m", flush=True)

    rows = map_in_processes(walk_job, jobs, args.workers, on_result=lambda i, row, done: line(row, done))
    results = verdicts(rows)
    for f, verdict in results.items():
        print(f"{f}: {verdict}")
    if args.out is not None:
        args.out.parent.mkdir(parents=True, exist_ok=True)
        args.out.write_text(json.dumps(json_safe({"rows": rows, "verdicts": results}), indent=1))
    return 0 if all(v == "ok" for v in results.values()) else 1


if __name__ == "__main__":
    sys.exit(main())
