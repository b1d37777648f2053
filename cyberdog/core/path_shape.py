"""Beyond the paper: the SHAPE of a foot path at a fixed lift height and gait timing, as 5 numbers. Pure numpy.

The paper learns a foot trajectory with DDPG and finds it 9–12 % cheaper than the cheaper of the composite
cycloid and the straight line. In our simulation that saving comes from the learned path's lower lift
height, not from its shape. The shape question is asked directly by a search over this parameterisation
(`cyberdog.analysis.shape_search`, derivative-free on the simulator): with the lift height H, the step length
S = v·stance_time and the trot timing all fixed, how much Eq. (7) energy can the path's shape save against the
composite cycloid? This module holds only the shape: its parameters, bounds and the trajectory they make.

Parameterisation (`ShapeParams`, 5 numbers with bounds, `PARAM_BOUNDS`). Phase φ ∈ [0, 1) over the gait
cycle, φ = 0 at lift-off; swing for φ < β = swing_time / period with τ = φ / β, stance after with
σ = (φ − β) / (1 − β). x̂ = x / S and ẑ = z / H relative to the neutral point (z = 0 on the ground).
With c(s) = s − sin(2πs)/(2π) the cycloid's timing law (c(0) = 0, c(1) = 1, zero slope at both ends):

- swing x̂(τ) = u(w(τ)) − ½, where w(τ) = τ + x_skew·τ(1 − τ) is a monotone phase warp (x_skew > 0 moves
  the foot forward sooner in the swing, < 0 lifts first and moves forward later) and u is the timing law
  `x_law` blends: 0 → the cycloid's c, +1 → constant speed (w itself, softer peak speed but velocity jumps
  at lift-off and touch-down), −1 → c(c(w)) (slower at the ends, faster mid-swing); beyond +1 the
  blend (1 − a)·c + a·w extrapolates past constant speed (faster at the ends than mid-swing), still monotone
  for a ≤ 2 (its slope 2 − a at mid-swing), bounded at 1.5. So the foot never moves backward in swing and
  x̂ runs exactly −½ → +½;
- swing ẑ(τ) = g(τ / z_peak) rising and g((1 − τ) / (1 − z_peak)) falling, g(s) = 1 − (1 − c(s))^k with
  k = 2^z_fullness_log2: z_peak moves the apex in the swing (0.5 = mid-swing), k > 1 lifts and lowers
  faster with a flatter top (toward the rectangle), k < 1 a leaner, sharper apex. ẑ = 1 exactly at τ =
  z_peak, so the lift height stays H; ẑ(0) = ẑ(1) = 0 with zero slope;
- stance: z = 0 (a straight line on the ground) and x̂(σ) = ½ − [(1 − stance_law)·σ + stance_law·c(σ)]:
  0 → the paper's constant speed, 1 → slower at both ends, which matches the swing's zero end velocity
  (continuous velocity at lift-off and touch-down) at the price of an uneven body push.
Positions are continuous at both swing/stance switches for every parameter value (x̂ = ±½, ẑ = 0 there).
`CYCLOID_PARAMS` = (0, 0, 0.5, 0, 0) is exactly the composite cycloid with the constant-speed stance.

The path is replayed as a `SampledTrajectory` (a periodic cubic spline through `DEFAULT_POINTS` samples per
cycle, normalised by S and H, so one file serves every speed), which is also what the optimiser evaluates:
what is optimised is what is saved. The spline rounds the cycloid's velocity jump at the stance/swing
switches within about one sample (1 ms); replaying the sampled cycloid costs within about 0.1 % of the
analytic one (checked in the table: "cycloid (sampled)").

The search over these parameters (the objective, the optimiser) is `cyberdog.analysis.shape_search`.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np

from cyberdog.config import GaitConfig
from cyberdog.core.trajectories import SampledTrajectory

PARAM_NAMES = ("x_law", "x_skew", "z_peak", "z_fullness_log2", "stance_law")
PARAM_BOUNDS = {  # (low, high), all dimensionless
    "x_law": (-1.0, 1.5),  # swing x timing: −1 sharper c∘c, 0 cycloid, +1 constant speed, >1 faster ends
    "x_skew": (-0.6, 0.6),  # swing x phase warp w = τ + s·τ(1−τ); |s| < 1 keeps w monotone
    "z_peak": (0.3, 0.7),  # swing phase τ of the apex z = H
    "z_fullness_log2": (-1.0, 1.5),  # log2 k, g = 1 − (1 − c)^k: k = 0.5 … 2.8 (≥ 0.5: z C¹ at the apex)
    "stance_law": (0.0, 1.0),  # stance x timing: 0 constant speed, 1 the cycloid law (slow ends)
}
DEFAULT_POINTS = 400  # samples per gait cycle: 1 ms apart at the 0.4 s cycle
MIN_POINTS = 40


def _timing_law(s: np.ndarray) -> np.ndarray:
    """The cycloid's timing law c(s) = s − sin(2πs)/(2π) on [0, 1]: 0 → 1 with zero slope at both ends."""
    return s - np.sin(2.0 * np.pi * s) / (2.0 * np.pi)


