#!/usr/bin/env python3
"""One stiffness table from several `evaluate.py stiffness` runs: seeds walked apart (on other machines, or a
seed trained later), summarised together.

Every walk of the study is deterministic and belongs to one seed's label (its learned path, its policy, the
common trajectories and the searched shape at that path's lift, on the same robots), so the walks of runs over
disjoint seeds are exactly the walks one run over all of them makes. This reads each run's
`stiffness_walks.json`, refuses a seed that two runs both walked (unless their walks are equal to the last
digit: the same seed walked twice) and runs that differ in their stiffnesses or speeds, and writes the
summary as `evaluate.py stiffness` does (`stiffness.{csv,json,md}`, `stiffness_walks.json`) into a new folder.

    python tools/merge_stiffness.py runs/stiffness_320_s012 runs/stiffness_320_s34 --out runs/stiffness_320_s01234
"""
from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from cyberdog.analysis.stiffness import write_stiffness

WALKS = "stiffness_walks.json"
WALL_CLOCK = ("wall_s",)  # fields that differ between two walks of the same seed (machine time, not physics)


def walk_key(row: dict) -> tuple:
    return tuple(row.get(k) for k in ("seed", "trajectory", "robot", "draw", "speed_mps", "pd_scale"))


def physics(row: dict) -> dict:
    return {k: v for k, v in row.items() if k not in WALL_CLOCK}


def merge(runs: list[list[dict]], names: list[str]) -> list[dict]:
    """The walks of all runs, each once; ValueError on a seed walked differently by two runs, or on runs whose
    stiffnesses or speeds differ."""
    grids = {name: (sorted({r["pd_scale"] for r in rows}), sorted({r["speed_mps"] for r in rows}))
             for name, rows in zip(names, runs)}
    if len(set(map(str, grids.values()))) > 1:
        raise ValueError("the runs walk different PD scales or speeds: "
                         + "; ".join(f"{n}: scales {g[0]}, speeds {g[1]}" for n, g in grids.items()))
    merged: dict[tuple, dict] = {}
    owner: dict[tuple, str] = {}
    for name, rows in zip(names, runs):
        for row in rows:
            key = walk_key(row)
            if key in merged and physics(merged[key]) != physics(row):
                raise ValueError(f"seed {row.get('seed')!r} ({row.get('trajectory')}, {row.get('speed_mps')} m/s, PD "
                                 f"{row.get('pd_scale')}x) was walked by {owner[key]} and {name} with different "
                                 "results: not the same seed's paths")
            merged.setdefault(key, row)
            owner.setdefault(key, name)
    return list(merged.values())


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("runs", type=Path, nargs="+", help=f"output folders of evaluate.py stiffness (with {WALKS})")
    p.add_argument("--out", type=Path, required=True, help="a new folder for the merged table")
    args = p.parse_args(argv)
    if len(args.runs) < 2:
        p.error("give two runs or more")
    missing = [str(r) for r in args.runs if not (r / WALKS).is_file()]
    if missing:
        p.error(f"no {WALKS} in {', '.join(missing)}")
    if args.out.exists() and any(args.out.iterdir()):
        p.error(f"{args.out} holds files: choose a new --out (results are never overwritten)")
    try:
        rows = merge([json.loads((r / WALKS).read_text()) for r in args.runs], [str(r) for r in args.runs])
    except ValueError as err:
        print(f"merge_stiffness: {err}", file=sys.stderr)
        return 1
    args.out.mkdir(parents=True, exist_ok=True)
    seeds = sorted({str(r.get("seed")) for r in rows})
    print(f"{len(rows)} walks of {len(seeds)} seeds ({', '.join(seeds)}) from {len(args.runs)} runs\n")
    print(write_stiffness(rows, args.out))
    print(f"wrote {args.out}/stiffness.{{csv,json,md}} and {WALKS}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
