"""tools/optimize_trajectory.py --set: the shape is searched and replayed under the walk config asked for, and
a search under another config never replaces a shipped path."""
from __future__ import annotations

import importlib.util
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
spec = importlib.util.spec_from_file_location("optimize_trajectory", ROOT / "tools/optimize_trajectory.py")
tool = importlib.util.module_from_spec(spec)
spec.loader.exec_module(tool)


def test_overrides_reach_the_walk_config_and_keep_the_result_in_the_run_folder(tmp_path):
    args = tool.parse_args(["--set", "controller.sagittal_placement_gain=0.1", "--out", str(tmp_path)])
    assert args.base.controller.sagittal_placement_gain == 0.1
    assert args.result == tmp_path / "optimized_trajectory.json"
    plain = tool.parse_args(["--out", str(tmp_path)])
    assert plain.base.controller.sagittal_placement_gain == 0.0
    assert plain.result.parent == ROOT / "results" / "searched_shapes"


def test_a_bad_override_fails_before_any_walk(tmp_path, capsys):
    with pytest.raises(SystemExit):
        tool.parse_args(["--set", "controller.no_such_gain=1", "--out", str(tmp_path)])
    assert "no_such_gain" in capsys.readouterr().err


class _Stop(Exception):
    pass


def _search_arguments(monkeypatch, argv: list[str]) -> dict:
    """The keyword arguments `main(argv)` hands the search (a stand-in that stops there, before any walk)."""
    seen = {}

    def fake_search(*a, **kw):
        seen.update(kw)
        raise _Stop

    monkeypatch.setattr(tool.shape_search, "optimize_shape", fake_search)
    with pytest.raises(_Stop):
        tool.main([*argv, "--max-evals", "2"])
    return seen


def test_the_search_walks_under_the_overridden_config(tmp_path, monkeypatch):
    seen = _search_arguments(monkeypatch, ["--set", "controller.sagittal_placement_gain=0.2", "--out", str(tmp_path)])
    assert seen["base"].controller.sagittal_placement_gain == 0.2


def test_the_gains_reach_the_search_and_a_bad_pair_fails_before_any_walk(tmp_path, monkeypatch, capsys):
    seen = _search_arguments(monkeypatch, ["--gains", "1:1", "0.5:1", "1:2", "--out", str(tmp_path)])
    assert seen["gains"] == [(1.0, 1.0), (0.5, 1.0), (1.0, 2.0)]
    assert tool.parse_args(["--gains", "1:2", "--out", str(tmp_path)]).result.name.endswith("_gains.json")
    for bad in (["--gains", "1"], ["--gains", "1:9"], ["--gains", "1:2", "--replay-only", __file__]):
        with pytest.raises(SystemExit):
            tool.parse_args([*bad, "--out", str(tmp_path)])
    assert "KP:KD" in capsys.readouterr().err


def test_the_foot_inset_reaches_the_search_and_names_the_file(tmp_path, monkeypatch, capsys):
    seen = _search_arguments(monkeypatch, ["--foot-inset", "0.02", "--out", str(tmp_path)])
    assert seen["foot_inset"] == 0.02
    assert tool.parse_args(["--foot-inset", "0.02", "--out", str(tmp_path)]).result.name.endswith("_inset20.json")
    assert _search_arguments(monkeypatch, ["--out", str(tmp_path)])["foot_inset"] == 0.0
    for bad in (["--foot-inset", "0.15"], ["--foot-inset", "nan"], ["--foot-inset", "0.02", "--replay-only", __file__]):
        with pytest.raises(SystemExit):
            tool.parse_args([*bad, "--out", str(tmp_path)])
    assert "--foot-inset" in capsys.readouterr().err
