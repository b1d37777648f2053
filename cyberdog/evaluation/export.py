"""`evaluate.py export`: a result taken out of the project in the forms a robot takes.

- `--policy ACTOR.pt`: the actor as TorchScript (`policy_torchscript.pt`) and ONNX (`policy.onnx`), graphs from
  the raw observation to the action, and `policy.json`, the sidecar: the observation's and the action's layout,
  units and scales, the control period, the walk a foot-mode policy needs, the source actor file, and the largest
  difference of each graph from the PyTorch actor on a rollout's observations (`cyberdog.rl.policy_export`).
- `--gait PATH.json` (a learned path, or a searched shape of results/searched_shapes/): one gait period of the
  drivers' command at `--speed` and `--rate` frames per second, per frame and joint q, q̇, kp, kd, τ_ff
  (`gait.csv`, with `gait.json` beside it), from the trot the path was recorded under
  (`cyberdog.analysis.gait_export`), checked against `--limits` (default: the CyberDog's,
  configs/robots/cyberdog_limits.yaml), then replayed in the simulator for `--replay-duration` s
  (`gait_replay.json`; exit status 1 where the replay falls or leaves the ±5 % band).

The command line (`cyberdog.evaluation.parsers`) imports this module for its help text and options (`LINE`,
`PARAGRAPH`, `add_options`): it imports neither the simulator, nor numpy, nor torch until an export runs.
"""
from __future__ import annotations

import json
import sys
from pathlib import Path

from cyberdog.evaluation.options import UsageError, positive

DEFAULT_RATE = 500.0  # Hz, the CyberDog motor SDK's command loop (cyberdog.core.joint_table.SDK_RATE_HZ)
RATE_RANGE = (100.0, 2000.0)  # Hz: SimConfig's controller period is at most 10 ms; 0.5 ms frames at the finest
LIMITS_FILE = "configs/robots/cyberdog_limits.yaml"  # the built-in limits, as a file to copy and edit
POLICY_FILES = ("policy_torchscript.pt", "policy.onnx", "policy.json")
GAIT_FILES = ("gait.csv", "gait.json", "gait_replay.json")
LINE = "a policy as TorchScript + ONNX (--policy), a foot path as a joint table at the drivers' rate (--gait)"
PARAGRAPH = ("--policy ACTOR.pt: the actor as TorchScript and ONNX graphs from the raw observation to the action, "
             "checked against the PyTorch actor on a rollout's observations, with policy.json documenting the "
             "observation and action layouts, units, scales and the control period. --gait PATH.json: one gait "
             "period of the drivers' command (q, q̇, kp, kd, τ_ff per frame and joint) at --speed and --rate from "
             "the trot's steady-state command (gait.csv + gait.json), checked against --limits, then replayed "
             "in the simulator (gait_replay.json; exit status 1 where it falls or leaves the ±5 % band).")


def rate(text: str) -> float:
    value = positive(text)
    lo, hi = RATE_RANGE
    if not lo <= value <= hi:
        import argparse

        raise argparse.ArgumentTypeError(f"must be a rate in [{lo:g}, {hi:g}] Hz, got {text!r}")
    return value


def add_options(p) -> None:
    """The options of `export` (besides the shared walk config and output folder)."""
    p.add_argument("--policy", type=Path, default=None, metavar="ACTOR",
                   help="an actor file (stage<N>_actor.pt, as load_actor reads it) to export as TorchScript + ONNX")
    p.add_argument("--gait", type=Path, default=None, metavar="PATH",
                   help="a learned path file (results/battery/paths/seed0_1mps.json) or a searched shape "
                        "(results/searched_shapes/*.json) to export as a joint table")
    p.add_argument("--speed", type=positive, default=1.0,
                   help="m/s: the gait's speed (a learned path serves speeds within ±5 %% of its own), and the "
                        "policy's check rollout's (default 1.0)")
    p.add_argument("--rate", type=rate, default=DEFAULT_RATE,
                   help=f"frames per second of the joint table (default {DEFAULT_RATE:g}, the CyberDog motor SDK's; "
                        f"in [{RATE_RANGE[0]:g}, {RATE_RANGE[1]:g}], a whole number of frames per gait period)")
    p.add_argument("--limits", type=Path, default=None, metavar="FILE",
                   help=f"the robot's limits the table must keep (YAML; default the CyberDog's, as {LIMITS_FILE})")
    p.add_argument("--no-settle", dest="settle", action="store_false",
                   help="the trot's command without the speed and heading corrections a closed-loop walk settles "
                        "to (default: with them; the uncorrected table walks slower and turns)")
    p.add_argument("--replay-duration", type=positive, default=10.0, metavar="S",
                   help="s the exported table is replayed in the simulator (default 10)")
    p.add_argument("--no-replay", dest="replay", action="store_false", help="do not replay the table")


def _check_inputs(args) -> None:
    """Every input named exists and no output would land on one, before any work."""
    if args.policy is None and args.gait is None:
        raise UsageError("export needs --policy ACTOR.pt (a policy) and/or --gait PATH.json (a foot path)")
    for option, path in (("--policy", args.policy), ("--gait", args.gait), ("--limits", args.limits),
                         ("--config", args.config)):
        if path is not None and not path.is_file():
            raise UsageError(f"{option} {path}: no such file")
    from cyberdog.evaluation.output import new_out

    args.out = args.out or new_out()
    outputs = (POLICY_FILES if args.policy else ()) + (GAIT_FILES if args.gait else ())
    inputs = {p.resolve() for p in (args.policy, args.gait, args.limits, args.config) if p is not None}
    for name in outputs:
        if (args.out / name).resolve() in inputs:
            raise UsageError(f"--out {args.out}: its {name} is an input of this export; choose another --out")


