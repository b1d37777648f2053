#!/usr/bin/env python
"""Copy a finished training run into a small shipped result folder (results/<recipe>/policy/seed<N>/).

    python tools/ship_result.py runs/table5/seed0 --out results/table5/policy/seed0

The run is a train.py run folder, or a seed folder of a preset's phases. Writes (never over an existing folder
unless --force): stage1_actor.pt and stage2_actor.pt (the final actors of the two stages; no stage1_actor.pt for
a stage-2 run started from another's agent), config.yaml (the resolved experiment), metrics.csv (the training
log, for Figure 6) and metadata.json (seed, env steps, episodes and wall time per stage, final window scores, the
git commit of the code, the source run). Checkpoints with replay buffers are not copied (tens of MB).

A seed folder ships its last phase's run, or with --all-phases the recipe's two actors: stage<N>_actor.pt from
the last phase that ends with stage N, config.yaml and metrics.csv of the last phase, recipe_phases.yaml (every
phase's resolved settings), metrics_<phase>.csv of each phase and, in metadata.json, each phase's summary. A
phase whose final agent was copied into the seed folder from another (a lineage continued from a kept `main`)
has no log there: metadata.json lists it under placed_phases, and its wall time is not in the seed's.
"""
from __future__ import annotations

import argparse
import csv
import json
import shutil
import subprocess
import sys
from pathlib import Path

from cyberdog.config.preset import final_run, is_lineage, read_phases
from cyberdog.provenance import portable_path

REPO = Path(__file__).resolve().parents[1]
FILES = {"stage1_final_actor.pt": "stage1_actor.pt", "stage2_final_actor.pt": "stage2_actor.pt",
         "config.yaml": "config.yaml", "metrics.csv": "metrics.csv"}
OPTIONAL = {"stage1_final_actor.pt"}  # a stage-2 run started with --init-from has no stage-1 actor of its own
MAX_BYTES = 2_000_000  # the shipped folder stays under 2 MB


