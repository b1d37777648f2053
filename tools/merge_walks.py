#!/usr/bin/env python3
"""The walks of several `evaluate.py` runs, assembled into the input of one table.

    python tools/merge_walks.py stiffness runs/stiffness_320_s012 runs/stiffness_320_s34 --out runs/stiffness_320_s01234
    python tools/merge_walks.py gains runs/gains_kp05 runs/gains_kp05_rematched ... \
        --out results/figures_input/gains_walks.json
    python tools/merge_walks.py conditions runs/payload3 runs/friction0.4 runs/friction1.2 \
        --out results/figures_input/conditions_searched_pick.json

stiffness: one stiffness table from several `evaluate.py stiffness` runs, seeds walked apart (on other machines,
  or a seed trained later) summarised together. Every walk of the study is deterministic and belongs to one
  seed's label (its learned path, its policy, the common trajectories and the searched shape at that path's lift,
  on the same robots), so the walks of runs over disjoint seeds are exactly the walks one run over all of them
  makes. Each run's `stiffness_walks.json` is read; a seed that two runs both walked is refused (unless their
  walks are equal to the last digit: the same seed walked twice), as are runs that differ in their stiffnesses or
  speeds; the summary is written as `evaluate.py stiffness` writes it (`stiffness.{csv,json,md}`,
  `stiffness_walks.json`) into a new folder. Exit 1 on a conflict between the runs.

gains: the gains table's walks from `evaluate.py prototype` runs, one per changed gain: each run's walks labelled
  with the gain it changed and by how much, into one JSON file (`results/figures_input/gains_walks.json` for the
  gains table, made by `tools/make_readme_tables.py`). A run is one prototype run with the drivers' kp or kd (one
  of them, the same factor on every joint) set apart from the default (`PIDConfig`), read from its `config.yaml`;
  its walks were re-commanded for those gains where they say `pd_matched` (`prototype --pd-matched-from-default`).
  Every walk gets `gain` ("kp" or "kd"), `gain_scale` (the factor) and keeps `pd_matched`. A run that changes both
  gains, neither, or the two unevenly across joints is refused, as is a gain, factor and kind (as commanded or
  re-commanded) given twice. Exit 2 on a refused run or an existing --out.

conditions: a searched-start recipe's conditions rows' walks from `evaluate.py prototype` runs, each with one setting
  of `cyberdog.analysis.conditions_table.CONDITIONS` (a payload, the floor's friction) set apart from its default
  and the drivers' gains at theirs, read from its `config.yaml`: each run's walks labelled `condition` (the setting)
  and `condition_value`, into one JSON file (`results/figures_input/conditions_NAME.json`). A run that changes none
  of them, several, or the gains is refused, as are a setting and value given twice and runs whose settings differ
  beyond their conditions (another engine, robot or trot); the reference shape is not in `config.yaml`: each run
  must walk the table's (step 8 of `tools/ship_searched.py`). Exit 2 on a refused run or an existing --out.
"""
from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

import yaml

from cyberdog.analysis.conditions_table import CONDITIONS
from cyberdog.analysis.stiffness import write_stiffness
from cyberdog.config import PIDConfig, WalkConfig

STIFFNESS_WALKS = "stiffness_walks.json"
WALL_CLOCK = ("wall_s",)  # fields that differ between two walks of the same seed (machine time, not physics)


# ---- stiffness ------------------------------------------------------------------------------------------------
def walk_key(row: dict) -> tuple:
    return tuple(row.get(k) for k in ("seed", "trajectory", "robot", "draw", "speed_mps", "pd_scale"))


def physics(row: dict) -> dict:
    return {k: v for k, v in row.items() if k not in WALL_CLOCK}


def merge_stiffness(runs: list[list[dict]], names: list[str]) -> list[dict]:
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


def stiffness_command(p: argparse.ArgumentParser, args: argparse.Namespace) -> int:
    if len(args.runs) < 2:
        p.error("give two runs or more")
    missing = [str(r) for r in args.runs if not (r / STIFFNESS_WALKS).is_file()]
    if missing:
        p.error(f"no {STIFFNESS_WALKS} in {', '.join(missing)}")
    if args.out.exists() and any(args.out.iterdir()):
        p.error(f"{args.out} holds files: choose a new --out (results are never overwritten)")
    try:
        rows = merge_stiffness([json.loads((r / STIFFNESS_WALKS).read_text()) for r in args.runs],
                               [str(r) for r in args.runs])
    except ValueError as err:
        print(f"merge_walks stiffness: {err}", file=sys.stderr)
        return 1
    args.out.mkdir(parents=True, exist_ok=True)
    seeds = sorted({str(r.get("seed")) for r in rows})
    print(f"{len(rows)} walks of {len(seeds)} seeds ({', '.join(seeds)}) from {len(args.runs)} runs\n")
    print(write_stiffness(rows, args.out))
    print(f"wrote {args.out}/stiffness.{{csv,json,md}} and {STIFFNESS_WALKS}")
    return 0


