"""The torque agent's rows in the result tables (`cyberdog.analysis.readme_tables`, `torque_table`): its check
(`torque_check.json`), Table 5's rows of its paths, and the seeds it was never tuned on beside the tuning seeds',
each from the shipped results relabelled, so that a row is what its walks give."""
from __future__ import annotations

from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def test_the_torque_rows_of_table5_count_the_seeds_trained_and_the_fresh_seeds_stand_apart(tmp_path):
    """Table 5's torque rows say how many of the seeds the check walked have a path that replays (a seed whose
    path does not replay has none, so the comparison alone cannot count it); comparison_torque_fresh.json (the
    seeds never tuned on) gives rows of their own, named by their seeds, equal to the shipped rows' numbers for
    the same walks relabelled."""
    import json
    import shutil

    from cyberdog.analysis.readme_tables import make_tables
    source = ROOT / "results" / "figures_input"
    for f in source.glob("*.json"):
        shutil.copy(f, tmp_path / f.name)
    walks = json.loads((source / "comparison_torque.json").read_text())
    check = json.loads((source / "torque_check.json").read_text())
    with_path = {w["seed"] for w in walks if w.get("seed")}
    trained = {w["label"] for w in check["walks"] if w["label"] != "trot"}
    relabel = {f"seed{k}": f"seed{k + 10}" for k in range(10)}
    (tmp_path / "comparison_torque_fresh.json").write_text(json.dumps(
        [dict(w, seed=relabel.get(str(w.get("seed")), w.get("seed"))) for w in walks]))
    (tmp_path / "torque_check_fresh.json").write_text(json.dumps(
        {key: [dict(w, label=relabel.get(w["label"], w["label"])) for w in check[key]] for key in check}))
    def table5_rows() -> dict:
        return {line.split("|")[1].strip(): line.split("|")[2:5]
                for line in make_tables(tmp_path)["table5"].splitlines()[2:]}

    row = table5_rows()
    tuned = row["**D_t on E, the paper's agent (joint torques)**"]
    assert all(c.strip().endswith(f" of {len(trained)})") for c in tuned)
    assert all(int(c.split("(")[-1].split(" of")[0]) <= len(with_path) for c in tuned)
    named = f"seeds {min(int(s[4:]) for s in with_path) + 10}–{max(int(s[4:]) for s in with_path) + 10}"
    fresh = row[f"**D_t on E, the paper's agent, {named} (never tuned on)**"]
    assert fresh == tuned
    assert row[f"D_t on the electrical energy, the paper's agent, {named}"] == \
        row["D_t on the electrical energy, the paper's agent"]
    (tmp_path / "torque_check_fresh.json").unlink()  # without the fresh check: the seeds with a path
    fresh = table5_rows()[f"**D_t on E, the paper's agent, {named} (never tuned on)**"]
    assert all(c.strip().endswith(f" of {len(with_path)})") for c in fresh)


def test_the_torque_table_counts_the_walks_and_averages_each_stage_over_the_seeds():
    """torque_check.json (a policy check of the torque recipe's actors): the band count over every robot and
    stage, each stage's electrical J/m and stage 2's per-metre saving as the mean of the seeds, the lowest seed
    beside it, the trot's own row; a saving where a stage missed the band is left out."""
    from cyberdog.analysis.policy_check import stage_reductions
    from cyberdog.analysis.torque_table import TORQUE_SAVING_ROW, torque_markdown

    def walk(label, stage, robot, speed, j_per_m, walks=True):
        return {"label": label, "stage": stage, "robot": robot, "speed_command_mps": speed, "walks": walks,
                "fell": False, "duration_s": 10.0, "energy_J": 1000.0, "energy_per_metre_J": 100.0,
                "electrical_per_metre_J": j_per_m}

    walks = [walk("seed0", 1, "ideal", 1.0, 400.0), walk("seed0", 2, "ideal", 1.0, 360.0),
             walk("seed1", 1, "ideal", 1.0, 500.0), walk("seed1", 2, "ideal", 1.0, 400.0),
             walk("seed2", 1, "ideal", 1.0, 450.0), walk("seed2", 2, "ideal", 1.0, 300.0, walks=False),
             walk("trot", 0, "ideal", 1.0, 356.0)]
    table = torque_markdown({"walks": walks, "reductions": stage_reductions(walks)})
    row = {line.split("|")[1].strip(): line.split("|")[2].strip() for line in table.splitlines()[2:]}
    assert row["walks in the ±5 % band, no fall (both stages; ideal robot)"] == "5 of 6"
    assert row["electrical J/m, stage 1 (ideal robot)"].startswith("450 ± ")
    assert row["**electrical J/m, stage 2 (ideal robot)**"].startswith("**353 ± ")  # (360 + 400 + 300) / 3
    assert row[TORQUE_SAVING_ROW.format(robot="ideal robot")].endswith("(lowest 10.0 %)** (2 of 3 seeds)")  # not 2
    assert row[TORQUE_SAVING_ROW.format(robot="ideal robot")].startswith("**15.0 % ± ")  # mean of 10 and 20
    assert row["electrical J/m, the trot controller (H = 0.10 m, ideal robot)"] == "356"


