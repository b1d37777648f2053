"""The robot an `evaluate.py` sub-command walks: the walk config of --config and --set, and the hardware model of
its hardware-like walks.

That model is HARDWARE_LIKE, or the --config file's `hardware:` section where it has one (read as training reads
env.hardware: its fields over HardwareConfig()'s, every effect off; config.yaml holds every field), with `--set
hardware.FIELD=V` laid over it. The prototype and stiffness runs walk it (`--prototype-modes hardware`, each draw
its own seed), `check` on paths walks its spread and hardware parts on it (each check robot its own seed),
`stance-force` walks each path on it (as the first check robot), and the video walks it with `--video-robot
hardware`, the default where hardware settings are given. A sub-command that walks no hardware-like robot refuses
`--set hardware.*` in one line (it would change nothing) and walks a --config file's hardware section not at all,
with a note saying so. The output's config.yaml records the walk config and the model walked (null where the run
walks the ideal robot only, `cyberdog.config.walked`), so that --config of it walks the same robot.
"""
from __future__ import annotations

import sys

from cyberdog import config as C
from cyberdog.evaluation.options import UsageError

HARDWARE_PREFIX = "hardware."  # the --set prefix of the hardware model's fields
# where a sub-command walks no hardware-like robot: what it walks instead, or the option that made it so
IDEAL_ONLY = {
    "all": "with --no-prototype or --prototype-modes ideal and no hardware video (Table 5 walks the ideal robot)",
    "baselines": "(the baselines walk the ideal robot of Section 4.1)",
    "compare": "(Table 5, Section 4.1, walks the ideal robot; the prototype run walks hardware-like ones)",
    "extract": "(the policies roll out in their own env, and the replay check walks its own validation robots)",
    "prototype": "with --prototype-modes ideal", "stiffness": "with --prototype-modes ideal",
    "video": "with --video-robot ideal", "check": "with --parts ideal",
    "pd-match": "(the paths are re-commanded from walks on the ideal robot)",
    "export": "(the joint table is made and replayed on the ideal robot)",
    "figures": "(it draws saved results)",
    "pick": "(it reads the costs saved in the paths)",
}
ALWAYS_HARDWARE = {"stance-force"}  # sub-commands that walk a hardware-like robot whatever their options


def walk_config(args) -> C.WalkConfig:
    """The walk config of --config and --set. Sets `args.hardware`, the hardware model the run's hardware-like
    walks use (module docstring; e.g. --set hardware.latency_s=0.005 hardware.mass_uncertainty=0.1),
    `args.hardware_sets`, the `--set hardware.*` given, and `args.config_hardware`, whether the --config file has a
    hardware section."""
    sets = [str(s) for s in getattr(args, "overrides", [])]
    is_hardware = [s.strip().startswith(HARDWARE_PREFIX) and "=" in s for s in sets]
    robot = [s.split("=", 1)[0].strip().removeprefix(HARDWARE_PREFIX) + "=" + s.split("=", 1)[1]
             for s, hw in zip(sets, is_hardware) if hw]
    try:
        given = C.load_walked(args.config) if args.config else C.WalkedRobot(C.WalkConfig())
        args.hardware = C.override(given.hardware or C.HARDWARE_LIKE, robot)
        cfg = C.override(given.walk, [s for s, hw in zip(sets, is_hardware) if not hw])
    except (ValueError, OSError) as err:
        raise UsageError(f"config error: {err}") from None
    args.config_hardware = given.hardware is not None
    args.hardware_sets = [f"--set {s.split('=', 1)[0].strip()}" for s, hw in zip(sets, is_hardware) if hw]
    return cfg


def video_robot(args) -> str:
    """The robot the video walks: --video-robot, else "hardware" where hardware settings are given (--set
    hardware.* or a --config file's hardware section), else "ideal"."""
    return args.video_robot or ("hardware" if args.hardware_sets or args.config_hardware else "ideal")


def _walks_hardware(args) -> bool | None:
    """Whether the sub-command of `args` walks a hardware-like robot (None: `check --runs`, whose policies walk
    in their own env and which refuses every --set but the engine itself)."""
    command = args.command
    prototype = "hardware" in getattr(args, "prototype_modes", ())
    if command in ("prototype", "stiffness"):
        return prototype
    if command == "video":
        return video_robot(args) == "hardware"
    if command == "all":
        return (prototype and not args.no_prototype) or (args.video and video_robot(args) == "hardware")
    if command == "check":
        return None if args.runs else args.parts is None or set(args.parts) != {"ideal"}
    return command in ALWAYS_HARDWARE


def walked_hardware(args, cfg: C.WalkConfig) -> C.HardwareConfig | None:
    """The hardware model of the run's hardware-like walks (`args.hardware`, after `walk_config` made `cfg`), None
    where the run walks the ideal robot only: there `--set hardware.*` is a UsageError and a --config file's
    hardware section gets a note on stderr that it is not used. A model whose latency or filter period is no
    whole number of `cfg`'s controller periods is a UsageError."""
    walks = _walks_hardware(args)
    if walks is False:
        why = f" {IDEAL_ONLY[args.command]}" if args.command in IDEAL_ONLY else ""
        if args.hardware_sets:
            raise UsageError(f"{', '.join(args.hardware_sets)}: evaluate.py {args.command} walks no hardware-like "
                             f"robot{why}, so hardware settings change nothing; leave them out")
        if args.config_hardware:
            print(f"evaluate.py: note: --config {args.config}'s hardware section is not used: evaluate.py "
                  f"{args.command} walks no hardware-like robot{why}", file=sys.stderr)
    if not walks:
        return None
    try:
        return C.WalkedRobot(cfg, args.hardware).hardware
    except ValueError as err:
        raise UsageError(f"config error: {err}") from None


__all__ = ["HARDWARE_PREFIX", "IDEAL_ONLY", "video_robot", "walk_config", "walked_hardware"]
