"""A gait as a joint table: one gait period of the motor drivers' command, frame by frame, at the drivers' rate.

CyberDog's motor drivers take, per joint and frame, (q_des, q̇_des, kp, kd, τ_ff) (`cyberdog.core.drivers`;
docs/robot.md, "The robot's joint drivers": the SDK's loop runs at 500 Hz). A `JointTable` holds one gait period
of such frames; repeated, it is the gait. Its CSV has one row per frame (`frame`, `t_s`, then per joint in
`JOINTS` order its five columns, `COLUMNS`, units in the names) and a JSON sidecar beside it (`<name>.json`: rate,
frames, period, joint order, columns and units, and the header the exporter adds: speed, source, ...).

`JointLimits` are the limits a robot's drivers set on such a table (the CyberDog's: `JointLimits.cyberdog()`,
the same values as configs/robots/cyberdog_limits.yaml); `check_limits` refuses a table that breaks one, in one
line naming the frame, the joint and the limit. Pure numpy.
"""
from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from cyberdog.config import JOINT_NAMES, LEG_NAMES, ActuatorConfig, RobotConfig
from cyberdog.core.drivers import JointCommand

FORMAT = "cyberdog.joint_table"
JOINTS = tuple(f"{leg}_{joint}" for leg in LEG_NAMES for joint in JOINT_NAMES)  # LF_abad, LF_hip, ..., RH_knee
COLUMNS = ("q", "dq", "kp", "kd", "tau_ff")  # per joint and frame: CyberDog's (q_des, qd_des, kp, kd, tau_ff)
UNITS = {"q": "rad", "dq": "rad/s", "kp": "N·m/rad", "kd": "N·m·s/rad", "tau_ff": "N·m"}
CSV_SUFFIX = {"q": "rad", "dq": "radps", "kp": "Nm_per_rad", "kd": "Nms_per_rad", "tau_ff": "Nm"}

# CyberDog's motor SDK (MiRoboticsLab cyberdog_motor_sdk; docs/robot.md, "The robot's joint drivers")
SDK_RATE_HZ = 500.0  # Hz, the SDK's command loop
SDK_KP_RANGE = (0.0, 200.0)  # N·m/rad, the kp a command may carry
SDK_KD_RANGE = (0.0, 10.0)  # N·m·s/rad, the kd a command may carry
SDK_POSITION_JUMP_DEG = (8.0, 10.0, 12.0)  # deg per frame (abad, hip, knee): the SDK clamps a larger jump


class JointLimitError(ValueError):
    """A joint table that breaks a limit, or a limits file that cannot be read; the message is one line."""


