#!/usr/bin/env python3
"""Does a fixed path hold the gait its policy walked? The policy, its mean path, and a hand-over, on one robot.

A foot-mode policy's saving reaches the tables through its extracted path: the mean of the foot shifts it
commanded over its settled cycles, replayed open loop through the IK + PID trot (`evaluate.py extract`). When
the replayed path costs more than the policy did, this script shows where the difference lives. On one
hardware-like robot (`--hardware-seed`, its mass draw and sensor streams; neither the prototype's robots,
seeds 0 .., nor the extraction check's, 1000–1005), at one speed, three walks of `--duration` s:

1. the policy, closed loop (deterministic, its env with the domain randomisation off);
2. the mean commanded path of walk 1's settled cycles in the ±5 % band, replayed from a stand;
3. the policy until `--handover` s, then that path on its own (zero actions, the path's shift at the same
   clock): the path started *on the policy's gait*;
4. with `--sagittal`, the path without its sideways (y) shift, from a stand: the x-z part alone.

With `--placement K` the paths (walks 2 and 4) are replayed by a trot with sagittal foot placement at gain K s
(`ControllerConfig.sagittal_placement_gain`; without it, the policy's own trot's, off unless it was trained with
it): does foot placement hold the orbit the path loses?

For each: the steady orbit of its last cycles (`cyberdog.analysis.orbit`: the period with which the cycles'
Eq. (7) energy and speed repeat, their means, the speed's spread) and the electrical energy per metre of the
whole walk (walks 1 and 2, from a stand). If walk 3 leaves the policy's orbit for walk 2's, the policy's gait
is one the fixed path cannot hold: its saving is in the policy's feedback, however small its shifts' cycle-to-
cycle variation (printed too), not in any path it commands.

    python notebook/tools/replay_orbit.py --actor runs/battery_stiff/seed2/stage2_final_actor.pt --speed 1.2
"""
from __future__ import annotations

import argparse
import dataclasses
import json
import math
import sys
from pathlib import Path

import numpy as np

from cyberdog.analysis.extract import ExtractionError, clock_cycles, commanded_from_rollout
from cyberdog.analysis.orbit import MAX_PERIOD, STEADY_WINDOW, TOLERANCE, steady_orbit
from cyberdog.analysis.report import json_safe
from cyberdog.analysis.walk import walk
from cyberdog.core.foot_offsets import FootOffsetPath
from cyberdog.core.learned_set import LearnedPath

DEFAULT_HARDWARE_SEED = 2000  # a robot no table walks: the prototype's are seeds 0 .., the check's 1000-1005


