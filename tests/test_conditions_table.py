"""A searched-start recipe's paths with a payload and on other floors: `tools/merge_walks.py conditions` labels each
run by the one setting it changed, the table's rows are each condition's own walks summarised (fresh seeds only),
and the shipped walks hold what the README says of them."""
from __future__ import annotations

import dataclasses
import importlib.util
import json
from pathlib import Path

import pytest
import yaml

from cyberdog import config as C
from cyberdog.analysis import conditions_table as ct
from cyberdog.analysis import prototype_summary as ps
from cyberdog.analysis import searched_start_table as sst
from cyberdog.analysis.markdown_cells import mean_ci
from cyberdog.config.walked import WalkedRobot

ROOT = Path(__file__).resolve().parents[1]
FIGURES = ROOT / "results" / "figures_input"
spec = importlib.util.spec_from_file_location("merge_walks", ROOT / "tools/merge_walks.py")
merge = importlib.util.module_from_spec(spec)
spec.loader.exec_module(merge)


def _walks() -> list[dict]:
    """The shipped battery prototype walks (seeds 0-4); seed 0 stands for a tuning seed."""
    return json.loads((FIGURES / "prototype.json").read_text())


def _rows(table: str) -> dict[str, list[str]]:
    return {cells[0]: cells[1:] for cells in ([c.strip() for c in ln.strip("|").split("|")]
                                                for ln in table.splitlines()[2:])}


def _at(walks: list[dict], setting: str, value: float, scale: float = 1.0) -> list[dict]:
    """`walks` as a conditions run of `setting` = `value`, the learned paths' battery scaled by `scale`."""
    return [{**w, "condition": setting, "condition_value": value,
             **({"battery_used_pct": w["battery_used_pct"] * scale} if w["trajectory"] == "learned" else {})}
            for w in walks]


def _saving(walks: list[dict], key: str = "battery_saving_pct", trajectory: str = "learned") -> list[str]:
    by = {r["speed_mps"]: r for r in ps.summary_rows(walks)
          if r["robot"] == "hardware" and r["trajectory"] == trajectory}
    return [mean_ci(by[v], key, ".1f", " %", sign=key != "battery_saving_pct") for v in sorted(by)]


def test_each_conditions_rows_are_its_own_walks_summarised():
    walks = _walks()
    speeds = sorted({w["speed_mps"] for w in walks})
    heavy, slippery = _at(walks, "robot.payload", 3.0, scale=1.1), _at(walks, "sim.ground_friction", 0.4)
    rows = dict(ct.conditions_rows(slippery + heavy, speeds))
    assert list(rows)[0] == "the saving with a 3 kg payload"  # CONDITIONS' order, whatever the walks' order
    assert rows["the saving with floor friction 0.4"] == _saving(walks)
    assert rows["the saving with a 3 kg payload"] == _saving(heavy) != _saving(walks)
    assert rows[f"a 3 kg payload: {ct.INSET_SHAPE}'s saving"] == _saving(walks, trajectory=ps.REFERENCE)
    assert rows[f"a 3 kg payload: learned against {ct.INSET_SHAPE}"] == _saving(heavy, "battery_vs_searched_pct")
    with pytest.raises(ValueError, match="not a condition"):
        ct.condition_label("pid.kp", 2.0)


def test_the_recipes_table_holds_the_fresh_seeds_conditions_rows_alone():
    walks = _walks()
    fresh = [w for w in walks if w["seed"] != "seed0"]
    tuned = _at([w for w in walks if w["seed"] == "seed0"], "robot.payload", 3.0, scale=0.5)
    table = _rows(sst.searched_start_markdown(walks, conditions_walks=_at(fresh, "robot.payload", 3.0) + tuned))
    assert table["the saving with a 3 kg payload, seeds 1–4"] == _saving(fresh)
    assert not any("seed0" in k or "seeds 0–4" in k for k in table)
    assert "the saving with a 3 kg payload, seeds 1–4" not in _rows(sst.searched_start_markdown(walks))
    fewer = _at([w for w in fresh if w["seed"] != "seed4"], "sim.ground_friction", 0.4)  # a run over fewer seeds
    table = _rows(sst.searched_start_markdown(walks, conditions_walks=_at(fresh, "robot.payload", 3.0) + fewer))
    named = {"the saving with a 3 kg payload, seeds 1–4", "the saving with floor friction 0.4, seeds 1–3"}
    assert named <= set(table)


def _run(folder: Path, config: dict) -> Path:
    folder.mkdir()
    (folder / "config.yaml").write_text(json.dumps(config))  # (YAML reads JSON)
    (folder / "prototype.json").write_text(json.dumps([{"trajectory": "learned", "seed": "seed20"}]))
    return folder


