"""notebook/tools/replay_orbit.py: its refusals, and the four walks it compares (policy, path, hand-over, path
without its sideways shift)."""
from __future__ import annotations

import importlib.util
import json
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]
BATTERY_ACTOR = ROOT / "notebook/results/policy_battery/stage2_actor.pt"

spec = importlib.util.spec_from_file_location("replay_orbit", ROOT / "notebook/tools/replay_orbit.py")
tool = importlib.util.module_from_spec(spec)
spec.loader.exec_module(tool)


@pytest.mark.parametrize("extra", [["--speed", "0"], ["--speed", "1.2", "--handover", "30"],
                                   ["--speed", "1.2", "--duration", "6"], ["--speed", "1.2", "--pd-scale", "-1"],
                                   ["--speed", "1.2", "--handover", "8.01"], ["--speed", "1.2", "--placement", "-0.1"]])
def test_the_tool_refuses_bad_walks_before_walking(extra, tmp_path):
    with pytest.raises(SystemExit):
        tool.main(["--actor", str(BATTERY_ACTOR), "--out", str(tmp_path / "o.json"), *extra])
    assert not (tmp_path / "o.json").exists()


def test_the_tool_never_overwrites_and_refuses_a_torque_actor(tmp_path, capsys):
    existing = tmp_path / "o.json"
    existing.write_text("{}")
    with pytest.raises(SystemExit):
        tool.main(["--actor", str(BATTERY_ACTOR), "--speed", "1.2", "--out", str(existing)])
    assert existing.read_text() == "{}"
    with pytest.raises(SystemExit):
        tool.main(["--actor", str(ROOT / "notebook/results/policy_torque/stage2_actor.pt"), "--speed", "1.2"])
    assert "not on foot targets" in capsys.readouterr().err


def test_the_tool_walks_the_policy_its_path_the_hand_over_and_the_sagittal_path(tmp_path, capsys):
    out = tmp_path / "orbit.json"
    assert tool.main(["--actor", str(BATTERY_ACTOR), "--speed", "1.0", "--duration", "7", "--handover", "2",
                      "--sagittal", "--out", str(out)]) == 0
    report = json.loads(out.read_text())
    walks = report["walks"]
    assert list(walks) == ["policy", "path", "policy, then path from 2 s", "path without its sideways shift"]
    for name, w in walks.items():
        assert not w["fell"], name
        assert w["orbit"]["cycles"] == 12 and len(w["cycles"]) >= 12
        assert w["orbit"]["energy_J"] == pytest.approx(np.mean([c["energy_J"] for c in w["cycles"][-12:]]))
    assert walks["policy, then path from 2 s"]["electrical_J_per_m"] is None  # half policy, half path
    assert walks["path"]["electrical_J_per_m"] > 0
    # the same robot and path but no sideways shift: another walk
    assert walks["path without its sideways shift"]["cycles"] != walks["path"]["cycles"]
    # until the hand-over the hand-over walk is the policy's walk, cycle for cycle
    assert walks["policy, then path from 2 s"]["cycles"][:5] == walks["policy"]["cycles"][:5]
    assert "period" in capsys.readouterr().out


def test_the_tools_placement_reaches_the_replayed_path_only(tmp_path):
    """--placement K: the path's replay walks with the trot's sagittal foot placement, the policy as trained."""
    runs = {}
    for k in ("0", "0.3"):
        out = tmp_path / f"orbit_{k}.json"
        assert tool.main(["--actor", str(BATTERY_ACTOR), "--speed", "1.2", "--duration", "7", "--handover", "2",
                          "--placement", k, "--out", str(out)]) == 0
        runs[k] = json.loads(out.read_text())
    assert runs["0.3"]["sagittal_placement_gain_s"] == 0.3
    assert runs["0.3"]["walks"]["policy"] == runs["0"]["walks"]["policy"]
    assert runs["0.3"]["walks"]["path"]["cycles"] != runs["0"]["walks"]["path"]["cycles"]
