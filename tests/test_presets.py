"""Presets as recipes: a delta over its base resolves to the settings its shipped actors trained with, its phases run
as one lineage per seed that resumes mid-phase, and a broken preset is one line."""
from __future__ import annotations

import argparse
import json
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

from cyberdog import config as C
from conftest import assert_made_by

ROOT = Path(__file__).resolve().parents[1]


def _phases(name: str) -> dict[str, C.Phase]:
    """The phases of configs/<name>."""
    return {p.name: p for p in C.load_preset(ROOT / "configs" / name).phases}


def test_a_shipped_phase_resolves_to_the_settings_its_shipped_actors_trained_with():
    """results/<recipe>/policy/seed<N>/config.yaml records the settings its actors trained with: the battery
    recipe's `band` phase is them but for the seed (seeds 0-4 and 5-9 alike; the searched start's 20-29 and the
    lineages of its two-lineage pick, its wide-command variant's 30-34); Table 5's phase is seed 0's but for the
    seed's own field."""
    for recipe, preset, at_least in (("battery", "battery", 5), ("battery_searched", "battery_searched", 5),
                                     ("battery_searched_wide", "battery_searched_wide", 5),
                                     ("battery_searched_pick", "battery_searched", 10)):
        band = _phases(f"{preset}.yaml")["band"]
        shipped = sorted((ROOT / "results" / recipe / "policy").glob("seed*"))
        assert len(shipped) >= at_least, recipe
        for folder in shipped:
            made = C.load(C.ExperimentConfig, folder / "config.yaml")
            assert set(C.changed_settings(band.config, made)) <= {"train.seed"}, folder.name
            assert made.train.seed == int(folder.name.removeprefix("seed"))
    table5 = _phases("table5.yaml")["train"]
    made = C.load(C.ExperimentConfig, ROOT / "results" / "table5" / "policy" / "seed0" / "config.yaml")
    assert table5.stage == "both"
    assert set(C.changed_settings(table5.config, made)) <= {"train.seed"} and made.train.seed == 0


def test_the_torque_recipes_shipped_actors_were_made_by_its_phases_as_they_resolve_now():
    """results/torque/policy/seed<N>/recipe_phases.yaml records the settings of every phase its two actors came from
    (tools/ship.py policy --all-phases): they are configs/torque.yaml's phases as it resolves today, but for the
    seed, and every phase ran in the seed's own lineage (none placed from another run: the one command, from
    scratch). The same for the seeds it was never tuned on (results/torque/fresh/), where shipped."""
    recipe = C.load_preset(ROOT / "configs" / "torque.yaml").phases
    torque = ROOT / "results" / "torque"
    shipped = sorted((torque / "policy").glob("seed*")) + sorted((torque / "fresh" / "policy").glob("seed*"))
    assert len(shipped) >= 5
    for folder in shipped:
        assert_made_by(folder / "recipe_phases.yaml", recipe)
        meta = json.loads((folder / "metadata.json").read_text())
        assert meta["placed_phases"] == [], folder


def test_every_phase_of_every_shipped_preset_is_checked_and_the_lineages_start_where_they_did():
    assert set(p.name for p in (ROOT / "configs").glob("*.yaml")) == {"table5.yaml", "battery.yaml", "torque.yaml",
                                                                       "battery_searched.yaml", "paper.yaml",
                                                                       "battery_searched_wide.yaml", "tiny.yaml"}
    for battery in ("battery.yaml", "battery_searched.yaml", "battery_searched_wide.yaml"):
        assert [(p.name, p.start) for p in _phases(battery).values()] == [
            ("stage1", None), ("stage2", "stage1/stage1_final.pt"), ("band", "stage2/stage2_final.pt")]
    assert [(p.name, p.start) for p in _phases("torque.yaml").values()] == [
        ("main", None), ("speed", "main/stage1_final.pt"), ("band", "speed/stage1_final.pt"),
        ("energy", "band/stage1_final.pt"), ("energy2", "energy/stage2_final.pt"),
        ("energy3", "energy2/stage2_final.pt"), ("energy4", "energy3/stage2_final.pt")]
    assert C.load_preset(ROOT / "configs/battery.yaml").extract == {"replay_attempts": 16, "candidates": 2}
    assert not C.load_preset(ROOT / "configs/tiny.yaml").phased  # a plain two-stage run, as before phases


