#!/usr/bin/env python
"""Train the CyberDog walking agent with TD3 or DDPG in two stages (paper Section 3).

The command line lives in the package, `cyberdog/train_cli.py` (`python train.py --help` shows it all; `python -m
cyberdog.train_cli` is the same command, and what a sweep launches for each seed). This script adds what only a
checkout has: a sweep's learning-curve figure, drawn by `plots/` from the sweep's learning_curves.csv.
"""
from __future__ import annotations

import sys

from cyberdog.train_cli import main


def draw_learning_curves(sweep_dir) -> list:
    """learning_curves.png of a sweep folder, from its learning_curves.csv (matplotlib: imported only here)."""
    from plots.learning_curves import learning_curves

    return learning_curves(sweep_dir, pdf=False)


if __name__ == "__main__":
    sys.exit(main(draw_learning_curves=draw_learning_curves))
