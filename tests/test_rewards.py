"""Reward terms of the paper's Eq. (10)–(11): closed forms, weights, stage presets, errors."""
import dataclasses
import math

import pytest

from cyberdog.config import REWARD_TERM_NAMES, STAGE1_REWARD, STAGE2_REWARD, RewardConfig
from cyberdog.core import rewards as R

STEP = dict(v_x=0.8, v_target=1.2, y=0.03, z=0.27, z_nominal=0.30, sample_time=0.025, episode_time=10.0,
            step_energy_J=3.5)


def test_each_term_closed_form():
    assert R.speed_term(0.8, 1.2) == pytest.approx(0.16)
    assert R.speed_term(1.2, 0.8) == R.speed_term(0.8, 1.2)
    assert R.y_offset_term(-0.1) == pytest.approx(0.01)
    assert R.fuselage_term(0.27, 0.30) == pytest.approx(0.0009)
    assert R.keep_moving_term(0.025, 10.0) == pytest.approx(0.0025)
    assert R.energy_term(3.5) == 3.5


def test_keep_moving_sums_to_one_over_an_episode():
    assert sum(R.keep_moving_term(0.025, 10.0) for _ in range(400)) == pytest.approx(1.0)


def test_reward_terms_keys_and_values():
    terms = R.reward_terms(**STEP)
    assert tuple(terms) == REWARD_TERM_NAMES
    assert terms == pytest.approx({"speed": 0.16, "y_offset": 0.0009, "fuselage": 0.0009,
                                   "keep_moving": 0.0025, "energy": 3.5})


def test_paper_eq11_value():
    terms = R.reward_terms(**STEP)
    expected = -2 * 0.16 - 20 * 0.0009 - 50 * 0.0009 + 25 * 0.0025 - 0.2 * 3.5
    assert R.total_reward(terms, RewardConfig()) == pytest.approx(expected)


@pytest.mark.parametrize("cfg", [RewardConfig(), STAGE1_REWARD, STAGE2_REWARD,
                                 RewardConfig(speed=-1.3, keep_moving=7.0, energy=-0.01, z_nominal=0.25)])
def test_weighted_terms_sum_exactly_to_total(cfg):
    terms = R.reward_terms(**STEP)
    weighted = R.weighted_terms(terms, cfg)
    assert sum(weighted.values()) == R.total_reward(terms, cfg)
    for n in REWARD_TERM_NAMES:
        assert weighted[n] == cfg.weights[n] * terms[n]


@pytest.mark.parametrize("name", REWARD_TERM_NAMES)
def test_zero_weight_turns_a_term_off(name):
    terms = R.reward_terms(**STEP)
    off = dataclasses.replace(RewardConfig(), **{name: 0.0})
    assert R.weighted_terms(terms, off)[name] == 0.0
    on = R.weighted_terms(terms, RewardConfig())
    assert R.total_reward(terms, off) == pytest.approx(R.total_reward(terms, RewardConfig()) - on[name])


def test_stage_presets_differ_only_in_energy():
    assert STAGE1_REWARD.energy == 0.0 and STAGE2_REWARD.energy == -0.2
    assert dataclasses.replace(STAGE1_REWARD, energy=STAGE2_REWARD.energy) == STAGE2_REWARD
    assert STAGE2_REWARD.weights == {"speed": -2.0, "y_offset": -20.0, "fuselage": -50.0,
                                     "keep_moving": 25.0, "energy": -0.2}
    terms = R.reward_terms(**STEP)
    diff = R.total_reward(terms, STAGE1_REWARD) - R.total_reward(terms, STAGE2_REWARD)
    assert diff == pytest.approx(0.2 * 3.5)


@pytest.mark.parametrize("field,value", [("speed", 2.0), ("y_offset", 0.1), ("fuselage", math.nan),
                                         ("energy", 0.2), ("keep_moving", -1.0), ("keep_moving", math.inf),
                                         ("z_nominal", 0.0), ("z_nominal", 0.9)])
def test_bad_config_raises_naming_the_field(field, value):
    with pytest.raises(ValueError, match=f"RewardConfig.{field}"):
        RewardConfig(**{field: value})


def test_bad_inputs_raise():
    with pytest.raises(ValueError, match="episode_time"):
        R.keep_moving_term(0.025, 0.0)
    with pytest.raises(ValueError, match="step_energy_J"):
        R.energy_term(-1.0)
    with pytest.raises(ValueError, match="missing"):
        R.weighted_terms({"speed": 1.0}, RewardConfig())
