"""The result files every table is written as (`cyberdog.analysis.report.write_rows`): CSV, JSON and Markdown of
one set of rows, rows with different extras sharing one table, no file for no rows."""
import csv


def read_csv(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def test_result_rows_with_different_extras_share_one_table(tmp_path):
    from cyberdog.analysis.report import write_rows

    write_rows([{"set": "paper", "E": 1.0}, {"set": "same_lift", "E": 2.0, "D_ref": -5.0}], tmp_path, "t")
    rows = read_csv(tmp_path / "t.csv")
    assert list(rows[0]) == ["set", "E", "D_ref"] and rows[0]["D_ref"] == "" and rows[1]["D_ref"] == "-5.0"
    assert "| same_lift | 2 | -5 |" in (tmp_path / "t.md").read_text()


def test_an_empty_table_writes_no_file(tmp_path):
    """No rows, no files (a prototype run on one robot has no ideal-vs-hardware gaps: no prototype_gaps.*)."""
    from cyberdog.analysis.prototype import write_prototype
    from cyberdog.analysis.report import write_rows

    write_rows([], tmp_path, "t")
    assert list(tmp_path.iterdir()) == []
    write_prototype([], tmp_path)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["prototype.md"]
