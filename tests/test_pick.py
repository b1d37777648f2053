"""`evaluate.py pick`: per speed, the learned path cheapest on the extraction's check robots among several
extractions' paths, saved under one label that the loader then reads back."""
from __future__ import annotations

import json

import pytest

import evaluate
from conftest import commanded
from cyberdog.analysis.replay_check import check_settings
from cyberdog.core.learned_set import LearnedSet
from cyberdog.evaluation.options import UsageError
from cyberdog.evaluation.pick import check_cost, load_candidates, pick

CONTROLLER = {"sagittal_placement_gain": 0.2}


def checked(speed: float, seed: int, kept_cost: float, other_cost: float = 999.0, dz: float = -0.01, **check):
    """A commanded path as extraction keeps it: two candidates on the check robots, the kept one (rollout seed 1)
    at `kept_cost` J/m; `check` overrides what the check walked."""
    path = commanded(speed, dz, seed)
    path.provenance.update({"rollout_seed": 1, "cycle": "mean", "policy": f"runs/s/seed{seed}/band", "replay_check": {
        "status": "ok", "candidates": [{"rollout_seed": 0, "cycle": "mean", "electrical_J_per_m": other_cost},
                                       {"rollout_seed": 1, "cycle": "mean", "electrical_J_per_m": kept_cost}],
        **check_settings(), "controller": CONTROLLER, **check}})
    return path


def save(folder, label, *paths):
    from cyberdog.core.learned_set import LearnedPath

    return [LearnedPath(label, p).save(folder) for p in paths]


@pytest.fixture
def two_lineages(tmp_path):
    """Seed 40 cheaper at 1.0 m/s, seed 140 cheaper at 1.2, and only seed 140 with a path at 1.4."""
    a, b = tmp_path / "a" / "learned", tmp_path / "b" / "learned"
    save(a, "seed40", checked(1.0, 40, 200.0, dz=-0.01), checked(1.2, 40, 260.0, dz=-0.02))
    save(b, "seed140", checked(1.0, 140, 230.0, dz=-0.03), checked(1.2, 140, 240.0, dz=-0.04),
         checked(1.4, 140, 300.0, dz=-0.05))
    return a, b


def test_the_cost_is_the_kept_candidates_not_the_cheapest_rejected_one():
    p = checked(1.0, 3, kept_cost=250.0, other_cost=240.0)  # kept by rollout seed and cycle
    assert check_cost(p.provenance, "x")[0] == 250.0
    p.provenance["rollout_seed"] = 5  # a kept path its check did not record
    with pytest.raises(UsageError, match="no electrical energy per metre for the kept path"):
        check_cost(p.provenance, "x")
    del p.provenance["replay_check"]
    with pytest.raises(UsageError, match="did not run the replay check"):
        check_cost(p.provenance, "x")


def test_each_speed_keeps_the_path_cheaper_on_the_check_robots(two_lineages):
    picks = pick(load_candidates(list(two_lineages)))
    kept = {v: (c.label, c.electrical_J_per_m, len(group)) for v, (c, group) in picks.items()}
    assert kept == {1.0: ("seed40", 200.0, 2), 1.2: ("seed140", 240.0, 2), 1.4: ("seed140", 300.0, 1)}


def test_costs_checked_by_different_walks_are_refused(tmp_path, two_lineages):
    other = tmp_path / "c"
    save(other, "seed7", checked(1.0, 7, 100.0, hardware_like_pd_scales=[1.0]))
    with pytest.raises(UsageError, match="checked by different walks"):
        pick(load_candidates([*two_lineages, other]))


def test_costs_of_checks_on_robots_set_apart_are_refused_where_both_record_it(tmp_path, two_lineages):
    other = tmp_path / "c"  # extracted with --set pid.kd=[3,3,3]: its check robots were damped apart
    save(other, "seed7", checked(1.0, 7, 100.0, walk_settings={"pid.kd": [3.0, 3.0, 3.0]}))
    same = tmp_path / "d"
    save(same, "seed8", checked(1.0, 8, 100.0, walk_settings={}))
    with pytest.raises(UsageError, match="checked by different walks"):
        pick(load_candidates([same, other]))
    assert pick(load_candidates([*two_lineages, other]))[1.0][0].label == "seed7"  # the others record none


