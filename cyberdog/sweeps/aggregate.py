"""Across-seed results of a sweep: learning curves with a 95 % band, evaluation of every seed's policies, tables.

Written into the sweep folder (inputs — the seed run folders — are only read):

    learning_curves.png / .csv   Figure 6 with bands: episode score vs env steps of the stage, stage 1 and stage
                                 2, every seed interpolated onto a common step grid (the steps all seeds
                                 reached), mean and 95 % t-interval across seeds; also the trainer's
                                 moving-window score
    evaluation.json              per seed: run_dir, actor files, training summary and rollout metrics of the
                                 stage-1 and stage-2 final actors; then mean, 95 % CI half-width and n per metric
    aggregate.csv / .md          the summary table: one row per seed, then mean and 95 % CI

Evaluation is one deterministic `rollout` per actor (`cyberdog.rl.rollout`, the env the actor was trained in,
`speed` m/s for `duration` s): mean speed over the second half, fell, energy per metre (Eq. 7 energy over
forward distance), and the stage-2 vs stage-1 change of energy per metre in %. `duration=0` skips it.

Part of the sweeps package (the design's "sweeps" layer owns aggregation): it reads the sweep folder's
format (sweep.json, seed<N>/), so it lives beside the code that writes that format, and the analysis layer
below knows nothing about sweeps.
"""
from __future__ import annotations

import csv
import json
import math
import re
from functools import partial
from pathlib import Path

import numpy as np

from cyberdog import config as C
from cyberdog.analysis.parallel import map_in_processes
from cyberdog.analysis.report import json_safe, markdown_table, write_rows
from cyberdog.analysis.stats import mean_ci, mean_ci_band
from cyberdog.metrics_csv import read_stages
from cyberdog.sweeps.folder import is_sweep_dir, load_sweep, seed_dir
from cyberdog.sweeps.process import SweepError

EVAL_FORMAT, EVAL_VERSION = "cyberdog-sweep-evaluation", 1
ROLLOUT_METRICS = ("mean_speed_mps", "fell", "energy_per_m_J", "distance_m", "energy_J")
GRID_POINTS = 200
CURVES_CSV = "learning_curves.csv"  # the bands on the step grid (plots.learning_curves draws them)
# a process pool for the rollouts only pays off when they are long (each worker imports torch and PyBullet)
PARALLEL_EVAL_MIN_S = 60.0


# ---- inputs ----------------------------------------------------------------------------------------------------
def seed_runs(sweep_dir) -> list[tuple[str, Path]]:
    """(label, run folder) of every seed: from sweep.json if the folder is a sweep, else every sub-folder with a
    metrics.csv (so a hand-made folder of runs aggregates too)."""
    sweep_dir = Path(sweep_dir)
    if not sweep_dir.is_dir():
        raise SweepError(f"{sweep_dir} is not a folder")
    if is_sweep_dir(sweep_dir):
        return [(str(s), C.final_run(seed_dir(sweep_dir, s))) for s in load_sweep(sweep_dir).seeds]
    runs = sorted((p for p in sweep_dir.iterdir() if (p / "metrics.csv").is_file()),
                  key=lambda p: (int(m[1]) if (m := re.fullmatch(r"seed(\d+)", p.name)) else math.inf, p.name))
    if not runs:
        raise SweepError(f"{sweep_dir} is neither a sweep folder (sweep.json) nor a folder of run folders "
                         f"(sub-folders with metrics.csv)")
    return [(m[1] if (m := re.fullmatch(r"seed(\d+)", p.name)) else p.name, p) for p in runs]


def stage_curves(run_dir) -> dict[int, dict[str, np.ndarray]]:
    """Per stage: env steps since the stage began (at each episode end), episode score, window-mean score."""
    out = {}
    for stage, log in read_stages(Path(run_dir) / "metrics.csv").items():  # complete rows only
        # the stage's first episode starts with the stage (fresh env), so its start is env_steps - length
        start = log["env_steps"][0] - log["length"][0]
        out[stage] = {"env_steps": log["env_steps"] - start, "score": log["score"],
                      "window_score": log["window_mean_score"]}
    return out


def training_summary(curves: dict) -> dict:
    out = {}
    for stage, c in curves.items():
        out[f"stage{stage}_env_steps"] = int(c["env_steps"][-1])
        out[f"stage{stage}_episodes"] = int(len(c["score"]))
        out[f"stage{stage}_best_score"] = float(np.max(c["score"]))
        out[f"stage{stage}_final_window_score"] = float(c["window_score"][-1])
    return out


# ---- learning curves -------------------------------------------------------------------------------------------
def learning_curves(per_seed: list[dict], points: int = GRID_POINTS) -> dict[int, dict[str, np.ndarray]]:
    """Interpolate every seed's curves onto one grid per stage spanning the steps all seeds reached; mean and
    95 % CI half-width across seeds at every grid point."""
    out = {}
    for stage in sorted({s for c in per_seed for s in c}):
        curves = [c[stage] for c in per_seed if stage in c and len(c[stage]["env_steps"])]
        lo = max(c["env_steps"][0] for c in curves)
        hi = min(c["env_steps"][-1] for c in curves)
        grid = np.linspace(lo, hi, points) if hi > lo else np.array([hi])
        res = {"env_steps": grid, "n_seeds": np.full(grid.shape, len(curves))}
        for key in ("score", "window_score"):
            stacked = np.array([np.interp(grid, c["env_steps"], c[key]) for c in curves])
            res[f"{key}_mean"], res[f"{key}_ci95"] = mean_ci_band(stacked)
        out[stage] = res
    return out