@dataclass(frozen=True)
class ShapeParams:
    """The 5 shape numbers (see the module docstring); defaults are the composite cycloid."""

    x_law: float = 0.0
    x_skew: float = 0.0
    z_peak: float = 0.5
    z_fullness_log2: float = 0.0
    stance_law: float = 0.0

    def __post_init__(self) -> None:
        for name in PARAM_NAMES:
            value = getattr(self, name)
            lo, hi = PARAM_BOUNDS[name]
            if not (isinstance(value, (int, float, np.floating, np.integer)) and math.isfinite(value)
                    and lo <= value <= hi):
                raise ValueError(f"ShapeParams.{name} must be a finite number in [{lo}, {hi}], got {value!r}")

    def as_array(self) -> np.ndarray:
        return np.array([getattr(self, n) for n in PARAM_NAMES], dtype=float)

    @classmethod
    def from_array(cls, values: Sequence[float]) -> "ShapeParams":
        values = np.asarray(values, dtype=float).ravel()
        if values.shape != (len(PARAM_NAMES),):
            raise ValueError(f"shape parameters need {len(PARAM_NAMES)} values {PARAM_NAMES}, got {values.shape}")
        return cls(**{n: float(v) for n, v in zip(PARAM_NAMES, values)})

    def as_dict(self) -> dict:
        return {n: float(getattr(self, n)) for n in PARAM_NAMES}


CYCLOID_PARAMS = ShapeParams()
_LOW = np.array([PARAM_BOUNDS[n][0] for n in PARAM_NAMES])
_HIGH = np.array([PARAM_BOUNDS[n][1] for n in PARAM_NAMES])


def to_unit(params: ShapeParams) -> np.ndarray:
    """Parameters scaled to [0, 1]^5 by their bounds (the optimiser's coordinates: comparable step sizes)."""
    return (params.as_array() - _LOW) / (_HIGH - _LOW)


def from_unit(u: Sequence[float]) -> ShapeParams:
    """Inverse of `to_unit`; values a hair outside [0, 1] (round-off) are clipped."""
    u = np.clip(np.asarray(u, dtype=float), 0.0, 1.0)
    return ShapeParams.from_array(_LOW + u * (_HIGH - _LOW))


# ---------------------------------------------------------------------------------------------------------
# the path, normalised (x̂ = x / S, ẑ = z / H)
# ---------------------------------------------------------------------------------------------------------

def _check_unit_interval(name: str, a: Any) -> np.ndarray:
    a = np.asarray(a, dtype=float)
    if not np.all(np.isfinite(a)) or np.any(a < -1e-12) or np.any(a > 1 + 1e-12):
        raise ValueError(f"{name} must be finite and in [0, 1]")
    return np.clip(a, 0.0, 1.0)


def swing_x_hat(tau: Any, p: ShapeParams) -> np.ndarray:
    """Swing x / S at swing phase τ ∈ [0, 1]: −½ at lift-off, +½ at touch-down, never decreasing."""
    tau = _check_unit_interval("swing phase tau", tau)
    w = tau + p.x_skew * tau * (1.0 - tau)  # monotone warp of [0, 1] for |x_skew| < 1
    c = _timing_law(w)
    other = w if p.x_law >= 0 else _timing_law(c)  # constant speed, or the sharper c∘c
    a = abs(p.x_law)  # a > 1 extrapolates toward faster ends; slope (1 − a)(1 − cos 2πw) + a ≥ 0 for a ≤ 2
    return (1.0 - a) * c + a * other - 0.5


