"""Gaits as data (phase offsets + duty factor) and the clock that turns time into each leg's phase. Pure numpy.

A leg's phase φ ∈ [0, 1) runs over its own cycle with φ = 0 at lift-off (the convention of
`cyberdog.core.trajectories`): the leg swings for φ < 1 − duty_factor and is in stance after. At time t,
φ_leg = (t / period + offset_leg) mod 1. Legs are ordered LF, RF, LH, RH everywhere.

The paper's diagonal trot (Figure 9): LF and RH swing together, RF and LH half a cycle later.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from cyberdog.config import LEG_NAMES, GaitConfig

_PHASE_DECIMALS = 12  # phases are rounded to 1e-12 so legs half a cycle apart agree on a boundary
_PHASE_SCALE = 10.0 ** _PHASE_DECIMALS  # np.round(x, 12) is rint(x · 1e12) / 1e12; `round(x * 1e12)` is that rint


@dataclass(frozen=True)
class Gait:
    """A periodic gait: each leg's phase offset (fraction of a cycle) and the stance share of the cycle."""

    phase_offsets: tuple[float, float, float, float]  # LF, RF, LH, RH, in cycles, each in [0, 1)
    duty_factor: float  # stance_time / period, in (0, 1)

    def __post_init__(self) -> None:
        offsets = tuple(float(v) for v in np.ravel(self.phase_offsets))
        if len(offsets) != len(LEG_NAMES) or not all(np.isfinite(v) and 0.0 <= v < 1.0 for v in offsets):
            raise ValueError(f"Gait.phase_offsets must be 4 values in [0, 1) ({', '.join(LEG_NAMES)}), "
                             f"got {self.phase_offsets!r}")
        if not (np.isfinite(self.duty_factor) and 0.0 < self.duty_factor < 1.0):
            raise ValueError(f"Gait.duty_factor must be in (0, 1), got {self.duty_factor!r}")
        object.__setattr__(self, "phase_offsets", offsets)
        object.__setattr__(self, "duty_factor", float(self.duty_factor))

    @property
    def swing_fraction(self) -> float:
        """Share of the cycle in swing, 1 − duty_factor."""
        return 1.0 - self.duty_factor

    @property
    def offsets(self) -> np.ndarray:
        """(4,) phase offsets as an array."""
        return np.asarray(self.phase_offsets)


def diagonal_trot(gait_cfg: GaitConfig) -> Gait:
    """The paper's diagonal trot (Figure 9): offsets from GaitConfig.phase_offsets (default LF, RH at 0 and
    RF, LH at ½) and duty factor stance_time / period."""
    return Gait(tuple(np.mod(gait_cfg.phase_offsets, 1.0)), gait_cfg.stance_time / gait_cfg.period)


class GaitScheduler:
    """Time → per-leg gait phase for a `Gait` with cycle `period` (s).

    Every method takes t (s) as a scalar (returns (4,)) or an array of shape (n,) (returns (n, 4)).
    """

    def __init__(self, gait: Gait, period: float) -> None:
        if not (np.isfinite(period) and period > 0):
            raise ValueError(f"GaitScheduler period must be > 0 s and finite, got {period!r}")
        self.gait = gait
        self.period = float(period)

    @classmethod
    def from_config(cls, gait_cfg: GaitConfig) -> "GaitScheduler":
        """Diagonal trot with the period of `gait_cfg`."""
        return cls(diagonal_trot(gait_cfg), gait_cfg.period)

    def _time(self, t: Any) -> np.ndarray:
        t = np.asarray(t, dtype=float)
        if not np.all(np.isfinite(t)):
            raise ValueError("time t must be finite")
        return t[..., None]

    def leg_phases(self, t: Any) -> np.ndarray:
        """(…, 4) phase of each leg in [0, 1): (t / period + offset) mod 1, 0 = lift-off; `phases_at` at
        each time."""
        t = self._time(t)[..., 0]
        return np.array([self.phases_at(ti) for ti in t.ravel().tolist()]).reshape(t.shape + (4,))

    def phases_at(self, t: float) -> list[float]:
        """The 4 legs' phases at one time t (s), as Python floats: the one law (the controller calls it at
        every period, so it builds no arrays). Each is (t / period + offset) mod 1, rounded to 1e-12 so that
        legs half a cycle apart agree on a boundary: round(x · 1e12) / 1e12, half to even as np.round(x, 12)."""
        t = float(t)
        if not math.isfinite(t):
            raise ValueError("time t must be finite")
        cycles = t / self.period
        phases = []
        for offset in self.gait.phase_offsets:
            phase = round(((cycles + offset) % 1.0) * _PHASE_SCALE) / _PHASE_SCALE
            phases.append(0.0 if phase >= 1.0 else phase)
        return phases

    def in_swing(self, t: Any) -> np.ndarray:
        """(…, 4) bool: leg in swing (phase < swing fraction)."""
        return self.leg_phases(t) < self.gait.swing_fraction

    def in_stance(self, t: Any) -> np.ndarray:
        """(…, 4) bool: leg in stance (foot meant to be on the ground)."""
        return ~self.in_swing(t)

    def swing_phase(self, t: Any) -> np.ndarray:
        """(…, 4) swing phase τ = phase / swing fraction ∈ [0, 1) for legs in swing; NaN for legs in stance."""
        phase = self.leg_phases(t)
        beta = self.gait.swing_fraction
        return np.where(phase < beta, phase / beta, np.nan)

    def stance_phase(self, t: Any) -> np.ndarray:
        """(…, 4) stance phase σ = (phase − swing fraction) / duty factor ∈ [0, 1) in stance; NaN in swing."""
        phase = self.leg_phases(t)
        beta = self.gait.swing_fraction
        return np.where(phase >= beta, (phase - beta) / self.gait.duty_factor, np.nan)

    def cycle_index(self, t: Any) -> np.ndarray | int:
        """Index of the gait-clock cycle containing t: floor(t / period) (the clock of a leg with offset 0)."""
        k = np.floor(np.round(np.asarray(t, dtype=float) / self.period, _PHASE_DECIMALS)).astype(int)
        return int(k) if k.ndim == 0 else k
