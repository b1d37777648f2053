"""Which gait cycle does a walk settle into? The steady orbit of a walk, cycle by cycle.

A foot-mode policy walks in closed loop; its extracted path is a fixed function of the gait phase, replayed
open loop through the IK + PID trot. The two can walk the same mean foot path and still settle into different
orbits: measured on one hardware-like robot, a policy whose shifts vary by half a millimetre from cycle to cycle
holds a period-1 gait (every cycle alike), while its mean path, replayed, settles into a cycle that repeats
only every third step, with 17 % more energy per cycle. `steady_orbit` says which: the gait-clock cycles'
Eq. (7) energy and speed (`cyberdog.analysis.extract.clock_cycles`) over the last `window` cycles, the
smallest period p ≤ `max_period` with which they repeat (the cycles p apart within a band of `tolerance` of
their mean, so that a slow drift is no period), or None, and the spread of the speed over the window.

Pure numpy.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

STEADY_WINDOW = 12  # cycles: the last ~5 s of a 0.4 s gait cycle, four repeats of a period-3 orbit
MAX_PERIOD = 4
TOLERANCE = 0.05  # share of the window's mean: a period-3 orbit's repeats scatter over 3 J of 60 (sensor noise)


@dataclass(frozen=True)
class SteadyOrbit:
    """The last `cycles` gait cycles of a walk."""

    cycles: int
    period: int | None  # smallest p with the cycles p apart alike (energy and speed); None: none ≤ MAX_PERIOD
    energy_J: float  # mean Eq. (7) energy per cycle
    speed_mps: float  # mean forward speed
    speed_min_mps: float
    speed_max_mps: float

    def describe(self) -> str:
        period = f"period {self.period}" if self.period else f"no period ≤ {MAX_PERIOD}"
        return (f"{period} over its last {self.cycles} cycles: {self.energy_J:.1f} J and {self.speed_mps:.3f} m/s "
                f"per cycle (speed {self.speed_min_mps:.3f}–{self.speed_max_mps:.3f} m/s)")


def repeat_period(values, max_period: int = MAX_PERIOD, tolerance: float = TOLERANCE) -> int | None:
    """Smallest p in 1..max_period such that, for every phase r < p and every column of `values` (cycles ×
    quantities, or one quantity per cycle), the cycles r, r + p, r + 2p, ... span at most tolerance · mean|x|
    (each phase seen at least twice); None if there is none."""
    x = np.asarray(values, dtype=float)
    x = x[:, None] if x.ndim == 1 else x
    if x.ndim != 2 or not np.all(np.isfinite(x)):
        raise ValueError(f"values must be a finite (cycles,) or (cycles, quantities) array, got shape {x.shape}")
    if not (isinstance(max_period, int) and max_period >= 1):
        raise ValueError(f"max_period must be an int >= 1, got {max_period!r}")
    if not tolerance > 0:
        raise ValueError(f"tolerance must be > 0, got {tolerance!r}")
    scale = tolerance * np.abs(x).mean(axis=0)
    for p in range(1, min(max_period, len(x) // 2) + 1):
        if all(np.all(np.ptp(x[r::p], axis=0) <= scale) for r in range(p)):
            return p
    return None


def steady_orbit(cycles, window: int = STEADY_WINDOW, max_period: int = MAX_PERIOD,
                 tolerance: float = TOLERANCE) -> SteadyOrbit:
    """The `SteadyOrbit` of the last `window` of `cycles` (objects with .energy J and .speed m/s, in order:
    `clock_cycles`' Cycle). A window needs at least 2·max_period cycles, so that each period is seen twice."""
    if not (isinstance(window, int) and window >= 2 * max_period):
        raise ValueError(f"window must be an int >= 2 * max_period ({2 * max_period}), got {window!r}")
    if len(cycles) < window:
        raise ValueError(f"{len(cycles)} cycles, fewer than the window of {window}: walk longer")
    last = cycles[-window:]
    x = np.array([(c.energy, c.speed) for c in last], dtype=float)
    return SteadyOrbit(cycles=window, period=repeat_period(x, max_period, tolerance),
                       energy_J=float(x[:, 0].mean()), speed_mps=float(x[:, 1].mean()),
                       speed_min_mps=float(x[:, 1].min()), speed_max_mps=float(x[:, 1].max()))


__all__ = ["MAX_PERIOD", "STEADY_WINDOW", "SteadyOrbit", "TOLERANCE", "repeat_period", "steady_orbit"]
