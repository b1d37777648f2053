"""notebook/tools/closed_loop_battery.py: the policy, its replayed path and the matched cycloid on the same robots."""
from __future__ import annotations

import dataclasses
import importlib.util
import json
from pathlib import Path

import pytest

from cyberdog import config as C
from cyberdog.analysis.walk import walk
from cyberdog.core.learned_set import LearnedSet, learned_files

ROOT = Path(__file__).resolve().parents[2]
spec = importlib.util.spec_from_file_location("closed_loop_battery", ROOT / "notebook/tools/closed_loop_battery.py")
closed_loop = importlib.util.module_from_spec(spec)
spec.loader.exec_module(closed_loop)
ACTOR = ROOT / "notebook/results/policy_battery/stage2_actor.pt"
LEARNED = ROOT / "notebook/results/learned_battery"


def test_three_walks_per_robot_with_the_cycloid_at_the_paths_own_lift(tmp_path):
    out = tmp_path / "cl"
    assert closed_loop.main(["--actors", str(ACTOR), "--labels", "seed0", "--learned", str(LEARNED), "--speeds",
                             "1.0", "--draws", "1", "--duration", "3", "--workers", "1", "--out", str(out)]) == 0
    rows = json.loads((out / "closed_loop.json").read_text())
    assert [r["walk"] for r in rows] == ["closed loop", "replay", "cycloid"]
    energies = [r["electrical_kJ_per_100m"] for r in rows]
    assert all(e > 0 for e in energies) and len(set(energies)) == 3  # three different walks
    # the cycloid walked at the learned path's own lift height on the hardware-like robot of draw 0
    lift = LearnedSet.load(learned_files([LEARNED])).path("seed0", 1.0).lift_height
    gait = C.GaitConfig(speed=1.0, lift_height=lift)
    r = walk(dataclasses.replace(C.WalkConfig(), gait=gait), 3.0, hardware=C.HARDWARE_LIKE)
    assert energies[2] == pytest.approx(100.0 * r.electrical_energy / r.distance / 1e3)
    assert "closed loop" in (out / "closed_loop.md").read_text()


def test_actors_and_labels_must_pair_up(tmp_path):
    with pytest.raises(SystemExit):
        closed_loop.main(["--actors", str(ACTOR), "--labels", "seed0", "seed1", "--out", str(tmp_path)])
    with pytest.raises(SystemExit):
        closed_loop.main(["--actors", str(tmp_path / "none.pt"), "--labels", "seed0", "--out", str(tmp_path)])
    with pytest.raises(SystemExit):  # no path of that label in the learned set: refused before any walk
        closed_loop.main(["--actors", str(ACTOR), "--labels", "seed9", "--learned", str(LEARNED), "--out",
                          str(tmp_path)])
