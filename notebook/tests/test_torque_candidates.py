"""The torque recipe's candidates kept in the log (notebook/configs/torque_*.yaml, notebook/results/): each resolves to
the recipe's phases but for the settings its comments name, and its kept results were made by those phases."""
from __future__ import annotations

import dataclasses
from pathlib import Path

import pytest

from cyberdog import config as C
from conftest import assert_made_by

ROOT = Path(__file__).resolve().parents[2]
NOTEBOOK = ROOT / "notebook" / "configs"


def _phases(name: str) -> dict[str, C.Phase]:
    """The phases of configs/<name>, or of a recipe of the log given as notebook/configs/<name>."""
    path = ROOT / name if name.startswith("notebook/") else ROOT / "configs" / name
    return {p.name: p for p in C.load_preset(path).phases}


@pytest.mark.parametrize("candidate, changed", [
    # notebook/2026-12-02_torque_stage2.md: the keep-moving bonus raised with |E| in both stage-2 phases
    ("torque_bonus.yaml", {"energy": {"train.stage2.reward.keep_moving"},
                           "energy2": {"train.stage2.reward.keep_moving"}}),
    # ... and the speed term over a stride beyond a deadband, with a stronger energy term and a longer warm-up
    ("torque_band_energy.yaml", {
        "energy": {"train.stage2.reward.keep_moving", "train.stage2.reward.energy", "train.stage2.reward.speed",
                   "train.stage2.reward.speed_window", "train.stage2.reward.speed_deadband",
                   "train.stage2.critic_warmup_updates", "train.stage2.critic_warmup_targets"},
        "energy2": {"train.stage2.reward.keep_moving", "train.stage2.reward.energy", "train.stage2.reward.speed",
                    "train.stage2.reward.speed_window", "train.stage2.reward.speed_deadband"}}),
])
def test_a_torque_stage2_candidate_changes_only_what_it_says_and_keeps_stage_1(candidate, changed):
    """The candidates of the torque recipe's stage 2 (notebook/configs/) resolve to the recipe's phases as they were
    (torque_previous.yaml) but for the settings their comments name; stage 1 (main, speed) is the recipe's, so a
    lineage whose stage 1 was made by notebook/configs/torque_stage1.yaml continues into either; where D rises with
    E, a walk nets stage 1's bonus per step for a stage-2 walk's 12.4 J of electrical energy a step
    (D/400 − |E|·12.4 ≈ 7.5)."""
    previous, mine = _phases("notebook/configs/torque_previous.yaml"), _phases(f"notebook/configs/{candidate}")
    stage1 = _phases("notebook/configs/torque_stage1.yaml")
    assert list(mine) == list(previous) and list(stage1) == ["main", "speed"]
    for name in ("main", "speed"):
        assert mine[name].stage == stage1[name].stage == previous[name].stage
        assert C.changed_settings(mine[name].config, previous[name].config) == {}
        assert C.changed_settings(stage1[name].config, previous[name].config) == {}
    for name, keys in changed.items():
        assert mine[name].stage == previous[name].stage == "2"
        assert set(C.changed_settings(mine[name].config, previous[name].config)) == keys, name
        reward = mine[name].config.train.stage2.reward
        assert reward.keep_moving / 400 - abs(reward.energy) * 12.4 == pytest.approx(7.5, abs=0.2), name


