"""notebook/tools/extract_at_stiffness.py: its refusals, before any rollout."""
from __future__ import annotations

import importlib.util
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
spec = importlib.util.spec_from_file_location("extract_at_stiffness", ROOT / "notebook/tools/extract_at_stiffness.py")
tool = importlib.util.module_from_spec(spec)
spec.loader.exec_module(tool)


@pytest.mark.parametrize("scale", ["0", "-1", "nan"])
def test_a_stiffness_that_is_not_positive_is_refused(scale, tmp_path):
    with pytest.raises(SystemExit):
        tool.main(["--actor", str(ROOT / "notebook/results/policy_battery/stage2_actor.pt"), "--pd-scale", scale,
                   "--out", str(tmp_path)])


def test_a_missing_actor_and_a_torque_actor_are_refused(tmp_path, capsys):
    with pytest.raises(SystemExit):
        tool.main(["--actor", str(tmp_path / "none.pt"), "--pd-scale", "1.4", "--out", str(tmp_path)])
    with pytest.raises(SystemExit):  # a torque policy commands no foot path
        tool.main(["--actor", str(ROOT / "notebook/results/policy_torque/stage2_actor.pt"), "--pd-scale", "1.4",
                   "--out", str(tmp_path)])
    assert "not on foot targets" in capsys.readouterr().err
    assert not (tmp_path / "learned").exists()
