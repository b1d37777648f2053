"""Learning curves of a seed sweep: episode score against env steps of each stage, mean and 95 % CI across
seeds, with the trainer's moving-window score.

Drawn from the sweep folder's `learning_curves.csv`, which `cyberdog.sweeps.aggregate` writes (every seed
interpolated onto one step grid per stage); Figure 6 (`plots.figure6`) shows single runs by episode instead.
"""
from __future__ import annotations

import csv
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from cyberdog.sweeps.aggregate import CURVES_CSV
from plots.style import save_figure, styled

STEM = "learning_curves"
CSV_NAME = CURVES_CSV  # written by cyberdog.sweeps.aggregate
NUMBER_COLUMNS = ("env_steps", "n_seeds", "score_mean", "score_ci95", "window_score_mean", "window_score_ci95")


def read_curves(path: str | Path) -> dict[int, dict[str, np.ndarray]]:
    """Per stage, every column of a learning_curves.csv as a float array (empty cells: NaN)."""
    out: dict[int, dict[str, list[float]]] = {}
    with open(path, newline="") as f:
        for row in csv.DictReader(f):
            d = out.setdefault(int(row["stage"]), {k: [] for k in NUMBER_COLUMNS})
            for k in NUMBER_COLUMNS:
                d[k].append(float(row[k]) if row.get(k) not in (None, "") else np.nan)
    return {s: {k: np.asarray(v) for k, v in d.items()} for s, d in sorted(out.items())}


@styled
def draw(curves: dict[int, dict[str, np.ndarray]], title: str = "") -> Figure:
    """One panel per stage: mean episode score with its 95 % band, and the moving-window mean."""
    if not curves:
        raise ValueError("no learning curves to draw")
    fig = Figure(figsize=(5.5 * len(curves), 4.0), layout="constrained")
    axes = fig.subplots(1, len(curves), squeeze=False)[0]
    for ax, (stage, c) in zip(axes, curves.items()):
        x, m, h = c["env_steps"], c["score_mean"], np.nan_to_num(c["score_ci95"])
        ax.fill_between(x, m - h, m + h, alpha=0.25, color="C0", label="95 % CI across seeds")
        ax.plot(x, m, color="C0", label="episode score, mean")
        ax.plot(x, c["window_score_mean"], color="C1", ls="--", label="moving-window score, mean")
        ax.set_title(f"stage {stage} ({int(c['n_seeds'][0])} seeds)")
        ax.set_xlabel("env steps in the stage")
        ax.set_ylabel("episode score")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    if title:
        fig.suptitle(title)
    return fig


def learning_curves(sweep_dir: str | Path, out_dir: str | Path | None = None, **save) -> list[Path]:
    """Draw the curves of `sweep_dir` (its learning_curves.csv) into `out_dir` (default: the sweep folder)."""
    sweep_dir = Path(sweep_dir)
    fig = draw(read_curves(sweep_dir / CSV_NAME), f"{sweep_dir.resolve().name}: mean and 95 % CI across seeds")
    return save_figure(fig, sweep_dir if out_dir is None else out_dir, STEM, **save)


__all__ = ["CSV_NAME", "STEM", "draw", "learning_curves", "read_curves"]
