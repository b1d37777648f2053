"""The gains table (docs/results.md, the README's headline of it): its rows from `tools/merge_walks.py gains`'s
walks, as commanded, re-commanded and the policies closed loop (the tool itself: tests/test_merge_walks.py)."""
from __future__ import annotations

from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def test_the_gains_table_rows_are_each_runs_walks_as_the_prototype_summary_gives_them(tmp_path):
    """gains_walks.json's rows: the default prototype walks relabelled as a gains run give the default row's
    numbers, as commanded and re-commanded each its own row, kp's first."""
    import json
    import shutil

    from cyberdog.analysis.gains_table import (GAINS_DEFAULT_POLICY_ROW, GAINS_DEFAULT_ROW, SEARCHED_SAVING,
                                               VS_SEARCHED)
    from cyberdog.analysis.readme_tables import make_tables
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
    # the prototype walks hold the searched shape: each as-commanded run's rows against it follow its own
    searched = [f"{{}}, as commanded: {label}" for label in (SEARCHED_SAVING, VS_SEARCHED)]
    assert list(row) == [GAINS_DEFAULT_ROW, GAINS_DEFAULT_POLICY_ROW, "**kp 0.5×, re-commanded**",
                         "kp 2×, as commanded", *(r.format("kp 2×") for r in searched), "**kp 2×, re-commanded**",
                         "kd 2×, as commanded",
                         *(r.format("kd 2×") for r in searched), "**kd 2×, re-commanded**"]
    assert row["kd 2×, as commanded"] == row[GAINS_DEFAULT_ROW]
    prototype = {line.split("|")[1].strip(): line.split("|")[2:5] for line in tables["prototype"].splitlines()[2:]}
    assert row[f"kd 2×, as commanded: {VS_SEARCHED}"] == [c.replace("*", "") for c in prototype[
        "learned against the shape searched for the battery (the best alternative)"]]
    assert [c.strip("* ") for c in row["**kp 0.5×, re-commanded**"]] == [c.strip() for c in row[GAINS_DEFAULT_ROW]]


def test_a_gains_run_that_walked_the_policies_gives_their_row_beside_the_default_gains_policy_row(tmp_path):
    """A gains run with the policies closed loop among its walks (`prototype --closed-loop`): their own row after
    that factor's path rows, and at the top the default gains' policy row from the stiffness run's PD 1× walks
    (relabelled here, the same walks give the same numbers); a run without policies has no such row."""
    import json
    import shutil

    from cyberdog.analysis.gains_table import (GAINS_DEFAULT_POLICY_ROW, GAINS_DEFAULT_ROW, SEARCHED_SAVING,
                                               VS_SEARCHED)
    from cyberdog.analysis.readme_tables import make_tables
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
    assert list(row) == [GAINS_DEFAULT_ROW, GAINS_DEFAULT_POLICY_ROW, "kp 2×, as commanded",
                         f"kp 2×, as commanded: {SEARCHED_SAVING}", f"kp 2×, as commanded: {VS_SEARCHED}",
                         "**kp 2×, re-commanded**", "kd 2×, as commanded",
                         f"kd 2×, as commanded: {SEARCHED_SAVING}", f"kd 2×, as commanded: {VS_SEARCHED}",
                         "**kd 2×, re-commanded**", "kd 2×, the policy, closed loop"]
    assert row["kd 2×, the policy, closed loop"] == row[GAINS_DEFAULT_POLICY_ROW] != row[GAINS_DEFAULT_ROW]
    (tmp_path / "stiffness_walks.json").unlink()  # no default-gains policy walks shipped: no default policy row
    assert GAINS_DEFAULT_POLICY_ROW not in make_tables(tmp_path)["gains"]