def write_learning_curves(curves: dict, folder: Path, draw=None) -> list[Path]:
    """learning_curves.csv (the bands on the step grid), then, with `draw` (folder → files written, e.g. the
    checkout's `plots.learning_curves`), the figure drawn from it."""
    folder = Path(folder)
    path = folder / CURVES_CSV
    cols = ["stage", "env_steps", "n_seeds", "score_mean", "score_ci95", "window_score_mean", "window_score_ci95"]
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(cols)
        for stage, c in curves.items():
            for i in range(len(c["env_steps"])):
                w.writerow([stage] + [float(c[k][i]) if k != "n_seeds" else int(c[k][i]) for k in cols[1:]])
    return [path, *(draw(folder) if draw is not None else [])]


# ---- evaluation -------------------------------------------------------------------------------------------------
def evaluate_actor(path: str, speed: float, duration: float, seed: int = 0) -> dict:
    """Rollout metrics of one actor file (module-level so that a process pool can run it)."""
    import torch

    from cyberdog.rl.rollout import load_actor, rollout

    torch.set_num_threads(1)
    r = rollout(load_actor(path), speed=speed, duration=duration, seed=seed)
    return {k: v for k, v in r.summary().items()}


def check_eval_options(eval_duration: float | None, eval_speed: float | None) -> None:
    """SweepError for an evaluation rollout length or speed that cannot be (None: the default, fine)."""
    if eval_duration is not None and not (math.isfinite(eval_duration) and eval_duration >= 0):
        raise SweepError(f"--eval-duration must be >= 0 s (0 = no evaluation), got {eval_duration}")
    if eval_speed is not None and not (math.isfinite(eval_speed) and eval_speed >= 0):
        raise SweepError(f"--eval-speed must be >= 0 m/s, got {eval_speed}")


def aggregate_sweep(sweep_dir, eval_duration: float = 10.0, eval_speed: float = 1.0, workers: int = 1,
                    progress: bool = True, echo=print, draw_learning_curves=None) -> dict:
    """Read every seed's metrics.csv, evaluate its final actors, and write the curves, evaluation.json and the
    summary table into `sweep_dir`. Seeds without data are listed under "missing", not fatal.
    draw_learning_curves: folder → files, draws learning_curves.png from the CSV (None: the CSV only)."""
    check_eval_options(eval_duration, eval_speed)
    sweep_dir = Path(sweep_dir)
    entries, missing, curves_per_seed = _read_seeds(sweep_dir)
    stages = sorted({s for c in curves_per_seed for s in c})
    if eval_duration > 0:
        _evaluate_actors(entries, eval_speed, eval_duration, workers, progress, echo)
    rows, stats, columns = _summary(entries, stages, eval_duration > 0)
    md = _write_summary(sweep_dir, rows, stats, columns, missing, eval_duration, eval_speed)
    curves = learning_curves(curves_per_seed)
    figure = write_learning_curves(curves, sweep_dir, draw_learning_curves)[1:]
    evaluation = {"format": EVAL_FORMAT, "version": EVAL_VERSION, "sweep_dir": str(sweep_dir.resolve()),
                  "evaluation": ({"speed_mps": eval_speed, "duration_s": eval_duration, "rollout_seed": 0,
                                  "reward": "stage2"} if eval_duration > 0 else None),
                  "seeds": entries, "mean_ci95": stats, "missing": missing}
    (sweep_dir / "evaluation.json").write_text(json.dumps(json_safe(evaluation), indent=1) + "\n")
    echo(f"aggregate: wrote aggregate.csv/.md, evaluation.json, {CURVES_CSV}"
         + (f", {', '.join(p.name for p in figure)}" if figure else " (no figure: `python -m plots --from "
            f"{sweep_dir}` draws it)") + f" in {sweep_dir}")
    return {"rows": rows, "stats": stats, "curves": curves, "evaluation": evaluation, "markdown": md}


def _read_seeds(sweep_dir: Path) -> tuple[list[dict], list[dict], list[dict]]:
    """(entries, missing, curves per seed): each seed with logged episodes, its actors and training summary."""
    entries, missing, curves_per_seed = [], [], []
    for label, run_dir in seed_runs(sweep_dir):
        curves = stage_curves(run_dir)
        if not curves:
            missing.append({"seed": label, "run_dir": str(run_dir.resolve()), "reason": "no metrics.csv rows"})
            continue
        curves_per_seed.append(curves)
        actors = {f"stage{s}": str((run_dir / f"stage{s}_final_actor.pt").resolve()) for s in sorted(curves)
                  if (run_dir / f"stage{s}_final_actor.pt").is_file()}
        entries.append({"seed": int(label) if label.isdigit() else label, "run_dir": str(run_dir.resolve()),
                        "actors": actors, "training": training_summary(curves), "metrics": {}})
    if not entries:
        raise SweepError(f"{sweep_dir}: no seed has logged an episode yet; nothing to aggregate")
    return entries, missing, curves_per_seed