def test_the_torque_speed_band_candidate_adds_a_band_phase_and_keeps_its_speed_form_through_stage_2():
    """notebook/configs/torque_speed_band.yaml (notebook/2026-12-02_torque_stage2.md): the recipe's main and speed
    phases as they are, then a stage-1 band phase that pays r_v over a stride beyond 2 % of the command, the same
    speed form in both stage-2 phases, whose only other changes are the bonus raised with |E| (a walk nets stage 1's
    D/400 = 7.5 a step for 12.4 J a step), the critics' warm-up and a slower actor (3e-5)."""
    previous = _phases("notebook/configs/torque_previous.yaml")
    mine = _phases("notebook/configs/torque_speed_band.yaml")
    assert list(mine) == ["main", "speed", "band", "energy", "energy2"]
    assert [(p.name, p.start) for p in mine.values()][2:] == [
        ("band", "speed/stage1_final.pt"), ("energy", "band/stage1_final.pt"), ("energy2", "energy/stage2_final.pt")]
    for name in ("main", "speed"):
        assert C.changed_settings(mine[name].config, previous[name].config) == {}, name
    band = mine["band"].config.train.stage1
    assert mine["band"].stage == "1" and mine["band"].config.env.prior_weight == 0.0
    assert set(C.changed_settings(mine["band"].config, previous["speed"].config)) == {
        "train.stage1.reward.speed", "train.stage1.reward.speed_window", "train.stage1.reward.speed_deadband",
        "train.stage1.max_env_steps", "train.stage1.critic_warmup_updates"}  # its targets follow, as in main
    speed_form = {"train.stage2.reward.speed", "train.stage2.reward.speed_window", "train.stage2.reward.speed_deadband",
                  "train.stage2.reward.keep_moving"}
    assert set(C.changed_settings(mine["energy"].config, previous["energy"].config)) == speed_form | {
        "train.stage2.critic_warmup_updates", "train.stage2.critic_warmup_targets", "train.stage2.actor_lr"}
    assert set(C.changed_settings(mine["energy2"].config, previous["energy2"].config)) == speed_form | {
        "train.stage2.actor_lr"}
    for name in ("energy", "energy2"):
        stage2 = mine[name].config.train.stage2
        assert (stage2.reward.speed, stage2.reward.speed_window, stage2.reward.speed_deadband) == (
            band.reward.speed, band.reward.speed_window, band.reward.speed_deadband), name
        assert stage2.reward.keep_moving / 400 - abs(stage2.reward.energy) * 12.4 == pytest.approx(7.5, abs=0.2), name
        assert stage2.actor_lr == 3e-5 < mine[name].config.agent.actor_lr, name


def test_the_torque_speed_relative_continuation_changes_only_the_speed_scale_and_the_energy_weight():
    """notebook/configs/torque_speed_relative.yaml: torque_speed_band.yaml's phases as they are, then energy3rel from
    its stage-2 agent with r_v on the error as a share of the set speed (A = -432: -300 in m/s at 1.2 m/s),
    E = -1.2 and D raised so that a walk still nets stage 1's 7.5 a step."""
    band = _phases("notebook/configs/torque_speed_band.yaml")
    mine = _phases("notebook/configs/torque_speed_relative.yaml")
    assert list(mine) == [*band, "energy3rel"] and mine["energy3rel"].start == "energy2/stage2_final.pt"
    for name in band:
        assert C.changed_settings(mine[name].config, band[name].config) == {}, name
    assert set(C.changed_settings(mine["energy3rel"].config, band["energy2"].config)) == {
        "train.stage2.max_env_steps", "train.stage2.reward.energy", "train.stage2.reward.keep_moving",
        "train.stage2.reward.speed", "train.stage2.reward.speed_relative"}
    reward = mine["energy3rel"].config.train.stage2.reward
    in_metres = band["energy2"].config.train.stage2.reward.speed
    assert reward.speed_relative and reward.speed == pytest.approx(in_metres * 1.2 ** 2)  # the same at 1.2 m/s
    assert reward.keep_moving / 400 - abs(reward.energy) * 12.4 == pytest.approx(7.5, abs=0.2)


