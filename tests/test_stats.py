import math

import numpy as np
import pytest

from cyberdog.analysis.stats import mean_ci, mean_ci_band


def test_mean_ci_matches_t_interval_by_hand():
    x = [1.0, 2.0, 4.0]
    m, h = mean_ci(x)
    s = np.std(x, ddof=1)
    assert m == pytest.approx(7 / 3)
    assert h == pytest.approx(4.302652729911275 * s / math.sqrt(3))  # t_{0.975, 2}


def test_mean_ci_covers_the_true_mean_about_95_percent_of_the_time():
    rng = np.random.default_rng(0)
    hits = 0
    for _ in range(2000):
        m, h = mean_ci(rng.normal(5.0, 2.0, size=5))
        hits += abs(m - 5.0) <= h
    assert 0.93 < hits / 2000 < 0.97


def test_mean_ci_edge_cases():
    assert math.isnan(mean_ci([])[0])
    m, h = mean_ci([3.0, float("nan")])
    assert m == 3.0 and math.isnan(h)
    with pytest.raises(ValueError):
        mean_ci([1, 2], confidence=1.5)


def test_band_is_per_column():
    curves = np.array([[0.0, 1.0], [2.0, 1.0]])
    m, h = mean_ci_band(curves)
    assert m.tolist() == [1.0, 1.0] and h[1] == 0.0 and h[0] > 0