def test_the_command_saves_the_picks_under_one_label_that_loads_back(tmp_path, two_lineages, capsys):
    out = tmp_path / "picked"
    assert evaluate.main(["pick", "--learned", *map(str, two_lineages), "--out", str(out)]) == 0
    learned = LearnedSet.load([out / "learned"])
    assert learned.labels == ["seed40"] and learned.speeds() == [1.0, 1.2, 1.4]
    # the kept path itself: seed 140's 1.2 m/s path has its own lift (0.10 - 0.04 m at mid-swing)
    p = learned.path("seed40", 1.2)
    assert p.provenance["seed"] == 140 and p.lift_height == pytest.approx(
        LearnedSet.load([two_lineages[1] / "seed140_1.2mps.json"]).path("seed140", 1.2).lift_height)
    record = p.provenance["picked"]
    assert [c["electrical_J_per_m"] for c in record["candidates"]] == [260.0, 240.0] and record["kept"] == 1
    assert [c["policy"] for c in record["candidates"]] == ["runs/s/seed40/band", "runs/s/seed140/band"]
    rows = json.loads((out / "pick.json").read_text())
    assert sum(r["kept"] for r in rows) == 3 and len(rows) == 5
    assert "kept seed140's path (240.00 J/m" in capsys.readouterr().out


@pytest.mark.parametrize("extra, words", [
    (["--set", "gait.lift_height=0.1"], "walks nothing"),
    (["--label", "a/b"], "a label is a file-name part"),
])
def test_settings_that_change_nothing_and_bad_labels_are_refused(tmp_path, two_lineages, extra, words, capsys):
    rc = evaluate.main(["pick", "--learned", *map(str, two_lineages), "--out", str(tmp_path / "o"), *extra])
    assert rc == 2 and words in capsys.readouterr().err and not (tmp_path / "o").exists()


def test_a_config_is_refused_in_one_line_before_it_is_read(tmp_path, two_lineages, capsys):
    cfg = tmp_path / "walk.yaml"  # a walk config with a hardware section, which a walking command would note
    cfg.write_text("hardware:\n  seed: 3\n")
    rc = evaluate.main(["pick", "--learned", *map(str, two_lineages), "--config", str(cfg),
                        "--out", str(tmp_path / "o")])
    captured = capsys.readouterr()
    assert rc == 2 and captured.out == "" and captured.err.count("\n") == 1 and "walks nothing" in captured.err


def test_unchecked_or_single_paths_are_refused(tmp_path, capsys):
    bare = tmp_path / "bare"
    save(bare, "seed1", commanded(1.0, -0.01, 1))
    assert evaluate.main(["pick", "--learned", str(bare), "--out", str(tmp_path / "o")]) == 2
    assert "did not run the replay check" in capsys.readouterr().err
    one = tmp_path / "one"  # one lineage: a path at each speed, nothing to choose between
    save(one, "seed1", checked(1.0, 1, 200.0), checked(1.2, 1, 210.0))
    assert evaluate.main(["pick", "--learned", str(one), "--out", str(tmp_path / "o")]) == 2
    assert "nothing to choose between" in capsys.readouterr().err


def test_an_output_folder_holding_an_input_is_refused_whatever_the_file_names(tmp_path, two_lineages, capsys):
    a, b = two_lineages  # a re-made output folder is cleared first: an input inside it would be lost
    rc = evaluate.main(["pick", "--learned", str(a), str(b), "--label", "best", "--out", str(b.parent), "--force"])
    assert rc == 2 and "an input of this pick" in capsys.readouterr().err
    assert (b / "seed140_1.4mps.json").is_file()


def test_a_path_given_twice_is_refused_not_picked_against_itself(tmp_path, two_lineages, capsys):
    a, b = two_lineages
    rc = evaluate.main(["pick", "--learned", str(a), str(b), str(b / "seed140_1mps.json"), "--out", str(tmp_path / "o")])
    assert rc == 2 and "is given twice" in capsys.readouterr().err
    copy = tmp_path / "copy"  # the same lineage extracted into two folders: with --lineage-offset, refused
    save(copy, "seed140", checked(1.0, 140, 231.0))
    rc = evaluate.main(["pick", "--learned", str(a), str(b), str(copy), "--lineage-offset", "100",
                        "--out", str(tmp_path / "o")])
    assert rc == 2 and "lineage seed140 has two paths at 1 m/s" in capsys.readouterr().err