def swing_z_hat(tau: Any, p: ShapeParams) -> np.ndarray:
    """Swing z / H at swing phase τ ∈ [0, 1]: 0 at both ends, exactly 1 at τ = z_peak, nowhere above 1."""
    tau = _check_unit_interval("swing phase tau", tau)
    k = 2.0 ** p.z_fullness_log2
    s = np.where(tau <= p.z_peak, tau / p.z_peak, (1.0 - tau) / (1.0 - p.z_peak))
    # clipped: round-off may put c a hair above 1, and a negative base to a fractional power is nan
    return 1.0 - np.clip(1.0 - _timing_law(np.clip(s, 0.0, 1.0)), 0.0, 1.0) ** k


def stance_x_hat(sigma: Any, p: ShapeParams) -> np.ndarray:
    """Stance x / S at stance phase σ ∈ [0, 1]: +½ at touch-down, −½ at lift-off (z = 0 throughout)."""
    sigma = _check_unit_interval("stance phase sigma", sigma)
    return 0.5 - ((1.0 - p.stance_law) * sigma + p.stance_law * _timing_law(sigma))


def _check_swing_fraction(swing_fraction: float) -> float:
    if not (isinstance(swing_fraction, (int, float, np.floating)) and 0.0 < swing_fraction < 1.0):
        raise ValueError(f"swing_fraction must be in (0, 1), got {swing_fraction!r}")
    return float(swing_fraction)


def normalised_cycle(phase: Any, p: ShapeParams, swing_fraction: float) -> tuple[np.ndarray, np.ndarray]:
    """(x̂, ẑ) over the gait cycle at phases φ ∈ [0, 1): swing for φ < swing_fraction, stance after."""
    beta = _check_swing_fraction(swing_fraction)
    phi = np.asarray(phase, dtype=float)
    if not np.all(np.isfinite(phi)) or np.any(phi < 0) or np.any(phi >= 1):
        raise ValueError("phase must be finite and in [0, 1)")
    swing = phi < beta
    tau = np.where(swing, phi / beta, 0.0)
    sigma = np.where(swing, 0.0, (phi - beta) / (1.0 - beta))
    x = np.where(swing, swing_x_hat(tau, p), stance_x_hat(sigma, p))
    z = np.where(swing, swing_z_hat(tau, p), 0.0)
    return x, z


def shape_trajectory(p: ShapeParams, gait: GaitConfig | None = None, n_points: int = DEFAULT_POINTS,
                     provenance: dict | None = None, foot_inset: float = 0.0) -> SampledTrajectory:
    """The shape as a `SampledTrajectory` for the gait's timing (its swing fraction) and lift height.

    The samples are stored in metres at the gait's S (= speed·stance_time, or 0.2 m where the speed is 0)
    and H; the trajectory is normalised by them, so it replays at any speed's S and at whatever H the walk
    is configured with (set the walk's lift_height to the same H to keep the optimised height). foot_inset: m,
    every foot nearer the body's midline (`SampledTrajectory.foot_inset`).
    """
    gait = gait or GaitConfig(lift_height=0.10)
    if not (isinstance(n_points, (int, np.integer)) and n_points >= MIN_POINTS):
        raise ValueError(f"n_points must be an integer >= {MIN_POINTS}, got {n_points!r}")
    beta = gait.swing_time / gait.period
    phase = np.arange(n_points) / n_points
    x_hat, z_hat = normalised_cycle(phase, p, beta)
    step_length = gait.step_length if gait.step_length > 0 else 0.2  # m; only normalises x
    meta = {"source": "cyberdog.core.path_shape", "shape_params": p.as_dict(),
            "swing_fraction": beta, "period_s": gait.period, "swing_time_s": gait.swing_time,
            "n_points": int(n_points), **(provenance or {})}
    return SampledTrajectory(phase, step_length * x_hat, gait.lift_height * z_hat, step_length,
                             gait.lift_height, meta, foot_inset)