def test_the_wide_command_recipe_is_the_searched_recipe_but_for_the_commanded_speeds():
    """configs/battery_searched_wide changes one thing in every phase of the searched recipe: the command is drawn
    over 0.9-1.5 m/s, so that the speeds the paths are taken at lie inside the range; its extraction is the searched
    recipe's, and it is a valid config."""
    narrow, wide = _phases("battery_searched.yaml"), _phases("battery_searched_wide.yaml")
    assert list(narrow) == list(wide)
    for name in narrow:
        assert C.changed_settings(narrow[name].config, wide[name].config) == {
            "env.target_speed_range": ([1.0, 1.4], [0.9, 1.5])}, name
    assert C.load_preset(ROOT / "configs/battery_searched_wide.yaml").extract == C.load_preset(
        ROOT / "configs/battery_searched.yaml").extract
    for phase in wide.values():
        C.check_planned_updates(phase.config, (int(phase.stage),))


def _write(path: Path, data: dict) -> Path:
    path.write_text(yaml.safe_dump(data))
    return path


@pytest.mark.parametrize("change, words", [
    (dict(base="b.yaml"), ["base loop", "a.yaml -> b.yaml -> a.yaml"]),
    (dict(phases=[{"name": "Stage One", "stage": 1}]), ["phase 'Stage One'", "lower-case"]),
    (dict(phases=[{"name": "one", "stage": 3}]), ["phase 'one'", "stage must be 1, 2 or both"]),
    (dict(phases=[{"name": "one", "stage": 2}]), ["phase 'one'", "stage 2 alone"]),
    (dict(phases=[{"name": "one", "stage": 1}, {"name": "one", "stage": 2}]), ["a phase before it"]),
    (dict(phases=[{"name": "one", "stage": 1}, {"name": "two", "stage": 2, "from": "three/x.pt"}]), ["a phase before it"]),
    (dict(phases=[{"name": "one", "stage": 1, "set": {"train": {"batch_size": "x"}}}]), ["phase 'one'", "batch_size"]),
    (dict(extract={"replay_attempt": 3}), ["extract.replay_attempt", "replay_attempts"]),
    (dict(stages=[]), ["unknown key", "stages"]),
])
def test_a_broken_preset_is_one_line_naming_the_file(tmp_path, change, words):
    _write(tmp_path / "b.yaml", {"base": "a.yaml"})
    path = _write(tmp_path / "a.yaml", {"base": str(ROOT / "configs/tiny.yaml"), **change})
    with pytest.raises(ValueError) as err:
        C.load_preset(path)
    message = str(err.value)
    assert "\n" not in message and "a.yaml" in message
    for w in words:
        assert w in message
    out = subprocess.run([sys.executable, str(ROOT / "train.py"), "--config", str(path), "--run-dir",
                          str(tmp_path / "run")], capture_output=True, text=True, cwd=ROOT)
    assert out.returncode != 0 and len(out.stderr.strip().splitlines()) == 1 and words[0] in out.stderr
    assert not (tmp_path / "run").exists()


def _tiny_lineage(tmp_path: Path, third_budget: int) -> Path:
    return _write(tmp_path / f"lineage{third_budget}.yaml", {
        "base": str(ROOT / "configs/tiny.yaml"), "summary": "three tiny phases",
        "phases": [{"name": "first", "stage": 1}, {"name": "second", "stage": 2},
                   {"name": "third", "stage": 2, "set": {"train": {"stage2": {"max_env_steps": third_budget,
                                                                               "reward": {"energy": -0.1}}}}}],
        "extract": {"replay_attempts": 2}})


def _train(*args) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, str(ROOT / "train.py"), "--no-progress", *map(str, args)],
                          capture_output=True, text=True, cwd=ROOT)


def _episodes(run: Path) -> list[str]:
    return (run / "metrics.csv").read_text().splitlines()