def test_the_torque_speed_cap_candidate_keeps_the_band_phase_relative_and_caps_r_v_below_the_bonus():
    """notebook/configs/torque_speed_cap.yaml: the recipe's main and speed phases as they are, torque_speed_band.yaml's
    band phase with r_v as a share of the set speed at the same weight at 1.2 m/s, then three stage-2 phases with the
    same r_v (relative, over a stride, no deadband, capped at 15 %) where a walk at the cap still nets 1.5-3 a step
    above a fall: D/400 > |A|·cap² + |E|·12.4 J."""
    previous = _phases("notebook/configs/torque_previous.yaml")
    band = _phases("notebook/configs/torque_speed_band.yaml")
    mine = _phases("notebook/configs/torque_speed_cap.yaml")
    assert list(mine) == ["main", "speed", "band", "energy", "energy2", "energy3"]
    assert [p.start for p in mine.values()][3:] == [
        "band/stage1_final.pt", "energy/stage2_final.pt", "energy2/stage2_final.pt"]
    for name in ("main", "speed"):
        assert C.changed_settings(mine[name].config, previous[name].config) == {}, name
    assert set(C.changed_settings(mine["band"].config, band["band"].config)) == {
        "train.stage1.reward.speed", "train.stage1.reward.speed_relative"}
    stage1 = mine["band"].config.train.stage1.reward
    assert stage1.speed == pytest.approx(band["band"].config.train.stage1.reward.speed * 1.2 ** 2)
    energies = []
    for name in ("energy", "energy2", "energy3"):
        stage2 = mine[name].config.train.stage2
        r = stage2.reward
        assert (r.speed_relative, r.speed_window, r.speed_deadband, r.speed_cap) == (True, 0.4, 0.0, 0.15), name
        assert 1.5 < r.keep_moving / 400 - abs(r.speed) * r.speed_cap ** 2 - abs(r.energy) * 12.4 < 3.0, name
        assert stage2.actor_lr == 3e-5 and mine[name].config.env.prior_weight == 0.0, name
        energies.append(r.energy)
    assert energies == [-0.3, -0.6, -1.2]
    assert [mine[n].config.train.stage2.max_env_steps for n in ("energy", "energy2", "energy3")] == [
        150_000, 50_000, 100_000]


def test_the_recipe_is_the_capped_stage1_candidate_as_it_was_tried_and_energy3_once_more():
    """configs/torque.yaml is notebook/configs/torque_capped_stage1.yaml promoted with nothing changed (the same
    phases from the same starts with the same settings, so the candidate's seeds are the recipe's up to energy3),
    and one phase more: energy4, energy3's settings from energy3's final agent."""
    recipe, candidate = _phases("torque.yaml"), _phases("notebook/configs/torque_capped_stage1.yaml")
    assert [(p.name, p.stage, p.start) for p in recipe.values()] == [
        (p.name, p.stage, p.start) for p in candidate.values()] + [("energy4", "2", "energy3/stage2_final.pt")]
    for name in candidate:
        assert C.changed_settings(recipe[name].config, candidate[name].config) == {}, name
    assert C.changed_settings(recipe["energy4"].config, recipe["energy3"].config) == {}
    assert recipe["energy4"].config.train.stage2.reward.energy == -1.2


def test_the_torque_speed_cap_results_were_made_by_its_phases_as_they_resolve_now():
    """notebook/results/torque_speed_cap/seed<N>/phases.yaml records the phases its two actors came from: the
    candidate's as it resolves today, but for the seed; the checks of those actors hold seeds 0-4's walks."""
    import json

    recipe = C.load_preset(ROOT / "notebook" / "configs" / "torque_speed_cap.yaml").phases
    folders = sorted((ROOT / "notebook" / "results" / "torque_speed_cap").glob("seed*"))
    assert [f.name for f in folders] == ["seed0", "seed1", "seed2", "seed3", "seed4"]
    for folder in folders:
        assert_made_by(folder / "phases.yaml", recipe)
        assert (folder / "stage1_actor.pt").is_file() and (folder / "stage2_actor.pt").is_file()
    labels = set()
    for name in ("policy_check.json", "policy_check_seeds3-4.json"):
        check = json.loads((ROOT / "notebook" / "results" / "torque_speed_cap" / name).read_text())
        labels |= {w["label"] for w in check["walks"]}
    assert labels == {f.name for f in folders}


