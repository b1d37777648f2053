#!/usr/bin/env python3
"""Controller periods per second of the scripted walk (`cyberdog.analysis.walk.walk`): trot controller + motor
drivers + Robot (each period: the controller once, the drivers at each of its physics steps).

Walks the composite cycloid at 1.0 m/s (default config) on one reused robot, several repetitions, and prints
each repetition's rate and the best (the machine is shared, so the best is the least disturbed number), by
the wall clock and by this process's CPU time (which leaves out the time other processes held the CPU).

    python bench/walk_throughput.py [--duration 2.0] [--repeats 3] [--speed 1.0] [--trajectory cycloid]
"""
from __future__ import annotations

import argparse
import dataclasses
import time

from cyberdog.analysis.walk import walk
from cyberdog.config import WalkConfig
from cyberdog.sim.robot import Robot


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--duration", type=float, default=2.0, help="s walked per repetition (default 2.0)")
    p.add_argument("--repeats", type=int, default=3)
    p.add_argument("--speed", type=float, default=1.0, help="m/s (default 1.0)")
    p.add_argument("--trajectory", default="cycloid", choices=("cycloid", "straight"))
    args = p.parse_args()
    cfg = WalkConfig()
    cfg = dataclasses.replace(cfg, gait=dataclasses.replace(cfg.gait, speed=args.speed,
                                                            trajectory=args.trajectory))
    robot = Robot(cfg.robot, cfg.actuator, cfg.sim)
    rates = []
    try:
        for i in range(args.repeats):
            t0, c0 = time.perf_counter(), time.process_time()
            result = walk(cfg, args.duration, robot=robot)
            elapsed, cpu = time.perf_counter() - t0, time.process_time() - c0
            steps = round(result.duration / cfg.sim.controller_dt)
            rates.append((steps / elapsed, steps / cpu))
            print(f"rep {i}: {rates[-1][0]:8.0f} controller periods/s (CPU time: {rates[-1][1]:8.0f}; "
                  f"{cfg.sim.physics_substeps} physics steps each)  ({steps} periods in {elapsed:.2f} s, "
                  f"E = {result.energy:.3f} J, v = {result.mean_speed:.4f} m/s)", flush=True)
    finally:
        robot.close()
    print(f"best: {max(r[0] for r in rates):.0f} controller periods/s, by CPU time {max(r[1] for r in rates):.0f} "
          f"({args.trajectory}, {args.speed} m/s)")


if __name__ == "__main__":
    main()
