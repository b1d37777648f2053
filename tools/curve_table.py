#!/usr/bin/env python3
"""A run's learning curve as a table: its episodes binned by env steps of the stage.

Reads train.py's `metrics.csv` (one row per finished episode) and prints, per stage and per bin of env steps,
the number of episodes, their mean and longest length (agent steps), how many ended in a fall ("not logged" for
episodes logged before metrics.csv had a `fell` column), the mean episode score and the wall time the bin took
(a gap of over 10 min between two episodes, a stop and a --resume, not counted). Bins end at `--edges` (env
steps of the stage; default: every 100,000) and at the stage's last step; an episode falls in the bin holding
the env step it ended at.

    python tools/curve_table.py runs/paper_s0 --edges 20000 40000 60000 80000 100000
    python tools/curve_table.py runs/paper_s0/metrics.csv --out runs/paper_s0_curve.md
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from cyberdog.metrics_csv import read_rows, read_stages

COLUMNS = ("env steps", "episodes", "mean length (steps)", "longest", "falls", "mean score", "wall (min)")
PAUSE_S = 600.0  # s; no episode takes this long (400 agent steps), so a longer gap is a stop between runs
NEEDED = ("stage", "env_steps", "length", "score", "wall_time_s")  # and `fell` where logged (NaN where not)


def read_metrics(path: Path) -> dict[int, dict[str, np.ndarray]]:
    """Per stage, the log's columns (the package's reader, `cyberdog.metrics_csv`; an empty cell reads as NaN, and
    so does `fell` of a log older than that column) plus `stage_steps`: the env steps counted within the stage
    (`env_steps` is the run's total, so a stage's count starts at the previous stage's last)."""
    stages = read_stages(path)
    if not stages:
        rows = read_rows(path)  # why nothing: a file of other columns, or a log with no episode yet
        if rows and "stage" not in rows[0]:
            raise ValueError(f"{path}: not a train.py metrics.csv (no column stage)")
        raise ValueError(f"{path}: no episode logged yet")
    missing = [c for c in NEEDED if c != "stage" and any(c not in d for d in stages.values())]
    if missing:
        raise ValueError(f"{path}: not a train.py metrics.csv (no column {', '.join(missing)})")
    before = 0.0
    for d in stages.values():
        d.setdefault("fell", np.full(len(d["length"]), np.nan))
        d["stage_steps"] = d["env_steps"] - before
        before = float(d["env_steps"][-1])
    return stages


def bin_edges(last_step: float, edges: list[float] | None, every: float) -> list[float]:
    """Bin upper edges below the stage's last step, then that step: `edges` if given, else every `every`."""
    inner = sorted(edges) if edges else list(np.arange(every, last_step, every))
    return [e for e in inner if e < last_step] + [last_step]


def steps_label(lo: float, hi: float) -> str:
    def k(x: float) -> str:
        return f"{x:.0f}" if x < 1000 else f"{x / 1000:.0f} k" if round(x / 1000) < 1000 else f"{x / 1e6:.3g} M"
    return f"{k(lo)}–{k(hi)}"


def training_seconds(wall_time_s: np.ndarray, pause_s: float = PAUSE_S) -> np.ndarray:
    """Seconds of training behind each episode: the wall-clock time since the episode logged before it, with a
    gap longer than `pause_s` (a stop and a --resume) counted as nothing; the stage's first episode: 0."""
    dt = np.diff(wall_time_s, prepend=wall_time_s[0])
    return np.where(dt > pause_s, 0.0, dt)


def _falls(flags: np.ndarray) -> str:
    """How many episodes fell, and their share, among those whose log says ("not logged" where none does)."""
    known = flags[~np.isnan(flags)]
    if not known.size:
        return "not logged"
    n = int(known.sum())
    return f"{n:,} ({n / known.size:.1%})" + ("" if known.size == flags.size else f" of {known.size:,} logged")


def curve_rows(stage: dict[str, np.ndarray], edges: list[float] | None = None, every: float = 100_000
               ) -> list[dict]:
    """One row per bin of `stage` (a `read_metrics` entry); a bin with no episode ending in it is left out."""
    steps = stage["stage_steps"]
    busy = training_seconds(stage["wall_time_s"])
    rows, lo = [], 0.0
    for hi in bin_edges(float(steps[-1]), edges, every):
        sel = (steps > lo) & (steps <= hi)
        if sel.any():
            rows.append({"env steps": steps_label(lo, hi), "episodes": int(sel.sum()),
                         "mean length (steps)": float(stage["length"][sel].mean()),
                         "longest": int(stage["length"][sel].max()),
                         "falls": _falls(stage["fell"][sel]),
                         "mean score": float(stage["score"][sel].mean()),
                         "wall (min)": float(busy[sel].sum()) / 60.0})
        lo = hi
    return rows


def markdown(rows: list[dict]) -> str:
    fmt = {"mean length (steps)": "{:.1f}", "mean score": "{:+.2f}", "wall (min)": "{:.1f}"}
    lines = ["| " + " | ".join(COLUMNS) + " |", "|" + "---|" * len(COLUMNS)]
    for r in rows:
        cells = [fmt[c].format(r[c]) if c in fmt else (f"{r[c]:,}" if isinstance(r[c], int) else r[c])
                 for c in COLUMNS]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("run", type=Path, help="a run folder of train.py, or its metrics.csv")
    p.add_argument("--edges", type=float, nargs="+", default=None,
                   help="upper edges of the bins, env steps of the stage (default: every --every)")
    p.add_argument("--every", type=float, default=100_000, help="bin width in env steps (default 100000)")
    p.add_argument("--out", type=Path, default=None, help="also write the tables to this markdown file")
    args = p.parse_args(argv)
    path = args.run / "metrics.csv" if args.run.is_dir() else args.run
    if not path.is_file():
        p.error(f"{path}: no such metrics file")
    if args.every <= 0 or (args.edges and min(args.edges) <= 0):
        p.error("bin edges and --every must be positive env-step counts")
    try:
        stages = read_metrics(path)
    except ValueError as err:
        p.error(str(err))
    text = []
    for s, d in stages.items():
        text.append(f"stage {s}: {len(d['length']):,} episodes, {int(d['stage_steps'][-1]):,} env steps "
                    f"({path})\n\n" + markdown(curve_rows(d, args.edges, args.every)))
    out = "\n\n".join(text)
    print(out)
    if args.out:
        if args.out.resolve() == path.resolve():
            p.error("--out would overwrite the metrics file it reads")
        args.out.parent.mkdir(parents=True, exist_ok=True)
        args.out.write_text(out + "\n")
        print(f"wrote {args.out}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
