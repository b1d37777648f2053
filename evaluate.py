#!/usr/bin/env python3
"""Evaluate foot trajectories on the simulated CyberDog (paper Section 4).

Sub-commands:
  baselines   walk 10 s at 1.0, 1.2 and 1.4 m/s with the composite cycloid and straight-line trajectories
              and print speed, drift, posture, energy (Eq. 7), energy per 100 m, CoT, peak torque and speed.

With no sub-command, runs every part that exists. Outputs go to --out (default runs/evaluate-<time>/),
never over inputs.
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from cyberdog import config as C
from cyberdog.analysis.baselines import BASELINES, PAPER_SPEEDS, baseline_rows
from cyberdog.analysis.report import markdown_table, write_rows

BASELINE_COLUMNS = ["trajectory", "speed_command_mps", "mean_speed_mps", "lateral_drift_m", "height_min_m",
                    "height_max_m", "max_roll_rad", "max_pitch_rad", "fell", "energy_J", "energy_per_100m_kJ",
                    "cost_of_transport", "peak_torque_Nm", "peak_joint_speed_radps"]


def parse_args(argv=None):
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("command", nargs="?", default="all", choices=["all", "baselines"],
                   help="which part to run (default: all)")
    p.add_argument("--config", type=Path, default=None,
                   help="YAML walk config (WalkConfig sections: robot, actuator, sim, gait, pid, controller, "
                        "energy); default: the built-in defaults")
    p.add_argument("--set", nargs="*", default=[], metavar="SECTION.FIELD=VALUE",
                   help="config overrides, e.g. gait.lift_height=0.1 gait.straight_shape=trapezoid")
    p.add_argument("--speeds", type=float, nargs="+", default=list(PAPER_SPEEDS), help="m/s (default 1.0 1.2 1.4)")
    p.add_argument("--trajectories", nargs="+", default=list(BASELINES), choices=list(BASELINES),
                   help="baseline trajectories to walk")
    p.add_argument("--duration", type=float, default=10.0, help="s per walk (default 10, the paper's Tf)")
    p.add_argument("--out", type=Path, default=None, help="output folder (default runs/evaluate-<time>)")
    args = p.parse_args(argv)
    if any(v < 0 for v in args.speeds):
        p.error(f"--speeds must be >= 0 m/s, got {args.speeds}")
    if args.duration <= 0:
        p.error(f"--duration must be > 0 s, got {args.duration}")
    return args


def main(argv=None) -> int:
    args = parse_args(argv)
    cfg = C.load(C.WalkConfig, args.config) if args.config else C.WalkConfig()
    cfg = C.override(cfg, args.set)
    out = args.out or Path("runs") / time.strftime("evaluate-%Y%m%d-%H%M%S")
    out.mkdir(parents=True, exist_ok=True)
    C.save(cfg, out / "config.yaml")
    t0 = time.perf_counter()
    if args.command in ("all", "baselines"):
        rows = baseline_rows(cfg, args.speeds, args.trajectories, args.duration)
        write_rows(rows, out, "baselines")
        print(markdown_table(rows, BASELINE_COLUMNS))
    print(f"wrote {out}/ in {time.perf_counter() - t0:.1f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