@dataclass
class JointTable:
    """One gait period of the drivers' command: `rate` frames per second, arrays (frames, 12) in `JOINTS` order."""

    rate: float  # Hz, frames per second
    q: np.ndarray  # rad, joint targets
    dq: np.ndarray  # rad/s, joint speed targets
    kp: np.ndarray  # N·m/rad
    kd: np.ndarray  # N·m·s/rad
    tau_ff: np.ndarray  # N·m, feedforward torque, added after the drivers' PD clamp
    header: dict = field(default_factory=dict)  # speed, source, ... (JSON-serialisable)

    def __post_init__(self) -> None:
        if not (math.isfinite(self.rate) and self.rate > 0):
            raise ValueError(f"rate must be > 0 Hz, got {self.rate!r}")
        for name in COLUMNS:
            a = np.asarray(getattr(self, name), dtype=float)
            if a.ndim != 2 or a.shape[1] != len(JOINTS) or len(a) == 0:
                raise ValueError(f"JointTable.{name} must be (frames >= 1, 12), got {a.shape}")
            if not np.all(np.isfinite(a)):
                raise ValueError(f"JointTable.{name} must be finite")
            setattr(self, name, a)
        shapes = {getattr(self, name).shape for name in COLUMNS}
        if len(shapes) != 1:
            raise ValueError(f"JointTable's columns must have one shape, got {sorted(shapes)}")

    @property
    def frames(self) -> int:
        return len(self.q)

    @property
    def period(self) -> float:
        """s, the gait period the table repeats."""
        return self.frames / self.rate

    def command(self, frame: int) -> JointCommand:
        """The drivers' command of `frame` (taken modulo the period's frames: the table repeats)."""
        k = frame % self.frames
        return JointCommand(self.q[k].tolist(), self.dq[k].tolist(), self.tau_ff[k].tolist(), self.kp[k].tolist(),
                            self.kd[k].tolist())

    # ---- files ----------------------------------------------------------------------------------------------
    def description(self) -> dict:
        """The JSON sidecar: the table's layout, then `header`."""
        return {"format": FORMAT, "version": 1, "rate_hz": self.rate, "frames": self.frames,
                "period_s": self.period, "joint_order": list(JOINTS),
                "columns": {c: {"unit": UNITS[c], "csv": f"<joint>_{c}_{CSV_SUFFIX[c]}"} for c in COLUMNS},
                "frame_time": "t_s = frame / rate_hz; the table repeats after the last frame", **self.header}

    def csv_header(self) -> list[str]:
        return ["frame", "t_s"] + [f"{j}_{c}_{CSV_SUFFIX[c]}" for j in JOINTS for c in COLUMNS]

    def write(self, csv_path: str | Path) -> tuple[Path, Path]:
        """The CSV at `csv_path` and its JSON sidecar beside it (same name, .json), each written atomically."""
        csv_path = Path(csv_path)
        values = np.stack([getattr(self, c) for c in COLUMNS], axis=2).reshape(self.frames, -1)  # joint-major
        k = np.arange(self.frames)
        rows = np.column_stack([k, k / self.rate, values])
        lines = [",".join(self.csv_header())] + [
            ",".join([str(int(r[0]))] + [f"{x:.10g}" for x in r[1:]]) for r in rows]
        json_path = csv_path.with_suffix(".json")
        _atomic_write(csv_path, "\n".join(lines) + "\n")
        _atomic_write(json_path, json.dumps(self.description(), indent=1) + "\n")
        return csv_path, json_path

    @classmethod
    def read(cls, csv_path: str | Path) -> "JointTable":
        """A table written by `write` (its CSV and the JSON beside it); ValueError naming what does not fit."""
        csv_path = Path(csv_path)
        try:
            meta = json.loads(csv_path.with_suffix(".json").read_text())
            lines = csv_path.read_text().splitlines()
        except (OSError, ValueError) as err:
            raise ValueError(f"joint table {csv_path} is unreadable: {err}") from None
        if meta.get("format") != FORMAT:
            raise ValueError(f"{csv_path.with_suffix('.json')} is not a joint table's sidecar (format "
                             f"{meta.get('format')!r}, expected {FORMAT!r})")
        table = cls(float(meta["rate_hz"]), *[np.zeros((1, 12))] * len(COLUMNS))
        if lines[0].split(",") != table.csv_header():
            raise ValueError(f"{csv_path}: its columns are not a joint table's (expected {table.csv_header()[:4]} ...)")
        data = np.array([[float(x) for x in line.split(",")] for line in lines[1:]])
        per_joint = data[:, 2:].reshape(len(data), len(JOINTS), len(COLUMNS))
        header = {k: v for k, v in meta.items() if k not in table.description()}
        return cls(float(meta["rate_hz"]), *[per_joint[:, :, i] for i in range(len(COLUMNS))], header=header)


def _atomic_write(path: Path, text: str) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_text(text)
    os.replace(tmp, path)


