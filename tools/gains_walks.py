#!/usr/bin/env python3
"""The gains table's walks from `evaluate.py prototype` runs, one per changed gain: each run's walks labelled with
the gain it changed and by how much, into one JSON file (`results/figures_input/gains_walks.json` for the
README's gains table, made by `tools/make_readme_tables.py`).

A run is one prototype run with the drivers' kp or kd (one of them, the same factor on every joint) set apart
from the default (`PIDConfig`), read from its `config.yaml`; its walks were re-commanded for those gains where
they say `pd_matched` (`prototype --pd-matched-from-default`). Every walk gets `gain` ("kp" or "kd"),
`gain_scale` (the factor) and keeps `pd_matched`. A run that changes both gains, neither, or the two
unevenly across joints is refused, as is a gain, factor and kind (as commanded or re-commanded) given twice.

    python tools/gains_walks.py runs/gains_kp05 runs/gains_kp05_rematched ... --out results/figures_input/gains_walks.json
"""
from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import yaml

from cyberdog.config import PIDConfig


def run_gain(folder: Path) -> tuple[str, float]:
    """("kp" or "kd", factor over the default) of a prototype run folder's config; ValueError otherwise."""
    pid = (yaml.safe_load((folder / "config.yaml").read_text()) or {}).get("pid", {})
    default = PIDConfig()
    changed = {}
    for gain in ("kp", "kd"):
        values, base = [float(v) for v in pid.get(gain, getattr(default, gain))], getattr(default, gain)
        factors = {round(v / b, 6) for v, b in zip(values, base)}
        if len(factors) != 1:
            raise ValueError(f"{folder}: {gain} {values} is not one factor of the default {list(base)}")
        if factors != {1.0}:
            changed[gain] = factors.pop()
    if len(changed) != 1:
        raise ValueError(f"{folder}: a gains run changes kp or kd alone, this one changes {sorted(changed) or 'neither'}")
    return next(iter(changed.items()))


def gains_walks(folders: list[Path]) -> list[dict]:
    walks, seen = [], {}
    for folder in folders:
        gain, scale = run_gain(folder)
        rows = json.loads((folder / "prototype.json").read_text())
        kinds = {bool(r.get("pd_matched")) for r in rows if r["trajectory"] == "learned"}
        if len(kinds) != 1:
            raise ValueError(f"{folder}: its learned walks are partly re-commanded")
        key = (gain, scale, kinds.pop())
        if key in seen:
            raise ValueError(f"{folder}: {gain} × {scale:g} ({'re-commanded' if key[2] else 'as commanded'}) "
                             f"is also {seen[key]}")
        seen[key] = folder
        walks += [dict(r, gain=gain, gain_scale=scale) for r in rows]
    return walks


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("runs", type=Path, nargs="+", help="evaluate.py prototype output folders")
    p.add_argument("--out", type=Path, required=True, help="the JSON file to write (refused if it exists)")
    p.add_argument("--force", action="store_true", help="overwrite --out")
    args = p.parse_args()
    if args.out.exists() and not args.force:
        print(f"error: {args.out} exists (--force to overwrite)", file=sys.stderr)
        return 2
    try:
        walks = gains_walks(args.runs)
    except (ValueError, OSError) as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    args.out.write_text(json.dumps(walks, separators=(",", ":")))
    print(f"{len(walks)} walks of {len(args.runs)} runs -> {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
