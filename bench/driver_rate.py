#!/usr/bin/env python3
"""Convergence of the motor drivers' PD in its rate: Eq. (7) energy per metre of a scripted walk.

The walk is `cyberdog.analysis.walk.walk` on the ideal robot: the composite cycloid, 6 s from a stand, at each
speed and each joint PD (kp, kd the same for abad, hip and knee). Each is walked with the configured physics
step (`SimConfig.physics_dt`, 1.25 ms: the drivers' PD at 800 Hz) and with every finer step asked for
(`--physics-ms 0.625`: 1.6 kHz), the controller period held at `--controller-ms` (2.5 ms, 400 Hz). The drivers
close their PD at every physics step, so a finer step is a faster driver; the table gives J/m per rate and
each finer rate's deviation from the first. A fall is marked.

    python bench/driver_rate.py [--speeds 1.0 1.4] [--kp 30 60 120] [--kd 1 2 4] [--physics-ms 1.25 0.625]
                                [--controller-ms 2.5] [--duration 6]
"""
from __future__ import annotations

import argparse
import itertools

from cyberdog import config as C
from cyberdog.analysis.walk import walk


def walk_cfg(speed: float, kp: float, kd: float, physics_ms: float, controller_ms: float) -> C.WalkConfig:
    base = C.WalkConfig()
    return C.replace(base, gait=C.replace(base.gait, speed=speed, trajectory="cycloid"),
                     pid=C.replace(base.pid, kp=(kp,) * 3, kd=(kd,) * 3),
                     sim=C.replace(base.sim, physics_dt=physics_ms / 1e3, controller_dt=controller_ms / 1e3))


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--speeds", type=float, nargs="+", default=[1.0, 1.4], help="m/s (default 1.0 1.4)")
    p.add_argument("--kp", type=float, nargs="+", default=[30.0, 60.0, 120.0], help="N·m/rad (default 30 60 120)")
    p.add_argument("--kd", type=float, nargs="+", default=[1.0, 2.0, 4.0], help="N·m·s/rad (default 1 2 4)")
    p.add_argument("--physics-ms", type=float, nargs="+", default=[1.25, 0.625],
                   help="physics steps, ms; the first is the reference column (default 1.25 0.625)")
    p.add_argument("--controller-ms", type=float, default=2.5, help="controller period, ms (default 2.5)")
    p.add_argument("--duration", type=float, default=6.0, help="s walked (default 6)")
    args = p.parse_args()
    rates = " | ".join(f"{1e3 / ms:.0f} Hz J/m" for ms in args.physics_ms)
    devs = " | ".join(f"{1e3 / ms:.0f} Hz vs {1e3 / args.physics_ms[0]:.0f} Hz" for ms in args.physics_ms[1:])
    print(f"controller {1e3 / args.controller_ms:.0f} Hz, drivers' PD at the physics rate, {args.duration:g} s "
          f"cycloid walks, ideal robot\n")
    print(f"| speed m/s | kp | kd | {rates} | {devs} |")
    print("|---" * (3 + 2 * len(args.physics_ms) - 1) + "|")
    for speed, kp, kd in itertools.product(args.speeds, args.kp, args.kd):
        cells = []
        for ms in args.physics_ms:
            r = walk(walk_cfg(speed, kp, kd, ms, args.controller_ms), duration=args.duration)
            cells.append((r.energy_per_metre, r.fell))
        ref = cells[0][0]
        shown = " | ".join(f"{e:.1f}{' (fell)' if fell else ''}" for e, fell in cells)
        dev = " | ".join(f"{100 * (e / ref - 1):+.2f} %" for e, _ in cells[1:])
        print(f"| {speed:g} | {kp:g} | {kd:g} | {shown} | {dev} |", flush=True)


if __name__ == "__main__":
    main()