def test_one_input_holding_several_seeds_at_a_speed_needs_the_lineage_offset(tmp_path, two_lineages, capsys):
    a, b = two_lineages
    save(a, "seed41", checked(1.0, 41, 150.0))  # a sweep's folder: seeds 40 and 41 side by side
    rc = evaluate.main(["pick", "--learned", str(a), str(b), "--out", str(tmp_path / "o")])
    assert rc == 2 and "--lineage-offset" in capsys.readouterr().err and not (tmp_path / "o").exists()


def test_a_sweeps_lineages_are_picked_seed_by_seed_with_a_lineage_offset(tmp_path, two_lineages, capsys):
    a, b = two_lineages
    save(a, "seed41", checked(1.0, 41, 210.0))  # seed 41's lineages: 41 and 141
    save(b, "seed141", checked(1.0, 141, 205.0))
    out = tmp_path / "picked"
    assert evaluate.main(["pick", "--learned", str(a), str(b), "--lineage-offset", "100", "--out", str(out)]) == 0
    learned = LearnedSet.load([out / "learned"])
    assert learned.labels == ["seed40", "seed41"]
    assert learned.path("seed41", 1.0).provenance["seed"] == 141 and learned.path("seed40", 1.0).provenance["seed"] == 40
    assert not learned.has("seed41", 1.2)  # neither of its lineages has a path there
    save(tmp_path / "c", "seed2", checked(1.0, 2, 200.0))  # seed 2 has one lineage: nothing to choose
    assert evaluate.main(["pick", "--learned", str(a), str(b), str(tmp_path / "c"), "--lineage-offset", "100",
                          "--out", str(tmp_path / "o2")]) == 2
    assert "seed2: one learned path at each speed" in capsys.readouterr().err


def test_the_shipped_picked_paths_are_the_pick_of_the_shipped_lineages():
    """results/battery_searched_pick/paths/ holds, per seed N and speed, the path of lineage N or N + 100 (its
    lineage_paths/) that `pick` keeps by the check robots, the same offsets and trot, with every candidate's cost
    recorded (the lifts as a saved path works them out again, to 1 µm); every seed whose two lineages are shipped
    has its picks, and nothing else is there."""
    from pathlib import Path

    shipped = Path(__file__).resolve().parents[1] / "results" / "battery_searched_pick"
    lineages = load_candidates([shipped / "lineage_paths"])
    seeds = sorted({c.seed % 100 for c in lineages if c.seed >= 100})
    assert seeds and all(any(c.seed == s for c in lineages) for s in seeds)
    expected = {}
    for s in seeds:
        for speed, (kept, group) in pick([c for c in lineages if c.seed in (s, s + 100)]).items():
            expected[f"seed{s}_{speed:g}mps.json"] = (kept, group)
    picked = {f.name: f for f in (shipped / "paths").glob("seed*_*mps.json")}
    assert expected and sorted(picked) == sorted(expected)
    for name, (kept, group) in expected.items():
        saved, source = json.loads(picked[name].read_text()), json.loads(kept.file.read_text())
        record = saved["provenance"].pop("picked")
        assert saved["provenance"].pop("label") == name.split("_")[0]
        source["provenance"].pop("label", None)
        lifts = [(saved.pop(k), source.pop(k)) for k in ("own_lift_height_m", "leg_lift_heights_m")]
        assert saved == source, name  # the offsets, the trot, the provenance but for the pick's own keys
        assert all(a == pytest.approx(b, abs=1e-6) for a, b in lifts), name  # m, as the saved path works them out
        assert {c["seed"]: c["electrical_J_per_m"] for c in record["candidates"]} == {
            c.seed: c.electrical_J_per_m for c in group}, name
        assert record["candidates"][record["kept"]]["seed"] == kept.seed, name
