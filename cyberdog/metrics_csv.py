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
from pathlib import Path

import numpy as np


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


def run_name(path: str | Path) -> str:
    """The name a figure gives the run that wrote `path`: its run folder's name (e.g. `policy_speeds`)."""
    path = Path(path).resolve()
    return path.parent.name or path.stem


__all__ = ["read_rows", "read_stages", "run_name"]
