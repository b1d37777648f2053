#!/usr/bin/env python3
"""A commanded path extracted at the joint PD's stiffness it is replayed at: does it keep the saving?

`evaluate.py extract` takes the commanded foot path from rollouts at the PD the policy was trained with, and
`evaluate.py stiffness` replays that one path at every stiffness. A policy sees the stiffness through the
state and may command another path under a stiffer PD; this script asks whether the path it commands *there*
replays better there. For one actor: a deterministic rollout at each speed in the actor's env with the joint
PD scaled by `--pd-scale` (kp × s, kd × √s: `PIDConfig.stiffness_scaled`; the env's own gain draws on top, as
in training, unless `--fixed-gains`), the mean commanded path of its settled cycles (`commanded_from_rollout`:
the first rollout, env seed 0, 1, ..., that gives one), then the prototype run at the same stiffness on the
hardware-like robots (`run_prototype`: the path beside the common trajectories at its lift, the battery saving against the cheaper
one). No candidate selection and no replay check: a measurement, not an extraction for shipping.

    python notebook/tools/extract_at_stiffness.py --actor notebook/results/policy_battery/stage2_actor.pt \\
        --label seed0 --pd-scale 1.4 --out runs/extract_at_1.4
"""
from __future__ import annotations

import argparse
import dataclasses
import json
import math
import sys
from pathlib import Path

from cyberdog.analysis import prototype_summary as ps
from cyberdog.analysis.extract import ExtractionError, commanded_from_rollout
from cyberdog.analysis.prototype import run_prototype
from cyberdog.analysis.report import json_safe
from cyberdog.core.learned_set import LearnedPath, LearnedSet


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--actor", type=Path, required=True, help="a stage-2 actor file (foot mode)")
    p.add_argument("--label", default="seed0", help="the label of its paths (default seed0)")
    p.add_argument("--pd-scale", type=float, required=True, help="the joint PD's stiffness factor s")
    p.add_argument("--speeds", type=float, nargs="+", default=[1.0, 1.2, 1.4], help="m/s (default 1.0 1.2 1.4)")
    p.add_argument("--attempts", type=int, default=3, help="rollouts (env seeds 0, 1, ...) tried per speed")
    p.add_argument("--fixed-gains", action="store_true",
                   help="the env's kp and kd draws off: the rollout's PD is exactly s times the configured one (for "
                        "a policy that observes the stiffness, env.observe_pd_stiffness, the path at s itself)")
    p.add_argument("--out", type=Path, required=True, help="folder for learned/, walks.json and saving.json")
    args = p.parse_args(argv)
    if not (math.isfinite(args.pd_scale) and args.pd_scale > 0):
        p.error(f"--pd-scale must be > 0, got {args.pd_scale}")
    if not args.actor.is_file():
        p.error(f"no actor file {args.actor}")
    from cyberdog.rl.rollout import load_actor, rollout

    actor = load_actor(args.actor)
    env = actor.config.env
    if env.action_mode != "foot":
        p.error(f"{args.actor} acts on {env.action_mode}, not on foot targets: it commands no path")
    env = dataclasses.replace(env, walk=dataclasses.replace(env.walk, pid=env.walk.pid.stiffness_scaled(args.pd_scale)))
    if args.fixed_gains:
        env = dataclasses.replace(env, randomization=dataclasses.replace(env.randomization, kp_factor=(1.0, 1.0),
                                                                         kd_factor=(1.0, 1.0)))
    paths = []
    for v in args.speeds:
        for seed in range(args.attempts):
            r = rollout(actor, speed=v, duration=10.0, seed=seed, env_config=env)
            try:
                ex = commanded_from_rollout(r, env, "mean", provenance={"rollout_seed": seed, "pd_scale": args.pd_scale})
            except ExtractionError as err:
                print(f"{v:g} m/s, env seed {seed}: no path ({err})", flush=True)
                continue
            print(f"{v:g} m/s, env seed {seed}: {r.mean_speed:.3f} m/s, H = {LearnedPath(args.label, ex.path).lift_height:.3f} m", flush=True)
            paths.append(LearnedPath(args.label, ex.path))
            break
        else:
            print(f"{v:g} m/s: no rollout gave a path; left out", flush=True)
    if not paths:
        print("no path at any speed", file=sys.stderr)
        return 1
    learned = LearnedSet(paths)
    learned.save(args.out / "learned")
    rows = run_prototype(learned=learned, speeds=[p.speed for p in paths], modes=("hardware",), workers=1,
                         pd_scale=args.pd_scale, every_walk=False)
    summary = [r for r in ps.summary_rows(rows) if r["trajectory"] == "learned"]
    for r in summary:
        print(f"PD {args.pd_scale:g}x, {r['speed_mps']:g} m/s: battery saving against the cheaper common trajectory "
              f"{r['battery_saving_pct_mean']:.1f} % ({r['counted']} of {r['walks']} walks count, {r['fell']} fell)")
    (args.out / "walks.json").write_text(json.dumps(json_safe(rows), indent=1))
    (args.out / "saving.json").write_text(json.dumps(json_safe(summary), indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