def test_the_remade_torque_stage1_agents_continue_a_candidates_lineage_at_its_speed_phase(tmp_path):
    """notebook/results/torque_stage1_remade/seed<N> (notebook/2026-12-02_torque_stage2.md) holds the `main` phase's
    final agent (critics included) of notebook/configs/torque_stage1.yaml: phases as the recipe's now, an agent after
    300,000 env steps of stage 1, and a lineage of a candidate holding it as main/stage1_final.pt skips `main`."""
    import shutil

    import torch

    from cyberdog.lineage import run_lineage

    folders = sorted((ROOT / "notebook" / "results" / "torque_stage1_remade").glob("seed*"))
    assert [f.name for f in folders] == ["seed0", "seed1", "seed2"]
    recipe = _phases("notebook/configs/torque_previous.yaml")
    for folder in folders:
        phases, _ = C.read_phases(folder)
        assert [p.name for p in phases] == ["main", "speed"] and phases[0].config.train.seed == int(folder.name[4:])
        for p in phases:
            made = _with_seed(p.config, 0)
            assert C.changed_settings(made, _with_seed(recipe[p.name].config, 0)) == {}, p.name
        agent = torch.load(folder / "main_stage1_final.pt", weights_only=True)
        assert agent["kind"] == "stage_final" and agent["stage"] == 1 and agent["env_steps"] == 300_000
        seed = tmp_path / folder.name
        C.write_phases(seed, C.load_preset(NOTEBOOK / "torque_bonus.yaml"), int(folder.name[4:]))
        (seed / "main").mkdir()
        shutil.copy(folder / "main_stage1_final.pt", seed / "main" / "stage1_final.pt")
        started = []
        run_lineage(seed, lambda cfg, label, **kw: started.append(label) or 1, say=lambda _: None)
        assert started and "phase speed" in started[0]  # main is done: the lineage goes on at speed


def _with_seed(cfg: C.ExperimentConfig, seed: int) -> C.ExperimentConfig:
    """`cfg` with train.seed = `seed` (to compare two seeds' settings)."""
    return dataclasses.replace(cfg, train=dataclasses.replace(cfg.train, seed=seed))


def test_the_capped_stage1_candidate_caps_only_the_recipes_two_stage1_phases_without_the_prior():
    """notebook/configs/torque_capped_stage1.yaml: torque_speed_cap.yaml with RewardConfig.speed_cap in `speed` and
    `band` (the stage-1 phases without the prior), each low enough that a walk at the cap still nets the bonus:
    D/400 > |A|·r_v(cap) at the fastest command (in m/s for `speed`, relative for `band`)."""
    recipe = _phases("notebook/configs/torque_speed_cap.yaml")
    mine = _phases("notebook/configs/torque_capped_stage1.yaml")
    assert [(p.name, p.stage, p.start) for p in mine.values()] == [(p.name, p.stage, p.start) for p in recipe.values()]
    for name in recipe:
        changed = set(C.changed_settings(mine[name].config, recipe[name].config))
        assert changed == ({"train.stage1.reward.speed_cap"} if name in ("speed", "band") else set()), name
    fastest = max(recipe["main"].config.env.target_speed_range)
    for name in ("speed", "band"):
        r = mine[name].config.train.stage1.reward
        worst = abs(r.speed) * (r.speed_cap * (1.0 if r.speed_relative else fastest)) ** 2
        assert 0 < r.speed_cap and worst < r.keep_moving / 400, name


def test_the_capped_stage1_results_were_made_by_its_phases_and_their_checks_hold_every_seed():
    """notebook/results/torque_capped_stage1/seed<N>/recipe_phases.yaml records the phases its two actors came from:
    the candidate's as it resolves today, but for the seed; each seed has a check of its actors."""
    import json

    recipe = C.load_preset(NOTEBOOK / "torque_capped_stage1.yaml").phases
    kept = ROOT / "notebook" / "results" / "torque_capped_stage1"
    folders = sorted(kept.glob("seed*"))
    assert folders
    for folder in folders:
        assert_made_by(folder / "recipe_phases.yaml", recipe)
        assert (folder / "stage1_actor.pt").is_file() and (folder / "stage2_actor.pt").is_file()
    labels = {w["label"] for f in kept.glob("policy_check*.json") for w in json.loads(f.read_text())["walks"]}
    assert {f.name for f in folders} <= labels
