"""Figure 6: the training curve, episode score (Σ r_t over the episode) against episode, stages 1 and 2.

Drawn from a run's `metrics.csv` (`cyberdog.metrics_csv`); the title names the run(s) shown by recipe and
seed ("table5, seed 0" for results/table5/policy/seed0/), so a figure cannot be mistaken for another policy's.
Each run's raw episode scores are drawn faint with a trailing moving mean on top, over the same number of
episodes in both stages (`WINDOW_EPISODES`, said in the legend); with several runs also their mean and 95 % CI
band (Student t, across runs).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from cyberdog.analysis.stats import mean_ci_band
from cyberdog.metrics_csv import read_stages, run_name
from plots.style import save_figure, styled

STEM = "figure6_reward_curves"
STAGE_TITLES = {1: "speed and direction, E = 0", 2: "with the energy term, Eq. (11)"}
WINDOW_EPISODES = 10  # episodes in the moving mean, both stages alike (4,000 env steps of 400-step episodes)


def moving_average(x: np.ndarray, window: int) -> np.ndarray:
    """Trailing mean over up to `window` points (the first points average what exists)."""
    x = np.asarray(x, dtype=float)
    c = np.cumsum(np.insert(x, 0, 0.0))
    idx = np.arange(1, len(x) + 1)
    lo = np.maximum(0, idx - window)
    return (c[idx] - c[lo]) / (idx - lo)


def labelled(metrics) -> dict[str, Path]:
    """{label: path} from a dict (kept) or from paths (labelled by recipe and seed, made unique)."""
    if isinstance(metrics, dict):
        return {str(k): Path(v) for k, v in metrics.items()}
    out: dict[str, Path] = {}
    for p in metrics:
        label, k = run_name(p), 1
        while label in out:
            k += 1
            label = f"{run_name(p)} ({k})"
        out[label] = Path(p)
    return out


@styled
def draw(metrics, window: int = WINDOW_EPISODES) -> Figure:
    """`metrics`: {run label: metrics.csv path} or a list of paths (labelled by recipe and seed); `window`:
    episodes in the trailing moving mean, the same in both stages."""
    if window < 1:
        raise ValueError(f"Figure 6's moving-mean window must be >= 1 episode, got {window}")
    runs = labelled(metrics)
    logs = {label: read_stages(p) for label, p in runs.items()}
    fig = Figure(figsize=(10, 3.8))
    axes = fig.subplots(1, 2)
    for ax, stage, tag in zip(axes, (1, 2), ("(a)", "(b)")):
        curves = []
        for i, (label, log) in enumerate(logs.items()):
            if stage not in log:
                continue
            ep, score = log[stage]["stage_episode"], log[stage]["score"]
            ma = moving_average(score, window)
            curves.append(ma)
            color = f"C{i % 10}"
            who = f"{label}: " if len(logs) > 1 else ""
            ax.plot(ep, score, color=color, alpha=0.25, lw=0.7, label=f"{who}episode score")
            if window > 1:
                ax.plot(ep, ma, color=color, lw=1.6, label=f"{who}moving mean of {window} episodes")
        if len(curves) > 1:
            n = min(len(c) for c in curves)
            m, ci = mean_ci_band(np.stack([c[:n] for c in curves]))
            x = np.arange(1, n + 1)
            ax.plot(x, m, color="k", lw=2, label=f"mean of {len(curves)} runs")
            ax.fill_between(x, m - np.nan_to_num(ci), m + np.nan_to_num(ci), color="k", alpha=0.15,
                            label="95 % CI")
        if curves:
            ax.legend(loc="lower right")
        else:
            ax.text(0.5, 0.5, f"no stage-{stage} episodes in the log", ha="center", va="center",
                    transform=ax.transAxes)
        ax.set_title(f"{tag} stage {stage}: {STAGE_TITLES[stage]}")
        ax.set_xlabel("episode (within the stage)")
        ax.set_ylabel("episode score Σ r_t")
        ax.grid(alpha=0.3)
    names = "; ".join(runs)
    fig.suptitle(f"Figure 6: reward curves of the two training stages, {'runs' if len(runs) > 1 else 'run'} "
                 f"{names} (moving mean over {window} episodes in both stages)", fontsize=10)
    return fig


def figure6(metrics, out_dir: str | Path, window: int = WINDOW_EPISODES, **save) -> list[Path]:
    """Draw Figure 6 from the training logs and write it into `out_dir`."""
    return save_figure(draw(metrics, window), out_dir, STEM, **save)


__all__ = ["STEM", "WINDOW_EPISODES", "draw", "figure6", "labelled", "moving_average"]
