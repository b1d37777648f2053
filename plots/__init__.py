"""The paper's figures, drawn from saved results only (matplotlib; each figure as PNG and PDF).

One module per figure; none runs physics or imports the simulator or torch (`tests/test_plots.py` checks):

    figure4          the common foot trajectories (computed by the pure-numpy `cyberdog.core.trajectories`)
    figure6          the training curve: episode score over episodes, from a run's metrics.csv
    figure7          the learned foot trajectory against the common ones, from learned/*.json
    figure10         joint power Σ|τ·θ̇| over two gait cycles, from walks.json + power_traces.npz
    figure13         energy (comparison.json) and battery use (prototype.json) against speed
    learning_curves  a seed sweep's curves with a 95 % band, from its learning_curves.csv
    results          reading a results folder written by `evaluate.py`
    walk_strip       the README's picture: the trot's frames (learned, cycloid) from `evaluate.py video`, the feet's paths
    shipped          the README's copies of Figures 7, 10 and 13 and the small inputs they are drawn from

`draw_all(results_dir, out_dir)` draws every figure the folder has inputs for; each module's `figureN(...)`
draws one and its `draw(...)` returns the matplotlib Figure; `python -m plots` is the command line.
"""
from __future__ import annotations

from pathlib import Path

from plots import figure4, figure6, figure7, figure10, figure13, learning_curves  # the modules
from plots.results import load_results
from plots.style import DPI

FIGURES = ("4", "6", "7", "10", "13", "learning_curves", "walk_strip")


def draw_all(results_dir: str | Path, out_dir: str | Path, metrics=None, only=None, dpi: int = DPI,
             pdf: bool = True, learned=None, log=print) -> list[Path]:
    """Draw every figure that `results_dir` (a folder written by `evaluate.py`) has the inputs for into
    `out_dir`; returns the files written.

    metrics: training logs for Figure 6 ({label: metrics.csv} or a list of paths); default: the folder's own
    metrics.csv if it is a training run folder. only: figure names to draw (of FIGURES, "figure" prefix
    optional; default all). learned: files or folders of learned paths for Figure 7 instead of the folder's.
    """
    results = load_results(results_dir, learned)
    wanted = set(FIGURES if only is None else (str(f).removeprefix("figure") for f in only))
    unknown = wanted - set(FIGURES)
    if unknown:
        raise ValueError(f"unknown figure(s) {sorted(unknown)}; choose from {', '.join(FIGURES)}")
    if metrics is None and (results.folder / "metrics.csv").is_file():
        metrics = [results.folder / "metrics.csv"]
    g, save = results.gait, {"dpi": dpi, "pdf": pdf}
    skipped, paths = [], []
    if "4" in wanted:
        paths += figure4.figure4(out_dir, 0.2, g.lift_height, g.straight_shape, g.swing_time, g.stance_time, **save)
    if "6" in wanted:
        if metrics:
            paths += figure6.figure6(metrics, out_dir, **save)
        else:
            skipped.append("6 (no training log: pass metrics.csv)")
    if "7" in wanted:
        if results.learned:
            paths += figure7.figure7(results.learned, out_dir, g.straight_shape, g.lift_height, g.swing_time,
                             g.stance_time, **save)
        else:
            skipped.append("7 (no learned/*.json)")
    if "10" in wanted:
        if results.walks:
            paths += figure10.figure10(results.walks, results.power, out_dir, g.lift_height, **save)
        else:
            skipped.append("10 (no walks.json + power_traces.npz)")
    if "13" in wanted:
        if results.rows:
            paths += figure13.figure13(results.rows, out_dir, results.prototype_rows, **save)
        else:
            skipped.append("13 (no comparison.json)")
    if "learning_curves" in wanted and (results.folder / learning_curves.CSV_NAME).is_file():
        paths += learning_curves.learning_curves(results.folder, out_dir, **save)
    if "walk_strip" in wanted:
        from plots import walk_strip  # here, not above: `python -m plots.walk_strip` runs it as __main__

        if (results.folder / walk_strip.INPUT_NAME).is_file():
            paths += walk_strip.walk_strip(results.folder, out_dir, **save)
        elif only is not None:
            skipped.append(f"walk_strip (no {walk_strip.INPUT_NAME}: python -m plots.walk_strip)")
    if skipped and log:
        log(f"figures skipped (no input in {results.folder}): {'; '.join(skipped)}")
    return paths


__all__ = ["FIGURES", "draw_all"]
