"""`evaluate.py pd-match`: learned paths re-commanded for another joint PD, written as path files.

A learned path is a command: what the robot does with it depends on the joint PD that follows it. For gains of
your own, this keeps the gait the path walks under the walk config's PD (default kp 60 N·m/rad, kd 2 N·m·s/rad
per joint type, the PD the shipped policies trained around) and re-solves its foot shifts for the new gains
(`cyberdog.analysis.pd_match_recording`: each path walked for `RECORD_S` s on the ideal robot under the trot it
was recorded with; the method in docs/evaluation.md, "Re-commanded for the PD"). Each re-commanded path is written as
`<out>/learned/<same file name>` with the PD it is for in its provenance (`pd_matched`). Walk it under that PD:

    python evaluate.py pd-match results/battery/paths --kp 84 84 84 --kd 2.4 2.4 2.4 --out runs/my_pd
    python evaluate.py prototype --learned runs/my_pd/learned --set "pid.kp=[84,84,84]" "pid.kd=[2.4,2.4,2.4]"

(`--pd-scale S` instead: kp × S, kd × √S, `PIDConfig.stiffness_scaled`; the trot the paths record is applied by
evaluate.py unless --set changes the controller, and the trot each path is re-solved under is the one it records
then: `recorded_trot.made_under`). The command line (`cyberdog.evaluation.parsers`) imports this
module for its help text and options (`LINE`, `PARAGRAPH`, `add_options`): it imports neither the simulator nor
numpy until it runs.
"""
from __future__ import annotations

import dataclasses
from pathlib import Path

from cyberdog.evaluation.options import UsageError, non_negative, positive

LINE = "re-command learned paths for another joint PD (--pd-scale S, or --kp/--kd) and write them"
PARAGRAPH = ("each commanded path file (or folder of them) walks on the ideal robot under the walk config's PD and "
             "the trot it was recorded with, and its foot shifts are re-solved so that the new PD executes the "
             "same motion (cyberdog.analysis.pd_match_recording); written as learned/<same name> with the PD it "
             "is for in its provenance. Walk them with `prototype --learned OUT/learned --set pid.kp=... "
             "pid.kd=...`.")


def add_options(p) -> None:
    """The options of `pd-match` (besides the shared walk config and output folder)."""
    p.add_argument("paths", nargs="+", type=Path, metavar="PATH",
                   help="commanded path files (<label>_<v>mps.json) or folders of them")
    gains = p.add_mutually_exclusive_group(required=True)
    gains.add_argument("--pd-scale", type=positive, metavar="S", help="the PD S times as stiff: kp × S, kd × √S")
    gains.add_argument("--kp", type=positive, nargs=3, metavar=("ABAD", "HIP", "KNEE"), help="new kp, N·m/rad")
    p.add_argument("--kd", type=non_negative, nargs=3, metavar=("ABAD", "HIP", "KNEE"),
                   help="new kd, N·m·s/rad (with --kp; default: the configured kd)")


def new_pid(args, own):
    """The PD the paths are re-commanded for: `own` (a PIDConfig) scaled (kp × s, kd × √s) or the gains given."""
    if args.pd_scale is not None:
        return own.stiffness_scaled(args.pd_scale)
    return dataclasses.replace(own, kp=tuple(args.kp), kd=tuple(args.kd if args.kd is not None else own.kd))


def cmd_pd_match(args, cfg) -> int:
    from cyberdog.analysis.pd_match_recording import RECORD_S, SETTLE_S, pd_matched_foot_offsets
    from cyberdog.core.commanded_path import CommandedPath
    from cyberdog.evaluation.learned import open_path_rewrite
    from cyberdog.evaluation.recorded_trot import made_under, trot_for

    if args.kd is not None and args.kp is None:
        raise UsageError("--kd goes with --kp (--pd-scale scales kd by itself)")
    try:
        target = new_pid(args, cfg.pid)
    except ValueError as err:
        raise UsageError(f"the new PD: {err}") from None
    run, paths = open_path_rewrite(args, cfg, "a sampled path has no foot shifts to re-solve")
    for path in paths:
        walk_cfg = trot_for(args, cfg, path.recorded_controller, path.file_name(), walked="it is recorded under it")
        walk_cfg, trajectory, offsets = path.walk_args(walk_cfg, path.speed)
        matched = pd_matched_foot_offsets(walk_cfg, trajectory, offsets, target)
        shift = float(abs(matched.offsets - offsets.offsets).max()) * 1e3  # mm
        record = {"from_pid": dataclasses.asdict(walk_cfg.pid), "to_pid": dataclasses.asdict(target),
                  "recorded_on": f"the ideal robot, {RECORD_S:g} s, the first {SETTLE_S:g} s left out"}
        out = run.out / "learned" / path.file_name()
        CommandedPath(path.path.speed, path.path.gait, matched,
                      made_under({**path.provenance, "pd_matched": record}, walk_cfg)).save(out)
        print(f"{path.label} at {path.speed:g} m/s: foot shifts moved by up to {shift:.1f} mm -> {out}")
    return run.finish()


__all__ = ["add_options", "cmd_pd_match", "new_pid"]
