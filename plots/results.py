"""Reading the results folder that `evaluate.py` writes (all / compare / prototype): the figures' only input.

    config.yaml                   the walk config (the gait: lift height, straight-line shape, swing and stance)
    comparison.json               one row per comparison walk (Figure 13a)
    walks.json, power_traces.npz  per walk metadata and total joint power Σ|τ·θ̇| at the physics rate (Figure 10)
    prototype.json                the prototype walks (Figure 13b)
    learned/<label>.json          the learned paths walked (Figure 7)

Every reader returns None (or {}) for a file that is not there, so a folder written by a part of
`evaluate.py` draws the figures it has inputs for. Nothing here imports the simulator or torch.
"""
from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from cyberdog import config as C
from cyberdog.core.commanded_path import CommandedPath, load_foot_path
from cyberdog.core.trajectories import SampledTrajectory

FIGURE7_SPEED = 1.0  # m/s: Figure 7 shows each seed's path at this speed (or the nearest one it has)


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


def _json(path: Path):
    return json.loads(path.read_text()) if path.is_file() else None


def load_gait(folder: Path) -> C.GaitConfig:
    """The gait of the walks (config.yaml, which evaluate.py writes first); the defaults if absent."""
    path = folder / "config.yaml"
    return C.load(C.WalkConfig, path).gait if path.is_file() else C.WalkConfig().gait


def load_power(folder: Path) -> dict[int, np.ndarray] | None:
    path = folder / "power_traces.npz"
    if not path.is_file():
        return None
    with np.load(path) as z:  # keys walk_<id>
        return {int(k.split("_")[1]): np.asarray(z[k], dtype=float) for k in z.files}


def learned_files(folder: Path) -> list[Path]:
    """The learned path files of a folder (its per-cycle tables `*_cycles.*` left out)."""
    if not folder.is_dir():
        return []
    return sorted(f for f in folder.glob("*.json") if not f.stem.endswith("_cycles"))


def load_learned(files: list[Path], speed: float = FIGURE7_SPEED) -> dict[str, SampledTrajectory]:
    """One x–z path per seed for Figure 7: of a seed's commanded paths (one per speed) the one nearest
    `speed`, as its reference leg's (LF) path; a sampled (measured) path as it is. Labels: `seed<N>` from
    the file's provenance, else the file name."""
    groups: dict[str, dict[float, CommandedPath]] = {}
    out: dict[str, SampledTrajectory] = {}
    for f in files:
        t = load_foot_path(f)
        seed = t.provenance.get("seed")
        label = f"seed{seed}" if seed is not None else f.stem
        if isinstance(t, CommandedPath):
            groups.setdefault(label, {})[t.speed] = t
        else:
            out[label if label not in out else f.stem] = t
    for label, by_speed in groups.items():
        nearest = min(by_speed, key=lambda v: abs(v - speed))
        out[label] = by_speed[nearest].as_sampled("LF")
    return dict(sorted(out.items(), key=lambda kv: _label_key(kv[0])))


def _label_key(label: str) -> tuple:
    """seed2 before seed10; other labels after the seeds, by name."""
    digits = label[4:] if label.startswith("seed") else ""
    return (0, int(digits), "") if digits.isdigit() else (1, 0, label)


def expand_learned(paths) -> list[Path]:
    """Learned path files named by the user: files as given, folders as their learned path files."""
    out = []
    for p in map(Path, paths):
        if not p.exists():
            raise FileNotFoundError(f"learned trajectory {p} does not exist")
        out += learned_files(p) if p.is_dir() else [p]
    return out


def load_results(folder: str | Path, learned=None) -> SavedResults:
    """Everything the figures can use from `folder` (a folder written by `evaluate.py`); `learned`: files or
    folders of learned paths for Figure 7 instead of the folder's own learned/."""
    folder = Path(folder)
    if not folder.is_dir():
        raise FileNotFoundError(f"results folder {folder} does not exist")
    files = expand_learned(learned) if learned else learned_files(folder / "learned")
    walks, power = _json(folder / "walks.json"), load_power(folder)
    if walks is None or power is None:  # Figure 10 needs both
        walks = power = None
    return SavedResults(folder=folder, gait=load_gait(folder), rows=_json(folder / "comparison.json"),
                        walks=walks, power=power, prototype_rows=_json(folder / "prototype.json"),
                        learned=load_learned(files))


__all__ = ["FIGURE7_SPEED", "SavedResults", "expand_learned", "learned_files", "load_gait", "load_learned", "load_power",
           "load_results"]
