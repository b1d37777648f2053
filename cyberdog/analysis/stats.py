"""Across-seed statistics: mean and a 95 % confidence interval (Student's t). Pure numpy/scipy."""
from __future__ import annotations

import math

import numpy as np
from scipy import stats


def mean_ci(values, confidence: float = 0.95) -> tuple[float, float]:
    """(mean, half-width) of the two-sided Student-t confidence interval of the mean of `values`.

    NaNs are dropped. One value gives a half-width of nan (no spread to estimate); none gives (nan, nan).
    """
    if not 0 < confidence < 1:
        raise ValueError(f"confidence must be in (0, 1), got {confidence!r}")
    x = np.asarray(values, dtype=float).ravel()
    x = x[np.isfinite(x)]
    if x.size == 0:
        return math.nan, math.nan
    m = float(x.mean())
    if x.size == 1:
        return m, math.nan
    half = float(stats.t.ppf(0.5 + confidence / 2, x.size - 1) * x.std(ddof=1) / math.sqrt(x.size))
    return m, half


def mean_ci_band(curves: np.ndarray, confidence: float = 0.95) -> tuple[np.ndarray, np.ndarray]:
    """Per-column mean and CI half-width of a (seeds, points) array (learning curves with a band)."""
    curves = np.atleast_2d(np.asarray(curves, dtype=float))
    pairs = [mean_ci(curves[:, j], confidence) for j in range(curves.shape[1])]
    return np.array([p[0] for p in pairs]), np.array([p[1] for p in pairs])
