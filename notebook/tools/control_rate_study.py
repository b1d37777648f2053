#!/usr/bin/env python3
"""Convergence study of the two rates of the simulated robot: the joint controller's and the contact solver's.

For each cell of the grid, control rate 1000 / 400 / 200 Hz (whole divisors of the agent's Ts = 25 ms) x
physics step 0.5 / 1 / 1.25 ms (where it divides the control period), plus the reference (control and physics
at 2 kHz), this script

1. runs `evaluate.py compare` on the shipped learned paths (results/table5/paths/, 5 seeds x 1.0 / 1.2 / 1.4 m/s)
   with `--set sim.controller_dt=... sim.physics_dt=...`, into `<out>/<cell>/` (Table 5 at matched lift and
   the paper's protocol, every walk in comparison.json);
2. times the shipped training preset's env (configs/table5.yaml: foot mode, zero action, stage-2
   reward) at that cell, in this process, CPU time;

and prints one markdown table: per cell, the mean Eq. (7) and electrical energy of the baselines (composite
cycloid and straight line, at matched lift and at the paper's 0.15 m) and of the learned paths, each as its
deviation from the reference cell; D_t at matched lift per speed; falls and walks outside the ±5 % speed band;
env steps/s. The table is also written to `<out>/study.md` and the numbers to `<out>/study.json`.

    python notebook/tools/control_rate_study.py [--out runs/control_rate] [--cells 400:1.25 1000:1 ...] [--workers 2]

A cell already computed (its folder holds table5_summary.csv) is read, not walked again: the study resumes.
"""
from __future__ import annotations

import argparse
import json
import math
import statistics
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
REFERENCE = (2000, 0.5)  # (control Hz, physics ms)
GRID = [(1000, 0.5), (1000, 1.0), (400, 0.5), (400, 1.25), (200, 0.5), (200, 1.0), (200, 1.25)]
SPEEDS = (1.0, 1.2, 1.4)
BASELINES = ("cycloid", "straight")


def cell_name(hz: int, ms: float) -> str:
    return f"control{hz}Hz_physics{ms:g}ms"


def sim_sets(hz: int, ms: float) -> list[str]:
    return [f"sim.controller_dt={1.0 / hz:.10g}", f"sim.physics_dt={ms / 1e3:.10g}"]


def run_cell(hz: int, ms: float, out: Path, workers: int) -> Path:
    folder = out / cell_name(hz, ms)
    if (folder / "table5_summary.csv").is_file():
        print(f"{folder.name}: already walked, read from {folder}", flush=True)
        return folder
    cmd = [sys.executable, str(ROOT / "evaluate.py"), "compare", "--no-reference", "--workers", str(workers),
           "--out", str(folder), "--force", "--set", *sim_sets(hz, ms)]
    print(f"{folder.name}: {' '.join(cmd[1:])}", flush=True)
    t0 = time.perf_counter()
    subprocess.run(cmd, check=True, cwd=ROOT, stdout=subprocess.DEVNULL)
    print(f"{folder.name}: {time.perf_counter() - t0:.0f} s", flush=True)
    return folder


def env_rate(hz: int, ms: float, steps: int, repeats: int) -> float:
    """Median env steps per CPU second of the shipped preset's env at this cell (zero action, from a reset)."""
    from cyberdog import config as C
    from cyberdog.config.preset import load_preset
    from cyberdog.envs.cyberdog_env import CyberDogEnv

    env_cfg = load_preset(ROOT / "configs/table5.yaml").config.env
    env_cfg = C.override(C.ExperimentConfig(env=env_cfg), [f"env.walk.{s}" for s in sim_sets(hz, ms)]).env
    env = CyberDogEnv(env_cfg, reward="stage2")
    action = np.zeros(12, dtype=np.float32)
    rates = []
    for i in range(repeats):
        env.reset(seed=i)
        c0 = time.process_time()
        for _ in range(steps):
            if env.step(action)[2]:
                env.reset()
        rates.append(steps / (time.process_time() - c0))
    env.close()
    return statistics.median(rates)


