"""The robot a walk ran on, in a few words, for a video frame or a figure: "ideal robot", or "hardware-like
robot" with the hardware settings that differ from HARDWARE_LIKE's ("latency 5 ms"). Config only, no physics."""
from __future__ import annotations

from dataclasses import fields

from cyberdog.config import HARDWARE_LIKE, HardwareConfig, PIDConfig, to_dict

# how a hardware setting is named: field -> (words, factor to the unit shown, unit)
SETTING_WORDS = {"latency_s": ("latency", 1e3, "ms"), "joint_angle_noise_std": ("encoder noise", 1.0, "rad"),
                 "joint_velocity_noise_std": ("joint speed noise", 1.0, "rad/s"),
                 "mass_uncertainty": ("mass ±", 100.0, "%"), "estimator_dt": ("estimator period", 1e3, "ms")}


def robot_name(hardware: HardwareConfig | None) -> str:
    """ "ideal robot" (None) or "hardware-like robot" with the settings that differ from HARDWARE_LIKE's."""
    if hardware is None:
        return "ideal robot"
    changed = [_setting_words(f.name, getattr(hardware, f.name)) for f in fields(HardwareConfig)
               if getattr(hardware, f.name) != getattr(HARDWARE_LIKE, f.name)]
    return f"hardware-like robot{' (' + ', '.join(changed) + ')' if changed else ''}"


def robot_words(hardware: HardwareConfig | None, pid: PIDConfig) -> str:
    """`robot_name`, then the joint PD's gains: "ideal robot  kp 60/60/60  kd 2/2/2"."""
    return f"{robot_name(hardware)}  kp {'/'.join(f'{g:g}' for g in pid.kp)}  kd {'/'.join(f'{g:g}' for g in pid.kd)}"


def _setting_words(name: str, value) -> str:
    if name in SETTING_WORDS:
        words, factor, unit = SETTING_WORDS[name]
        return f"{words}{'' if words.endswith('±') else ' '}{value * factor:g} {unit}"
    if isinstance(value, bool):
        return f"{name.replace('_', ' ')} {'on' if value else 'off'}"
    if name == "estimator":
        return "estimator " + ", ".join(f"{k} {v:g}" for k, v in to_dict(value).items()
                                        if v != getattr(HARDWARE_LIKE.estimator, k))
    return f"{name.replace('_', ' ')} {value:g}"


__all__ = ["SETTING_WORDS", "robot_name", "robot_words"]
