#!/usr/bin/env python3
"""Evaluate foot trajectories on the simulated CyberDog (paper Sections 3 and 4).

  python evaluate.py                  # all: Table 5, the prototype experiment and the figures (the default)
  python evaluate.py SUB --help       # SUB: all, baselines, extract, compare, prototype, stiffness, figures,
                                      #      video, check, pd-match, stance-force, export, pick

The sub-commands live in `cyberdog/evaluation/`: `cli.py` parses (each sub-command has only its own options,
`parsers.py`), `commands.py` runs one sub-command, `learned.py` and `extraction.py` load or extract the learned
trajectories, `parts.py` walks, tabulates and draws; `check.py`, `pd_match.py`, `stance_force.py`, `export.py`
and `pick.py` are those sub-commands, options included. The last line printed names the output folder.
"""
from __future__ import annotations

import sys

from cyberdog.evaluation.cli import parse_args

# names scripts and tests import from evaluate.py; loaded on first use, so that --help stays light
_LIBRARY = {"load_learned": "cyberdog.evaluation.learned", "DEFAULT_LEARNED": "cyberdog.evaluation.learned"}


def draw_figures(results_dir, out_dir, metrics=None, only=None, learned=None) -> list:
    """The figures of a results folder, drawn by the checkout's `plots/` (matplotlib: imported only here)."""
    import plots

    return plots.draw_all(results_dir, out_dir, metrics, only, learned=learned)


def main(argv: list[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    args = parse_args(argv)  # --help and mistyped options end here, before the simulator is imported
    from cyberdog.evaluation.commands import run

    return run(args, argv, draw_figures=draw_figures)


def __getattr__(name: str):
    if name in _LIBRARY:
        import importlib

        return getattr(importlib.import_module(_LIBRARY[name]), name)
    raise AttributeError(f"module 'evaluate' has no attribute {name!r}")


if __name__ == "__main__":
    sys.exit(main())
