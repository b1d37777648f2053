"""A preset's phases are deltas: each phase's `set:` changes the phase before it (the first phase's, the preset's
own settings), and no shipped preset restates a setting already in force."""
from __future__ import annotations

import dataclasses
from pathlib import Path

import pytest
import yaml

from cyberdog import config as C

ROOT = Path(__file__).resolve().parents[1]
CONFIGS = ROOT / "configs"

# configs/torque.yaml's phases: (name, stage, the settings that change from the phase before it)
STAGE1_SPEED_TERM_OFF = {"train.stage1.reward.speed_relative": False, "train.stage1.reward.speed_window": 0.0,
                         "train.stage1.reward.speed_deadband": 0.0, "train.stage1.reward.speed_cap": 0.0}
TORQUE_PHASES = [
    ("main", "1", {}),
    ("speed", "1", {"env.prior_weight": 0.0, "train.stage1.reward.speed": -100.0,
                    "train.stage1.reward.speed_cap": 0.15, "train.stage1.max_env_steps": 100000,
                    "train.stage1.critic_warmup_updates": 2000}),
    ("band", "1", {"train.stage1.reward.speed": -432.0, "train.stage1.reward.speed_relative": True,
                   "train.stage1.reward.speed_window": 0.4, "train.stage1.reward.speed_deadband": 0.02,
                   "train.stage1.reward.speed_cap": 0.12, "train.stage1.max_env_steps": 50000,
                   "train.stage1.critic_warmup_updates": 5000}),
    ("energy", "2", {**STAGE1_SPEED_TERM_OFF, "train.stage1.reward.speed": -20.0,
                     "train.stage1.max_env_steps": 300000, "train.stage1.critic_warmup_updates": 20000,
                     "train.stage2.reward.speed": -600.0, "train.stage2.reward.speed_relative": True,
                     "train.stage2.reward.speed_window": 0.4, "train.stage2.reward.speed_cap": 0.15,
                     "train.stage2.reward.keep_moving": 8000.0, "train.stage2.actor_lr": 3e-5,
                     "train.stage2.critic_warmup_updates": 5000, "train.stage2.critic_warmup_targets": True}),
    ("energy2", "2", {"train.stage2.reward.energy": -0.6, "train.stage2.reward.keep_moving": 9500.0,
                      "train.stage2.max_env_steps": 50000, "train.stage2.critic_warmup_updates": 2000,
                      "train.stage2.critic_warmup_targets": False}),
    ("energy3", "2", {"train.stage2.reward.energy": -1.2, "train.stage2.reward.keep_moving": 12000.0,
                      "train.stage2.max_env_steps": 100000}),
    ("energy4", "2", {}),
]


def _with(cfg, changes: dict):
    """`cfg` with the dotted fields of `changes` replaced (nested dataclasses.replace)."""
    for dotted, value in changes.items():
        cfg = _replace_path(cfg, dotted.split("."), value)
    return cfg


def _replace_path(node, path: list[str], value):
    if len(path) == 1:
        assert hasattr(node, path[0]), path
        return dataclasses.replace(node, **{path[0]: value})
    return dataclasses.replace(node, **{path[0]: _replace_path(getattr(node, path[0]), path[1:], value)})


def test_the_torque_recipe_resolves_phase_by_phase_to_the_previous_phase_with_its_few_changes():
    preset = C.load_preset(CONFIGS / "torque.yaml")
    assert [(p.name, p.stage) for p in preset.phases] == [(n, s) for n, s, _ in TORQUE_PHASES]
    previous = preset.config  # the first phase trains with the preset's own settings
    for phase, (name, _, changes) in zip(preset.phases, TORQUE_PHASES):
        assert phase.config == _with(previous, changes), name
        previous = phase.config


def _leaves(mapping: dict, prefix: str = "") -> dict:
    out = {}
    for key, value in mapping.items():
        out.update(_leaves(value, f"{prefix}{key}.") if isinstance(value, dict) else {f"{prefix}{key}": value})
    return out


def _in_force(config: C.ExperimentConfig) -> dict:
    return _leaves(C.to_dict(config))


def _repeats(path: Path) -> list[str]:
    """'<file> phase <name>: <setting> = <value>' for every setting a phase's `set:` gives the value it has in the
    settings that set changes."""
    data = yaml.safe_load(path.read_text()) or {}
    spec = data.get("phases") or []
    preset = C.load_preset(path)
    found = []
    in_force = preset.config
    for item, phase in zip(spec, preset.phases):
        before = C.load_preset(path.parent / item["preset"]).config if item.get("preset") else in_force
        now = _in_force(before)
        found += [f"{path.name} phase {phase.name}: {k} = {v!r}" for k, v in _leaves(item.get("set") or {}).items()
                  if k in now and now[k] == v]
        if not item.get("preset"):
            in_force = phase.config
    return found


@pytest.mark.parametrize("path", sorted(CONFIGS.glob("*.yaml")), ids=lambda p: p.name)
def test_no_phase_of_a_shipped_preset_sets_what_is_already_in_force(path):
    assert _repeats(path) == []


def _write(path: Path, data: dict) -> Path:
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    return path


def test_each_phase_changes_the_one_before_it_and_a_borrowed_preset_phase_changes_nothing_after_it(tmp_path):
    _write(tmp_path / "other.yaml", {"summary": "x", "train": {"batch_size": 16}})
    path = _write(tmp_path / "p.yaml", {"summary": "phases", "train": {"batch_size": 64}, "phases": [
        {"name": "one", "stage": 1, "set": {"train": {"score_window": 7}}},
        {"name": "side", "stage": 2, "preset": "other.yaml", "set": {"train": {"buffer_size": 5000}}},
        {"name": "two", "stage": 2, "set": {"train": {"stage2": {"max_env_steps": 123}}}},
        {"name": "three", "stage": 2}]})
    phases = {p.name: p.config.train for p in C.load_preset(path).phases}
    assert (phases["one"].batch_size, phases["one"].score_window) == (64, 7)
    default = C.ExperimentConfig().train
    assert (phases["side"].batch_size, phases["side"].score_window, phases["side"].buffer_size) == (
        16, default.score_window, 5000)
    assert (phases["two"].batch_size, phases["two"].score_window, phases["two"].buffer_size) == (
        64, 7, default.buffer_size)
    assert phases["two"].stage2.max_env_steps == 123
    assert phases["three"] == phases["two"]


def test_a_repeated_setting_is_found(tmp_path):
    path = _write(tmp_path / "p.yaml", {"summary": "x", "train": {"batch_size": 64}, "phases": [
        {"name": "one", "stage": 1, "set": {"train": {"batch_size": 64, "score_window": 7}}},
        {"name": "two", "stage": 2, "set": {"train": {"score_window": 7}}}]})
    assert _repeats(path) == ["p.yaml phase one: train.batch_size = 64", "p.yaml phase two: train.score_window = 7"]