@dataclass(frozen=True)
class JointLimits:
    """What a robot's drivers accept in a joint table; per joint type (abad, hip, knee) where it differs."""

    torque: float  # N·m, |tau_ff|
    joint_speed: float  # rad/s, |dq|
    kp: tuple[float, float]  # N·m/rad, (lowest, highest)
    kd: tuple[float, float]  # N·m·s/rad, (lowest, highest)
    position_jump: tuple[float, float, float]  # rad, |q| change from one frame to the next (abad, hip, knee)
    position: tuple[tuple[float, float], tuple[float, float], tuple[float, float]]  # rad, (low, high) per type
    source: str = ""  # where the limits come from (a file, or the built-in CyberDog's)

    @classmethod
    def cyberdog(cls, robot: RobotConfig | None = None, actuator: ActuatorConfig | None = None) -> "JointLimits":
        """The CyberDog's: torque and speed from `actuator` (ActuatorConfig's torque clip and zero-torque speed),
        joint ranges from `robot` (RobotConfig), gains and the per-frame jump from the motor SDK (`SDK_*`)."""
        r, a = robot or RobotConfig(), actuator or ActuatorConfig()
        return cls(torque=a.torque_limit, joint_speed=a.zero_torque_speed, kp=SDK_KP_RANGE, kd=SDK_KD_RANGE,
                   position_jump=tuple(math.radians(d) for d in SDK_POSITION_JUMP_DEG),
                   position=((-r.abad_limit, r.abad_limit), tuple(r.hip_limit), tuple(r.knee_limit)),
                   source="the CyberDog's (RobotConfig, ActuatorConfig, cyberdog_motor_sdk)")

    @classmethod
    def from_dict(cls, d: dict, source: str = "") -> "JointLimits":
        """From a limits file's mapping (configs/robots/cyberdog_limits.yaml's keys; the jump in degrees);
        JointLimitError naming the key and what it must be."""
        if not isinstance(d, dict):
            raise JointLimitError(f"limits{_of(source)} must be a mapping of the keys {sorted(LIMIT_KEYS)}")
        unknown, missing = sorted(set(d) - set(LIMIT_KEYS)), sorted(set(LIMIT_KEYS) - set(d))
        if unknown or missing:
            raise JointLimitError(f"limits{_of(source)}: " + "; ".join(
                ([f"unknown key(s) {unknown}"] if unknown else []) + ([f"missing key(s) {missing}"] if missing else []))
                + f" (the keys: {', '.join(LIMIT_KEYS)})")
        torque = _number(d, "torque_limit_Nm", source, positive=True)
        speed = _number(d, "joint_speed_limit_radps", source, positive=True)
        kp, kd = _range(d, "kp_range_Nm_per_rad", source), _range(d, "kd_range_Nms_per_rad", source)
        jump = _per_type(d, "position_jump_deg", source, lambda k, v: _number({k: v}, k, source, positive=True))
        position = _per_type(d, "position_range_rad", source, lambda k, v: _range({k: v}, k, source))
        return cls(torque, speed, kp, kd, tuple(math.radians(v) for v in jump), position, source)

    def to_dict(self) -> dict:
        """The mapping `from_dict` reads (the jump in degrees)."""
        return {"torque_limit_Nm": self.torque, "joint_speed_limit_radps": self.joint_speed,
                "kp_range_Nm_per_rad": list(self.kp), "kd_range_Nms_per_rad": list(self.kd),
                "position_jump_deg": {j: math.degrees(v) for j, v in zip(JOINT_NAMES, self.position_jump)},
                "position_range_rad": {j: list(v) for j, v in zip(JOINT_NAMES, self.position)}}


LIMIT_KEYS = ("torque_limit_Nm", "joint_speed_limit_radps", "kp_range_Nm_per_rad", "kd_range_Nms_per_rad",
              "position_jump_deg", "position_range_rad")


def _of(source: str) -> str:
    return f" ({source})" if source else ""


def _number(d: dict, key: str, source: str, positive: bool = False) -> float:
    v = d[key]
    ok = isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) and (v > 0 or not positive)
    if not ok:
        raise JointLimitError(f"limits{_of(source)}: {key} must be a finite number{' > 0' if positive else ''}, "
                              f"got {v!r}")
    return float(v)


def _range(d: dict, key: str, source: str) -> tuple[float, float]:
    v = d[key]
    if not (isinstance(v, (list, tuple)) and len(v) == 2
            and all(isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x) for x in v)
            and v[0] <= v[1]):
        raise JointLimitError(f"limits{_of(source)}: {key} must be [low, high] with low <= high, got {v!r}")
    return float(v[0]), float(v[1])


