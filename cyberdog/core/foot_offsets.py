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

A path may also carry a joint torque over the phase, τ_i(φ) (N·m, abad / hip / knee of leg i), that the trot adds to
its feedforward (`JointCommand.feedforward`): the force a path makes its joints exert, written as a force rather
than as a position error the joint PD turns into one (`cyberdog.analysis.stance_force`), so that the gains a
user sets do not scale it.

Pure numpy; the interpolation itself is written once, in Python floats, since the trot controller calls
`at` at every controller period (400 Hz by default).
"""
from __future__ import annotations

import math

import numpy as np

LEGS = 4


class FootOffsetPath:
    """Per-leg foot-target offsets over the gait phase, and optionally a joint torque over it.

    offsets: (4, n, 3) m, leg order LF, RF, LH, RH, sample k at the leg's phase k / n (n ≥ 4).
    period: s, the gait cycle the phase runs over (turns dΔp/dφ into m/s).
    feedforward: (4, n, 3) N·m, each leg's (abad, hip, knee) torque added to the trot's feedforward at the same
        phases; None: none (a path of offsets alone).
    """

    def __init__(self, offsets, period: float, feedforward=None):
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
        self._rows = _rows(table)
        self.feedforward = None
        self._feedforward_rows = None
        if feedforward is not None:
            torque = np.array(feedforward, dtype=float)
            if torque.shape != table.shape:
                raise ValueError(f"feedforward must have the offsets' shape {table.shape} (N·m per leg, phase and "
                                 f"joint), got {torque.shape}")
            if not np.all(np.isfinite(torque)):
                raise ValueError("feedforward must be finite")
            self.feedforward, self._feedforward_rows = torque, _rows(torque)

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

    def feedforward_at(self, phases) -> list[tuple[float, float, float]]:
        """N·m: the joint torques (abad, hip, knee) of the four legs at their phases (4 floats, wrapping), as a list
        of tuples; zeros where the path carries none."""
        rows = self._feedforward_rows
        if rows is None:
            return [(0.0, 0.0, 0.0)] * LEGS
        return [_interpolate(rows[leg], self.n, phase)[0] for leg, phase in enumerate(phases)]

    def add_feedforward(self, tau: list[float], phases, share: float = 1.0) -> None:
        """Add `share` of the path's joint torques at the legs' `phases` to `tau` (12 floats, N·m, legs LF, RF, LH,
        RH × abad, hip, knee) in place; nothing where the path carries none."""
        if self._feedforward_rows is None:
            return
        for leg, torques in enumerate(self.feedforward_at(phases)):
            for j, torque in enumerate(torques):
                tau[3 * leg + j] += share * torque

    def _interpolate(self, leg: int, phase: float) -> tuple[tuple[float, float, float], tuple[float, float, float]]:
        """One leg's offset (m) at `phase` (wrapping) and its slope (m per unit phase) on that segment."""
        return _interpolate(self._rows[leg], self.n, phase)

    def rms(self) -> np.ndarray:
        """(4, 3) m, the root-mean-square offset per leg and axis over the cycle."""
        return np.sqrt(np.mean(self.offsets ** 2, axis=1))

    @classmethod
    def zero(cls, period: float, n: int = 4) -> "FootOffsetPath":
        """No shift: the plain trot."""
        return cls(np.zeros((LEGS, n, 3)), period)

    @classmethod
    def from_samples(cls, phases, offsets, period: float, n: int, feedforward=None) -> "FootOffsetPath":
        """Build the table from recorded samples: `phases` (m, 4) each leg's phase at each sample, `offsets`
        (m, 4, 3) m (and `feedforward`, (m, 4, 3) N·m, or None); the samples of one leg are sorted by phase and
        interpolated periodically at k / n."""
        phases = np.mod(np.asarray(phases, dtype=float), 1.0)
        offsets = np.asarray(offsets, dtype=float)
        if phases.ndim != 2 or phases.shape[1] != LEGS or offsets.shape != phases.shape + (3,):
            raise ValueError(f"phases must be (m, 4) and offsets (m, 4, 3), got {phases.shape}, {offsets.shape}")
        if feedforward is not None and np.shape(feedforward) != offsets.shape:
            raise ValueError(f"feedforward samples must have the offsets' shape {offsets.shape}, got "
                             f"{np.shape(feedforward)}")
        if len(phases) < 4:
            raise ValueError(f"need at least 4 samples, got {len(phases)}")
        torque = None if feedforward is None else _on_grid(phases, np.asarray(feedforward, dtype=float), n)
        return cls(_on_grid(phases, offsets, n), period, torque)

    def to_dict(self) -> dict:
        # 1 µm steps: far below what IK + PID can track, and it keeps a 400-sample table near 50 kB; 0.1 mN·m
        # steps of torque, far below the drivers' resolution
        out = {"period_s": self.period, "offsets_m": np.round(self.offsets, 6).tolist()}
        if self.feedforward is not None:
            out["feedforward_Nm"] = np.round(self.feedforward, 4).tolist()
        return out

    @classmethod
    def from_dict(cls, data: dict) -> "FootOffsetPath":
        try:
            return cls(data["offsets_m"], data["period_s"], data.get("feedforward_Nm"))
        except KeyError as e:
            raise ValueError(f"foot offset path lacks the field {e.args[0]!r}") from None

    def __eq__(self, other) -> bool:
        if not (isinstance(other, FootOffsetPath) and self.period == other.period
                and self.offsets.shape == other.offsets.shape and bool(np.all(self.offsets == other.offsets))):
            return False
        if self.feedforward is None or other.feedforward is None:
            return self.feedforward is None and other.feedforward is None
        return bool(np.all(self.feedforward == other.feedforward))

    def __repr__(self) -> str:
        rms_mm = 1e3 * float(math.sqrt(np.mean(self.offsets ** 2)))
        return f"FootOffsetPath(n={self.n}, period={self.period:g} s, rms={rms_mm:.2f} mm)"


