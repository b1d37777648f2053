"""The shipped recipes against the search's long-form presets they replaced (notebook/configs/): each shipped phase
resolves to the long form and the command that made the shipped actors; the log's torque recipe of the ideal robot
(torque_band.yaml) and the gains continuation of the battery recipe likewise."""
from __future__ import annotations

import json
from pathlib import Path

import pytest

from cyberdog import config as C

ROOT = Path(__file__).resolve().parents[2]
NOTEBOOK = ROOT / "notebook" / "configs"


def _long(name: str, *sets: str) -> C.ExperimentConfig:
    """A long-form preset of the search (earlier file form) with the command line's --set of the shipped run."""
    return C.override(C.load(C.ExperimentConfig, NOTEBOOK / name), list(sets))


def _phases(name: str) -> dict[str, C.Phase]:
    """The phases of configs/<name>, or of a recipe of the log given as notebook/configs/<name>."""
    path = ROOT / name if name.startswith("notebook/") else ROOT / "configs" / name
    return {p.name: p for p in C.load_preset(path).phases}


BAND = "notebook/configs/torque_band.yaml"  # notebook/results/policy_torque_band: the ideal robot's torque recipe

# Each shipped phase against the long form and the command that made the shipped actors (docs/results.md).
SHIPPED = {
    ("table5.yaml", "train"): ("both", _long("quick_speeds.yaml", "train.stage2.max_env_steps=160000")),
    # stage 1 only: quick_speeds.yaml's stage-2 budget (40,000) is never used by a stage-1 run
    ("battery.yaml", "stage1"): ("1", _long("quick_speeds.yaml", "train.stage2.max_env_steps=160000")),
    ("battery.yaml", "stage2"): ("2", _long("quick_speeds_battery_loop.yaml")),
    ("battery.yaml", "band"): ("2", _long("quick_speeds_battery_band.yaml")),
    (BAND, "main"): ("both", _long("torque_prior.yaml")),
    (BAND, "speed1"): ("1", _long("torque_prior.yaml", "env.prior_weight=0", "train.stage1.reward.speed=-100",
                            "train.stage2.reward.speed=-100", "train.stage1.max_env_steps=100000",
                            "train.stage1.critic_warmup_updates=2000")),
    (BAND, "speed2"): ("2", _long("torque_prior.yaml", "train.stage1.reward.speed=-100",
                            "train.stage2.reward.speed=-100", "train.stage2.max_env_steps=100000")),
    (BAND, "energy"): ("2", _long("torque_prior.yaml", "train.stage1.reward.speed=-100",
                            "train.stage2.reward.speed=-100", "train.stage2.reward.energy=-0.6",
                            "train.stage2.max_env_steps=50000")),
}


@pytest.mark.parametrize("preset, phase", sorted(SHIPPED), ids=lambda x: str(x))
def test_a_shipped_phase_resolves_to_the_long_form_it_replaced(preset, phase):
    stage, long_form = SHIPPED[(preset, phase)]
    resolved = _phases(preset)[phase]
    assert resolved.stage == stage
    assert C.changed_settings(resolved.config, long_form) == {}


def test_the_gains_continuation_is_the_band_phase_with_wider_gains_and_made_its_actors():
    """notebook/configs/battery_gains.yaml (notebook/2026-12-01_gains_phase.md) changes configs/battery.yaml's band
    phase in the gains drawn, the drivers' rate and how the continuation starts; its actors (notebook/results/
    policy_battery_gains/seed<N>) were trained with it, each from the shipped band actor of its seed (an actor file:
    its critics were new whatever fresh_critics says)."""
    gains = C.load(C.ExperimentConfig, NOTEBOOK / "battery_gains.yaml")
    assert set(C.changed_settings(_phases("battery.yaml")["band"].config, gains)) == {
        "env.walk.sim.physics_dt", "env.randomization.kp_factor", "env.randomization.kd_factor",
        "train.stage2.max_env_steps", "train.stage2.actor_anchor", "train.stage2.critic_warmup_updates",
        "train.stage2.critic_warmup_targets", "train.stage2.fresh_critics"}
    assert gains.env.randomization.kd_factor == (0.5, 2.0) and gains.train.stage2.fresh_critics
    shipped = sorted((ROOT / "notebook" / "results" / "policy_battery_gains").glob("seed*"))
    assert shipped
    for folder in shipped:
        made = C.load(C.ExperimentConfig, folder / "config.yaml")
        assert set(C.changed_settings(gains, made)) <= {"train.seed", "train.stage2.fresh_critics"}, folder.name
        start = json.loads((folder / "metadata.json").read_text())["init_from"]
        assert start == f"results/battery/policy/{folder.name}/stage2_actor.pt" and (ROOT / start).is_file()
