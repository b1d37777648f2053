"""The learned foot paths of a set of policies: the one type that extraction writes and that the comparison
(Table 5), the prototype run, the video and the figures read.

A `LearnedSet` maps a label (the policy's seed, "seed3", else the file's name) to that policy's paths. A path
(`LearnedPath`) is one of two kinds, and only this module tells them apart:

- commanded (`CommandedPath`): what a foot-mode policy commanded, the trot's base path plus its per-leg shift,
  recorded at one speed. A label has one per speed.
- sampled (`SampledTrajectory`): one x-z path (e.g. a measured foot path), rescaled to every speed. A label
  has exactly one.

The rule for "the path of this label at speed v" (`LearnedSet.at`), the same for every table and figure: a
commanded path recorded within ±`SPEED_BAND` (5 %, the band a walk's mean speed must hold) of v, the nearest if
several; a sampled path at any speed. A label without one is an error, never a silent gap.

What a reader needs of a path, whatever its kind: its own lift height (the matched-lift baselines' H), the walk
config, foot trajectory and foot offsets to replay it (`walk_args`), the x-z path a figure draws (`figure_path`),
its provenance (policy, seed, speed, extraction options) and its file. Pure numpy; files are JSON.

A path is recorded under one trot controller (the policy's: `ControllerConfig`, e.g. with or without sagittal
foot placement), and a path learned under one controller need not walk the same under another. Extraction
writes the controller into the provenance (`recorded_controller`), so that an evaluation walks every trajectory
of a comparison under the paths' own by default, and says so where it walks them under another
(`cyberdog.evaluation.recorded_trot`).
"""
from __future__ import annotations

import dataclasses
import json
from dataclasses import dataclass
from pathlib import Path
from typing import Iterable

from cyberdog.config import WalkConfig
from cyberdog.config.paper import SPEED_BAND as PAPER_SPEED_BAND
from cyberdog.core.commanded_path import FORMAT as COMMANDED_FORMAT
from cyberdog.core.commanded_path import CommandedPath
from cyberdog.core.foot_offsets import FootOffsetPath
from cyberdog.core.trajectories import SampledTrajectory

SPEED_BAND = PAPER_SPEED_BAND  # a commanded path serves speeds within ±5 % of the one it was recorded at
CYCLES_SUFFIX = "_cycles"  # extraction's per-cycle tables beside the paths (not paths)


class LearnedSetError(ValueError):
    """A learned path file or set that cannot be read or used as asked."""


@dataclass(frozen=True)
class LearnedPath:
    """One learned path of one label: a commanded path (one speed) or a sampled one (every speed)."""

    label: str
    path: CommandedPath | SampledTrajectory

    @property
    def commanded(self) -> bool:
        """True for a commanded path (recorded at one speed), False for a sampled one."""
        return isinstance(self.path, CommandedPath)

    @property
    def speed(self) -> float | None:
        """m/s the path was recorded at; None for a sampled path (it serves every speed)."""
        return self.path.speed if self.commanded else None

    @property
    def lift_height(self) -> float:
        """m, the path's own lift height: a commanded path's mean over its legs, a sampled path's recorded H."""
        return self.path.own_lift_height() if self.commanded else float(self.path.lift_height)

    @property
    def period(self) -> float | None:
        """s, the gait period the path was recorded with (None where a sampled file does not say)."""
        return self.path.gait.period if self.commanded else self.path.provenance.get("period_s")

    @property
    def provenance(self) -> dict:
        return self.path.provenance

    @property
    def recorded_controller(self) -> dict | None:
        """The trot controller's settings (`ControllerConfig` fields) the path was recorded under; None where the
        file does not say (extracted before the record was kept)."""
        return self.provenance.get("controller")

    def serves(self, speed: float) -> bool:
        """Whether this path walks at `speed` (m/s) by the set's rule."""
        return not self.commanded or abs(self.path.speed - speed) <= SPEED_BAND * speed

    def walk_args(self, base: WalkConfig, speed: float) -> tuple[WalkConfig, SampledTrajectory | None,
                                                                 FootOffsetPath | None]:
        """(config, foot trajectory, foot offsets) of `cyberdog.analysis.walk.walk` that replay the path at
        `speed`: a commanded path with its own base trot and its offsets, a sampled one as the trot's
        trajectory at its own lift height (so that it is replayed as recorded); the rest of `base` kept."""
        if not self.serves(speed):
            raise LearnedSetError(f"{self.label}'s path recorded at {self.speed:g} m/s does not walk at {speed:g} m/s")
        if self.commanded:
            return dataclasses.replace(base, gait=dataclasses.replace(self.path.gait, speed=float(speed))), \
                None, self.path.offsets
        gait = dataclasses.replace(base.gait, speed=float(speed), lift_height=self.lift_height)
        return dataclasses.replace(base, gait=gait), self.path, None

    def figure_path(self, leg: str = "LF") -> SampledTrajectory:
        """The x-z path a figure draws: a commanded path's reference leg (the paper's single foot; contact
        level at z = 0), a sampled path as it is."""
        return self.path.as_sampled(leg) if self.commanded else self.path

    def file_name(self) -> str:
        """`<label>_<v>mps.json` for a commanded path, `<label>.json` for a sampled one."""
        return f"{self.label}_{self.speed:g}mps.json" if self.commanded else f"{self.label}.json"

    def save(self, folder: str | Path) -> Path:
        return self.path.save(Path(folder) / self.file_name())


