"""The command line of `evaluate.py`: one sub-parser per sub-command, each with only the options it uses.

This module assembles the parser: each sub-command's options come from its function in `parsers` (the blocks
several share from `options`). Nothing here imports the simulator or numpy, so that `evaluate.py SUB --help`
answers at once.
"""
from __future__ import annotations

import argparse
import difflib
import sys

# the defaults and the usage error callers take from the command line's module (declared in `options`)
from cyberdog.evaluation.options import (BASELINE_CHOICES, CYCLE_CHOICES, DEFAULT_PROTOTYPE_DISTANCE,  # noqa: F401
                                         DEFAULT_PROTOTYPE_DRAWS, DEFAULT_PROTOTYPE_RUN_UP, EXTRACT_DEFAULTS,
                                         UsageError)
from cyberdog.evaluation.parsers import COMMANDS

DEFAULT_COMMAND = "all"

DESCRIPTION = """\
Evaluate foot trajectories on the simulated CyberDog (paper Sections 3 and 4).

Without a sub-command, `all` runs. `evaluate.py SUB --help` lists the options of one sub-command.

Outputs go to --out (default runs/evaluate-<time>/), never over inputs; a folder that already holds results is
refused unless --force (which first removes the files previous runs recorded in its outputs.json); every file a
run writes is listed at the end and recorded in outputs.json; the last line names the folder.
"""


class _Parser(argparse.ArgumentParser):
    """An unknown option that another sub-command takes is named with the sub-commands that take it."""

    known: dict[str, list[str]] = {}  # option string -> sub-commands that accept it, filled by build_parser

    def error(self, message):
        if message.startswith("unrecognized arguments:"):
            hints = [f"{opt} is an option of: {', '.join(self.known[opt])}"
                     for opt in message.split(":", 1)[1].split() if opt in self.known]
            if hints:
                message += " (" + "; ".join(hints) + ")"
        super().error(message)


def build_parser() -> argparse.ArgumentParser:
    top = _Parser(prog="evaluate.py", description=DESCRIPTION, formatter_class=argparse.RawDescriptionHelpFormatter)
    subs = top.add_subparsers(dest="command", metavar="SUB-COMMAND", parser_class=_Parser, required=True)
    sub = {}
    for name, (line, paragraph, add_options) in COMMANDS.items():
        sub[name] = subs.add_parser(name, help=line, description=f"{name}: {paragraph}")
        add_options(sub[name])
    known: dict[str, list[str]] = {}
    for name, p in sub.items():
        for action in p._actions:
            for opt in action.option_strings:
                if opt not in ("-h", "--help"):
                    known.setdefault(opt, []).append(name)
    _Parser.known = known
    top.sub_commands = sub
    return top


def parse_args(argv: list[str]) -> argparse.Namespace:
    """Parse `argv` (without the program name); no sub-command means `all`, as in `evaluate.py --out DIR`.
    An option the sub-command does not take ends the program (status 2) with a line naming the sub-commands
    that do take it."""
    argv = list(argv)
    if argv and not argv[0].startswith("-") and argv[0] not in COMMANDS:  # a word where a sub-command goes
        close = difflib.get_close_matches(argv[0], COMMANDS, n=1)
        hint = f"; did you mean '{close[0]}'?" if close else ""
        print(f"evaluate.py: error: unknown sub-command '{argv[0]}' (one of {', '.join(COMMANDS)}){hint}",
              file=sys.stderr)
        raise SystemExit(2)
    if not argv or (argv[0] not in COMMANDS and argv[0] not in ("-h", "--help")):
        argv.insert(0, DEFAULT_COMMAND)
    top = build_parser()
    args, extras = top.parse_known_args(argv)
    if extras:  # reported by the sub-command's parser, with its own usage line
        top.sub_commands[args.command].error(f"unrecognized arguments: {' '.join(extras)}")
    return args


__all__ = ["BASELINE_CHOICES", "COMMANDS", "CYCLE_CHOICES", "DEFAULT_PROTOTYPE_DISTANCE", "DEFAULT_PROTOTYPE_DRAWS",
           "DEFAULT_PROTOTYPE_RUN_UP", "EXTRACT_DEFAULTS", "UsageError", "build_parser", "parse_args"]
