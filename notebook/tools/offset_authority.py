#!/usr/bin/env python
"""Is the foot-mode policy's authority what keeps it from a cheaper shape? Walk a searched shape as foot offsets.

    python notebook/tools/offset_authority.py \\
        --shape results/searched_shapes/optimized_trajectory_H0.095.json --clip 0.03 0.06

A foot-mode policy (`CyberDog-v0`, action_mode="foot") can only shift each foot target of the trot's composite
cycloid by ±`foot_offset_scale` per axis (0.03 m in the shipped presets). This tool asks whether a shape the
direct search found (`tools/optimize_trajectory.py`) lies within that reach: at each speed it takes the
difference between the searched shape and the composite cycloid at the same step length and lift height H,
over the gait phase, as a periodic foot-offset path (`FootOffsetPath`, the same on all four legs; x forward
and z up, y unchanged), clips it to ±each `--clip` metres per axis, and walks the cycloid with that offset
path through the same IK + PID trot as Table 5. It prints, per speed: the largest offset the shape needs, and
the Eq. (7) and electrical energy of the cycloid, of each clipped offset path, of the unclipped one and of
the shape itself walked as a trajectory (the unclipped offset path differs from it only by the offsets'
linear interpolation between samples).

A saving that survives clipping to the policy's reach is one the policy's action space contains: the learned
paths' shortfall is then the learning's (exploration, budget, reward), not the action space's.
"""
from __future__ import annotations

import argparse
import dataclasses
import sys
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO))  # run as a script from anywhere

from cyberdog.analysis.parallel import map_in_processes  # noqa: E402
from cyberdog.analysis.walk import walk  # noqa: E402
from cyberdog.config import WalkConfig  # noqa: E402
from cyberdog.config.paper import PAPER_SPEEDS, PAPER_WALK_DURATION  # noqa: E402
from cyberdog.core.foot_offsets import LEGS, FootOffsetPath  # noqa: E402
from cyberdog.core.trajectories import CompositeCycloid, SampledTrajectory  # noqa: E402

SAMPLES = 400  # phases per cycle of the offset path (the recorder's resolution of a commanded path)


def shape_offsets(shape: SampledTrajectory, cfg: WalkConfig, n: int = SAMPLES) -> np.ndarray:
    """(n, 2) m: the shape's (x, z) minus the composite cycloid's at the same S and H, at phases k/n."""
    g = cfg.gait
    phase = np.arange(n) / n
    args = (g.step_length, g.lift_height, g.swing_time, g.stance_time)
    p_shape, _ = shape.position_velocity(phase, *args)
    p_cycloid, _ = CompositeCycloid().position_velocity(phase, *args)
    return p_shape - p_cycloid


def offset_path(delta: np.ndarray, period: float, clip: float | None) -> FootOffsetPath:
    """The (x, z) offsets, clipped to ±clip m per axis (None: not clipped), on all four legs."""
    d = delta if clip is None else np.clip(delta, -clip, clip)
    table = np.zeros((LEGS, len(d), 3))
    table[:, :, 0], table[:, :, 2] = d[:, 0], d[:, 1]
    return FootOffsetPath(table, period)


def run_walk(job: tuple) -> dict:
    """One walk (in a worker process): (speed, label, cfg, trajectory or None, offset path or None, duration)."""
    speed, label, cfg, trajectory, offsets, duration = job
    r = walk(cfg, duration, trajectory, foot_offsets=offsets)
    return {"speed": speed, "label": label, "energy_J": r.energy, "electrical_J": r.electrical_energy,
            "mean_speed": r.mean_speed, "fell": r.fell, "speed_ok": r.speed_ok}


def parse_args(argv=None) -> argparse.Namespace:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--shape", type=Path, default=REPO / "results" / "searched_shapes" / "optimized_trajectory_H0.095.json",
                   help="a shape saved by tools/optimize_trajectory.py (default: the shipped H = 0.095 m one); "
                        "walked at its own lift height")
    p.add_argument("--clip", type=float, nargs="+", default=[0.03],
                   help="m, per-axis reach to clip the offsets to (default 0.03, the presets' foot_offset_scale)")
    p.add_argument("--speeds", type=float, nargs="+", default=list(PAPER_SPEEDS), help="m/s (default 1.0 1.2 1.4)")
    p.add_argument("--duration", type=float, default=PAPER_WALK_DURATION, help="s per walk (default 10)")
    p.add_argument("--workers", type=int, default=None, help="parallel walk processes (default: CPU count)")
    args = p.parse_args(argv)
    if not args.shape.is_file():
        p.error(f"--shape {args.shape} does not exist")
    if not all(c > 0 and np.isfinite(c) for c in args.clip):
        p.error(f"--clip values must be > 0 m, got {args.clip}")
    if not all(v > 0 and np.isfinite(v) for v in args.speeds):
        p.error(f"--speeds must be > 0 m/s, got {args.speeds}")
    if not (args.duration > 0 and np.isfinite(args.duration)):
        p.error(f"--duration must be > 0 s, got {args.duration}")
    return args


def main(argv=None) -> int:
    args = parse_args(argv)
    shape = SampledTrajectory.load(args.shape)
    lift = float(shape.lift_height)
    base = WalkConfig()
    jobs, reach = [], {}
    for v in args.speeds:
        cfg = dataclasses.replace(base, gait=dataclasses.replace(base.gait, speed=v, lift_height=lift,
                                                                 trajectory="cycloid"))
        delta = shape_offsets(shape, cfg)
        reach[v] = np.abs(delta).max(axis=0)
        jobs.append((v, "composite cycloid", cfg, None, None, args.duration))
        for c in sorted(args.clip):
            jobs.append((v, f"cycloid + offsets clipped to ±{100 * c:g} cm", cfg, None,
                         offset_path(delta, cfg.gait.period, c), args.duration))
        jobs.append((v, "cycloid + offsets, not clipped", cfg, None, offset_path(delta, cfg.gait.period, None),
                     args.duration))
        jobs.append((v, "searched shape as the trajectory", cfg, shape, None, args.duration))
    print(f"{len(jobs)} walks of {args.duration:g} s at H = {lift:.3f} m ({args.shape})", flush=True)
    rows = map_in_processes(run_walk, jobs, args.workers)
    print("\n| v (m/s) | largest offset needed, x / z (mm) | walk | E, Eq. 7 (J) | vs cycloid | electrical (J) "
          "| vs cycloid | mean speed (m/s) | status |")
    print("|---|---|---|---|---|---|---|---|---|")
    for v in args.speeds:
        mine = [r for r in rows if r["speed"] == v]
        ref = mine[0]
        for r in mine:
            status = "fell" if r["fell"] else ("ok" if r["speed_ok"] else "speed miss")
            print(f"| {v:g} | {1e3 * reach[v][0]:.0f} / {1e3 * reach[v][1]:.0f} | {r['label']} | {r['energy_J']:.1f} "
                  f"| {100 * (r['energy_J'] / ref['energy_J'] - 1):+.1f} % | {r['electrical_J']:.0f} "
                  f"| {100 * (r['electrical_J'] / ref['electrical_J'] - 1):+.1f} % | {r['mean_speed']:.3f} | {status} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
