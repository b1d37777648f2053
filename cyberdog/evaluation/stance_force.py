"""`evaluate.py stance-force`: learned paths written as their feet's motion and their stance legs' force.

A learned path commands foot targets its stance feet do not reach; the joint PD turns the error into the force that
saves the energy, so the gains a user sets scale it. This writes each path as the motion its feet make with the
stance torque its joints exert as a feedforward the trot adds (`cyberdog.analysis.stance_force`: walked 10 s
after a 3 s run-up, under the trot it was recorded with and the walk config's PD, on the extraction's first
hardware-like check robot: HARDWARE_LIKE, or as --set hardware.* makes it, at seed 1000 + hardware.seed), its
fore-aft motion stretched until it walks there at the path's own speed, as
`<out>/learned/<same file name>` with how it was made in its provenance (`stance_force`) and the trot it was made
under as the one it records (`recorded_trot.made_under`: a --set controller.* here is the form's trot). Walk it as
any path, under any gains:

    python evaluate.py stance-force results/battery_searched_pick/paths --out runs/stance_force
    python evaluate.py prototype --learned runs/stance_force/learned --set "pid.kd=[4,4,4]"

The command line (`cyberdog.evaluation.parsers`) imports this module for its help text and options (`LINE`,
`PARAGRAPH`, `add_options`): it imports neither the simulator nor numpy until it runs.
"""
from __future__ import annotations

import dataclasses
from pathlib import Path

from cyberdog.evaluation.options import UsageError

LINE = "write learned paths as their feet's motion plus their stance legs' torque, a gait the gains do not scale"
PARAGRAPH = ("each commanded path file (or folder of them) walks on a hardware-like check robot under the walk "
             "config's PD and the trot it was recorded with; the feet's mean realised path becomes its foot path and "
             "the mean torque the joint PD exerted in stance a feedforward the trot adds, the motion stretched fore "
             "and aft until it walks at the path's speed (cyberdog.analysis.stance_force); written as "
             "learned/<same name>. Walk them with `prototype --learned OUT/learned`, under any --set pid.kp/pid.kd.")


def add_options(p) -> None:
    """The options of `stance-force` (besides the shared walk config and output folder)."""
    p.add_argument("paths", nargs="+", type=Path, metavar="PATH",
                   help="commanded path files (<label>_<v>mps.json) or folders of them")
    p.add_argument("--harmonics", type=int, default=None, metavar="K",
                   help="Fourier harmonics of the phase kept in the motion and the torque (default 6)")


def cmd_stance_force(args, cfg) -> int:
    from cyberdog.analysis.stance_force import HARMONICS, check_robot, stance_force_path
    from cyberdog.evaluation.learned import open_path_rewrite
    from cyberdog.evaluation.recorded_trot import made_under, trot_for

    harmonics = HARMONICS if args.harmonics is None else args.harmonics
    if not 1 <= harmonics <= 31:
        raise UsageError(f"--harmonics {harmonics}: between 1 and 31 (the path has 64 phases)")
    run, paths = open_path_rewrite(args, cfg, "a sampled path has no foot targets of its own to rewrite", _carried)
    for path in paths:
        walk_cfg = trot_for(args, cfg, path.recorded_controller, path.file_name(), walked="it is recorded under it")
        rewritten, record = stance_force_path(path.path, walk_cfg, check_robot(args.hardware), harmonics=harmonics)
        out = run.out / "learned" / path.file_name()
        dataclasses.replace(rewritten, provenance=made_under(rewritten.provenance, walk_cfg)).save(out)
        print(f"{path.label} at {path.speed:g} m/s: stance error {record['stance_error_rms_mm']:.1f} mm rms, mean "
              f"stance torque {' / '.join(f'{v:.2f}' for v in record['mean_feedforward_Nm'])} N·m (abad / hip / "
              f"knee), fore-aft motion x{record['sweep_stretch']:.3f} to walk its {record['path_speed_mps']:.3f} m/s "
              f"-> {out}")
    return run.finish()


def _carried(paths) -> str | None:
    """The refusal of paths that carry a torque already: the PD alone did not make their motion."""
    carried = [p.label for p in paths if p.path.offsets.feedforward is not None]
    return f"{', '.join(carried)}: already written with a stance torque" if carried else None


__all__ = ["add_options", "cmd_stance_force"]
