"""The gains table (docs/results.md, the README's headline of it): its rows from `tools/gains_walks.py`'s walks,
as commanded, re-commanded and the policies closed loop, and the tool that labels each run by its gain."""
from __future__ import annotations

from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def test_the_gains_table_rows_are_each_runs_walks_as_the_prototype_summary_gives_them(tmp_path):
    """gains_walks.json's rows: the default prototype walks relabelled as a gains run give the default row's
    numbers, as commanded and re-commanded each its own row, kp's first."""
    import json
    import shutil

    from cyberdog.analysis.readme_tables import GAINS_DEFAULT_POLICY_ROW, GAINS_DEFAULT_ROW, make_tables
    source = ROOT / "results" / "figures_input"
    for f in source.glob("*.json"):
        shutil.copy(f, tmp_path / f.name)
    walks = json.loads((source / "prototype.json").read_text())
    runs = [("kd", 2.0, True), ("kd", 2.0, False), ("kp", 2.0, True), ("kp", 0.5, True), ("kp", 2.0, False)]
    gains = [dict(w, gain=g, gain_scale=f, pd_matched=m) for g, f, m in runs for w in walks]
    (tmp_path / "gains_walks.json").write_text(json.dumps(gains))
    tables = make_tables(tmp_path)
    lines = tables["gains"].splitlines()[2:]
    row = {line.split("|")[1].strip(): line.split("|")[2:5] for line in lines}
    assert list(row) == [GAINS_DEFAULT_ROW, GAINS_DEFAULT_POLICY_ROW, "**kp 0.5×, re-commanded**", "kp 2×, as commanded",
                         "**kp 2×, re-commanded**", "kd 2×, as commanded", "**kd 2×, re-commanded**"]
    assert row["kd 2×, as commanded"] == row[GAINS_DEFAULT_ROW]
    assert [c.strip("* ") for c in row["**kp 0.5×, re-commanded**"]] == [c.strip() for c in row[GAINS_DEFAULT_ROW]]
    assert "kp 0.5×" not in tables["gains_headline"] and "**kd 2×, re-commanded**" in tables["gains_headline"]


def test_a_gains_run_that_walked_the_policies_gives_their_row_beside_the_default_gains_policy_row(tmp_path):
    """A gains run with the policies closed loop among its walks (`prototype --closed-loop`): their own row after
    that factor's path rows, and at the top the default gains' policy row from the stiffness run's PD 1× walks
    (relabelled here, the same walks give the same numbers); a run without policies has no such row."""
    import json
    import shutil

    from cyberdog.analysis.readme_tables import GAINS_DEFAULT_POLICY_ROW, GAINS_DEFAULT_ROW, make_tables
    source = ROOT / "results" / "figures_input"
    for f in source.glob("*.json"):
        shutil.copy(f, tmp_path / f.name)
    at_default = [w for w in json.loads((source / "stiffness_walks.json").read_text()) if w["pd_scale"] == 1.0]
    assert {w["trajectory"] for w in at_default} >= {"learned", "policy", "cycloid", "straight"}
    paths_only = json.loads((source / "prototype.json").read_text())
    gains = ([dict(w, gain="kd", gain_scale=2.0, pd_matched=False) for w in at_default]
             + [dict(w, gain=g, gain_scale=2.0, pd_matched=m) for g, m in (("kp", False), ("kp", True), ("kd", True))
                for w in paths_only])
    for w in gains:  # the re-commanded run's common trajectories cheaper: the policies are not measured on them
        if w["gain"] == "kd" and w["pd_matched"] and w["trajectory"] in ("cycloid", "straight"):
            w["battery_used_pct"] *= 0.5
    (tmp_path / "gains_walks.json").write_text(json.dumps(gains))
    lines = make_tables(tmp_path)["gains"].splitlines()[2:]
    row = {line.split("|")[1].strip(): line.split("|")[2:5] for line in lines}
    assert list(row) == [GAINS_DEFAULT_ROW, GAINS_DEFAULT_POLICY_ROW, "kp 2×, as commanded", "**kp 2×, re-commanded**",
                         "kd 2×, as commanded", "**kd 2×, re-commanded**", "kd 2×, the policy, closed loop"]
    assert row["kd 2×, the policy, closed loop"] == row[GAINS_DEFAULT_POLICY_ROW] != row[GAINS_DEFAULT_ROW]
    (tmp_path / "stiffness_walks.json").unlink()  # no default-gains policy walks shipped: no default policy row
    assert GAINS_DEFAULT_POLICY_ROW not in make_tables(tmp_path)["gains"]


def test_the_gains_walks_tool_labels_each_run_by_the_one_gain_it_changed(tmp_path):
    import importlib.util
    import json

    spec = importlib.util.spec_from_file_location("gains_walks", ROOT / "tools" / "gains_walks.py")
    tool = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(tool)

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
