"""The whole robot a run walked, as one file: the walk config's sections (robot, actuator, sim, gait, pid,
controller, energy) and beside them `hardware:`, the hardware model of its hardware-like walks (null: the run
walked the ideal robot only). `evaluate.py` writes its output's config.yaml so and reads --config so; a file
without `hardware:` (a plain walk config) is the ideal robot's."""
from __future__ import annotations

from dataclasses import dataclass, fields
from pathlib import Path
from typing import Optional

import yaml

from cyberdog.config._validate import _check
from cyberdog.config.hardware import HARDWARE_LIKE, HardwareConfig
from cyberdog.config.io import from_dict, merged, not_found, to_dict
from cyberdog.config.walk_settings import PIDConfig, WalkConfig

HARDWARE_SECTION = "hardware"
# how a hardware setting is named on a video frame: field -> (words, factor to the unit shown, unit)
_WORDS = {"latency_s": ("latency", 1e3, "ms"), "joint_angle_noise_std": ("encoder noise", 1.0, "rad"),
          "joint_velocity_noise_std": ("joint speed noise", 1.0, "rad/s"),
          "mass_uncertainty": ("mass ±", 100.0, "%"), "estimator_dt": ("estimator period", 1e3, "ms")}


@dataclass(frozen=True)
class WalkedRobot:
    """A walk config and the hardware model its hardware-like walks use (None: the ideal robot only)."""

    walk: WalkConfig
    hardware: Optional[HardwareConfig] = None

    def __post_init__(self) -> None:
        if self.hardware is None:
            return
        dt = self.walk.sim.controller_dt
        for name in ("latency_s", "estimator_dt"):
            value = getattr(self.hardware, name)
            _check(abs(value / dt - round(value / dt)) < 1e-6, f"HardwareConfig.{name} (hardware.{name})",
                   f"a whole multiple of sim.controller_dt ({dt} s)", value)

    def to_dict(self) -> dict:
        """The file's mapping: the walk config's sections, then `hardware` (None for the ideal robot)."""
        return {**to_dict(self.walk), HARDWARE_SECTION: None if self.hardware is None else to_dict(self.hardware)}

    @classmethod
    def from_dict(cls, data: dict | None) -> "WalkedRobot":
        """The robot of a file's mapping; a `hardware` section lays its fields over HARDWARE_LIKE's (as
        --set hardware.FIELD does), null or absent is the ideal robot. ValueError names a wrong field."""
        if data is not None and not isinstance(data, dict):
            raise ValueError(f"a walk config must be a mapping of sections, got {data!r}")
        data = dict(data or {})
        section = data.pop(HARDWARE_SECTION, None)
        if section is not None and not isinstance(section, dict):
            raise ValueError(f"the {HARDWARE_SECTION} section must be null (the ideal robot) or a mapping of "
                             f"HardwareConfig fields ({', '.join(f.name for f in fields(HardwareConfig))}), got "
                             f"{section!r}")
        hardware = None if section is None else from_dict(HardwareConfig, merged(to_dict(HARDWARE_LIKE), section),
                                                          HARDWARE_SECTION)
        return cls(from_dict(WalkConfig, data), hardware)


def save_walked(robot: WalkedRobot, path: str | Path) -> None:
    """Write `robot` as YAML at `path` (its folder made if missing)."""
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    with open(path, "w") as f:
        yaml.safe_dump(robot.to_dict(), f, sort_keys=False)


def load_walked(path: str | Path) -> WalkedRobot:
    """The robot of a walk config file (config.yaml of an `evaluate.py` output, or a plain walk config). A
    missing file raises `FileNotFoundError`, bad YAML or values `ValueError` naming the file and the field."""
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"config {path} is a folder, expected a YAML file" if path.is_dir()
                                else not_found(path, "config file"))
    try:
        data = yaml.safe_load(path.read_text())
    except yaml.YAMLError as err:
        raise ValueError(f"config {path} is not valid YAML: {' '.join(str(err).split())}") from None
    try:
        return WalkedRobot.from_dict(data)
    except ValueError as err:
        raise ValueError(f"{path}: {err}") from None


def robot_words(hardware: HardwareConfig | None, pid: PIDConfig) -> str:
    """The robot in a few words, for a video frame: "ideal robot" or "hardware-like robot" with the settings
    that differ from HARDWARE_LIKE's ("latency 5 ms"), then the joint PD's gains."""
    gains = f"kp {'/'.join(f'{g:g}' for g in pid.kp)}  kd {'/'.join(f'{g:g}' for g in pid.kd)}"
    if hardware is None:
        return f"ideal robot  {gains}"
    changed = [_setting_words(f.name, getattr(hardware, f.name)) for f in fields(HardwareConfig)
               if getattr(hardware, f.name) != getattr(HARDWARE_LIKE, f.name)]
    return f"hardware-like robot{' (' + ', '.join(changed) + ')' if changed else ''}  {gains}"


def _setting_words(name: str, value) -> str:
    if name in _WORDS:
        words, factor, unit = _WORDS[name]
        return f"{words}{'' if words.endswith('±') else ' '}{value * factor:g} {unit}"
    if isinstance(value, bool):
        return f"{name.replace('_', ' ')} {'on' if value else 'off'}"
    if name == "estimator":
        return "estimator " + ", ".join(f"{k} {v:g}" for k, v in to_dict(value).items()
                                        if v != getattr(HARDWARE_LIKE.estimator, k))
    return f"{name.replace('_', ' ')} {value:g}"


__all__ = ["HARDWARE_SECTION", "WalkedRobot", "load_walked", "robot_words", "save_walked"]
