"""Builders the test modules share (imported as `from conftest import ...`; no test module imports another).

Test tiers: `python -m pytest -q` runs everything (the README's command, CI's); `python -m pytest -q -m "not
slow"` is the quick tier, without the tests marked `slow` (each over about 30 s: trainings, full walks,
subprocess runs), for the edit-test loop.
"""
from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from cyberdog import config as C
from cyberdog.core.commanded_path import CommandedPath
from cyberdog.core.learned_set import LearnedPath, LearnedSet
from cyberdog.core.foot_offsets import FootOffsetPath
from cyberdog.metrics_csv import read_rows
from cyberdog.rl.logger import TIMING_COLUMNS

ROOT = Path(__file__).resolve().parents[1]
TINY = ROOT / "configs" / "tiny.yaml"


def tiny(*sets) -> C.ExperimentConfig:
    """configs/tiny.yaml with the overrides `sets` (strings, or lists of them, applied in order)."""
    flat = [s for group in sets for s in ([group] if isinstance(group, str) else group)]
    return C.override(C.load(C.ExperimentConfig, TINY), flat)


def assert_made_by(phases_file: Path, recipe: list) -> None:
    """The phases recorded in `phases_file` (a lineage's phases.yaml, or a shipped recipe_phases.yaml) are
    `recipe`'s (a preset's resolved phases) in order, from the same starts, with the same settings but the seed."""
    made = C.read_phases(phases_file)[0]
    assert [(p.name, p.stage, p.start) for p in made] == [(p.name, p.stage, p.start) for p in recipe]
    for mine, now in zip(made, recipe):
        assert set(C.changed_settings(mine.config, now.config)) <= {"train.seed"}, (str(phases_file), mine.name)


def metrics_rows(run_dir: Path) -> list[dict]:
    """A run's metrics.csv rows (the package's one reader, `cyberdog.metrics_csv`) without the timing columns,
    which differ between identical reruns."""
    return [{k: v for k, v in r.items() if k not in TIMING_COLUMNS} for r in read_rows(Path(run_dir) / "metrics.csv")]


def stop_after(trainer, env_steps: int) -> None:
    """Run `trainer` and stop it, as a crash would, once its env-step counter passes `env_steps` (set that to a
    checkpoint's step count: the run folder then holds the checkpoint written there)."""
    class Interrupt(Exception):
        pass

    bookkeep = trainer._bookkeep

    def interrupted(*args):
        if trainer.progress.env_steps > env_steps:
            raise Interrupt
        bookkeep(*args)

    trainer._bookkeep = interrupted
    with pytest.raises(Interrupt):
        trainer.run()


def walk_config(trajectory: str = "cycloid", speed: float = 1.0, lift_height: float | None = None,
                straight_shape: str = "rectangle", **controller) -> C.WalkConfig:
    """The default walk with another trajectory, speed, lift height (m; None: the default) or controller."""
    base = C.WalkConfig()
    gait = dataclasses.replace(base.gait, trajectory=trajectory, speed=speed, straight_shape=straight_shape,
                               **({} if lift_height is None else {"lift_height": lift_height}))
    return dataclasses.replace(base, gait=gait, controller=dataclasses.replace(base.controller, **controller))


def learned_set(**paths_by_label) -> LearnedSet:
    """A LearnedSet from label=[paths] (CommandedPath or SampledTrajectory)."""
    return LearnedSet(LearnedPath(label, p) for label, paths in paths_by_label.items() for p in paths)


def commanded(speed: float, dz: float, seed: int) -> CommandedPath:
    """A commanded path: the env's cycloid (H = 0.10 m) with the swing feet shifted by dz (m) at mid-swing, so
    that its own lift height is H + dz."""
    table = np.zeros((4, 40, 3))
    table[:, :20, 2] = dz * np.sin(np.pi * np.arange(20) / 20)
    return CommandedPath(speed, C.GaitConfig(lift_height=0.10), FootOffsetPath(table, 0.4), {"seed": seed})
