"""The README's figures: small PNGs of Figures 7, 10 and 13 of the shipped results and the walk strip, and their
inputs.

A full `evaluate.py` results folder is ~4 MB (mostly 10 s power traces of 49 walks at 1 kHz); the three
figures need a small part of it, shipped in `results/figures_input/`:

    config.yaml        the walk config (the gait the figures draw the baselines with)
    comparison.json    the paper set's rows (Figure 13a)
    walks.json         the walks Figure 10 shows (per speed: the first learned seed and the two baselines)
    power_traces.npz   their power, cut to the two gait cycles Figure 10 draws
    prototype.json     the prototype walks (Figure 13b)
    learned/<seed>.json  each seed's Figure 7 path (its reference leg's x–z path at 1.0 m/s)
    walk_strip.npz     the walk strip's cropped frames (written by `python -m plots.walk_strip`, not by the export)

`export_inputs(results_dir, dst)` writes that subset; drawn from it, the figures are the same as drawn from
the full folder (`tests/test_plots.py` checks). `python -m plots --from DIR --out plots/png --readme
--save-inputs results/figures_input` refreshes both after a new `evaluate.py` run; the README's figures are
redrawn from the shipped inputs with `python -m plots --from results/figures_input --out plots/png --readme`.
"""
from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np

from cyberdog.analysis.prototype_summary import REFERENCE
from plots.figure10 import chosen_walks, last_cycles_window
from plots.results import load_results

README_FIGURES = ("7", "10", "13", "walk_strip")
README_DPI = 80  # small enough for the repository (each PNG < 250 kB), large enough to read in a browser
ROOT = Path(__file__).resolve().parents[1]
SHIPPED_INPUTS = ROOT / "results" / "figures_input"
SHIPPED_PNG = ROOT / "plots" / "png"
INPUT_FILES = ("config.yaml", "comparison.json", "walks.json", "power_traces.npz", "prototype.json")


def export_inputs(results_dir: str | Path, dst: str | Path, cycles: int = 2) -> list[Path]:
    """Write the inputs of the README's figures from `results_dir` into `dst` (replacing what it held)."""
    results = load_results(results_dir)
    if not (results.rows and results.walks and results.learned):
        raise ValueError(f"{results_dir} lacks comparison.json, walks.json + power_traces.npz or learned/*.json "
                         "(a folder written by `evaluate.py` all or compare)")
    dst = Path(dst)
    if dst.resolve() == Path(results_dir).resolve():
        raise ValueError(f"--save-inputs {dst} is the folder the figures are drawn from")
    (dst / "learned").mkdir(parents=True, exist_ok=True)
    for old in [*(dst / "learned").glob("*.json"), *(dst / n for n in INPUT_FILES)]:
        old.unlink(missing_ok=True)  # only files this function writes: a stale seed must not linger
    paths = [dst / "config.yaml"]
    src = Path(results_dir)
    if (src / "config.yaml").is_file():
        shutil.copyfile(src / "config.yaml", paths[0])
    else:
        paths = []
    # Figure 13's rows, and the searched shape's: Table 5's row "learned against the direct search's shape"
    rows = [r for r in results.rows if r["trajectory"] in ("learned", "cycloid", "straight", REFERENCE)]
    shown = [w for by_key in chosen_walks(results.walks, results.gait.lift_height).values()
             for w in by_key.values()]
    power = {}
    for w in shown:  # only the window Figure 10 draws: its slice of the cut trace is the whole trace
        p = results.power[w["walk_id"]]
        power[f"walk_{w['walk_id']}"] = p[last_cycles_window(len(p), w["controller_dt_s"], w["period_s"], cycles)]
    outputs = {"comparison.json": rows, "walks.json": shown}
    if results.prototype_rows is not None:
        outputs["prototype.json"] = results.prototype_rows
    for name, data in outputs.items():
        (dst / name).write_text(json.dumps(data, indent=1) + "\n")
        paths.append(dst / name)
    np.savez_compressed(dst / "power_traces.npz", **power)
    paths.append(dst / "power_traces.npz")
    for label, traj in results.learned.items():
        paths.append(traj.save(dst / "learned" / f"{label}.json"))
    return paths


__all__ = ["README_DPI", "README_FIGURES", "SHIPPED_INPUTS", "SHIPPED_PNG", "export_inputs"]
