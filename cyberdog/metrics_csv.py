"""Reading a training run's `metrics.csv` (one row per finished episode, written by `cyberdog.rl.logger`).

The one reader of that file for everything that draws or aggregates training curves (`plots/`,
`cyberdog.sweeps.aggregate`). It lives at the package's top level, beside the other file-format helpers,
rather than next to the writer in `cyberdog/rl/`, because importing `cyberdog.rl` imports torch and the
readers must not: plotting and aggregation run on machines and in processes that never train.

A file may be read while its run is still writing it, or after the run was killed: only complete lines
(ended by a newline) are read, so a row cut in the middle of a write is never half-parsed. Rows whose
`stage` is not an integer (a damaged line) are skipped. Empty cells (a column a row did not fill) and the
logger's "nan" (no update yet) both read as NaN.
"""
from __future__ import annotations

import csv
import io
import math
import re
from pathlib import Path

import numpy as np

SEED_FOLDER = re.compile(r"^(?:(?P<name>.+?)_)?seed(?P<seed>\d+)$")  # a run folder named by its seed: quick_seed0


def read_rows(path: str | Path) -> list[dict[str, str]]:
    """The complete rows of a metrics.csv as {column: text}; [] for a missing or empty file."""
    path = Path(path)
    if not path.is_file():
        return []
    data = path.read_bytes()
    end = data.rfind(b"\n") + 1  # a last line without its newline is a write the run did not finish
    text = data[:end].decode("utf-8", errors="replace")
    rows = []
    for row in csv.DictReader(io.StringIO(text, newline="")):
        if None in row or None in row.values():  # more or fewer cells than the header: a damaged line
            continue
        rows.append(row)
    return rows


def _number(text: str) -> float:
    try:
        return float(text)
    except (TypeError, ValueError):
        return math.nan


def read_stages(path: str | Path) -> dict[int, dict[str, np.ndarray]]:
    """Per training stage (ascending): every column of the file as a float array, one entry per episode,
    in the order the episodes were logged. {} for a missing or empty file."""
    per_stage: dict[int, list[dict[str, str]]] = {}
    for row in read_rows(path):
        try:
            stage = int(row["stage"])
        except (KeyError, ValueError):
            continue
        per_stage.setdefault(stage, []).append(row)
    out = {}
    for stage, rows in sorted(per_stage.items()):
        out[stage] = {col: np.array([_number(r[col]) for r in rows], dtype=float) for col in rows[0]}
    return out


def stage_summary(rows: list[dict], stage: int) -> dict:
    """Env steps, episodes, wall time (from the logged episode end times) and final scores of one stage, from
    `read_rows`' rows ({} for a stage the rows lack): what a shipped policy's metadata.json says of its training."""
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


def run_name(path: str | Path) -> str:
    """The name a figure gives the run that wrote `path`, by recipe and seed where its folders say them:
    results/table5/policy/seed0/metrics.csv and runs/table5/seed0/metrics.csv → "table5, seed 0",
    runs/quick_seed3/ → "quick, seed 3", a phase of a lineage runs/table5/seed5/<phase>/ → "table5, seed 5
    (<phase>)"; a run folder not named by its seed keeps its folder's name."""
    folder, phase = Path(path).resolve().parent, ""
    m = SEED_FOLDER.match(folder.name)
    if m is None and SEED_FOLDER.match(folder.parent.name):
        folder, phase = folder.parent, f" ({folder.name})"
        m = SEED_FOLDER.match(folder.name)
    if m is None:
        return folder.name or Path(path).stem
    recipe = m["name"]
    if recipe is None:  # .../<recipe>/seed<N> or .../<recipe>/policy/seed<N>
        recipe = folder.parent.parent.name if folder.parent.name == "policy" else folder.parent.name
    return (f"{recipe}, seed {int(m['seed'])}" if recipe else f"seed {int(m['seed'])}") + phase


__all__ = ["read_rows", "read_stages", "run_name", "stage_summary"]
