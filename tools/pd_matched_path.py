#!/usr/bin/env python
"""Write a learned path re-commanded for another joint PD: the gait it walks under the configured PD, commanded
for your gains (`cyberdog.analysis.pd_matched`; the method in docs/pd_matching.md).

    python tools/pd_matched_path.py results/battery/paths/seed0_1.4mps.json --pd-scale 1.4 --out runs/pd14
    python tools/pd_matched_path.py PATH.json --kp 84 84 84 --kd 2.4 2.4 2.4 --out runs/my_pd

Each commanded path file (as `evaluate.py extract` writes them) is replayed for 8 s on the ideal robot under the
configured PD (kp 60, kd 2 N·m/rad, N·m·s/rad per joint type, the one the shipped policies trained around) and
its trot as recorded; its foot shifts are re-solved for the new gains and written as `<out>/<same name>` (never
over an existing file), with the PD it is for in its provenance (`pd_matched`). Walk it under that PD, e.g.
`python evaluate.py prototype --learned <out> --set "pid.kp=[84,84,84]" "pid.kd=[2.4,2.4,2.4]"` (plus the trot
the path records, which evaluate.py applies by itself unless --set changes the controller).
"""
from __future__ import annotations

import argparse
import dataclasses
import math
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

from cyberdog.analysis.pd_matched import RECORD_S, SETTLE_S, pd_matched_foot_offsets  # noqa: E402
from cyberdog.config import PIDConfig, WalkConfig  # noqa: E402
from cyberdog.core.commanded_path import CommandedPath  # noqa: E402
from cyberdog.core.learned_set import LearnedSet, LearnedSetError  # noqa: E402
from cyberdog.evaluation.trot import with_trot  # noqa: E402


def new_pid(args, own: PIDConfig) -> PIDConfig:
    """The PD the paths are re-commanded for: `own` scaled (kp × s, kd × √s) or the gains given."""
    if args.pd_scale is not None:
        return own.stiffness_scaled(args.pd_scale)
    return dataclasses.replace(own, kp=tuple(args.kp), kd=tuple(args.kd if args.kd is not None else own.kd))


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("paths", nargs="+", type=Path, help="commanded path files (<label>_<v>mps.json)")
    gains = p.add_mutually_exclusive_group(required=True)
    gains.add_argument("--pd-scale", type=float, metavar="S", help="the PD S times as stiff: kp × S, kd × √S")
    gains.add_argument("--kp", type=float, nargs=3, metavar=("ABAD", "HIP", "KNEE"), help="new kp, N·m/rad")
    p.add_argument("--kd", type=float, nargs=3, metavar=("ABAD", "HIP", "KNEE"),
                   help="new kd, N·m·s/rad (with --kp; default: the configured kd)")
    p.add_argument("--out", type=Path, required=True, help="folder to write the re-commanded paths to")
    args = p.parse_args(argv)
    if args.kd is not None and args.kp is None:
        p.error("--kd goes with --kp")
    if args.pd_scale is not None and not (math.isfinite(args.pd_scale) and args.pd_scale > 0):
        p.error(f"--pd-scale must be a finite number > 0, got {args.pd_scale}")
    base = WalkConfig()
    try:
        target = new_pid(args, base.pid)
        learned = LearnedSet.load(args.paths)
    except (ValueError, LearnedSetError) as err:
        p.error(str(err))
    for path in learned.paths():
        if not path.commanded:
            p.error(f"{path.label}: a sampled path has no foot shifts to re-solve; give a commanded path file")
        out = args.out / path.file_name()
        if out.exists():
            p.error(f"{out} exists: choose another --out (outputs never overwrite)")
        cfg = with_trot(base, path.recorded_controller) if path.recorded_controller else base
        cfg, trajectory, offsets = path.walk_args(cfg, path.speed)
        matched = pd_matched_foot_offsets(cfg, trajectory, offsets, target)
        shift = float(abs(matched.offsets - offsets.offsets).max()) * 1e3
        record = {"from_pid": dataclasses.asdict(cfg.pid), "to_pid": dataclasses.asdict(target),
                  "recorded_on": f"the ideal robot, {RECORD_S:g} s, the first {SETTLE_S:g} s left out"}
        commanded = CommandedPath(path.path.speed, path.path.gait, matched,
                                  {**path.provenance, "pd_matched": record})
        commanded.save(out)
        print(f"{path.label} at {path.speed:g} m/s: foot shifts moved by up to {shift:.1f} mm -> {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