def _per_type(d: dict, key: str, source: str, read) -> tuple:
    v = d[key]
    if not (isinstance(v, dict) and sorted(v) == sorted(JOINT_NAMES)):
        raise JointLimitError(f"limits{_of(source)}: {key} must map each of {', '.join(JOINT_NAMES)} to its "
                              f"limit, got {v!r}")
    return tuple(read(f"{key}.{j}", v[j]) for j in JOINT_NAMES)


def limit_breaks(table: JointTable, limits: JointLimits) -> list[str]:
    """One line per kind of limit the table breaks, naming its first breaking frame and joint (and how many frames
    break it); [] for a table within every limit. The jump is checked across the period's seam too (last frame to
    the first: the table repeats)."""
    n, types = table.frames, np.arange(len(JOINTS)) % len(JOINT_NAMES)
    lo = np.array([limits.position[t][0] for t in types])
    hi = np.array([limits.position[t][1] for t in types])
    jump = np.abs(np.roll(table.q, -1, axis=0) - table.q)  # frame k: k -> k + 1 (the last: -> 0)
    checks = [  # (the breaking frames' mask, the values, what, unit, the limit's words)
        ((table.q < lo) | (table.q > hi), table.q, "q", "rad", lambda j: f"the joint range [{lo[j]:.4g}, {hi[j]:.4g}]"
         " rad (position_range_rad)"),
        (np.abs(table.dq) > limits.joint_speed, table.dq, "dq", "rad/s",
         lambda j: f"the speed limit ±{limits.joint_speed:.4g} rad/s (joint_speed_limit_radps)"),
        (np.abs(table.tau_ff) > limits.torque, table.tau_ff, "tau_ff", "N·m",
         lambda j: f"the torque limit ±{limits.torque:.4g} N·m (torque_limit_Nm)"),
        ((table.kp < limits.kp[0]) | (table.kp > limits.kp[1]), table.kp, "kp", "N·m/rad",
         lambda j: f"the range [{limits.kp[0]:g}, {limits.kp[1]:g}] N·m/rad (kp_range_Nm_per_rad)"),
        ((table.kd < limits.kd[0]) | (table.kd > limits.kd[1]), table.kd, "kd", "N·m·s/rad",
         lambda j: f"the range [{limits.kd[0]:g}, {limits.kd[1]:g}] N·m·s/rad (kd_range_Nms_per_rad)"),
        (jump > np.array([limits.position_jump[t] for t in types]), jump, "the jump of q to the next frame", "rad",
         lambda j: f"the per-frame jump limit {math.degrees(limits.position_jump[types[j]]):.4g} deg "
                   f"(position_jump_deg.{JOINT_NAMES[types[j]]})"),
    ]
    lines = []
    for mask, values, what, unit, limit in checks:
        if mask.any():
            k, j = (int(i) for i in np.argwhere(mask)[0])
            seam = " (to frame 0: the period repeats)" if what.startswith("the jump") and k == n - 1 else ""
            count = int(mask.any(axis=1).sum())
            lines.append(f"frame {k} (t = {k / table.rate:.4f} s){seam}, joint {JOINTS[j]}: {what} "
                         f"{values[k, j]:.4g} {unit} breaks {limit(j)}{_of(limits.source)}"
                         + (f"; {count} frames break it" if count > 1 else ""))
    return lines


def check_limits(table: JointTable, limits: JointLimits) -> None:
    """JointLimitError, one line naming the frame, the joint and the limit, where the table breaks a limit (the
    first kind it breaks; `limit_breaks` lists them all)."""
    breaks = limit_breaks(table, limits)
    if breaks:
        more = f" (and {len(breaks) - 1} more kind(s) of limit)" if len(breaks) > 1 else ""
        raise JointLimitError(breaks[0] + more)


__all__ = ["COLUMNS", "FORMAT", "JOINTS", "JointLimitError", "JointLimits", "JointTable", "LIMIT_KEYS",
           "SDK_KD_RANGE", "SDK_KP_RANGE", "SDK_POSITION_JUMP_DEG", "SDK_RATE_HZ", "UNITS", "check_limits",
           "limit_breaks"]