class LearnedSet:
    """Learned paths by label: per label, commanded paths at distinct speeds or one sampled path."""

    def __init__(self, paths: Iterable[LearnedPath] = ()):
        self._by_label: dict[str, list[LearnedPath]] = {}
        for p in paths:
            self.add(p)

    def add(self, p: LearnedPath) -> None:
        """Add a path; a second path of a label at the same speed, or a mix of kinds in a label, is an error."""
        if not isinstance(p, LearnedPath):
            raise TypeError(f"a LearnedSet holds LearnedPath values, got {type(p).__name__}")
        mine = self._by_label.setdefault(p.label, [])
        if mine and (not p.commanded or not mine[0].commanded):
            raise LearnedSetError(f"{p.label} has a sampled path, which serves every speed, and another path")
        if any(abs(q.speed - p.speed) < 1e-9 for q in mine):
            raise LearnedSetError(f"two learned paths for {p.label} at {p.speed:g} m/s")
        mine.append(p)
        mine.sort(key=lambda q: q.speed or 0.0)

    # ---- reading --------------------------------------------------------------------------------------------
    @property
    def labels(self) -> list[str]:
        """The labels, seeds in numeric order (seed2 before seed10), then the others by name."""
        return sorted(self._by_label, key=_label_key)

    def __len__(self) -> int:
        return len(self._by_label)

    def __bool__(self) -> bool:
        return bool(self._by_label)

    def __repr__(self) -> str:
        return "LearnedSet(" + "; ".join(
            f"{label}: " + ", ".join("every speed" if p.speed is None else f"{p.speed:g} m/s" for p in ps)
            for label, ps in ((label, self._by_label[label]) for label in self.labels)) + ")"

    def paths(self) -> list[LearnedPath]:
        """Every path, label by label, by speed."""
        return [p for label in self.labels for p in self._by_label[label]]

    def speeds(self) -> list[float]:
        """The speeds (m/s) the commanded paths were recorded at, ascending; [] if all are sampled."""
        return sorted({p.speed for p in self.paths() if p.commanded})

    def path(self, label: str, speed: float) -> LearnedPath:
        """The path of `label` at `speed` (m/s), by the module's rule; LearnedSetError if it has none."""
        if label not in self._by_label:
            raise LearnedSetError(f"no learned paths labelled {label!r} (the set has {', '.join(self.labels)})")
        serving = [p for p in self._by_label[label] if p.serves(speed)]
        if not serving:
            have = ", ".join(f"{p.speed:g}" for p in self._by_label[label])
            raise LearnedSetError(f"{label} has no learned path at {speed:g} m/s (its paths are at {have} m/s; "
                                  f"a path serves speeds within ±{100 * SPEED_BAND:g} % of its own)")
        return min(serving, key=lambda p: 0.0 if p.speed is None else abs(p.speed - speed))

    def has(self, label: str, speed: float) -> bool:
        """Whether `label` has a path at `speed` (m/s), by the module's rule."""
        return any(p.serves(speed) for p in self._by_label.get(label, ()))

    def covers(self, speed: float) -> bool:
        """Whether every label has a path at `speed`."""
        return bool(self) and all(self.has(label, speed) for label in self._by_label)

    def at(self, speed: float) -> dict[str, LearnedPath]:
        """Every label's path at `speed` (m/s), by the module's rule; LearnedSetError naming what is missing."""
        if not self:
            raise LearnedSetError("the learned set is empty")
        return {label: self.path(label, speed) for label in self.labels}

    def subset(self, labels: Iterable[str]) -> "LearnedSet":
        """The paths of `labels` only."""
        labels = list(labels)
        for label in labels:
            if label not in self._by_label:
                raise LearnedSetError(f"no learned paths labelled {label!r} (the set has {', '.join(self.labels)})")
        return LearnedSet(p for label in labels for p in self._by_label[label])

    def figure_paths(self, speed: float) -> dict[str, SampledTrajectory]:
        """The x-z path per label that a figure draws at `speed`: `path(label, speed)`'s, so a table row at that
        speed and its figure show the same path; a label without a path there (an extraction that found none,
        walked with --skip-missing-paths) is left out, and LearnedSetError where no label has one."""
        here = {label: self.path(label, speed).figure_path() for label in self.labels if self.has(label, speed)}
        return here or {label: p.figure_path() for label, p in self.at(speed).items()}

    def figure_speed(self, preferred: float) -> float:
        """`preferred` (m/s) if a label has a path there, else the set's lowest recorded speed (a figure must
        name one)."""
        return preferred if any(self.has(label, preferred) for label in self.labels) or not self.speeds() \
            else self.speeds()[0]

    # ---- files ------------------------------------------------------------------------------------------------
    def save(self, folder: str | Path, overwrite: bool = True) -> list[Path]:
        """One JSON per path in `folder` (`LearnedPath.file_name`); with overwrite=False existing files stay."""
        out = []
        for p in self.paths():
            target = Path(folder) / p.file_name()
            out.append(target if target.is_file() and not overwrite else p.save(folder))
        return out

    @classmethod
    def load(cls, paths: Iterable[str | Path]) -> "LearnedSet":
        """The one loader of learned paths: files as given, folders as their JSON files (extraction's
        `*_cycles` tables left out). Labels: the provenance's `label` where it names one (`evaluate.py pick`),
        else `seed<N>` from its training seed, else the file name."""
        learned = cls()
        for f in learned_files(paths):
            path = read_path(f)
            seed = path.provenance.get("seed")
            # a label the file names (a picked path saved under its reported seed), else its training seed's
            label = path.provenance.get("label") or (f"seed{seed}" if seed is not None else f.stem)
            if not isinstance(path, CommandedPath) and label in learned._by_label:
                label = f.stem  # two sampled paths of one seed: by file
            try:
                learned.add(LearnedPath(label, path))
            except LearnedSetError as err:
                raise LearnedSetError(f"{err} ({f})") from None
        return learned