def _load_policy(args) -> None:
    """The actor file loads and the ONNX packages are there, or a UsageError naming what is wrong."""
    from cyberdog.rl.checkpoint import CheckpointError
    from cyberdog.rl.policy_export import ExportDependencyError, require_onnx
    from cyberdog.rl.rollout import load_actor

    try:
        require_onnx()
        load_actor(args.policy)
    except (ExportDependencyError, CheckpointError) as err:
        raise UsageError(f"--policy {args.policy}: {err}") from None


def _gait_table(args, cfg):
    """The joint table of --gait at --speed and --rate, within --limits (UsageError otherwise)."""
    from cyberdog.analysis.gait_export import load_limits, make_gait_table
    from cyberdog.control.gait_table import frames_per_period
    from cyberdog.core.joint_table import JointLimitError, check_limits
    from cyberdog.core.learned_set import LearnedSet
    from cyberdog.evaluation.recorded_trot import searched_trot, trot_for
    from cyberdog.provenance import portable_path

    try:
        limits = load_limits(args.limits)
    except JointLimitError as err:
        raise UsageError(f"--limits: {err}") from None
    learned = LearnedSet.load([args.gait])  # LearnedSetError: unreadable, a message naming the file
    label = learned.labels[0]
    path = learned.path(label, args.speed)  # LearnedSetError: recorded at another speed
    recorded = path.recorded_controller if path.commanded else searched_trot(path.path)
    cfg = trot_for(args, cfg, recorded, f"--gait {portable_path(args.gait)}", walked="the table is its command")
    walk_cfg, trajectory, offsets = path.walk_args(cfg, args.speed)
    try:
        frames_per_period(walk_cfg.gait.period, args.rate)
    except ValueError as err:
        raise UsageError(f"--rate: {err}") from None
    header = {"source": portable_path(args.gait), "label": label, "kind": "commanded" if path.commanded else "sampled",
              "limits": limits.source, "limit_values": limits.to_dict()}
    try:
        table, _ = make_gait_table(walk_cfg, args.speed, args.rate, trajectory, offsets, args.settle, header)
        check_limits(table, limits)
    except JointLimitError as err:
        raise UsageError(f"the joint table of --gait {args.gait} breaks a limit: {err}") from None
    except ValueError as err:
        raise UsageError(f"--gait {args.gait}: {err}") from None
    return table, walk_cfg


def cmd_export(args, cfg) -> int:
    """The `export` sub-command: inputs checked, the gait's table made and checked, then the files written."""
    from cyberdog.evaluation.output import open_run

    _check_inputs(args)
    if args.policy is not None:
        _load_policy(args)
    table = walk_cfg = None
    if args.gait is not None:
        table, walk_cfg = _gait_table(args, cfg)
    run = open_run(args, walk_cfg or cfg)  # config.yaml: the walk the table was made from
    status = 0
    if args.policy is not None:
        from cyberdog.rl.policy_export import export_policy

        files = export_policy(args.policy, run.out, speed=args.speed)
        checked = json.loads(files["sidecar"].read_text())["parity"]
        worst = {k: max(checked[f"torchscript_{k}"], checked[f"onnx_{k}"]) for k in ("action", "action_si")}
        print(f"policy: TorchScript and ONNX; largest difference from the PyTorch actor on {checked['observations']} "
              f"observations of a rollout: action {worst['action']:.2g}, action_si {worst['action_si']:.2g}")
    if table is not None:
        status = _write_gait(args, run.out, table, walk_cfg)
    finished = run.finish()
    return status or finished


def _write_gait(args, out: Path, table, walk_cfg) -> int:
    """Write the table, replay it (unless --no-replay); 1 where the replay falls or leaves the band."""
    from cyberdog.analysis.gait_export import replay_table
    from cyberdog.core.joint_table import JointTable

    csv_path, _ = table.write(out / GAIT_FILES[0])
    print(f"gait: {table.frames} frames of {1000 / table.rate:g} ms ({table.period:g} s period) at "
          f"{args.speed:g} m/s; within the limits of {table.header['limits']}")
    if not args.replay:
        return 0
    replay = replay_table(JointTable.read(csv_path), walk_cfg, args.speed, args.replay_duration)  # as written
    (out / GAIT_FILES[2]).write_text(json.dumps({"table": GAIT_FILES[0], **replay.summary()}, indent=1) + "\n")
    print(replay.line())
    ok = replay.summary()["in_band"] and not replay.result.fell
    if not ok:
        print("evaluate.py: the replayed table " + ("fell" if replay.result.fell else "left the speed band"),
              file=sys.stderr)
    return 0 if ok else 1


__all__ = ["DEFAULT_RATE", "GAIT_FILES", "LIMITS_FILE", "LINE", "PARAGRAPH", "POLICY_FILES", "add_options",
           "cmd_export", "rate"]