def _evaluate_actors(entries: list[dict], speed: float, duration: float, workers: int, progress: bool,
                     echo) -> None:
    """One rollout of every final actor into its entry's "metrics", and the stage-2 vs stage-1 energy change."""
    from tqdm import tqdm

    jobs = [(i, name, path) for i, e in enumerate(entries) for name, path in e["actors"].items()]
    if not jobs:
        return
    echo(f"aggregate: evaluating {len(jobs)} actors ({duration:g} s at {speed:g} m/s each)")
    bar = tqdm(total=len(jobs), unit="rollout", desc="evaluate", disable=not progress, dynamic_ncols=True)
    parallel = workers > 1 and len(jobs) > 1 and duration * len(jobs) >= PARALLEL_EVAL_MIN_S
    try:
        metrics = map_in_processes(partial(evaluate_actor, speed=speed, duration=duration),
                                   [p for _, _, p in jobs], workers=min(workers, len(jobs)) if parallel else 1,
                                   on_result=lambda *_: bar.update())
    finally:
        bar.close()
    for (i, n, _), m in zip(jobs, metrics):
        entries[i]["metrics"][n] = m
    for e in entries:
        m = e["metrics"]
        if "stage1" in m and "stage2" in m:
            e1, e2 = m["stage1"]["energy_per_m_J"], m["stage2"]["energy_per_m_J"]
            m["energy_per_m_change_pct"] = 100.0 * (e2 - e1) / e1 if e1 and math.isfinite(e1) else math.nan


def _summary(entries: list[dict], stages: list[int], evaluated: bool) -> tuple[list[dict], dict, list[str]]:
    """(rows, stats, columns) of the summary table: one row per seed; mean, 95 % CI and n per column."""
    columns = ["seed"] + [f"stage{s}_{k}" for s in stages for k in ("env_steps", "episodes", "final_window_score")]
    if evaluated:
        columns += [f"stage{s}_{k}" for s in stages for k in ("mean_speed_mps", "fell", "energy_per_m_J")]
        if stages == [1, 2]:
            columns.append("energy_per_m_change_pct")
    rows = []
    for e in entries:
        row = {"seed": e["seed"], **{k: v for k, v in e["training"].items() if k in columns}}
        for s in stages:
            row.update({f"stage{s}_{k}": v for k, v in e["metrics"].get(f"stage{s}", {}).items()
                        if f"stage{s}_{k}" in columns})
        if "energy_per_m_change_pct" in e["metrics"]:
            row["energy_per_m_change_pct"] = e["metrics"]["energy_per_m_change_pct"]
        rows.append(row)
    stats = {}
    for c in columns[1:]:
        values = [float(r[c]) for r in rows if c in r and r[c] is not None]
        m, h = mean_ci(values)
        stats[c] = {"mean": m, "ci95": h, "n": int(np.isfinite(values).sum()) if values else 0}
    return rows, stats, columns


def _write_summary(sweep_dir: Path, rows: list[dict], stats: dict, columns: list[str], missing: list[dict],
                   eval_duration: float, eval_speed: float) -> str:
    """aggregate.csv/.json (the rows, then the mean and ci95 rows) and aggregate.md (with its legend); returns
    the Markdown."""
    write_rows(rows + [{"seed": s, **{c: stats[c][k] for c in columns[1:]}} for s, k in (("mean", "mean"),
                                                                                         ("ci95", "ci95"))],
               sweep_dir, "aggregate", columns)
    md_rows = rows + [{"seed": "**mean ± 95 % CI**",
                       **{c: (f"{stats[c]['mean']:.4g} ± {stats[c]['ci95']:.2g}" if math.isfinite(stats[c]["ci95"])
                              else f"{stats[c]['mean']:.4g}") for c in columns[1:]}}]
    eval_line = (f"Evaluation: one deterministic rollout per final actor, {eval_duration:g} s at {eval_speed:g} m/s; "
                 f"`fell` in the mean row is the fraction of seeds that fell." if eval_duration > 0
                 else "No evaluation (eval duration 0).")
    md = (f"# Sweep {sweep_dir.name}: {len(rows)} seeds\n\n{markdown_table(md_rows, columns)}\n\n"
          f"stage<N>_env_steps: env steps of the stage at the end of its last logged episode; final window score: "
          f"the trainer's moving-window mean episode score at that episode. 95 % CI: half-width of the Student-t "
          f"interval of the mean across seeds. {eval_line}\n")
    if missing:
        md += "\nMissing: " + "; ".join(f"seed {m['seed']} ({m['reason']})" for m in missing) + "\n"
    (sweep_dir / "aggregate.md").write_text(md)
    return md
