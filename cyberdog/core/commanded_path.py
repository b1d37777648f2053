"""The learned foot trajectory as the policy commanded it: the trot's path plus the policy's per-leg shift.

A foot-mode policy walks by shifting the trot controller's foot targets (`CyberDog-v0`, action_mode="foot").
What it commands over a gait cycle is therefore known exactly, without measuring the feet: the base path
(the composite cycloid at step length S = v·stance_time and lift height H, as the controller draws it)
plus a `FootOffsetPath` Δp_i(φ) for each leg i. A `CommandedPath` records both, with the speed it was
recorded at and where it came from, and replays as

    walk(cfg_with(base trajectory, S, H), foot_offsets=path.offsets)

i.e. through the same IK + PID trot, with no policy in the loop. Its foot path per leg (`leg_path`) and its
own lift height (`own_lift_height`, the mean over the four legs of the peak of the commanded z above the
commanded contact level) are what the matched-lift comparison and the figures use.

Pure numpy. Files are JSON ("format": "cyberdog.commanded_foot_path").
"""
from __future__ import annotations

import dataclasses
import json
import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from cyberdog.config import LEG_NAMES, GaitConfig
from cyberdog.core.foot_offsets import FootOffsetPath
from cyberdog.core.trajectories import SampledTrajectory, make_trajectory, swing_fraction

FORMAT = "cyberdog.commanded_foot_path"


@dataclass
class CommandedPath:
    """Base trot path + per-leg foot-target offsets over the phase, recorded at `speed`."""

    speed: float  # m/s, the command the path was recorded at (and is replayed at)
    gait: GaitConfig  # the controller's gait: base trajectory, period, swing time, lift height H
    offsets: FootOffsetPath  # the policy's shift of each foot target over its phase
    provenance: dict = field(default_factory=dict)

    def __post_init__(self) -> None:
        if not (np.isfinite(self.speed) and self.speed > 0):
            raise ValueError(f"speed must be > 0 m/s, got {self.speed!r}")
        if self.gait.trajectory == "sampled" and not self.gait.sampled_file:
            raise ValueError("a sampled base trajectory needs its file (GaitConfig.sampled_file)")
        if abs(self.offsets.period - self.gait.period) > 1e-9:
            raise ValueError(f"offset path period {self.offsets.period} s differs from the gait period "
                             f"{self.gait.period} s")
        self.gait = dataclasses.replace(self.gait, speed=float(self.speed))
        try:
            json.dumps(self.provenance)
        except TypeError as err:
            raise ValueError(f"provenance must be JSON-serialisable: {err}") from None

    @property
    def step_length(self) -> float:
        """m, S = v·stance_time of the base path."""
        return self.gait.step_length

    def leg_path(self, leg: int | str, n: int | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(phase, x, z) of one leg's commanded foot path at n equal phases (default: the offset table's),
        m, in the trajectory frame (x from the neutral point, z = 0 the base path's contact level)."""
        i = LEG_NAMES.index(leg) if isinstance(leg, str) else int(leg)
        n = n or self.offsets.n
        phase = np.arange(n) / n
        g = self.gait
        xz, _ = make_trajectory(g).position_velocity(phase, g.step_length, g.lift_height, g.swing_time,
                                                     g.stance_time)
        shift = self.offsets.sample(i, phase)
        return phase, xz[:, 0] + shift[:, 0], xz[:, 1] + shift[:, 2]

    def leg_lift_heights(self) -> np.ndarray:
        """(4,) m: per leg, the peak commanded z in swing above the median commanded z in stance."""
        beta = swing_fraction(self.gait.swing_time, self.gait.stance_time)
        out = []
        for leg in range(4):
            phase, _, z = self.leg_path(leg)
            swing = phase < beta
            out.append(float(z[swing].max() - np.median(z[~swing])))
        return np.array(out)

    def own_lift_height(self) -> float:
        """m, the lift height of the learned path: the mean of the four legs' (the baselines' matched H)."""
        return float(np.mean(self.leg_lift_heights()))

    def as_sampled(self, leg: str = "LF") -> SampledTrajectory:
        """One leg's commanded x–z path as a `SampledTrajectory` (the paper's single reference foot; for
        figures and for replaying one path on all four legs), contact level shifted to z = 0."""
        phase, x, z = self.leg_path(leg)
        beta = swing_fraction(self.gait.swing_time, self.gait.stance_time)
        z = z - np.median(z[phase >= beta])
        lift = float(z.max())
        return SampledTrajectory(phase, x, z, self.step_length, lift,
                                 {**self.provenance, "kind": "commanded path of one leg", "leg": leg,
                                  "own_lift_height_m": self.own_lift_height()})  # the H Table 5 matches

    # ---- files -------------------------------------------------------------------------------------------
    def to_dict(self) -> dict:
        g = self.gait
        return {"format": FORMAT, "version": 1, "speed_mps": self.speed,
                "gait": {"trajectory": g.trajectory, "straight_shape": g.straight_shape,
                         "trapezoid_fraction": g.trapezoid_fraction, "period": g.period,
                         "swing_time": g.swing_time, "lift_height": g.lift_height,
                         "phase_offsets": list(g.phase_offsets),
                         **({"sampled_file": g.sampled_file} if g.trajectory == "sampled" else {})},
                "own_lift_height_m": self.own_lift_height(),
                "leg_lift_heights_m": self.leg_lift_heights().tolist(),
                "offsets": self.offsets.to_dict(), "provenance": self.provenance}

    def save(self, path: str | Path) -> Path:
        """Write JSON atomically; returns the path."""
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp = path.with_name(path.name + ".tmp")
        tmp.write_text(json.dumps(self.to_dict(), separators=(",", ":")))
        os.replace(tmp, path)
        return path

    @classmethod
    def from_dict(cls, d: dict) -> "CommandedPath":
        if d.get("format") != FORMAT:
            raise ValueError(f"not a commanded foot path (format {d.get('format')!r}, expected {FORMAT!r})")
        try:
            g = d["gait"]
            gait = GaitConfig(speed=float(d["speed_mps"]), period=g["period"], swing_time=g["swing_time"],
                              lift_height=g["lift_height"], trajectory=g["trajectory"],
                              straight_shape=g["straight_shape"], trapezoid_fraction=g["trapezoid_fraction"],
                              phase_offsets=tuple(g["phase_offsets"]), sampled_file=g.get("sampled_file", ""))
            return cls(float(d["speed_mps"]), gait, FootOffsetPath.from_dict(d["offsets"]), d.get("provenance", {}))
        except KeyError as e:
            raise ValueError(f"commanded foot path lacks the field {e.args[0]!r}") from None

    @classmethod
    def load(cls, path: str | Path) -> "CommandedPath":
        path = Path(path)
        if not path.is_file():
            raise ValueError(f"commanded foot path file {str(path)!r} does not exist")
        return cls.from_dict(json.loads(path.read_text()))


__all__ = ["CommandedPath", "FORMAT"]
