"""notebook/tools/stance_terms.py: the phase split sums what it is given, per joint type, and the CLI refuses bad
gains."""
from __future__ import annotations

import argparse
import importlib.util
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]
spec = importlib.util.spec_from_file_location("stance_terms", ROOT / "notebook/tools/stance_terms.py")
tool = importlib.util.module_from_spec(spec)
spec.loader.exec_module(tool)


def test_the_split_sums_each_joint_type_over_the_masked_rows():
    rng = np.random.default_rng(0)
    values = rng.uniform(0, 5, (40, 12))
    mask = rng.uniform(size=(40, 12)) < 0.5
    dt = 0.01
    stance, swing = tool.by_joint_type(values, ~mask, dt), tool.by_joint_type(values, mask, dt)
    for j in range(3):  # abad, hip, knee: columns j, j + 3, j + 6, j + 9
        cols = [j, j + 3, j + 6, j + 9]
        assert stance[j] == pytest.approx(sum(values[r, c] for r in range(40) for c in cols if not mask[r, c]) * dt)
        assert stance[j] + swing[j] == pytest.approx(values[:, cols].sum() * dt)


def test_the_rms_is_over_the_masked_entries_only():
    values = np.zeros((4, 12))
    values[:, 2::3] = [[3.0], [4.0], [100.0], [100.0]]  # the knees
    mask = np.zeros((4, 12), bool)
    mask[:2] = True
    abad, hip, knee = tool.rms_by_joint_type(values, mask)
    assert (abad, hip) == (0.0, 0.0)
    assert knee == pytest.approx(np.sqrt((9 + 16) / 2))
    assert all(np.isnan(tool.rms_by_joint_type(values, np.zeros((4, 12), bool))))


@pytest.mark.parametrize("text", ["1", "a:b", "0:1", "1:-2"])
def test_gains_refuses_what_is_not_two_positive_factors(text):
    with pytest.raises(argparse.ArgumentTypeError):
        tool.gains(text)
    assert tool.gains("0.5:2") == (0.5, 2.0)
