"""tools/merge_walks.py: stiffness runs over disjoint seeds give the table one run over all of them gives; gains runs
are labelled each by the one gain it changed."""
from __future__ import annotations

import importlib.util
import json
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
WALKS = json.loads((ROOT / "results/figures_input/stiffness_walks.json").read_text())  # a shipped run, 5 seeds
spec = importlib.util.spec_from_file_location("merge_walks", ROOT / "tools/merge_walks.py")
tool = importlib.util.module_from_spec(spec)
spec.loader.exec_module(tool)


def run_folder(path: Path, rows: list[dict]) -> Path:
    path.mkdir(parents=True)
    (path / "stiffness_walks.json").write_text(json.dumps(rows))
    return path


def test_runs_over_disjoint_seeds_merge_into_the_whole_runs_table(tmp_path):
    a = run_folder(tmp_path / "a", [r for r in WALKS if r["seed"] in ("seed0", "seed1")])
    b = run_folder(tmp_path / "b", [r for r in WALKS if r["seed"] not in ("seed0", "seed1")])
    whole = run_folder(tmp_path / "whole", WALKS)
    assert tool.main(["stiffness", str(a), str(b), "--out", str(tmp_path / "merged")]) == 0
    from cyberdog.analysis.stiffness import write_stiffness
    write_stiffness(WALKS, whole)
    merged = json.loads((tmp_path / "merged/stiffness.json").read_text())
    expected = json.loads((whole / "stiffness.json").read_text())
    assert merged == expected
    assert any(r["seeds"] == 5 for r in merged if r["trajectory"] == "learned")  # the seeds of both runs
    assert len(json.loads((tmp_path / "merged/stiffness_walks.json").read_text())) == len(WALKS)


def test_a_seed_walked_twice_counts_once_and_a_seed_walked_differently_is_refused(tmp_path, capsys):
    seed0 = [r for r in WALKS if r["seed"] == "seed0"]
    a = run_folder(tmp_path / "a", seed0)
    b = run_folder(tmp_path / "b", [dict(r, wall_s=r["wall_s"] + 1.0) for r in WALKS])  # the same physics, later
    assert tool.main(["stiffness", str(a), str(b), "--out", str(tmp_path / "m1")]) == 0
    assert len(json.loads((tmp_path / "m1/stiffness_walks.json").read_text())) == len(WALKS)
    changed = [dict(r, electrical_energy_J=r["electrical_energy_J"] * 0.9) for r in seed0]
    c = run_folder(tmp_path / "c", changed)
    assert tool.main(["stiffness", str(a), str(c), "--out", str(tmp_path / "m2")]) == 1
    assert "different results" in capsys.readouterr().err
    assert not (tmp_path / "m2").exists()


def test_runs_of_other_stiffnesses_an_existing_output_and_a_missing_run_are_refused(tmp_path, capsys):
    a = run_folder(tmp_path / "a", [r for r in WALKS if r["seed"] == "seed0"])
    b = run_folder(tmp_path / "b", [r for r in WALKS if r["seed"] == "seed1" and r["pd_scale"] != 1.4])
    assert tool.main(["stiffness", str(a), str(b), "--out", str(tmp_path / "m")]) == 1
    assert "different PD scales" in capsys.readouterr().err
    full = tmp_path / "full"
    full.mkdir()
    (full / "keep.txt").write_text("x")
    with pytest.raises(SystemExit):
        tool.main(["stiffness", str(a), str(a), "--out", str(full)])
    assert (full / "keep.txt").read_text() == "x"
    with pytest.raises(SystemExit):
        tool.main(["stiffness", str(a), str(tmp_path / "none"), "--out", str(tmp_path / "m3")])


def test_the_gains_walks_are_labelled_by_the_one_gain_each_run_changed(tmp_path, capsys):
    def run(name, pid, matched=False):
        folder = tmp_path / name
        folder.mkdir()
        (folder / "config.yaml").write_text(json.dumps({"pid": pid}))  # (YAML reads JSON)
        (folder / "prototype.json").write_text(json.dumps([{"trajectory": "learned", "pd_matched": matched},
                                                           {"trajectory": "cycloid", "pd_matched": matched}]))
        return folder

    kd2 = run("kd2", {"kd": [4.0, 4.0, 4.0]})
    kd2m = run("kd2m", {"kd": [4.0, 4.0, 4.0]}, matched=True)
    walks = tool.gains_walks([kd2, kd2m])
    assert {(w["gain"], w["gain_scale"], w["pd_matched"]) for w in walks} == {("kd", 2.0, False), ("kd", 2.0, True)}
    for bad, words in (({"kp": [120.0] * 3, "kd": [4.0] * 3}, "changes"), ({}, "neither"),
                       ({"kp": [120.0, 60.0, 60.0]}, "not one factor")):
        with pytest.raises(ValueError, match=words):
            tool.gains_walks([run(f"bad{len(list(tmp_path.iterdir()))}", bad)])
    with pytest.raises(ValueError, match="also"):
        tool.gains_walks([kd2, run("kd2again", {"kd": [4.0, 4.0, 4.0]})])
    out = tmp_path / "gains_walks.json"
    assert tool.main(["gains", str(kd2), str(kd2m), "--out", str(out)]) == 0
    assert json.loads(out.read_text()) == walks
    assert tool.main(["gains", str(kd2), "--out", str(out)]) == 2  # never over an earlier file without --force
    assert "exists" in capsys.readouterr().err and json.loads(out.read_text()) == walks
