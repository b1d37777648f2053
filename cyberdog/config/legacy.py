"""Earlier `EnvConfig` fields, folded into the one hardware model (`EnvConfig.hardware`, a `HardwareConfig`).

The env once had its own latency, encoder noise, mass range and Kalman speed options. They are now the
fields of `HardwareConfig`, the same model the prototype walks use. Configs and actor files saved before the
change (and keyword options such as `gymnasium.make("CyberDog-v0", latency=0.003)`) still load: each old
field maps onto its `hardware` field here. One meaning changed with the fold: encoder noise and the Kalman
speed now reach the trot controller as well as the observation, as on the robot (before, only the policy
saw them).
"""
from __future__ import annotations

import dataclasses
from typing import Any

LEGACY_ENV_FIELDS = ("observation_source", "joint_noise", "joint_angle_noise_std", "joint_velocity_noise_std",
                     "latency", "mass_scale_range", "estimator_dt", "estimator")


def fold_legacy_env_fields(data: dict) -> dict:
    """`data` (EnvConfig fields, as a dict) with the earlier fields moved into `data["hardware"]` (a dict).

    Raises ValueError for an old value that has no equivalent (an asymmetric mass range)."""
    legacy = {k: data[k] for k in LEGACY_ENV_FIELDS if k in data}
    if not legacy:
        return data
    data = {k: v for k, v in data.items() if k not in legacy}
    hw = data.get("hardware") or {}
    hw = dataclasses.asdict(hw) if dataclasses.is_dataclass(hw) else dict(hw)
    source = legacy.get("observation_source", "true")
    if source not in ("true", "estimated"):
        raise ValueError(f"EnvConfig.observation_source (now EnvConfig.hardware.estimated_velocity) must be "
                         f"'true' or 'estimated', got {source!r}")
    if source == "estimated":
        hw["estimated_velocity"] = True
    if legacy.get("joint_noise"):
        hw["joint_angle_noise_std"] = legacy.get("joint_angle_noise_std", 0.002)  # the old defaults [G]
        hw["joint_velocity_noise_std"] = legacy.get("joint_velocity_noise_std", 0.05)
    if "latency" in legacy:
        hw["latency_s"] = legacy["latency"]
    m = tuple(legacy.get("mass_scale_range") or ())
    if m:
        if len(m) != 2 or abs((m[0] + m[1]) / 2 - 1.0) > 1e-9:
            raise ValueError(f"EnvConfig.mass_scale_range {list(m)}: only a range centred on 1 maps onto "
                             f"EnvConfig.hardware.mass_uncertainty (u: scale drawn from U(1 − u, 1 + u))")
        hw["mass_uncertainty"] = round((m[1] - m[0]) / 2, 12)
    if "estimator_dt" in legacy:
        hw["estimator_dt"] = legacy["estimator_dt"]
    if "estimator" in legacy:
        est = legacy["estimator"]
        est = dataclasses.asdict(est) if dataclasses.is_dataclass(est) else dict(est or {})
        # the old switch of the IMU noise; it only ever mattered with the estimate in use
        noise = bool(est.pop("noise", False))
        hw["imu_noise"] = noise and bool(hw.get("estimated_velocity", False))
        hw["estimator"] = est
    data["hardware"] = hw
    return data