def learned_files(paths: Iterable[str | Path]) -> list[Path]:
    """The learned path files named: files as given, folders expanded to their JSON files (no `*_cycles`)."""
    files = []
    for p in map(Path, paths):
        if p.is_dir():
            found = sorted(f for f in p.glob("*.json") if not f.stem.endswith(CYCLES_SUFFIX))
            if not found:
                raise LearnedSetError(f"learned path folder {p} holds no JSON file")
            files += found
        elif p.is_file():
            files.append(p)
        else:
            raise LearnedSetError(f"learned path {p} does not exist")
    return files


def read_path(file: str | Path) -> CommandedPath | SampledTrajectory:
    """One learned path file: a commanded path (JSON with its format tag) or a sampled trajectory."""
    file = Path(file)
    try:
        if file.suffix.lower() == ".json":
            d = json.loads(file.read_text())
            if isinstance(d, dict) and d.get("format") == COMMANDED_FORMAT:
                return CommandedPath.from_dict(d)
        return SampledTrajectory.load(file)
    except (OSError, ValueError, KeyError) as err:  # json.JSONDecodeError is a ValueError
        raise LearnedSetError(f"learned path {file} is unreadable: {err}") from None


def _label_key(label: str) -> tuple:
    """seed2 before seed10; other labels after the seeds, by name."""
    digits = label[4:] if label.startswith("seed") else ""
    return (0, int(digits), "") if digits.isdigit() else (1, 0, label)


__all__ = ["LearnedPath", "LearnedSet", "LearnedSetError", "SPEED_BAND", "learned_files", "read_path"]
