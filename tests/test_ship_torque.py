"""tools/ship.py torque: the torque recipe's re-make runs its steps in order and ships only what they produced."""
from __future__ import annotations

import importlib.util
import json
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
spec = importlib.util.spec_from_file_location("ship", ROOT / "tools/ship.py")
ship = importlib.util.module_from_spec(spec)
spec.loader.exec_module(ship)


def after(cmd: list, flag: str) -> list[str]:
    """The arguments that follow `flag` up to the next option."""
    i = cmd.index(flag) + 1
    out = []
    while i < len(cmd) and not str(cmd[i]).startswith("--"):
        out.append(str(cmd[i]))
        i += 1
    return out


@pytest.fixture
def fake_steps(monkeypatch, tmp_path):
    """Each step records its command and writes the file the real one would, as far as the re-make reads it."""
    calls = []
    monkeypatch.chdir(tmp_path)  # the re-make moves to the repository: back here after each test

    def step(cmd, stop_on_failure=True):
        cmd = [str(c) for c in cmd]
        calls.append(cmd)
        if "evaluate.py" not in cmd:  # tools/ship.py policy: the seed's folder
            Path(after(cmd, "--out")[0]).mkdir(parents=True, exist_ok=True)
            return True
        out = Path(after(cmd, "--out")[0])
        if cmd[2] == "extract":  # seed 2's policy has no cycle in the band: no path, a failed step
            assert not stop_on_failure  # the other seeds' paths are still shipped
            (out / "learned").mkdir(parents=True, exist_ok=True)
            seeds = [p.name for p in Path(after(cmd, "--sweep")[0]).iterdir() if p.name != "seed2"]
            for seed in seeds:
                (out / "learned" / f"{seed}.json").write_text("{}")
                (out / "learned" / f"{seed}_cycles.csv").write_text("")
                (out / "learned" / f"{seed}_cycles.json").write_text("{}")  # every cycle: not a path
            return len(seeds) == len(list(Path(after(cmd, "--sweep")[0]).iterdir()))
        out.mkdir(parents=True, exist_ok=True)
        name = {"check": "policy_check.json", "compare": "comparison.json", "prototype": "prototype.json"}
        (out / name[cmd[2]]).write_text(json.dumps({"step": cmd[2]}))
        return True

    monkeypatch.setattr(ship, "run", step)
    return calls


def test_the_remake_ships_each_seed_and_only_the_paths_the_extraction_found(tmp_path, fake_steps):
    runs, results = tmp_path / "runs", tmp_path / "results"
    for name in ("seed10", "seed2", "seed0", "notes"):
        (runs / name).mkdir(parents=True)
    for name in ("metadata.json", "recipe_phases.yaml", "stage2_actor.pt"):  # seed 2 was shipped before: kept
        (runs / "seed2" / name).write_text("seed 2")
    old_paths = results / "torque" / "paths"
    old_paths.mkdir(parents=True)
    (old_paths / "seed2.json").write_text("{}")  # shipped before: must not outlive a re-make without it
    (results / "figures_input").mkdir()

    assert ship.main(["torque", str(runs), "--work", str(tmp_path / "work"), "--results", str(results)]) == 0

    steps = [" ".join(c[1:3]) if c[1].startswith("tools") else c[2] for c in fake_steps]
    assert steps == ["tools/ship.py policy"] * 2 + ["check", "extract", "compare", "prototype"]
    assert [Path(c[3]).name for c in fake_steps[:2]] == ["seed0", "seed10"]  # by seed, not by name
    assert (results / "torque" / "policy" / "seed2" / "stage2_actor.pt").read_text() == "seed 2"
    check = fake_steps[2]
    assert [Path(r).name for r in after(check, "--runs")] == ["seed0", "seed2", "seed10"]
    assert after(check, "--robots") == ["ideal", "hardware:0", "hardware:1"]
    assert sorted(p.name for p in old_paths.iterdir()) == ["seed0.json", "seed10.json"]
    prototype = fake_steps[-1]
    # every seed's policy walks the protocol closed loop, seed 2's too, whose path does not replay
    assert [Path(a).parent.name for a in after(prototype, "--closed-loop")] == ["seed0", "seed2", "seed10"]
    for name, step in [("torque_check.json", "check"), ("comparison_torque.json", "compare"),
                       ("prototype_torque.json", "prototype")]:
        assert json.loads((results / "figures_input" / name).read_text()) == {"step": step}


