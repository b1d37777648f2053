#!/usr/bin/env python3
"""Convergence of the motor drivers' PD in its rate: Eq. (7) energy per metre of a scripted walk.

The walk is `cyberdog.analysis.walk.walk` on the ideal robot: the composite cycloid, 6 s from a stand, at each
speed and each joint PD (kp, kd the same for abad, hip and knee). The drivers close their PD at every physics
step, so the physics step is the drivers' rate. Each walk runs first at the step the walker picks for its gains
(`cyberdog.loop.walker.driver_rate_config`: the configured 1.25 ms, 800 Hz, halved until the PD is within the
bounds of `cyberdog.core.drivers`), then at that step divided by each `--finer` factor (2: twice as fast
drivers), the controller period held at `--controller-ms` (2.5 ms, 400 Hz). The table gives the picked rate,
J/m per rate and each finer rate's deviation from the picked one; the rule holds where every deviation is
within 1 %. A fall is marked. The last column is the battery's energy per metre at the picked rate (copper loss,
friction and driver efficiency, `WalkResult.electrical_energy`): what a gain costs the robot, beside Eq. (7)'s
|τ·ω|. `--run-up` leaves the start from a stand out of the result (the steady walk's cost).

    python bench/driver_rate.py [--speeds 1.0 1.4] [--kp 30 60 120] [--kd 1 2 4] [--finer 2]
                                [--controller-ms 2.5] [--duration 6] [--run-up 0]
"""
from __future__ import annotations

import argparse
import itertools

from cyberdog import config as C
from cyberdog.analysis.walk import walk
from cyberdog.loop.walker import driver_rate_config


def walk_cfg(speed: float, kp: float, kd: float, controller_ms: float) -> C.WalkConfig:
    base = C.WalkConfig()
    return C.replace(base, gait=C.replace(base.gait, speed=speed, trajectory="cycloid"),
                     pid=C.replace(base.pid, kp=(kp,) * 3, kd=(kd,) * 3),
                     sim=C.replace(base.sim, controller_dt=controller_ms / 1e3))


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--speeds", type=float, nargs="+", default=[1.0, 1.4], help="m/s (default 1.0 1.4)")
    p.add_argument("--kp", type=float, nargs="+", default=[30.0, 60.0, 120.0], help="N·m/rad (default 30 60 120)")
    p.add_argument("--kd", type=float, nargs="+", default=[1.0, 2.0, 4.0], help="N·m·s/rad (default 1 2 4)")
    p.add_argument("--finer", type=int, nargs="+", default=[2],
                   help="factors by which the picked physics step is divided for the comparison (default 2)")
    p.add_argument("--controller-ms", type=float, default=2.5, help="controller period, ms (default 2.5)")
    p.add_argument("--duration", type=float, default=6.0, help="s walked (default 6)")
    p.add_argument("--run-up", type=float, default=0.0,
                   help="s walked first and left out of the energies and distance (default 0: from a stand)")
    args = p.parse_args()
    if any(f < 2 for f in args.finer):
        p.error("--finer factors must be integers >= 2")
    if not 0 <= args.run_up < args.duration:
        p.error("--run-up must be >= 0 s and shorter than --duration")
    rates = " | ".join(f"{f}× J/m" for f in args.finer)
    devs = " | ".join(f"{f}× vs picked" for f in args.finer)
    run_up = f" after a {args.run_up:g} s run-up" if args.run_up else ""
    print(f"controller {1e3 / args.controller_ms:.0f} Hz, drivers' PD at the physics rate, {args.duration:g} s "
          f"cycloid walks{run_up}, ideal robot; J/m is Eq. (7)'s\n")
    print(f"| speed m/s | kp | kd | picked rate | picked J/m | {rates} | {devs} | battery J/m (picked) |")
    print("|---" * (6 + 2 * len(args.finer)) + "|")
    for speed, kp, kd in itertools.product(args.speeds, args.kp, args.kd):
        picked = driver_rate_config(walk_cfg(speed, kp, kd, args.controller_ms))
        h = picked.sim.physics_dt
        cells, battery = [], None
        for factor in (1, *args.finer):
            r = walk(C.replace(picked, sim=C.replace(picked.sim, physics_dt=h / factor)), duration=args.duration,
                     run_up=args.run_up)
            cells.append((r.energy_per_metre, r.fell))
            if battery is None:
                battery = r.electrical_energy / r.distance if r.distance > 0 else float("nan")
        ref = cells[0][0]
        shown = " | ".join(f"{e:.1f}{' (fell)' if fell else ''}" for e, fell in cells)
        dev = " | ".join(f"{100 * (e / ref - 1):+.2f} %" for e, _ in cells[1:])
        print(f"| {speed:g} | {kp:g} | {kd:g} | {1 / h:.0f} Hz | {shown} | {dev} | {battery:.1f} |", flush=True)


if __name__ == "__main__":
    main()
