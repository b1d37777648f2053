"""Foot-end trajectories (paper Section 2.3, Figure 4) behind one interface. Pure numpy (+ scipy spline).

Convention. A leg's gait phase φ ∈ [0, 1) runs over its own cycle, φ = 0 at lift-off. The leg swings for
φ < swing_fraction = swing_time / (swing_time + stance_time) and stands after. A foot position (x, z), m, is
relative to the neutral point under the hip at standing height: x forward, z = 0 the ground-contact level,
z > 0 lifted. In swing the foot goes forward from x = −S/2 to +S/2 and lifts to the height H and back to 0;
in stance it moves back from +S/2 to −S/2 at the constant speed v = S / stance_time with z = 0, which
carries the body forward at v. Velocities are time derivatives, m/s; in swing d/dt = (1/swing_time) d/dτ
with τ = φ / swing_fraction the swing phase.

Positions and velocities are relative to the hip. The foot's ground-frame velocity is the body velocity plus
the relative one: a swing that ends with zero relative velocity (the cycloid) lands moving at +v over the
ground, and the relative velocity then jumps to −v at the start of stance.

Implementations: `CompositeCycloid` (the paper's "composite pendulum", Figure 4a), `StraightLine` (Figure 4b;
the paper does not define the shape, three are offered), `SampledTrajectory` (a recorded full-cycle curve,
e.g. the trajectory extracted from the learned gait). `make_trajectory` builds one from a `GaitConfig`.
The cycloid and the straight line also evaluate one phase in Python floats (`foot_point`, the trot
controller's per-period path); `point_evaluator` returns it where it reproduces `position_velocity`.
"""
from __future__ import annotations

import json
import math
from abc import ABC, abstractmethod
from pathlib import Path
from typing import Any

import numpy as np
from scipy.interpolate import CubicSpline

from cyberdog.config import STRAIGHT_SHAPES, TRAJECTORY_NAMES, GaitConfig
from cyberdog.core import sampled_file


def swing_fraction(swing_time: float, stance_time: float) -> float:
    """Share of the cycle spent in swing: swing_time / (swing_time + stance_time) (= 1 − duty factor)."""
    return swing_time / (swing_time + stance_time)


def _check_finite_positive(name: str, value: float, allow_zero: bool = False) -> None:
    if not (np.isfinite(value) and (value >= 0 if allow_zero else value > 0)):
        raise ValueError(f"{name} must be {'>= 0' if allow_zero else '> 0'} and finite, got {value!r}")


def check_gait_args(step_length: float, lift_height: float, swing_time: float, stance_time: float) -> None:
    """ValueError naming the argument unless S ≥ 0 and H, swing and stance times > 0, all finite (m, s)."""
    _check_finite_positive("step_length (m)", step_length, allow_zero=True)
    _check_finite_positive("lift_height (m)", lift_height)
    _check_finite_positive("swing_time (s)", swing_time)
    _check_finite_positive("stance_time (s) (swing longer than the cycle?)", stance_time)


def _wrap_phase(phase: Any) -> np.ndarray:
    """Gait phase as a float array wrapped into [0, 1); non-finite phases raise ValueError."""
    phi = np.asarray(phase, dtype=float)
    if not np.all(np.isfinite(phi)):
        raise ValueError("phase must be finite")
    phi = np.mod(phi, 1.0)
    return np.where(phi >= 1.0, 0.0, phi)  # np.mod(-1e-17, 1) == 1.0


def _check_tau(tau: Any) -> np.ndarray:
    tau = np.asarray(tau, dtype=float)
    if not np.all(np.isfinite(tau)) or np.any(tau < -1e-12) or np.any(tau > 1 + 1e-12):
        raise ValueError("swing phase tau must be finite and in [0, 1]")
    return np.clip(tau, 0.0, 1.0)


def _point_args(phase: float, step_length: float, lift_height: float, swing_time: float,
                 stance_time: float) -> float:
    """Checks of `position_velocity` for one phase in plain floats (fast path); returns the wrapped phase.
    Anything the quick test rejects goes through the array checks, which raise the usual messages."""
    if not (step_length >= 0.0 and lift_height > 0.0 and swing_time > 0.0 and stance_time > 0.0
            and math.isfinite(step_length) and math.isfinite(lift_height) and math.isfinite(swing_time)
            and math.isfinite(stance_time)):
        check_gait_args(step_length, lift_height, swing_time, stance_time)
    if not math.isfinite(phase):
        raise ValueError("phase must be finite")
    phi = phase % 1.0  # float % is np.mod
    return 0.0 if phi >= 1.0 else phi