def cycles_of(result, period: float):
    return clock_cycles(result.traces, result.trace_dt, result.speed_command, period)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--actor", type=Path, required=True, help="a stage-2 actor file (foot mode)")
    p.add_argument("--speed", type=float, required=True, help="m/s commanded")
    p.add_argument("--hardware-seed", type=int, default=DEFAULT_HARDWARE_SEED,
                   help=f"HardwareConfig.seed of the robot (default {DEFAULT_HARDWARE_SEED})")
    p.add_argument("--pd-scale", type=float, default=1.0, help="the joint PD's stiffness factor (default 1)")
    p.add_argument("--duration", type=float, default=24.0, help="s of each walk (default 24)")
    p.add_argument("--handover", type=float, default=8.0, help="s of the policy before the path takes over "
                   "(default 8; a multiple of the agent step)")
    p.add_argument("--sagittal", action="store_true", help="also walk the path without its sideways shift (its "
                   "x-z part, the paper's kind of foot trajectory) from a stand")
    p.add_argument("--placement", type=float, default=None, metavar="K",
                   help="replay the paths (walks 2 and 4) with the trot's sagittal foot placement at gain K s "
                        "(ControllerConfig.sagittal_placement_gain; default: the policy's own, 0 unless it was "
                        "trained with it); the policy and the hand-over keep the controller it was trained with")
    p.add_argument("--cycles", action="store_true", help="print every cycle's energy and speed")
    p.add_argument("--out", type=Path, help="a JSON file for the three walks' cycles and orbits (not overwritten)")
    args = p.parse_args(argv)
    if not (math.isfinite(args.speed) and args.speed > 0):
        p.error(f"--speed must be > 0 m/s, got {args.speed}")
    if args.placement is not None and not (math.isfinite(args.placement) and args.placement >= 0):
        p.error(f"--placement must be >= 0 s, got {args.placement}")
    if not (math.isfinite(args.pd_scale) and args.pd_scale > 0):
        p.error(f"--pd-scale must be > 0, got {args.pd_scale}")
    if not (math.isfinite(args.duration) and math.isfinite(args.handover) and 0 < args.handover < args.duration):
        p.error(f"--handover ({args.handover}) must be > 0 s and before the end of --duration ({args.duration})")
    if not args.actor.is_file():
        p.error(f"no actor file {args.actor}")
    if args.out is not None and args.out.exists():
        p.error(f"{args.out} exists: choose another --out (results are never overwritten)")
    from cyberdog.rl.rollout import load_actor, rollout  # torch: only once the arguments are good

    actor = load_actor(args.actor)
    env = actor.config.env
    if env.action_mode != "foot":
        p.error(f"{args.actor} acts on {env.action_mode}, not on foot targets: it commands no path")
    hw = dataclasses.replace(env.hardware, seed=args.hardware_seed)
    walk_cfg = dataclasses.replace(env.walk, pid=env.walk.pid.stiffness_scaled(args.pd_scale))
    env = dataclasses.replace(env, hardware=hw, walk=walk_cfg)
    v, period = args.speed, env.walk.gait.period
    if abs(round(args.handover / env.control_dt) * env.control_dt - args.handover) > 1e-9:
        p.error(f"--handover {args.handover} s is not a multiple of the agent step ({env.control_dt:g} s)")
    if args.duration < 2.0 + STEADY_WINDOW * period or args.duration - args.handover < STEADY_WINDOW * period:
        p.error(f"--duration {args.duration} s leaves fewer than {STEADY_WINDOW} cycles ({STEADY_WINDOW * period:g} s) "
                "after the settle time or the hand-over: walk longer")

    policy = rollout(actor, speed=v, duration=args.duration, env_config=env, hardware_robot=True)
    try:
        ex = commanded_from_rollout(policy, env, "mean")
    except ExtractionError as err:
        print(f"the policy's walk gives no path: {err}", file=sys.stderr)
        return 1
    path = LearnedPath("policy", ex.path)
    if args.placement is not None:
        walk_cfg = dataclasses.replace(walk_cfg, controller=dataclasses.replace(
            walk_cfg.controller, sagittal_placement_gain=args.placement))
    placement = walk_cfg.controller.sagittal_placement_gain  # what the paths are replayed with (the env is built)
    cfg, trajectory, offsets = path.walk_args(walk_cfg, v)
    replay = walk(cfg, args.duration, trajectory, foot_offsets=offsets, hardware=hw, record=True)
    handed = rollout(actor, speed=v, duration=args.duration, env_config=env, hardware_robot=True,
                     then_path=(args.handover, ex.path.offsets))

    if args.sagittal:
        table = ex.path.offsets.offsets.copy()
        table[:, :, 1] = 0.0  # no sideways shift
        xz = dataclasses.replace(ex.path, offsets=FootOffsetPath(table, ex.path.offsets.period))
        cfg, trajectory, offsets = LearnedPath("policy", xz).walk_args(walk_cfg, v)
        sagittal = walk(cfg, args.duration, trajectory, foot_offsets=offsets, hardware=hw, record=True)

    shifts = np.stack([np.asarray(policy.traces["foot_offsets"])[ex.cycles[i].start:ex.cycles[i].end]
                       for i in ex.used])  # (cycles, samples, 4, 3) m
    variation = 1e3 * shifts.std(axis=0).mean(axis=(0, 1))
    placed = f", paths with sagittal placement {placement:g} s" if placement else ""
    rms = np.round(1e3 * ex.path.offsets.rms().mean(axis=0), 1).tolist()
    print(f"{args.actor} at {v:g} m/s on hardware-like robot {args.hardware_seed}, PD {args.pd_scale:g}x{placed}; "
          f"the mean path of {len(ex.used)} cycles (shift rms {rms} mm, cycle-to-cycle std "
          f"{np.round(variation, 2).tolist()} mm in x, y, z)")
    report = {"actor": str(args.actor), "speed_mps": v, "hardware_seed": args.hardware_seed,
              "pd_scale": args.pd_scale, "sagittal_placement_gain_s": placement, "duration_s": args.duration,
              "handover_s": args.handover,
              "shift_cycle_std_mm": variation.tolist(), "walks": {}}
    walks = (("policy", policy, True), ("path", replay, True),
             (f"policy, then path from {args.handover:g} s", handed, False))  # (name, walk, J/m of one gait)
    if args.sagittal:
        walks += (("path without its sideways shift", sagittal, True),)
    for name, r, from_stand in walks:
        cycles = cycles_of(r, period)
        orbit = None if r.fell else steady_orbit(cycles)
        line = f"  {name}: " + ("fell" if orbit is None else orbit.describe())
        if from_stand and not r.fell:
            line += f"; {r.electrical_energy / r.distance:.1f} J/m electrical from a stand"
        print(line)
        if args.cycles:
            print("    " + " ".join(f"{c.energy:.0f}J/{c.speed:.2f}" for c in cycles))
        report["walks"][name] = {
            "fell": r.fell,  # J/m from a stand; none for the hand-over, half policy and half path
            "electrical_J_per_m": r.electrical_energy / r.distance if from_stand and r.distance > 0 else None,
            "orbit": None if orbit is None else dataclasses.asdict(orbit),
            "cycles": [{"t_start_s": c.t_start, "energy_J": c.energy, "speed_mps": c.speed} for c in cycles]}
    print(f"  (period: the smallest p ≤ {MAX_PERIOD} with the cycles p apart alike, within {TOLERANCE:.0%}, over the "
          f"last {STEADY_WINDOW} cycles)")
    if args.out is not None:
        args.out.parent.mkdir(parents=True, exist_ok=True)
        args.out.write_text(json.dumps(json_safe(report), indent=1))
        print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