def test_a_lineage_runs_its_phases_in_order_and_resumed_mid_phase_continues_that_phase(tmp_path):
    folder = tmp_path / "seed3"
    first = _train("--config", _tiny_lineage(tmp_path, 100), "--seed", 3, "--run-dir", folder)
    assert first.returncode == 0, first.stderr
    phases, extract = C.read_phases(folder)
    assert [p.name for p in phases] == ["first", "second", "third"] and extract == {"replay_attempts": 2}
    assert all(p.config.train.seed == 3 for p in phases)
    assert (folder / "second" / "config.yaml").is_file() and C.final_run(folder) == folder / "third"
    assert C.load(C.ExperimentConfig, folder / "third/config.yaml").train.stage2.reward.energy == -0.1
    # the state a kill leaves mid-phase: third has its checkpoint (100 of its 200 env steps) and no final agent
    C.write_phases(folder, C.load_preset(_tiny_lineage(tmp_path, 200)), 3)
    for f in (folder / "third").glob("stage2_final*"):
        f.unlink()
    before = {name: _episodes(folder / name) for name in ("first", "second", "third")}
    again = _train("--resume", folder)
    assert again.returncode == 0, again.stderr
    assert "phase first (1/3, stage 1): done" in again.stdout and "phase second (2/3, stage 2): done" in again.stdout
    assert "phase third (3/3, stage 2): resuming" in again.stdout
    for name in ("first", "second"):  # finished phases are not trained again
        assert _episodes(folder / name) == before[name]
    after = _episodes(folder / "third")
    assert after[:len(before["third"])] == before["third"] and len(after) > len(before["third"])
    assert (folder / "third" / "stage2_final_actor.pt").is_file()


def test_a_failed_phase_names_the_seed_and_the_phase(tmp_path):
    folder = tmp_path / "lineage"
    C.write_phases(folder, C.load_preset(_tiny_lineage(tmp_path, 100)), 7)
    (folder / "first").mkdir()
    (folder / "first" / "stage1_final.pt").write_bytes(b"not a checkpoint")  # first looks done, its agent is not
    out = _train("--resume", folder)
    assert out.returncode != 0 and "first (1/3, stage 1): done" in out.stdout
    assert out.stderr.strip().splitlines()[-1].startswith("error: seed 7, phase second (2/3, stage 2):")


def test_extraction_takes_the_recipe_settings_unless_given(tmp_path):
    from cyberdog.evaluation import extraction as L
    from cyberdog.evaluation.cli import EXTRACT_DEFAULTS

    sweep = tmp_path / "sweep"
    C.write_phases(sweep / "seed5", C.load_preset(ROOT / "configs/battery.yaml"), 5)
    args = argparse.Namespace(sweep=sweep, **EXTRACT_DEFAULTS)
    assert L.take_recipe_extraction(args) == {"replay_attempts": 16, "candidates": 2}
    assert (args.replay_attempts, args.candidates, args.cycle) == (16, 2, "mean")
    given = argparse.Namespace(sweep=sweep, **{**EXTRACT_DEFAULTS, "candidates": 4})
    L.take_recipe_extraction(given)
    assert (given.replay_attempts, given.candidates) == (16, 4)
    assert C.final_run(sweep / "seed5") == sweep / "seed5" / "band"


def test_table5s_recipe_keeps_each_policys_first_path_unless_the_check_is_asked_for(tmp_path):
    """configs/table5.yaml's extraction is unchecked (Table 5 walks the ideal robot); the battery recipe, whose
    base it is, keeps its own checked extraction; --no-replay-check on a checked recipe's sweep stays given."""
    from cyberdog.evaluation import extraction as L
    from cyberdog.evaluation.cli import EXTRACT_DEFAULTS

    sweep = tmp_path / "table5"
    C.write_phases(sweep / "seed5", C.load_preset(ROOT / "configs/table5.yaml"), 5)
    args = argparse.Namespace(sweep=sweep, **EXTRACT_DEFAULTS)
    assert L.take_recipe_extraction(args) == {"replay_check": False} and args.replay_check is False
    battery = tmp_path / "battery"
    C.write_phases(battery / "seed5", C.load_preset(ROOT / "configs/battery.yaml"), 5)
    args = argparse.Namespace(sweep=battery, **{**EXTRACT_DEFAULTS, "replay_check": False})
    L.take_recipe_extraction(args)
    assert args.replay_check is False and args.replay_attempts == 16
    args = argparse.Namespace(sweep=battery, **EXTRACT_DEFAULTS)
    L.take_recipe_extraction(args)
    assert args.replay_check is True