# ---- gains ----------------------------------------------------------------------------------------------------
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
        raise ValueError(f"{folder}: a gains run changes kp or kd alone, this one changes "
                         f"{sorted(changed) or 'neither'}")
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


# ---- conditions -----------------------------------------------------------------------------------------------
def _gains_are_default(pid: dict) -> bool:
    """The drivers' kp and kd of a run's `pid` section are PIDConfig()'s (per joint)."""
    default = PIDConfig()
    try:
        return all([float(v) for v in pid.get(g, getattr(default, g))] == [float(v) for v in getattr(default, g)]
                   for g in ("kp", "kd"))
    except (TypeError, ValueError):  # a gain that is not a number per joint
        return False


def run_condition(folder: Path) -> tuple[str, float, dict]:
    """(setting, value) of the one condition a prototype run folder's config changes, and the rest of its config
    (the condition taken out: what every run of one table must share); ValueError otherwise."""
    config = yaml.safe_load((folder / "config.yaml").read_text()) or {}
    if not isinstance(config, dict):
        raise ValueError(f"{folder}: its config.yaml is not a mapping of sections")
    default, changed, rest = WalkConfig(), {}, json.loads(json.dumps(config))
    for setting in CONDITIONS:
        section, field = setting.split(".")
        base = getattr(getattr(default, section), field)
        raw = (config.get(section) or {}).get(field, base)
        try:
            value = round(float(raw), 6)  # as the rows print it
        except (TypeError, ValueError):
            raise ValueError(f"{folder}: {setting} = {raw!r} is not a number") from None
        if not math.isclose(value, base):
            changed[setting] = value
        (rest.get(section) or {}).pop(field, None)
        if rest.get(section) == {}:  # a section that held the condition alone
            rest.pop(section)
    if not _gains_are_default(config.get("pid") or {}):
        raise ValueError(f"{folder}: its drivers' gains are not the defaults (a gains run: merge_walks.py gains)")
    if len(changed) != 1:
        raise ValueError(f"{folder}: a conditions run changes one of {', '.join(CONDITIONS)}, this one changes "
                         f"{', '.join(sorted(changed)) or 'none'}")
    return (*next(iter(changed.items())), rest)


def conditions_walks(folders: list[Path]) -> list[dict]:
    """The runs' walks labelled by their condition; ValueError on a condition given twice or runs whose settings
    differ beyond their conditions (another engine, robot or trot: not one table's)."""
    walks, seen, shared = [], {}, None
    for folder in folders:
        setting, value, rest = run_condition(folder)
        if (setting, value) in seen:
            raise ValueError(f"{folder}: {setting} = {value:g} is also {seen[setting, value]}")
        if shared is not None and rest != shared[1]:
            other = sorted(k for k in {*rest, *shared[1]} if rest.get(k) != shared[1].get(k))
            raise ValueError(f"{folder} and {shared[0]} differ beyond their conditions (in {', '.join(other)})")
        seen[setting, value] = folder
        shared = shared or (folder, rest)
        rows = json.loads((folder / "prototype.json").read_text())
        walks += [dict(r, condition=setting, condition_value=value) for r in rows]
    return walks


def labelled_command(label: str, args: argparse.Namespace) -> int:
    """`gains` or `conditions`: the runs' walks labelled into --out."""
    if args.out.exists() and not args.force:
        print(f"error: {args.out} exists (--force to overwrite)", file=sys.stderr)
        return 2
    try:
        walks = (gains_walks if label == "gains" else conditions_walks)(args.runs)
    except (ValueError, OSError) as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(walks, separators=(",", ":")))
    print(f"{len(walks)} walks of {len(args.runs)} runs -> {args.out}")
    return 0


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = p.add_subparsers(dest="command", required=True, metavar="{stiffness,gains,conditions}")
    s = sub.add_parser("stiffness", help="one stiffness table from evaluate.py stiffness runs over other seeds")
    s.add_argument("runs", type=Path, nargs="+",
                   help=f"output folders of evaluate.py stiffness (with {STIFFNESS_WALKS})")
    s.add_argument("--out", type=Path, required=True, help="a new folder for the merged table")
    g = sub.add_parser("gains", help="the gains table's walks from evaluate.py prototype runs, one per changed gain")
    g.add_argument("runs", type=Path, nargs="+", help="evaluate.py prototype output folders")
    g.add_argument("--out", type=Path, required=True, help="the JSON file to write (refused if it exists)")
    g.add_argument("--force", action="store_true", help="overwrite --out")
    c = sub.add_parser("conditions", help="the conditions rows' walks from evaluate.py prototype runs, one per "
                       "payload or floor")
    c.add_argument("runs", type=Path, nargs="+", help="evaluate.py prototype output folders")
    c.add_argument("--out", type=Path, required=True, help="the JSON file to write (refused if it exists)")
    c.add_argument("--force", action="store_true", help="overwrite --out")
    args = p.parse_args(argv)
    if args.command == "stiffness":
        return stiffness_command(s, args)
    return labelled_command(args.command, args)


if __name__ == "__main__":
    sys.exit(main())
