"""tools/curve_table.py: a run's episodes binned by env steps of the stage, on a metrics.csv written here."""
from __future__ import annotations

import csv
import importlib.util
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
spec = importlib.util.spec_from_file_location("curve_table", ROOT / "tools/curve_table.py")
tool = importlib.util.module_from_spec(spec)
spec.loader.exec_module(tool)

FIELDS = ("stage", "episode", "env_steps", "length", "score", "fell", "wall_time_s")
# stage 1 ends at env step 250 of the run; stage 2's steps count from there (its 50th, 170th)
EPISODES = [  # stage, run's env steps at the episode's end, length, score, fell, wall clock (s)
    (1, 50, 10, -4.0, "", 1000.0),    # logged before the `fell` column existed
    (1, 120, 14, -2.0, 1, 1010.0),
    (1, 180, 12, 1.0, 0, 1030.0),
    (1, 250, 70, 3.0, 1, 5000.0),     # after a stop of over an hour: not training time
    (2, 300, 50, 10.0, 0, 5006.0),
    (2, 420, 120, 20.0, 0, 5030.0),
]


def write_metrics(path: Path, episodes=EPISODES) -> Path:
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(FIELDS)
        for i, (stage, steps, length, score, fell, wall) in enumerate(episodes, 1):
            w.writerow([stage, i, steps, length, score, fell, wall])
    return path


def test_episodes_fall_in_the_bin_of_the_stage_step_they_ended_at(tmp_path):
    stages = tool.read_metrics(write_metrics(tmp_path / "metrics.csv"))
    assert sorted(stages) == [1, 2]
    s1 = tool.curve_rows(stages[1], every=100)
    assert [r["env steps"] for r in s1] == ["0–100", "100–200", "200–250"]
    assert [r["episodes"] for r in s1] == [1, 2, 1]
    assert s1[1]["mean length (steps)"] == pytest.approx(13.0)
    assert s1[1]["longest"] == 14
    assert s1[1]["mean score"] == pytest.approx(-0.5)
    assert s1[1]["falls"] == "1 (50.0%)"
    assert s1[0]["falls"] == "not logged"  # not "no fall"
    # a bin holding episodes from before and after the `fell` column: the share of those logged
    assert tool.curve_rows(stages[1], edges=[1000])[0]["falls"] == "2 (66.7%) of 3 logged"
    # stage 2 counts its own steps: 50 and 170, so one episode in each of its two bins
    s2 = tool.curve_rows(stages[2], every=100)
    assert [r["episodes"] for r in s2] == [1, 1]
    assert s2[1]["mean score"] == pytest.approx(20.0)


def test_a_stop_between_two_episodes_is_not_counted_as_training_time(tmp_path):
    stages = tool.read_metrics(write_metrics(tmp_path / "metrics.csv"))
    rows = tool.curve_rows(stages[1], edges=[1000])  # one bin: the whole stage
    assert rows[0]["episodes"] == 4
    assert rows[0]["wall (min)"] == pytest.approx((10.0 + 20.0) / 60.0)  # the 3,970 s gap is a pause


def test_the_table_and_the_command_line(tmp_path, capsys):
    write_metrics(tmp_path / "metrics.csv")
    out = tmp_path / "curve.md"
    assert tool.main([str(tmp_path), "--every", "100", "--out", str(out)]) == 0
    text = out.read_text()
    assert "stage 1: 4 episodes, 250 env steps" in text and "stage 2: 2 episodes, 170 env steps" in text
    assert "| not logged |" in text and "| 1 (50.0%) |" in text
    with pytest.raises(SystemExit):  # the output may not overwrite the log it reads
        tool.main([str(tmp_path), "--out", str(tmp_path / "metrics.csv")])
    with pytest.raises(SystemExit):
        tool.main([str(tmp_path), "--every", "0"])
    (tmp_path / "other.csv").write_text("a,b\n1,2\n")
    with pytest.raises(SystemExit):
        tool.main([str(tmp_path / "other.csv")])
    assert "not a train.py metrics.csv" in capsys.readouterr().err


def test_a_log_older_than_the_fell_column_reads_as_not_logged(tmp_path):
    with open(tmp_path / "metrics.csv", "w", newline="") as f:
        w = csv.writer(f)
        w.writerow([c for c in FIELDS if c != "fell"])
        for i, (stage, steps, length, score, _, wall) in enumerate(EPISODES, 1):
            w.writerow([stage, i, steps, length, score, wall])
    stages = tool.read_metrics(tmp_path / "metrics.csv")
    assert [r["falls"] for r in tool.curve_rows(stages[1], every=100)] == ["not logged"] * 3
    assert [r["episodes"] for r in tool.curve_rows(stages[2], every=100)] == [1, 1]
