"""The shipped foot-target policy of Table 5 (results/table5/policy/seed0/, configs/table5.yaml seed 0) still walks in
today's simulator: both stages walk 10 s at 1.0 m/s without falling, at the command (±10 % over the last 5 s), and
stage 2, trained on Eq. 7's energy, uses less of it per metre than stage 1. A change of the robot, controller or env
that breaks the shipped policies fails here."""
from pathlib import Path

import pytest

from cyberdog.rl.rollout import load_actor, rollout

SHIPPED = Path(__file__).resolve().parents[1] / "results" / "table5" / "policy" / "seed0"


@pytest.fixture(scope="module")
def rollouts():
    return {stage: rollout(load_actor(SHIPPED / f"stage{stage}_actor.pt"), speed=1.0, duration=10.0, seed=0)
            for stage in (1, 2)}


@pytest.mark.parametrize("stage", [1, 2])
def test_each_stage_walks_at_the_command(rollouts, stage):
    r = rollouts[stage]
    assert not r.fell
    assert abs(r.mean_speed - 1.0) <= 0.1, r.mean_speed


def test_stage2_uses_less_energy_per_metre_than_stage1(rollouts):
    per_m = {s: r.energy / r.distance for s, r in rollouts.items()}
    assert per_m[2] < 0.97 * per_m[1], per_m