def test_seed_folders_from_several_inputs_replace_what_was_shipped(tmp_path, fake_steps):
    """A run folder and a kept seed folder given together ship exactly those seeds: a seed shipped before and not
    given is removed (the extraction reads every shipped seed), and a seed given twice is refused."""
    runs, kept, results = tmp_path / "runs", tmp_path / "kept" / "seed4", tmp_path / "results"
    (runs / "seed0").mkdir(parents=True)
    kept.mkdir(parents=True)
    for name in ("metadata.json", "recipe_phases.yaml", "stage2_actor.pt"):
        (kept / name).write_text("seed 4")
    stale = results / "torque" / "policy" / "seed7"
    stale.mkdir(parents=True)
    (results / "figures_input").mkdir()

    assert ship.main(["torque", str(runs), str(kept), "--work", str(tmp_path / "work"), "--results", str(results)]) == 0
    assert not stale.exists()
    assert Path(after(fake_steps[0], "--out")[0]).name == "seed0"  # re-made by tools/ship.py policy
    assert (results / "torque" / "policy" / "seed4" / "stage2_actor.pt").read_text() == "seed 4"
    assert [Path(r).name for r in after(fake_steps[1], "--runs")] == ["seed0", "seed4"]
    with pytest.raises(SystemExit, match="given twice: seed0"):
        ship.main(["torque", str(runs), str(runs / "seed0"), "--work", str(tmp_path / "w2"), "--results", str(results)])


def test_fresh_seeds_are_shipped_and_evaluated_apart_and_a_remake_without_them_removes_them(tmp_path, fake_steps):
    runs, fresh, results = tmp_path / "runs", tmp_path / "fresh", tmp_path / "results"
    for folder in (runs / "seed0", fresh / "seed6", fresh / "seed7"):
        folder.mkdir(parents=True)
    (results / "figures_input").mkdir(parents=True)
    argv = ["torque", str(runs), "--work", str(tmp_path / "work"), "--results", str(results)]

    assert ship.main(argv + ["--fresh", str(fresh)]) == 0
    steps = [" ".join(c[1:3]) if c[1].startswith("tools") else c[2] for c in fake_steps]
    assert steps == ["tools/ship.py policy"] * 3 + ["check", "extract", "compare", "prototype"] * 2
    fresh_check = fake_steps[7]
    assert [Path(r).name for r in after(fresh_check, "--runs")] == ["seed6", "seed7"]
    assert all(Path(r).parent == results / "torque" / "fresh" / "policy" for r in after(fresh_check, "--runs"))
    assert Path(after(fresh_check, "--out")[0]).parent.name == "fresh"  # not the tuning seeds' check folder
    assert sorted(p.name for p in (results / "torque" / "fresh" / "paths").iterdir()) == ["seed6.json", "seed7.json"]
    assert sorted(p.name for p in (results / "torque" / "paths").iterdir()) == ["seed0.json"]
    for name in ship.FRESH_FILES:
        assert (results / "figures_input" / name).is_file()

    assert ship.main(argv + ["--force"]) == 0
    assert not (results / "torque" / "fresh").exists()
    assert not any((results / "figures_input" / name).exists() for name in ship.FRESH_FILES)
    with pytest.raises(SystemExit, match="given both as tuned and as --fresh: seed0"):
        ship.main(argv + ["--fresh", str(runs / "seed0")])


def test_the_remake_refuses_a_folder_without_seeds_and_work_inside_the_runs(tmp_path, fake_steps):
    (tmp_path / "runs" / "notes").mkdir(parents=True)
    with pytest.raises(SystemExit, match="no seed<N> folders"):
        ship.main(["torque", str(tmp_path / "runs"), "--work", str(tmp_path / "work")])
    with pytest.raises(SystemExit, match="outside the run folder"):
        ship.main(["torque", str(tmp_path / "runs"), "--work", str(tmp_path / "runs" / "ship")])
    assert fake_steps == []
