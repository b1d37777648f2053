"""notebook/tools/smooth_offsets.py: the low-pass keeps the gait's slow harmonics and removes the agent step's."""
from __future__ import annotations

import importlib.util
import json
from pathlib import Path

import numpy as np
import pytest

from cyberdog.core.commanded_path import CommandedPath
from cyberdog.core.foot_offsets import FootOffsetPath

ROOT = Path(__file__).resolve().parents[2]
spec = importlib.util.spec_from_file_location("smooth_offsets", ROOT / "notebook/tools/smooth_offsets.py")
tool = importlib.util.module_from_spec(spec)
spec.loader.exec_module(tool)

N, PERIOD = 160, 0.4  # the shipped paths' table: 2.5 ms samples over a 0.4 s gait


def _table(harmonic_amplitudes: dict[int, float]) -> np.ndarray:
    phase = np.arange(N) / N
    wave = sum(a * np.sin(2 * np.pi * k * phase) for k, a in harmonic_amplitudes.items())
    return np.repeat(wave[None, :, None], 4, axis=0).repeat(3, axis=2) + 0.004  # a mean shift, kept


def test_slow_harmonics_pass_and_fast_ones_are_removed():
    slow = _table({1: 0.01, 5: 0.003})
    mixed = slow + _table({16: 0.002, 32: 0.001}) - 0.004
    out = tool.low_passed(FootOffsetPath(mixed, PERIOD), 8)
    np.testing.assert_allclose(out.offsets, slow, atol=1e-12)
    assert out.period == PERIOD
    with pytest.raises(ValueError, match="harmonics"):
        tool.low_passed(FootOffsetPath(slow, PERIOD), 0)


def test_the_rate_jumps_of_a_ramped_path_shrink():
    # the controller's ramp: a new shift every 10 samples (25 ms), linear in between, so the rate jumps
    steps = np.random.default_rng(0).normal(0, 0.01, 16)
    knots = np.append(steps, steps[0])
    ramp = np.concatenate([np.linspace(knots[i], knots[i + 1], 10, endpoint=False) for i in range(16)])
    table = np.repeat(ramp[None, :, None], 4, axis=0).repeat(3, axis=2)
    jump = lambda t: np.abs(np.diff(np.diff(t[0, :, 0], append=t[0, 0, 0]))).max()  # noqa: E731
    assert jump(tool.low_passed(FootOffsetPath(table, PERIOD), 8).offsets) < 0.5 * jump(table)


def test_the_tool_copies_every_path_and_records_the_low_pass(tmp_path):
    src = ROOT / "results/battery/paths"
    out = tmp_path / "learned"
    assert tool.main([str(src), str(out), "--harmonics", "8"]) == 0
    names = sorted(p.name for p in src.glob("*.json"))
    assert sorted(p.name for p in out.glob("*.json")) == names
    before, after = CommandedPath.load(src / names[0]), CommandedPath.load(out / names[0])
    assert after.speed == before.speed and after.gait == before.gait
    assert not np.allclose(after.offsets.offsets, before.offsets.offsets)
    assert json.loads((out / names[0]).read_text())["provenance"]["low_passed"]["harmonics"] == 8
    with pytest.raises(SystemExit):
        tool.main([str(out), str(out)])
