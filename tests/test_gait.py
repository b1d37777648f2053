"""Gait scheduler: diagonal trot pairs, swing counts, phase wrapping, swing phase, bad inputs."""
import numpy as np
import pytest

from cyberdog.config import LEG_NAMES, GaitConfig
from cyberdog.core.gait import Gait, GaitScheduler, diagonal_trot

LF, RF, LH, RH = (LEG_NAMES.index(n) for n in ("LF", "RF", "LH", "RH"))


def _circular_distance(a, b):
    d = np.mod(a - b, 1.0)
    return np.minimum(d, 1.0 - d)


def test_diagonal_trot_from_config():
    cfg = GaitConfig(period=0.5, swing_time=0.2)
    gait = diagonal_trot(cfg)
    assert gait.duty_factor == pytest.approx(0.3 / 0.5)
    assert gait.swing_fraction == pytest.approx(0.2 / 0.5)
    np.testing.assert_allclose(gait.offsets, cfg.phase_offsets)


def test_diagonal_pairs_in_phase_other_pair_half_a_cycle_later():
    sched = GaitScheduler.from_config(GaitConfig())
    t = np.linspace(0, 3.0, 3001)
    phases = sched.leg_phases(t)
    assert phases.shape == (len(t), 4)
    np.testing.assert_allclose(_circular_distance(phases[:, LF], phases[:, RH]), 0.0, atol=1e-9)
    np.testing.assert_allclose(_circular_distance(phases[:, RF], phases[:, LH]), 0.0, atol=1e-9)
    np.testing.assert_allclose(_circular_distance(phases[:, LF], phases[:, RF]), 0.5, atol=1e-9)
    # phase = (t / period + offset) mod 1, from its definition
    np.testing.assert_allclose(_circular_distance(phases[:, RF], t / 0.4 + 0.5), 0.0, atol=1e-9)


def test_exactly_two_legs_swing_at_duty_half():
    sched = GaitScheduler.from_config(GaitConfig(period=0.4, swing_time=0.2))
    t = np.concatenate([np.linspace(0, 4.0, 40001), np.arange(0, 200) * 0.2])  # includes every boundary
    swing = sched.in_swing(t)
    np.testing.assert_array_equal(swing.sum(axis=1), 2)
    np.testing.assert_array_equal(swing[:, LF], swing[:, RH])
    np.testing.assert_array_equal(swing[:, RF], swing[:, LH])
    np.testing.assert_array_equal(sched.in_stance(t), ~swing)
    # phase 0 is lift-off: LF swings right after t = 0 and stands right after half a cycle
    assert sched.in_swing(1e-6)[LF] and not sched.in_swing(0.2 + 1e-6)[LF]


def test_phases_wrap_into_unit_interval():
    sched = GaitScheduler(Gait((0.0, 0.5, 0.5, 0.0), 0.5), period=0.4)
    t = np.array([0.0, 0.4, 0.8, 1.2, 123.4, 0.39999999, 0.4 * 7])
    phases = sched.leg_phases(t)
    assert np.all((phases >= 0) & (phases < 1))
    np.testing.assert_allclose(sched.leg_phases(0.1), sched.leg_phases(0.1 + 5 * 0.4), atol=1e-9)
    assert sched.leg_phases(0.4 * 7)[LF] == 0.0  # whole cycles land exactly on lift-off
    assert sched.cycle_index(0.0) == 0 and sched.cycle_index(0.39) == 0
    assert sched.cycle_index(0.4 * 7) == 7 and sched.cycle_index(0.4 * 7 + 0.01) == 7
    np.testing.assert_array_equal(sched.cycle_index(np.array([0.1, 0.5, 0.9])), [0, 1, 2])


def test_swing_and_stance_phase():
    sched = GaitScheduler(Gait((0.0, 0.5, 0.5, 0.0), 0.6), period=0.5)  # swing 0.2 s, stance 0.3 s
    t = np.linspace(0, 1.0, 1001)
    tau = sched.swing_phase(t)
    sigma = sched.stance_phase(t)
    swing = sched.in_swing(t)
    np.testing.assert_array_equal(np.isnan(tau), ~swing)
    np.testing.assert_array_equal(np.isnan(sigma), swing)
    assert np.nanmin(tau) >= 0 and np.nanmax(tau) < 1 and np.nanmin(sigma) >= 0 and np.nanmax(sigma) < 1
    # LF: swing from 0 to 0.2 s, τ = t / 0.2; stance from 0.2 to 0.5 s, σ = (t − 0.2) / 0.3
    assert sched.swing_phase(0.05)[LF] == pytest.approx(0.25)
    assert sched.stance_phase(0.35)[LF] == pytest.approx(0.5)


@pytest.mark.parametrize("offsets, duty, match", [
    ((0.0, 0.5, 0.5), 0.5, "phase_offsets"),
    ((0.0, 0.5, 0.5, 1.0), 0.5, "phase_offsets"),
    ((0.0, 0.5, 0.5, 0.0), 1.0, "duty_factor"),
    ((0.0, 0.5, 0.5, 0.0), 0.0, "duty_factor"),
])
def test_bad_gait_raises(offsets, duty, match):
    with pytest.raises(ValueError, match=match):
        Gait(offsets, duty)


def test_bad_period_and_time_raise():
    with pytest.raises(ValueError, match="period"):
        GaitScheduler(Gait((0.0, 0.5, 0.5, 0.0), 0.5), period=0.0)
    with pytest.raises(ValueError, match="finite"):
        GaitScheduler.from_config(GaitConfig()).leg_phases(np.nan)