def stage_summary(rows: list[dict], stage: int) -> dict:
    """Env steps, episodes, wall time (from the logged episode end times) and final scores of one stage."""
    rs = [r for r in rows if int(r["stage"]) == stage]
    if not rs:
        return {}
    t = [float(r["wall_time_s"]) for r in rs]  # the clock time at each episode's end
    first_rate = float(rs[0]["env_steps_per_s"]) or float("nan")
    first_episode_s = float(rs[0]["length"]) / first_rate  # the first episode ran before the first log line
    gaps = sorted(b - a for a, b in zip(t, t[1:]))
    typical = gaps[len(gaps) // 2] if gaps else 0.0
    # a run resumed later (killed, or continued under a raised budget) has one long gap: counted as a typical
    # episode, so that the wall time is the training's, not the calendar's
    pauses = [g for g in gaps if g > max(20 * typical, 60.0)]
    return {"episodes": len(rs), "env_steps": int(sum(int(r["length"]) for r in rs)),
            "wall_time_s": round(t[-1] - t[0] - sum(pauses) + typical * len(pauses) + first_episode_s, 1),
            "pauses_excluded": len(pauses),
            "final_window_mean_score": float(rs[-1]["window_mean_score"]),
            "last_episode_score": float(rs[-1]["score"]),
            "last_episode_energy_J": float(rs[-1]["energy_J"])}


def git_commit() -> str:
    try:
        out = subprocess.run(["git", "rev-parse", "HEAD"], cwd=REPO, capture_output=True, text=True, check=True)
        return out.stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("run_dir", type=Path, help="a finished run folder (train.py output): both stages, or stage 2 "
                   "alone started from another's agent; or a preset's seed folder (its last phase's run)")
    p.add_argument("--out", type=Path, required=True, help="the shipped folder, e.g. results/table5/policy/seed0")
    p.add_argument("--force", action="store_true", help="replace an existing output folder")
    p.add_argument("--note", default="", help="free text stored in metadata.json")
    p.add_argument("--init-from", type=Path, default=None, metavar="ACTOR",
                   help="the file the run started from (train.py --init-from), where it is shipped: recorded in "
                        "metadata.json as init_from, relative to the repository")
    p.add_argument("--all-phases", action="store_true",
                   help="a preset's seed folder: ship the last stage-1 and the last stage-2 phase's actors and "
                        "every phase's log (default: its last phase's run)")
    args = p.parse_args(argv)
    if args.all_phases:
        return ship_lineage(args)
    if final_run(args.run_dir) != args.run_dir:
        args.run_dir = final_run(args.run_dir)
        print(f"a preset's seed folder: shipping its last phase, {args.run_dir}")
    missing = [f for f in FILES if not (args.run_dir / f).is_file() and f not in OPTIONAL]
    if missing:
        sys.exit(f"{args.run_dir} is not a finished run: missing {missing}")
    if args.out.exists() and not args.force:
        sys.exit(f"{args.out} exists; pass --force to replace it")
    if args.init_from is not None and not args.init_from.is_file():
        sys.exit(f"--init-from {args.init_from}: no such file (the run's start, where it is shipped)")
    args.out.mkdir(parents=True, exist_ok=True)
    for src, dst in FILES.items():
        if (args.run_dir / src).is_file():
            shutil.copy2(args.run_dir / src, args.out / dst)
    rows = _rows(args.run_dir)
    import yaml
    cfg = yaml.safe_load((args.run_dir / "config.yaml").read_text())
    meta = {"seed": cfg["train"]["seed"], "source_run": portable_path(args.run_dir), "git_commit": git_commit(),
            "stage1": stage_summary(rows, 1), "stage2": stage_summary(rows, 2), "note": args.note,
            **({"init_from": portable_path(args.init_from)} if args.init_from is not None else {}),
            "actors": "stage<N>_actor.pt = stage<N>_final_actor.pt of the run (the agent at the end of the stage)"}
    return write_metadata(args.out, meta)


def write_metadata(out: Path, meta: dict) -> int:
    """`out`/metadata.json, then the folder's files and size (a warning over MAX_BYTES); the exit status."""
    (out / "metadata.json").write_text(json.dumps(meta, indent=1) + "\n")
    size = sum(f.stat().st_size for f in out.iterdir())
    print(f"wrote {out} ({size / 1e6:.2f} MB): " + ", ".join(sorted(f.name for f in out.iterdir())))
    if size > MAX_BYTES:
        print(f"warning: {size / 1e6:.2f} MB is over the 2 MB the shipped folder should stay under", file=sys.stderr)
    return 0


def _rows(run: Path) -> list[dict]:
    with open(run / "metrics.csv") as f:
        return list(csv.DictReader(f))


def ship_lineage(args) -> int:
    """--all-phases: the recipe's two actors and every phase's log, from a preset's seed folder."""
    import yaml

    if not is_lineage(args.run_dir):
        sys.exit(f"{args.run_dir} is not a preset's seed folder (no phases.yaml): --all-phases needs one")
    phases = read_phases(args.run_dir)[0]
    runs = {p.name: args.run_dir / p.name for p in phases}
    shipped = {stage: next((p for p in reversed(phases) if p.last_stage == stage), None) for stage in (1, 2)}
    missing = [p.final_agent for p in phases if not (args.run_dir / p.final_agent).is_file()]
    missing += [f"{p.name}/stage{stage}_final_actor.pt" for stage, p in shipped.items()
                if p is not None and not (runs[p.name] / f"stage{stage}_final_actor.pt").is_file()]
    if missing:
        sys.exit(f"{args.run_dir} is not a finished lineage: missing {missing}")
    # a phase whose final agent was copied in from another folder (the lineage skips it) has no log of its own
    placed = [p.name for p in phases if not (runs[p.name] / "metrics.csv").is_file()]
    if phases[-1].name in placed:
        sys.exit(f"{args.run_dir}: its last phase {phases[-1].name} has no metrics.csv (it was not trained here)")
    if args.out.exists() and not args.force:
        sys.exit(f"{args.out} exists; pass --force to replace it")
    args.out.mkdir(parents=True, exist_ok=True)
    actors = {}
    for stage, last in shipped.items():
        if last is not None:
            shutil.copy2(runs[last.name] / f"stage{stage}_final_actor.pt", args.out / f"stage{stage}_actor.pt")
            actors[f"stage{stage}_actor.pt"] = f"{last.name}/stage{stage}_final_actor.pt"
    final = runs[phases[-1].name]
    shutil.copy2(final / "config.yaml", args.out / "config.yaml")
    shutil.copy2(final / "metrics.csv", args.out / "metrics.csv")
    # under another name: the shipped folder is not a lineage that train.py or extract --sweep would walk into
    shutil.copy2(args.run_dir / "phases.yaml", args.out / "recipe_phases.yaml")
    summaries = {}
    for p in phases:
        if p.name in placed:
            summaries[p.name] = {"stage": p.stage, "from": p.start, "placed": True}
            continue
        shutil.copy2(runs[p.name] / "metrics.csv", args.out / f"metrics_{p.name}.csv")
        rows = _rows(runs[p.name])
        summary = {s: stage_summary(rows, s) for s in (1, 2)}
        summaries[p.name] = {"stage": p.stage, "from": p.start, **{f"stage{s}": v for s, v in summary.items() if v},
                             "falls": sum(r.get("fell") in ("1", "True", "true") for r in rows)}
    wall = sum(ph[k]["wall_time_s"] for ph in summaries.values() for k in ("stage1", "stage2") if k in ph)
    meta = {"seed": yaml.safe_load((final / "config.yaml").read_text())["train"]["seed"],
            "source_run": portable_path(args.run_dir), "git_commit": git_commit(), "actors": actors,
            "phases": summaries, "wall_time_s": round(wall, 1), "placed_phases": placed, "note": args.note}
    return write_metadata(args.out, meta)


if __name__ == "__main__":
    sys.exit(main())
