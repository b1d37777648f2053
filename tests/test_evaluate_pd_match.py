"""`evaluate.py pd-match`: a shipped path re-commanded for another PD is written beside, never over, a file,
says which PD it is for, and walks under that PD as it walked under its own, where the plain command does not."""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

import evaluate
from cyberdog import config as C
from cyberdog.analysis.walk import walk
from cyberdog.core.learned_set import LearnedSet
from cyberdog.evaluation.recorded_trot import with_trot

ROOT = Path(__file__).resolve().parents[1]
SHIPPED = ROOT / "results/battery/paths/seed0_1.4mps.json"


def test_a_path_re_commanded_for_a_stiffer_pd_walks_there_as_it_walked_under_its_own(tmp_path):
    assert evaluate.main(["pd-match", str(SHIPPED), "--pd-scale", "1.4", "--out", str(tmp_path)]) == 0
    written = tmp_path / "learned" / SHIPPED.name
    record = json.loads(written.read_text())["provenance"]["pd_matched"]
    assert record["to_pid"]["kp"] == pytest.approx([84.0] * 3) and record["from_pid"]["kp"] == pytest.approx([60.0] * 3)
    own, matched = LearnedSet.load([SHIPPED]).paths()[0], LearnedSet.load([written]).paths()[0]
    assert np.max(np.abs(matched.path.offsets.offsets - own.path.offsets.offsets)) > 1e-3  # m
    base = with_trot(C.WalkConfig(), own.recorded_controller)
    stiff = C.replace(base, pid=base.pid.stiffness_scaled(1.4))
    cost = {}
    for name, path, cfg in (("own", own, base), ("plain", own, stiff), ("matched", matched, stiff)):
        walk_cfg, trajectory, offsets = path.walk_args(cfg, 1.4)
        r = walk(walk_cfg, 9.0, trajectory, foot_offsets=offsets, run_up=3.0, hardware=C.HARDWARE_LIKE)
        assert not r.fell
        cost[name] = r.energy / r.distance  # J/m, Eq. 7
    # on the prototype's first hardware-like robot, re-commanded, the stiff PD walks the own PD's gait to within a
    # few per cent; the plain command falls into a slower, rocking gait that costs far more
    assert abs(cost["matched"] / cost["own"] - 1) < 0.05, cost
    assert cost["plain"] / cost["own"] > 1.3, cost
    assert evaluate.main(["pd-match", str(SHIPPED), "--pd-scale", "1.4", "--out", str(tmp_path)]) == 2  # never over
    # nor over the paths it reads, even with --force
    assert evaluate.main(["pd-match", str(written), "--pd-scale", "1.4", "--out", str(tmp_path), "--force"]) == 2
    assert json.loads(written.read_text())["provenance"]["pd_matched"] == record


@pytest.mark.parametrize("args", [["--kd", "1", "1", "1"], ["--pd-scale", "0"], ["--pd-scale", "nan"],
                                  ["--pd-scale", "1.4", "--kp", "80", "80", "80"], ["--kp", "80", "80", "-1"]])
def test_bad_gains_are_refused_before_any_walk(args, tmp_path):
    with pytest.raises(SystemExit) as exit_:  # by the command line's parser
        evaluate.main(["pd-match", str(SHIPPED), *args, "--out", str(tmp_path)])
    assert exit_.value.code == 2
    assert not any(tmp_path.iterdir())


def test_kd_without_kp_and_a_sampled_path_are_refused_before_any_walk(tmp_path, capsys):
    from test_fast_paths import sampled_trajectory

    from cyberdog.core.learned_set import LearnedPath

    out = tmp_path / "out"
    assert evaluate.main(["pd-match", str(SHIPPED), "--pd-scale", "1.4", "--kd", "1", "1", "1", "--out", str(out)]) == 2
    assert "--kd goes with --kp" in capsys.readouterr().err
    sampled = LearnedPath("seed0", sampled_trajectory()).save(tmp_path / "in")
    assert evaluate.main(["pd-match", str(sampled), "--pd-scale", "1.4", "--out", str(out)]) == 2
    assert "no foot shifts" in capsys.readouterr().err
    assert not out.exists()