def _on_grid(phases: np.ndarray, values: np.ndarray, n: int) -> np.ndarray:
    """(4, n, 3): per leg, `values` (m, 4, 3) at its `phases` (m, 4) in [0, 1), sorted by phase and interpolated
    periodically at the phases k / n."""
    grid = np.arange(n) / n
    table = np.empty((LEGS, n, 3))
    for leg in range(LEGS):
        order = np.argsort(phases[:, leg], kind="stable")
        p = phases[order, leg]
        v = values[order, leg]
        p_ext = np.concatenate([p[-1:] - 1.0, p, p[:1] + 1.0])
        for axis in range(3):
            v_ext = np.concatenate([v[-1:, axis], v[:, axis], v[:1, axis]])
            table[leg, :, axis] = np.interp(grid, p_ext, v_ext)
    return table


def _rows(table: np.ndarray) -> list:
    """Per leg, per sample: the value and its slope to the next sample (wrapping, per unit phase), in floats."""
    n = table.shape[1]
    slope = (np.roll(table, -1, axis=1) - table) * n
    return [[(tuple(table[i, k]), tuple(slope[i, k])) for k in range(n)] for i in range(LEGS)]


def _interpolate(rows: list, n: int, phase: float) -> tuple[tuple[float, float, float], tuple[float, float, float]]:
    """The one interpolation, in floats: one leg's value at `phase` (wrapping) from its `rows` (`_rows`) of n
    samples, and its slope (per unit phase) on that segment."""
    u = (phase % 1.0) * n
    k = int(u)
    if k >= n:  # phase % 1.0 rounds up to 1.0 for tiny negative phases
        k, u = 0, 0.0
    (ox, oy, oz), slope = rows[k]
    f = u - k
    sx, sy, sz = slope
    return (ox + sx * f / n, oy + sy * f / n, oz + sz * f / n), slope


__all__ = ["FootOffsetPath"]
