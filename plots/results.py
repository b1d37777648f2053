"""Reading the results folder that `evaluate.py` writes (all / compare / prototype): the figures' only input.

    config.yaml                   the walk config (the gait: lift height, straight-line shape, swing and stance)
    comparison.json               one row per comparison walk (Figure 13a)
    walks.json, power_traces.npz  per walk metadata and total joint power Σ|τ·θ̇| at the physics rate (Figure 10)
    prototype.json                the prototype walks (Figure 13b)
    learned/*.json                the learned paths walked (Figure 7; read as a `LearnedSet`)

Every reader returns None (or {}) for a file that is not there, so a folder written by a part of
`evaluate.py` draws the figures it has inputs for. Nothing here imports the simulator or torch.
"""
from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from cyberdog import config as C
from cyberdog.core.learned_set import LearnedSet
from cyberdog.core.trajectories import SampledTrajectory

FIGURE7_SPEED = 1.0  # m/s: Figure 7 shows each seed's path at this speed (else at the lowest one the set has)


@dataclass
class SavedResults:
    """What a results folder holds for the figures; None where the part that writes it did not run."""

    folder: Path
    gait: C.GaitConfig
    rows: list[dict] | None = None  # comparison.json
    walks: list[dict] | None = None  # walks.json
    power: dict[int, np.ndarray] | None = None  # W at the physics rate, by walk_id
    prototype_rows: list[dict] | None = None  # prototype.json
    learned: dict[str, SampledTrajectory] = field(default_factory=dict)  # Figure 7's path per label
    learned_speed: float | None = None  # m/s, the speed of those paths (Table 5's rows at it walked the same)


def _json(path: Path):
    return json.loads(path.read_text()) if path.is_file() else None


def load_gait(folder: Path) -> C.GaitConfig:
    """The gait of the walks (config.yaml, which evaluate.py writes first); the defaults if absent."""
    path = folder / "config.yaml"
    return C.load_walked(path).walk.gait if path.is_file() else C.WalkConfig().gait


def load_power(folder: Path) -> dict[int, np.ndarray] | None:
    path = folder / "power_traces.npz"
    if not path.is_file():
        return None
    with np.load(path) as z:  # keys walk_<id>
        return {int(k.split("_")[1]): np.asarray(z[k], dtype=float) for k in z.files}


def load_results(folder: str | Path, learned=None) -> SavedResults:
    """Everything the figures can use from `folder` (a folder written by `evaluate.py`); `learned`: files or
    folders of learned paths for Figure 7 instead of the folder's own learned/."""
    folder = Path(folder)
    if not folder.is_dir():
        raise FileNotFoundError(f"results folder {folder} does not exist")
    own = folder / "learned"
    learned_set = LearnedSet.load(learned) if learned else (LearnedSet.load([own]) if own.is_dir() else LearnedSet())
    speed = learned_set.figure_speed(FIGURE7_SPEED) if learned_set else None
    walks, power = _json(folder / "walks.json"), load_power(folder)
    if walks is None or power is None:  # Figure 10 needs both
        walks = power = None
    return SavedResults(folder=folder, gait=load_gait(folder), rows=_json(folder / "comparison.json"),
                        walks=walks, power=power, prototype_rows=_json(folder / "prototype.json"),
                        learned=learned_set.figure_paths(speed) if learned_set else {}, learned_speed=speed)


__all__ = ["FIGURE7_SPEED", "SavedResults", "load_gait", "load_power", "load_results"]