def test_the_torque_tables_fresh_rows_are_those_seeds_check_as_the_table_gives_it(tmp_path):
    """torque_check_fresh.json (the recipe's seeds it was never tuned on, checked as seeds 0-4): the shipped check
    relabelled as seeds 5-9 gives a band count and a saving equal to the shipped rows', named by the seeds and in
    the headline; a seed whose stage 2 leaves the band is left out of the saving, and the cell says so."""
    import json
    import shutil

    from cyberdog.analysis.readme_tables import FRESH_SEEDS, make_tables
    from cyberdog.analysis.torque_table import TORQUE_FRESH_SAVING_ROW, TORQUE_FRESH_WALKS_ROW, TORQUE_WALKS_ROW
    source = ROOT / "results" / "figures_input"
    for f in source.glob("*.json"):
        shutil.copy(f, tmp_path / f.name)
    check = json.loads((source / "torque_check.json").read_text())
    relabel = {f"seed{k}": f"seed{k + 5}" for k in range(5)}
    for key in ("walks", "reductions"):
        check[key] = [dict(w, label=relabel.get(w["label"], w["label"])) for w in check[key]]
    (tmp_path / "torque_check_fresh.json").write_text(json.dumps(check))
    tables = make_tables(tmp_path)
    row = {line.split("|")[1].strip(): line.split("|")[2:5] for line in tables["torque"].splitlines()[2:]}
    walks_row = TORQUE_WALKS_ROW.format(robots="ideal robot, hardware-like draws 0 and 1")
    assert row[TORQUE_FRESH_WALKS_ROW.format(seeds=FRESH_SEEDS)] == row[walks_row]
    saving_row = TORQUE_FRESH_SAVING_ROW.format(seeds=FRESH_SEEDS)
    assert row[saving_row] == row["**stage 2's saving against stage 1, electrical per metre (ideal robot)**"]
    assert saving_row in tables["torque_headline"]
    def counted(speed: float) -> int:
        return sum(r["both_walk"] for r in check["reductions"]
                   if r["robot"] == "ideal" and r["speed_command_mps"] == speed)

    # seed 6's stage 2 off the band at 1.4 m/s on the ideal robot: its saving there is not counted
    before = counted(1.4)
    for r in check["reductions"]:
        if r["label"] == "seed6" and r["robot"] == "ideal" and r["speed_command_mps"] == 1.4:
            r["both_walk"] = False
    assert counted(1.4) == before - 1
    (tmp_path / "torque_check_fresh.json").write_text(json.dumps(check))
    row = {line.split("|")[1].strip(): line.split("|")[2:5]
           for line in make_tables(tmp_path)["torque"].splitlines()[2:]}
    assert row[saving_row][2].strip().endswith(f"({counted(1.4)} of 5 seeds)")
    for cell, speed in zip(row[saving_row], (1.0, 1.2, 1.4)):
        assert ("seeds)" in cell) == (counted(speed) < 5), speed


def test_the_torque_headline_names_the_fresh_seeds_checked_so_far(tmp_path):
    """A check of two fresh seeds (5 and 6) gives rows named "seeds 5–6": their walks in the full table, their
    saving in the headline too, equal to the full table's."""
    import json
    import shutil

    from cyberdog.analysis.readme_tables import make_tables
    from cyberdog.analysis.torque_table import TORQUE_FRESH_SAVING_ROW, TORQUE_FRESH_WALKS_ROW
    source = ROOT / "results" / "figures_input"
    for f in source.glob("*.json"):
        shutil.copy(f, tmp_path / f.name)
    check = json.loads((source / "torque_check.json").read_text())
    relabel = {"seed0": "seed5", "seed1": "seed6", "trot": "trot"}
    for key in ("walks", "reductions"):
        check[key] = [dict(w, label=relabel[w["label"]]) for w in check[key] if w["label"] in relabel]
    (tmp_path / "torque_check_fresh.json").write_text(json.dumps(check))
    tables = make_tables(tmp_path)
    rows = [TORQUE_FRESH_WALKS_ROW.format(seeds="seeds 5–6"), TORQUE_FRESH_SAVING_ROW.format(seeds="seeds 5–6")]
    full = {line.split("|")[1].strip(): line for line in tables["torque"].splitlines()[2:]}
    top = {line.split("|")[1].strip(): line for line in tables["torque_headline"].splitlines()[2:]}
    assert rows[0] in full and rows[0] not in top  # the headline keeps six rows: the walks stay in the full table
    assert rows[1] in full and top[rows[1]] == full[rows[1]]