def summarise(folder: Path) -> dict:
    """Mean energies per trajectory kind and set, D_t per speed, falls and off-band walks of one cell."""
    walks = json.loads((folder / "comparison.json").read_text())
    out: dict = {"falls": sum(bool(w["fell"]) for w in walks),
                 "off_band": sum(not w["speed_ok"] and not w["fell"] for w in walks), "walks": len(walks)}
    for traj in ("learned",) + BASELINES:
        for set_name in ("same_lift", "paper"):
            mine = [w for w in walks if w["trajectory"] == traj and w["set"] == set_name]
            if mine:
                out[f"{traj}_{set_name}_E"] = statistics.fmean(w["energy_J"] for w in mine)
                out[f"{traj}_{set_name}_el"] = statistics.fmean(w["electrical_energy_J"] for w in mine)
    with open(folder / "table5_summary.json") as f:
        summary = json.load(f)
    for row in summary:
        if row["set"] == "same_lift":
            v = row["speed_command_mps"]
            out[f"D_t_{v:g}"] = row["D_t_pct_mean"]
            out[f"D_t_el_{v:g}"] = row["D_t_electrical_pct_mean"]
    return out


def pct(x: float, ref: float) -> str:
    return f"{100.0 * (x / ref - 1.0):+.1f} %" if math.isfinite(x) and ref else "–"


def markdown(cells: dict, ref_key: str) -> str:
    ref = cells[ref_key]
    head = ["control / physics", "cycloid E", "straight E", "cycloid el.", "straight el.", "learned E",
            "learned el.", "D_t 1.0 / 1.2 / 1.4 (pts)", "falls, off-band", "env steps/s"]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for key, c in cells.items():
        base = [pct(statistics.fmean([c[f"{t}_{s}_{q}"] for s in ("same_lift", "paper")]),
                    statistics.fmean([ref[f"{t}_{s}_{q}"] for s in ("same_lift", "paper")]))
                for q in ("E", "el") for t in BASELINES]
        learned = [pct(c[f"learned_same_lift_{q}"], ref[f"learned_same_lift_{q}"]) for q in ("E", "el")]
        dt = " / ".join(f"{c[f'D_t_{v:g}']:.1f}" + ("" if key == ref_key else
                                                      f" ({c[f'D_t_{v:g}'] - ref[f'D_t_{v:g}']:+.1f})")
                        for v in SPEEDS)
        lines.append(f"| {key} | " + " | ".join(base + learned) + f" | {dt} | {c['falls']}, {c['off_band']} "
                     f"of {c['walks']} | {c['env_steps_per_s']:.0f} |")
    return "\n".join(lines)


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--out", default="runs/control_rate", help="study folder (default runs/control_rate)")
    p.add_argument("--cells", nargs="+", default=None, metavar="HZ:MS",
                   help="cells to run, e.g. 400:1.25 (default: the whole grid); the reference always runs")
    p.add_argument("--workers", type=int, default=2, help="walk processes per cell (default 2)")
    p.add_argument("--env-steps", type=int, default=400, help="env steps per timing repetition (default 400)")
    p.add_argument("--env-repeats", type=int, default=3, help="timing repetitions per cell (default 3)")
    args = p.parse_args()
    grid = GRID if args.cells is None else [(int(h), float(m)) for h, m in (c.split(":") for c in args.cells)]
    for hz, ms in grid:
        ctrl_ms = 1e3 / hz
        if 25.0 / ctrl_ms % 1 > 1e-9 or ctrl_ms / ms % 1 > 1e-9:
            sys.exit(f"cell {hz}:{ms}: the control period must divide 25 ms and the physics step the period")
    out = ROOT / args.out if not Path(args.out).is_absolute() else Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    cells = {}
    for hz, ms in [REFERENCE] + [c for c in grid if c != REFERENCE]:
        folder = run_cell(hz, ms, out, args.workers)
        key = f"{hz} Hz / {ms:g} ms" + (" (reference)" if (hz, ms) == REFERENCE else "")
        cells[key] = summarise(folder) | {"env_steps_per_s": env_rate(hz, ms, args.env_steps, args.env_repeats)}
        print(f"{key}: {cells[key]['env_steps_per_s']:.0f} env steps/s", flush=True)
    ref_key = next(iter(cells))
    table = markdown(cells, ref_key)
    (out / "study.md").write_text(table + "\n")
    (out / "study.json").write_text(json.dumps(cells, indent=1))
    print("\nEnergies: mean over the walks of each kind, as the deviation from the reference; D_t at matched lift "
          "(mean over seeds) and its change from the reference in points\n")
    print(table)


if __name__ == "__main__":
    main()
