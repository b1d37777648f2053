"""A seed's lineage: the phases of a preset (configs/<recipe>.yaml) trained one after another in one folder.

    <folder>/phases.yaml      every phase's resolved settings for this seed (written when the lineage begins)
    <folder>/<phase>/         an ordinary run folder of train.py per phase, started from the previous phase's
                              final agent (or the file its `from:` names)

`run_lineage` trains the phases in order and is its own resume: a finished phase (its final agent written) is
skipped, an interrupted one resumes from its checkpoint, a phase that died before its first checkpoint starts
again (what it left is moved to <phase>.discarded_<k>/). A failure names the seed and the phase. Standard library
and `cyberdog.config` only: the training itself is the `train` callable the command line passes in.
"""
from __future__ import annotations

import os
from pathlib import Path
from typing import Callable

from cyberdog import config as C


class LineageError(RuntimeError):
    """A lineage that cannot continue (a missing start file); the message names the seed and the phase."""


def run_lineage(folder: Path, train: Callable[..., int], say: Callable[[str], None] = print) -> int:
    """Train every phase of the lineage in `folder` not yet done; `train(cfg, label, **trainer_kwargs)`
    runs one phase and returns an exit code (0: done). Returns the first non-zero code, else 0."""
    folder = Path(folder)
    phases, _ = C.read_phases(folder)
    seed = phases[0].config.train.seed
    for i, phase in enumerate(phases, start=1):
        label = f"seed {seed}, phase {phase.name} ({i}/{len(phases)}, stage {phase.stage})"
        run = folder / phase.name
        if (folder / phase.final_agent).is_file():
            say(f"{label}: done ({phase.final_agent})")
            continue
        if (run / "checkpoint.pt").is_file():
            say(f"{label}: resuming from {run}/checkpoint.pt")
            code = train(phase.config, label, run_dir=run, resume=True)  # a budget raised since: continues
        else:
            start = folder / phase.start if phase.start else None
            if start is not None and not start.is_file():
                raise LineageError(f"{label}: its start {start} is missing (the phase before it did not finish)")
            _set_aside(run)
            say(f"{label}: starting" + (f" from {start}" if start else ""))
            stages = (1, 2) if phase.stage == "both" else (int(phase.stage),)
            code = train(phase.config, label, run_dir=run, stages=stages, init_from=start)
        if code:
            return code
    say(f"seed {seed}: every phase done; its actors: {folder / phases[-1].name}/")
    return 0


def _set_aside(run: Path) -> None:
    """Move what a phase that died before its first checkpoint left out of the way of a fresh start."""
    if run.is_dir() and any(run.iterdir()):
        k = 1 + sum(1 for p in run.parent.iterdir() if p.name.startswith(f"{run.name}.discarded_"))
        os.replace(run, run.with_name(f"{run.name}.discarded_{k}"))