def _walked(folder: Path, *settings: str) -> Path:
    """A run folder whose config.yaml is written as `evaluate.py prototype` writes it (every section, the gains per
    joint, a hardware model), with `settings` (`section.field=value`) changed."""
    walk = C.WalkConfig()
    for setting in settings:
        key, value = setting.split("=")
        section, field = key.split(".")
        value = yaml.safe_load(value)
        value = tuple(value) if isinstance(value, list) else float(value)
        walk = dataclasses.replace(walk, **{section: dataclasses.replace(getattr(walk, section), **{field: value})})
    C.save_walked(WalkedRobot(walk, C.HardwareConfig()), folder / "config.yaml")
    (folder / "prototype.json").write_text(json.dumps([{"trajectory": "learned", "seed": "seed20"}]))
    return folder


def test_runs_written_as_evaluate_writes_them_merge_and_must_agree_beyond_their_condition(tmp_path):
    heavy = _walked(tmp_path / "heavy", "robot.payload=3.0")
    slippery = _walked(tmp_path / "slippery", "sim.ground_friction=0.4")
    assert [(w["condition"], w["condition_value"]) for w in merge.conditions_walks([heavy, slippery])] == [
        ("robot.payload", 3.0), ("sim.ground_friction", 0.4)]
    mujoco = _walked(tmp_path / "mujoco", "sim.ground_friction=1.2")
    config = yaml.safe_load((mujoco / "config.yaml").read_text())
    config["sim"]["engine"] = "mujoco"
    (mujoco / "config.yaml").write_text(yaml.safe_dump(config))
    with pytest.raises(ValueError, match="differ beyond their conditions"):
        merge.conditions_walks([heavy, mujoco])
    with pytest.raises(ValueError, match="gains"):
        merge.conditions_walks([_walked(tmp_path / "kd2", "robot.payload=3.0", "pid.kd=[4.0,4.0,4.0]")])


def test_the_merge_labels_each_run_by_the_one_setting_it_changed(tmp_path, capsys):
    heavy = _run(tmp_path / "heavy", {"robot": {"payload": 3.0}, "sim": {"ground_friction": 0.8}})
    slippery = _run(tmp_path / "slippery", {"sim": {"ground_friction": 0.4}})
    walks = merge.conditions_walks([heavy, slippery])
    assert [(w["condition"], w["condition_value"]) for w in walks] == [("robot.payload", 3.0),
                                                                        ("sim.ground_friction", 0.4)]
    for name, config, words in (("none", {}, "changes none"),
                                ("both", {"robot": {"payload": 3.0}, "sim": {"ground_friction": 0.4}}, "changes robot"),
                                ("gains", {"robot": {"payload": 3.0}, "pid": {"kd": [4.0, 4.0, 4.0]}}, "gains")):
        with pytest.raises(ValueError, match=words):
            merge.conditions_walks([_run(tmp_path / name, config)])
    with pytest.raises(ValueError, match="also"):
        merge.conditions_walks([heavy, _run(tmp_path / "heavy_again", {"robot": {"payload": 3.0}})])
    out = tmp_path / "conditions.json"
    assert merge.main(["conditions", str(heavy), str(slippery), "--out", str(out)]) == 0
    assert json.loads(out.read_text()) == walks
    assert merge.main(["conditions", str(heavy), "--out", str(out)]) == 2  # never over an earlier file
    assert "exists" in capsys.readouterr().err


def test_the_shipped_conditions_keep_the_saving_within_a_point_with_no_fall():
    """README: with a 3 kg payload or on floors of friction 0.4 and 1.2 the picked paths' saving moves by under a
    point from the default's (the same paths on the same run without the setting), and none falls."""
    recipe = sst.SEARCHED_PICK
    conditions = json.loads((FIGURES / recipe.conditions_source).read_text())
    default = json.loads((FIGURES / recipe.inset_source).read_text())
    runs = {(w["condition"], w["condition_value"]) for w in conditions}
    assert runs == {("robot.payload", 3.0), ("sim.ground_friction", 0.4), ("sim.ground_friction", 1.2)}

    def saving(walks: list[dict]) -> dict[float, float]:
        return {r["speed_mps"]: r["battery_saving_pct_mean"] for r in ps.summary_rows(walks)
                if r["trajectory"] == "learned"}

    base = saving(default)
    for run in runs:
        at = [w for w in conditions if (w["condition"], w["condition_value"]) == run]
        assert {w["seed"] for w in at} == {w["seed"] for w in default}  # the same ten seeds
        assert not any(w["fell"] for w in at)
        assert saving(at).keys() == base.keys()
        assert all(abs(s - base[v]) < 1.0 for v, s in saving(at).items()), run
