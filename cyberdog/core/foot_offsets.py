"""A periodic shift of each foot's target over its gait phase: how a learned foot trajectory is represented.

A foot-mode policy (`CyberDog-v0`, action_mode="foot") moves each foot target of the trot controller by a
small offset (Δx, Δy, Δz), m, in the leg frame (x forward, y left, z up). Over one gait cycle, as a function
of each leg's own phase φ ∈ [0, 1) (φ = 0 at lift-off, as in `cyberdog.core.trajectories`), these offsets
are the whole of what the policy changed in the trot: the commanded foot path of leg i is

    p_i(φ) = p_trot(φ; S, H) + Δp_i(φ)

with p_trot the controller's own path (e.g. the composite cycloid at step length S and lift height H). A
`FootOffsetPath` holds Δp_i(φ) for the four legs LF, RF, LH, RH at `n` equal phases k/n and evaluates it,
and its rate of change dΔp_i/dt = dΔp_i/dφ / period (the trot's velocity feedforward), by periodic linear
interpolation. Each leg keeps its own path, because the four feet of a trot do not do the same work (a
policy shifts the hind feet differently from the front ones); `reference_leg` picks one for plots.

Pure numpy; the interpolation itself is written once, in Python floats, since the trot controller calls
`at` at every controller period (400 Hz by default).
"""
from __future__ import annotations

import math

import numpy as np

LEGS = 4


class FootOffsetPath:
    """Per-leg foot-target offsets over the gait phase.

    offsets: (4, n, 3) m, leg order LF, RF, LH, RH, sample k at the leg's phase k / n (n ≥ 4).
    period: s, the gait cycle the phase runs over (turns dΔp/dφ into m/s).
    """

    def __init__(self, offsets, period: float):
        table = np.array(offsets, dtype=float)
        if table.ndim != 3 or table.shape[0] != LEGS or table.shape[2] != 3 or table.shape[1] < 4:
            raise ValueError(f"offsets must have shape (4, n, 3) with n >= 4 phases, got {table.shape}")
        if not np.all(np.isfinite(table)):
            raise ValueError("offsets must be finite")
        if not (np.isfinite(period) and period > 0):
            raise ValueError(f"period must be > 0 s and finite, got {period!r}")
        self.offsets = table
        self.period = float(period)
        self.n = table.shape[1]
        # per leg, per sample: the offset and its slope to the next sample (wrapping), as Python floats
        slope = (np.roll(table, -1, axis=1) - table) * self.n  # m per unit phase
        self._rows = [[(tuple(table[i, k]), tuple(slope[i, k])) for k in range(self.n)] for i in range(LEGS)]

    def at(self, phases) -> tuple[list[tuple[float, float, float]], list[tuple[float, float, float]]]:
        """Offsets (m) and their rates (m/s) of the four legs at their phases (4 floats, any real value: the
        phase wraps), as lists of (x, y, z) tuples."""
        inv_period = 1.0 / self.period
        offsets, rates = [], []
        for leg, phase in enumerate(phases):
            offset, (sx, sy, sz) = self._interpolate(leg, phase)
            offsets.append(offset)
            rates.append((sx * inv_period, sy * inv_period, sz * inv_period))
        return offsets, rates

    def sample(self, leg: int, phase) -> np.ndarray:
        """(m, 3) offsets of one leg at the phases `phase` (m,): `at`'s interpolation at each."""
        phases = np.asarray(phase, dtype=float).reshape(-1).tolist()
        return np.array([self._interpolate(leg, p)[0] for p in phases]).reshape(len(phases), 3)

    def _interpolate(self, leg: int, phase: float) -> tuple[tuple[float, float, float], tuple[float, float, float]]:
        """The one interpolation, in floats: one leg's offset (m) at `phase` (wrapping) and its slope (m per
        unit phase) on that segment."""
        n = self.n
        u = (phase % 1.0) * n
        k = int(u)
        if k >= n:  # phase % 1.0 rounds up to 1.0 for tiny negative phases
            k, u = 0, 0.0
        (ox, oy, oz), slope = self._rows[leg][k]
        f = u - k
        sx, sy, sz = slope
        return (ox + sx * f / n, oy + sy * f / n, oz + sz * f / n), slope

    def rms(self) -> np.ndarray:
        """(4, 3) m, the root-mean-square offset per leg and axis over the cycle."""
        return np.sqrt(np.mean(self.offsets ** 2, axis=1))

    @classmethod
    def zero(cls, period: float, n: int = 4) -> "FootOffsetPath":
        """No shift: the plain trot."""
        return cls(np.zeros((LEGS, n, 3)), period)

    @classmethod
    def from_samples(cls, phases, offsets, period: float, n: int) -> "FootOffsetPath":
        """Build the table from recorded samples: `phases` (m, 4) each leg's phase at each sample, `offsets`
        (m, 4, 3) m; the samples of one leg are sorted by phase and interpolated periodically at k / n."""
        phases = np.mod(np.asarray(phases, dtype=float), 1.0)
        offsets = np.asarray(offsets, dtype=float)
        if phases.ndim != 2 or phases.shape[1] != LEGS or offsets.shape != phases.shape + (3,):
            raise ValueError(f"phases must be (m, 4) and offsets (m, 4, 3), got {phases.shape}, {offsets.shape}")
        if len(phases) < 4:
            raise ValueError(f"need at least 4 samples, got {len(phases)}")
        grid = np.arange(n) / n
        table = np.empty((LEGS, n, 3))
        for leg in range(LEGS):
            order = np.argsort(phases[:, leg], kind="stable")
            p = phases[order, leg]
            v = offsets[order, leg]
            p_ext = np.concatenate([p[-1:] - 1.0, p, p[:1] + 1.0])
            for axis in range(3):
                v_ext = np.concatenate([v[-1:, axis], v[:, axis], v[:1, axis]])
                table[leg, :, axis] = np.interp(grid, p_ext, v_ext)
        return cls(table, period)

    def to_dict(self) -> dict:
        # 1 µm steps: far below what IK + PID can track, and it keeps a 400-sample table near 50 kB
        return {"period_s": self.period, "offsets_m": np.round(self.offsets, 6).tolist()}

    @classmethod
    def from_dict(cls, data: dict) -> "FootOffsetPath":
        try:
            return cls(data["offsets_m"], data["period_s"])
        except KeyError as e:
            raise ValueError(f"foot offset path lacks the field {e.args[0]!r}") from None

    def __eq__(self, other) -> bool:
        return (isinstance(other, FootOffsetPath) and self.period == other.period
                and self.offsets.shape == other.offsets.shape and bool(np.all(self.offsets == other.offsets)))

    def __repr__(self) -> str:
        rms_mm = 1e3 * float(math.sqrt(np.mean(self.offsets ** 2)))
        return f"FootOffsetPath(n={self.n}, period={self.period:g} s, rms={rms_mm:.2f} mm)"


__all__ = ["FootOffsetPath"]