class FootTrajectory(ABC):
    """A foot trajectory: a swing path over τ ∈ [0, 1] plus the shared constant-speed stance."""

    name: str = ""
    foot_inset: float = 0.0  # m, each foot this much nearer the body's midline than below its hip (stance width)

    @abstractmethod
    def swing_path(self, tau: Any, step_length: float, lift_height: float
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Swing foot (x, z), m, and (dx/dτ, dz/dτ), m per unit τ, for swing phase τ ∈ [0, 1]."""

    def position_velocity(self, phase: Any, step_length: float, lift_height: float, swing_time: float,
                          stance_time: float) -> tuple[np.ndarray, np.ndarray]:
        """Foot position (..., 2) = (x, z), m, and velocity (..., 2), m/s, at gait phase(s) `phase`.

        Phases are wrapped into [0, 1). Swing: the class's `swing_path` at τ = φ / swing_fraction, velocity
        by the chain rule d/dt = (1/swing_time) d/dτ. Stance: x = S/2 − S·σ with σ = (φ − swing_fraction) /
        (1 − swing_fraction), constant velocity (−S / stance_time, 0), z = 0.
        """
        check_gait_args(step_length, lift_height, swing_time, stance_time)
        phi = _wrap_phase(phase)
        beta = swing_fraction(swing_time, stance_time)
        swing = phi < beta
        tau = np.where(swing, phi / beta, 0.0)
        x_sw, z_sw, dx_dtau, dz_dtau = self.swing_path(tau, step_length, lift_height)
        sigma = np.where(swing, 0.0, (phi - beta) / (1.0 - beta))
        x = np.where(swing, x_sw, 0.5 * step_length - step_length * sigma)
        z = np.where(swing, z_sw, 0.0)
        vx = np.where(swing, dx_dtau / swing_time, -step_length / stance_time)
        vz = np.where(swing, dz_dtau / swing_time, 0.0)
        return np.stack([x, z], axis=-1), np.stack([vx, vz], axis=-1)

    def foot_point(self, phase: float, step_length: float, lift_height: float, swing_time: float,
                   stance_time: float) -> tuple[float, float, float, float]:
        """`position_velocity` at one phase in Python floats, (x, z) m and (vx, vz) m/s (with `_swing_point`)."""
        phi = _point_args(phase, step_length, lift_height, swing_time, stance_time)
        return self.point_at(phi, swing_fraction(swing_time, stance_time), step_length, lift_height, swing_time,
                             stance_time)

    def point_at(self, phi: float, beta: float, step_length: float, lift_height: float, swing_time: float,
                 stance_time: float) -> tuple[float, float, float, float]:
        """`foot_point` at a phase φ already in [0, 1) with β = `swing_fraction(swing_time, stance_time)`, the
        arguments unchecked: the trot controller's per-period path, which checks them once per period."""
        if not phi < beta:  # the shared stance of `position_velocity`
            sigma = (phi - beta) / (1.0 - beta)
            return 0.5 * step_length - step_length * sigma, 0.0, -step_length / stance_time, 0.0
        x, z, dx_dtau, dz_dtau = self._swing_point(phi / beta, step_length, lift_height)
        return x, z, dx_dtau / swing_time, dz_dtau / swing_time

    def _swing_point(self, tau: float, step_length: float, lift_height: float) -> tuple[float, ...]:
        """`swing_path` at one τ in Python floats; a subclass with a float form overrides it."""
        raise NotImplementedError(f"{type(self).__name__} has no float swing point")


class CompositeCycloid(FootTrajectory):
    """The paper's composite pendulum (composite cycloid) swing, Figure 4a.

    x = S(τ − sin(2πτ)/2π) − S/2;  z = 2H(τ − sin(4πτ)/4π) for τ ≤ ½ and 2H(1 − τ + sin(4πτ)/4π) after.
    Velocity and acceleration are zero (relative to the hip) at lift-off and touch-down; z peaks at H at ½.
    """

    name = "cycloid"

    def swing_path(self, tau, step_length, lift_height):
        tau = _check_tau(tau)
        S, H = step_length, lift_height
        two_pi = 2.0 * np.pi
        x = S * (tau - np.sin(two_pi * tau) / two_pi) - 0.5 * S
        dx = S * (1.0 - np.cos(two_pi * tau))
        rising = tau <= 0.5
        s4 = np.sin(2.0 * two_pi * tau) / (2.0 * two_pi)
        z = np.where(rising, 2.0 * H * (tau - s4), 2.0 * H * (1.0 - tau + s4))
        dz_up = 2.0 * H * (1.0 - np.cos(2.0 * two_pi * tau))
        dz = np.where(rising, dz_up, -dz_up)
        return x, z, dx, dz

    def _swing_point(self, tau: float, step_length: float, lift_height: float
                     ) -> tuple[float, float, float, float]:
        """`swing_path` at one τ in Python floats, same formulas."""
        S, H = step_length, lift_height
        two_pi = 2.0 * math.pi
        x = S * (tau - math.sin(two_pi * tau) / two_pi) - 0.5 * S
        dx = S * (1.0 - math.cos(two_pi * tau))
        s4 = math.sin(2.0 * two_pi * tau) / (2.0 * two_pi)
        dz = 2.0 * H * (1.0 - math.cos(2.0 * two_pi * tau))
        if tau <= 0.5:
            z = 2.0 * H * (tau - s4)
        else:
            z, dz = 2.0 * H * (1.0 - tau + s4), -dz
        return x, z, dx, dz


class StraightLine(FootTrajectory):
    """Straight-line swing (the paper's Figure 4b), a polyline walked at constant path speed.

    Shapes (the paper does not define its straight-line path; the shape changes which trajectory is
    cheaper, so name it with any result):
    - "rectangle": straight up by H at x = −S/2, forward S at height H, straight down at x = +S/2;
    - "trapezoid": up to H while covering `trapezoid_fraction`·S, forward, down over the same share of S;
    - "triangle": straight up-forward to the apex (0, H) at half the stride, straight down-forward.
    The path speed |dp/dτ| equals the path length L for every τ, so the velocity is discontinuous at the
    corners (and at lift-off / touch-down): these jumps are the sudden power changes the paper reports for
    this trajectory. At a corner the velocity of the segment that starts there is returned.
    """

    name = "straight"

    def __init__(self, shape: str = "rectangle", trapezoid_fraction: float = 0.25) -> None:
        if shape not in STRAIGHT_SHAPES:
            raise ValueError(f"StraightLine shape must be one of {STRAIGHT_SHAPES}, got {shape!r}")
        if not 0.0 < trapezoid_fraction < 0.5:
            raise ValueError(f"trapezoid_fraction must be in (0, 0.5), got {trapezoid_fraction!r}")
        self.shape = shape
        self.trapezoid_fraction = trapezoid_fraction

    def corners(self, step_length: float, lift_height: float) -> np.ndarray:
        """(k, 2) vertices (x, z), m, of the swing polyline from lift-off to touch-down."""
        return np.asarray(self._corner_points(step_length, lift_height), dtype=float)

    def _corner_points(self, step_length: float, lift_height: float) -> list[tuple[float, float]]:
        S, H = step_length, lift_height
        if self.shape == "rectangle":
            pts = [(-S / 2, 0.0), (-S / 2, H), (S / 2, H), (S / 2, 0.0)]
        elif self.shape == "trapezoid":
            d = self.trapezoid_fraction * S
            pts = [(-S / 2, 0.0), (-S / 2 + d, H), (S / 2 - d, H), (S / 2, 0.0)]
        else:  # triangle
            pts = [(-S / 2, 0.0), (0.0, H), (S / 2, 0.0)]
        return pts

    def swing_path(self, tau, step_length, lift_height):
        tau = _check_tau(tau)
        vertices = self.corners(step_length, lift_height)
        seg = np.diff(vertices, axis=0)
        seg_len = np.hypot(seg[:, 0], seg[:, 1])
        total = seg_len.sum()  # path length L, m (> 0 because H > 0)
        cum = np.concatenate([[0.0], np.cumsum(seg_len)])
        s = tau * total
        # last segment with start <= s; zero-length segments (S = 0) are skipped by side="right"
        i = np.clip(np.searchsorted(cum, s, side="right") - 1, 0, len(seg) - 1)
        length = seg_len[i]
        safe = np.where(length > 0, length, 1.0)
        frac = np.where(length > 0, (s - cum[i]) / safe, 0.0)
        direction = seg[i] / safe[..., None]
        pos = vertices[i] + frac[..., None] * seg[i]
        return pos[..., 0], pos[..., 1], total * direction[..., 0], total * direction[..., 1]

    def _swing_point(self, tau: float, step_length: float, lift_height: float
                     ) -> tuple[float, float, float, float]:
        """`swing_path` at one τ in Python floats, the same polyline walk."""
        vertices = self._corner_points(float(step_length), float(lift_height))
        segments = [(b[0] - a[0], b[1] - a[1]) for a, b in zip(vertices[:-1], vertices[1:])]
        lengths = [math.hypot(dx, dz) for dx, dz in segments]
        starts = [0.0]  # path length at each segment's start (np.cumsum order)
        for length in lengths[:-1]:
            starts.append(starts[-1] + length)
        total = starts[-1] + lengths[-1]
        s = tau * total
        # last segment with start <= s, as searchsorted(side="right") − 1 clipped to the segments
        i = 0
        while i + 1 < len(segments) and starts[i + 1] <= s:
            i += 1
        (dx, dz), length = segments[i], lengths[i]
        safe = length if length > 0 else 1.0
        frac = (s - starts[i]) / safe if length > 0 else 0.0
        return vertices[i][0] + frac * dx, vertices[i][1] + frac * dz, total * (dx / safe), total * (dz / safe)


class SampledTrajectory(FootTrajectory):
    """A recorded full-cycle foot trajectory replayed as a periodic cubic spline (C²).

    The points (phase, x, z) cover the whole gait cycle with the same convention as the other trajectories
    (phase 0 = lift-off, x, z relative to the neutral point, z = 0 at ground contact). They are normalised by
    the recorded step length and lift height (x / S_rec, z / H_rec), so the curve can be replayed at another
    S and H: x = S·x̂(φ), z = H·ẑ(φ), velocity = (S·x̂'(φ), H·ẑ'(φ)) / period; `foot_inset` (m, within ±0.1)
    moves every foot toward the body's midline (a searched stance width; negative: wider). `position_velocity`
    uses the curve over the full cycle (no swing/stance split: the learned trajectory defines both), and
    `swing_path(τ, S, H)` evaluates the same curve with τ read as the cycle phase.
    Files: `save`/`load` write and read JSON (points + provenance) or, for a ".csv" suffix, CSV
    (`cyberdog.core.sampled_file`).
    """

    name = "sampled"
    MIN_POINTS = 4

    def __init__(self, phase: Any, x: Any, z: Any, step_length: float, lift_height: float,
                 provenance: dict | None = None, foot_inset: float = 0.0) -> None:
        phase, x, z = (np.asarray(a, dtype=float) for a in (phase, x, z))
        for name, a in (("phase", phase), ("x", x), ("z", z)):
            if a.ndim != 1:
                raise ValueError(f"sampled trajectory {name} must be one-dimensional, got shape {a.shape}")
            if not np.all(np.isfinite(a)):
                raise ValueError(f"sampled trajectory {name} must be finite")
        if not len(phase) == len(x) == len(z):
            raise ValueError(f"phase, x, z must have equal lengths, got {len(phase)}, {len(x)}, {len(z)}")
        if len(phase) < self.MIN_POINTS:
            raise ValueError(f"sampled trajectory needs at least {self.MIN_POINTS} points, got {len(phase)}")
        if np.any(np.diff(phase) <= 0):
            raise ValueError("sampled trajectory phases must be strictly increasing")
        if phase[0] < 0 or phase[-1] >= 1:
            raise ValueError(f"sampled trajectory phases must lie in [0, 1) (one cycle, without a duplicate "
                             f"end point), got {phase[0]!r} .. {phase[-1]!r}")
        _check_finite_positive("recorded step_length (m)", step_length)
        _check_finite_positive("recorded lift_height (m)", lift_height)
        if not (math.isfinite(foot_inset) and abs(foot_inset) < 0.1):
            raise ValueError(f"foot_inset must be finite and within ±0.1 m, got {foot_inset!r}")
        self.foot_inset = float(foot_inset)
        provenance = dict(provenance or {})
        try:
            json.dumps(provenance)
        except TypeError as err:
            raise ValueError(f"provenance must be JSON-serialisable: {err}") from None
        self.phase, self.x, self.z = phase, x, z
        self.step_length, self.lift_height = float(step_length), float(lift_height)
        self.provenance = provenance
        knots = np.append(phase, phase[0] + 1.0)  # close the cycle for the periodic spline
        self._x_hat = CubicSpline(knots, np.append(x, x[0]) / self.step_length, bc_type="periodic")
        self._z_hat = CubicSpline(knots, np.append(z, z[0]) / self.lift_height, bc_type="periodic")

    @classmethod
    def from_points(cls, phase: Any, x: Any, z: Any, step_length: float, lift_height: float,
                    provenance: dict | None = None) -> "SampledTrajectory":
        """Build from recorded points over one full cycle; S, H of the recording normalise x and z."""
        return cls(phase, x, z, step_length, lift_height, provenance)

    def _curve(self, phase: Any, step_length: float, lift_height: float):
        u = self.phase[0] + np.mod(_wrap_phase(phase) - self.phase[0], 1.0)
        return (step_length * self._x_hat(u), lift_height * self._z_hat(u),
                step_length * self._x_hat(u, 1), lift_height * self._z_hat(u, 1))

    def swing_path(self, tau, step_length, lift_height):
        return self._curve(_check_tau(tau), step_length, lift_height)

    def position_velocity(self, phase, step_length, lift_height, swing_time, stance_time):
        check_gait_args(step_length, lift_height, swing_time, stance_time)
        period = swing_time + stance_time
        x, z, dx, dz = self._curve(phase, step_length, lift_height)
        return np.stack([x, z], axis=-1), np.stack([dx / period, dz / period], axis=-1)

    # ---- files (cyberdog.core.sampled_file) -----------------------------------------------------------------
    def to_dict(self) -> dict:
        return {"format": sampled_file.FORMAT, "version": sampled_file.VERSION,
                "step_length_m": self.step_length, "lift_height_m": self.lift_height,
                "phase": self.phase.tolist(), "x_m": self.x.tolist(), "z_m": self.z.tolist(),
                **({"foot_inset_m": self.foot_inset} if self.foot_inset else {}), "provenance": self.provenance}

    def save(self, path: str | Path) -> Path:
        """Write JSON (or CSV if the suffix is ".csv") atomically; returns the path."""
        return sampled_file.write(path, self.to_dict())

    @classmethod
    def load(cls, path: str | Path) -> "SampledTrajectory":
        """Read a file written by `save` (JSON, or CSV by its ".csv" suffix)."""
        d = sampled_file.read(path)
        return cls(d["phase"], d["x_m"], d["z_m"], d["step_length_m"], d["lift_height_m"], d.get("provenance"),
                   d.get("foot_inset_m", 0.0))


def point_evaluator(trajectory: FootTrajectory):
    """The trajectory's one-phase float evaluator `point_at(phi, beta, S, H, swing_time, stance_time)` if it
    has one that matches its `position_velocity` (CompositeCycloid, StraightLine, and subclasses that change
    neither `swing_path` nor `position_velocity`), else None: callers then use `position_velocity`."""
    cls = type(trajectory)
    for base in (CompositeCycloid, StraightLine):
        same = ("_swing_point", "swing_path") + (("corners", "_corner_points") if base is StraightLine else ())
        if (isinstance(trajectory, base) and all(getattr(cls, n) is getattr(base, n) for n in same) and all(
                getattr(cls, n) is getattr(FootTrajectory, n) for n in ("point_at", "position_velocity"))):
            return trajectory.point_at
    return None


def make_trajectory(gait: GaitConfig) -> FootTrajectory:
    """The foot trajectory named by `gait.trajectory` (one of TRAJECTORY_NAMES)."""
    name = gait.trajectory
    if name == "cycloid":
        return CompositeCycloid()
    if name == "straight":
        return StraightLine(gait.straight_shape, gait.trapezoid_fraction)
    if name == "sampled":
        if not gait.sampled_file:
            raise ValueError("GaitConfig.sampled_file must name a JSON/CSV file when trajectory='sampled'")
        return SampledTrajectory.load(gait.sampled_file)
    raise ValueError(f"unknown trajectory {name!r}; allowed: {TRAJECTORY_NAMES}")
