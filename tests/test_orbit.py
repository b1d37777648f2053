"""The steady orbit of a walk (cyberdog.analysis.orbit) and the policy-to-path hand-over of a rollout."""
from __future__ import annotations

from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from cyberdog.analysis.orbit import repeat_period, steady_orbit
from cyberdog.core.foot_offsets import FootOffsetPath

ROOT = Path(__file__).resolve().parents[1]
BATTERY_ACTOR = ROOT / "results/battery/policy/seed0/stage2_actor.pt"  # a shipped foot-target policy
TORQUE_ACTOR = ROOT / "results/torque/policy/seed0/stage2_actor.pt"  # a shipped joint-torque policy


def cycles(energies, speeds):
    return [SimpleNamespace(energy=e, speed=s) for e, s in zip(energies, speeds)]


def test_a_period_three_orbit_is_told_from_a_period_one_orbit_with_the_same_scatter():
    rng = np.random.default_rng(0)
    noise = rng.uniform(-0.015, 0.015, size=(15, 2))  # a 3 % band at most, inside the 5 % tolerance
    steady = np.array([52.0, 1.16]) * (1 + noise)
    three = np.array([[59.0, 1.23], [62.0, 1.20], [61.0, 1.09]] * 5) * (1 + noise)
    assert repeat_period(steady) == 1
    assert repeat_period(three) == 3
    assert repeat_period(three[:, 1]) == 3  # one quantity is enough
    orbit = steady_orbit(cycles(*three.T))
    assert orbit.period == 3 and orbit.cycles == 12
    assert orbit.speed_min_mps < 1.10 < 1.22 < orbit.speed_max_mps
    assert orbit.energy_J == pytest.approx(three[-12:, 0].mean())
    assert "period 3" in orbit.describe()


def test_a_drifting_walk_has_no_period():
    drift = np.stack([np.linspace(40, 70, 16), np.linspace(0.8, 1.3, 16)], axis=1)
    assert repeat_period(drift) is None
    assert "no period" in steady_orbit(cycles(*drift.T)).describe()


@pytest.mark.parametrize("bad", [dict(values=[[1.0, np.nan]] * 5), dict(values=[1.0] * 5, max_period=0),
                                 dict(values=[1.0] * 5, tolerance=0.0)])
def test_bad_arguments_are_refused(bad):
    with pytest.raises(ValueError):
        repeat_period(**bad)


def test_a_window_longer_than_the_walk_is_refused():
    with pytest.raises(ValueError, match="walk longer"):
        steady_orbit(cycles([50.0] * 5, [1.0] * 5))
    with pytest.raises(ValueError, match="window"):
        steady_orbit(cycles([50.0] * 20, [1.0] * 20), window=4)


def test_after_the_hand_over_the_robot_gets_the_paths_shift_and_no_policy():
    from cyberdog.core.gait import GaitScheduler
    from cyberdog.rl.rollout import load_actor, rollout

    actor = load_actor(BATTERY_ACTOR)
    gait = actor.config.env.walk.gait
    table = np.zeros((4, 16, 3))
    table[:, :, 0] = 0.01 * np.sin(2 * np.pi * np.arange(16) / 16)  # m: a shift no policy commands
    table[:, :, 2] = 0.004
    path = FootOffsetPath(table, gait.period)
    r = rollout(actor, speed=1.0, duration=1.5, then_path=(1.25, path))  # after the 1 s speed ramp: whole shift
    t = np.asarray(r.traces["t"])
    recorded = np.asarray(r.traces["foot_offsets"])
    after = t >= 1.25 + actor.config.env.control_dt  # the policy's last shift has ramped out
    phases = GaitScheduler.from_config(gait).leg_phases(t[after])
    expected = np.array([path.at(ph)[0] for ph in phases])
    assert np.allclose(recorded[after], expected, atol=1e-9)
    before = rollout(actor, speed=1.0, duration=1.5)  # the same walk without a hand-over, up to it
    early = t < 1.25
    assert np.array_equal(np.asarray(before.traces["foot_offsets"])[early], recorded[early])
    assert not np.allclose(np.asarray(before.traces["foot_offsets"])[after], recorded[after])


def test_a_hand_over_off_the_agent_step_or_from_a_torque_policy_is_refused():
    from cyberdog.rl.rollout import load_actor, rollout

    actor = load_actor(BATTERY_ACTOR)
    path = FootOffsetPath.zero(actor.config.env.walk.gait.period)
    with pytest.raises(ValueError, match="multiple of the agent step"):
        rollout(actor, speed=1.0, duration=1.0, then_path=(0.51, path))
    with pytest.raises(ValueError, match="before the end"):
        rollout(actor, speed=1.0, duration=1.0, then_path=(1.0, path))
    torque = load_actor(TORQUE_ACTOR)
    with pytest.raises(ValueError, match="foot targets"):
        rollout(torque, speed=1.0, duration=1.0, then_path=(0.5, path))
