"""The whole robot a run walked, as one file: the walk config's sections (robot, actuator, sim, gait, pid,
controller, energy) and beside them `hardware:`, the hardware model of its hardware-like walks (null: the run
walked the ideal robot only). `evaluate.py` writes its output's config.yaml so, every hardware field written, and
reads --config so; a file without `hardware:` (a plain walk config) is the ideal robot's."""
from __future__ import annotations

from dataclasses import dataclass, fields
from pathlib import Path
from typing import Optional

import yaml

from cyberdog.config.hardware import HardwareConfig, check_controller_periods
from cyberdog.config.io import from_dict, read_settings, to_dict
from cyberdog.config.walk_settings import WalkConfig

HARDWARE_SECTION = "hardware"


@dataclass(frozen=True)
class WalkedRobot:
    """A walk config and the hardware model its hardware-like walks use (None: the ideal robot only)."""

    walk: WalkConfig
    hardware: Optional[HardwareConfig] = None

    def __post_init__(self) -> None:
        if self.hardware is not None:
            check_controller_periods(self.hardware, self.walk.sim.controller_dt, HARDWARE_SECTION,
                                     "sim.controller_dt")

    def to_dict(self) -> dict:
        """The file's mapping: the walk config's sections, then `hardware` (None for the ideal robot)."""
        return {**to_dict(self.walk), HARDWARE_SECTION: None if self.hardware is None else to_dict(self.hardware)}

    @classmethod
    def from_dict(cls, data: dict | None) -> "WalkedRobot":
        """The robot of a file's mapping; a `hardware` section is read as training reads its env.hardware: the
        fields it names laid over HardwareConfig()'s, every effect off (`to_dict` writes every field); null or
        absent is the ideal robot. ValueError names a wrong field."""
        if data is not None and not isinstance(data, dict):
            raise ValueError(f"a walk config must be a mapping of sections, got {data!r}")
        data = dict(data or {})
        section = data.pop(HARDWARE_SECTION, None)
        if section is not None and not isinstance(section, dict):
            raise ValueError(f"the {HARDWARE_SECTION} section must be null (the ideal robot) or a mapping of "
                             f"HardwareConfig fields ({', '.join(f.name for f in fields(HardwareConfig))}), got "
                             f"{section!r}")
        hardware = None if section is None else from_dict(HardwareConfig, section, HARDWARE_SECTION)
        return cls(from_dict(WalkConfig, data), hardware)


def save_walked(robot: WalkedRobot, path: str | Path) -> None:
    """Write `robot` as YAML at `path` (its folder made if missing)."""
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    with open(path, "w") as f:
        yaml.safe_dump(robot.to_dict(), f, sort_keys=False)


def load_walked(path: str | Path) -> WalkedRobot:
    """The robot of a walk config file (config.yaml of an `evaluate.py` output, or a plain walk config), read as
    every config file is (`cyberdog.config.io.read_settings`): a missing file raises `FileNotFoundError`, a
    folder, bad YAML, a training preset or bad values `ValueError` naming the file and the field."""
    data = read_settings(path, WalkConfig.__name__, [*(f.name for f in fields(WalkConfig)), HARDWARE_SECTION])
    try:
        return WalkedRobot.from_dict(data)
    except ValueError as err:
        raise ValueError(f"{path}: {err}") from None


__all__ = ["HARDWARE_SECTION", "WalkedRobot", "load_walked", "save_walked"]