def test_a_sweep_of_plain_run_folders_takes_the_extraction_of_the_preset_it_was_trained_from(tmp_path):
    """`train.py --config configs/table5.yaml --seeds ...` (one phase) writes plain run folders, not lineages:
    the sweep's record names the preset, whose extraction is taken; a sweep of no preset takes none."""
    import json

    from cyberdog.evaluation import extraction as L
    from cyberdog.evaluation.cli import EXTRACT_DEFAULTS

    sweep = tmp_path / "table5"
    (sweep / "seed0").mkdir(parents=True)
    (sweep / "sweep.json").write_text(json.dumps({"format": "cyberdog-sweep", "seeds": [0],
                                                   "source_config": str(ROOT / "configs/table5.yaml")}))
    args = argparse.Namespace(sweep=sweep, **EXTRACT_DEFAULTS)
    assert L.take_recipe_extraction(args) == {"replay_check": False} and args.replay_check is False
    (sweep / "sweep.json").write_text(json.dumps({"format": "cyberdog-sweep", "seeds": [0], "source_config": None}))
    args = argparse.Namespace(sweep=sweep, **EXTRACT_DEFAULTS)
    assert L.take_recipe_extraction(args) == {} and args.replay_check is True


def test_an_earlier_files_stage_and_agent_read_as_today():
    """Run folders and actor files written before a stage's reward was a RewardConfig (and while the agent had
    fast_update) read as the same settings, so that they resume and load."""
    old = {"agent": {"fast_update": True, "actor_lr": 1e-4},
           "train": {"stage2": {"reward": "stage2", "energy_weight": -0.05, "keep_moving_weight": 300.0,
                                "energy_model": "electrical", "speed_deadband": 0.015}}}
    cfg = C.from_dict(C.ExperimentConfig, old)
    assert cfg.agent.actor_lr == 1e-4
    assert cfg.train.stage2.reward == C.replace(C.STAGE2_REWARD, energy=-0.05, keep_moving=300.0,
                                                energy_model="electrical", speed_deadband=0.015)
    assert cfg.train.stage1.reward == C.STAGE1_REWARD
    with pytest.raises(ValueError, match="no field 'energy_weight'"):  # today's --set uses the reward's names
        C.override(cfg, ["train.stage2.energy_weight=-0.1"])


def test_a_recipe_sweep_runs_every_phase_of_every_seed_and_extraction_finds_the_last(tmp_path):
    """`train.py --config <recipe> --seeds 0-1`: one lineage per seed (one process each, the sweep's retries and
    status), aggregated on the last phase; `evaluate.py extract --sweep` takes each seed's last phase's actor."""
    from cyberdog.evaluation.learned import policy_paths

    preset = _write(tmp_path / "two.yaml", {"base": str(ROOT / "configs/tiny.yaml"), "summary": "two phases",
                                           "phases": [{"name": "first", "stage": 1}, {"name": "second", "stage": 2}]})
    sweep = tmp_path / "sweep"
    out = _train("--config", preset, "--seeds", "0-1", "--run-dir", sweep, "--eval-duration", 0)
    assert out.returncode == 0, out.stderr
    for seed in (0, 1):
        phases, _ = C.read_phases(sweep / f"seed{seed}")
        assert [p.config.train.seed for p in phases] == [seed, seed]
        assert (sweep / f"seed{seed}" / "second" / "stage2_final_actor.pt").is_file()
    assert policy_paths(None, sweep) == [sweep / f"seed{s}" / "second" / "stage2_final_actor.pt" for s in (0, 1)]
    assert "| 1 | 200 |" in (sweep / "aggregate.md").read_text()  # the last phase's stage-2 steps per seed
    assert "seed 0 attempt 1 started\n" in out.stdout  # a lineage's first start resumes nothing, and says so


def test_a_recipe_extraction_setting_is_checked_as_the_command_line_checks_it(tmp_path):
    from cyberdog.analysis.extract import CYCLE_CHOICES
    from cyberdog.config.preset import EXTRACT_CYCLES

    assert EXTRACT_CYCLES == CYCLE_CHOICES
    for bad, words in (({"cycle": "best"}, "one of"), ({"replay_attempts": True}, "positive integer"),
                       ({"rollout_duration": 0}, "positive number"), ({"replay_check": "no"}, "true or false")):
        path = _write(tmp_path / "x.yaml", {"base": str(ROOT / "configs/tiny.yaml"), "extract": bad})
        with pytest.raises(ValueError, match=words):
            C.load_preset(path)
