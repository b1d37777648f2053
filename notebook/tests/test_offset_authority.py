"""notebook/tools/offset_authority.py: a searched shape as foot offsets from the composite cycloid (no walking here)."""
import importlib.util
from pathlib import Path

import numpy as np
import pytest

from cyberdog.core import path_shape as so
from cyberdog.core.trajectories import CompositeCycloid
from conftest import walk_config

ROOT = Path(__file__).resolve().parents[2]
spec = importlib.util.spec_from_file_location("offset_authority", ROOT / "notebook" / "tools" / "offset_authority.py")
tool = importlib.util.module_from_spec(spec)
spec.loader.exec_module(tool)


def test_cycloid_plus_the_offsets_is_the_shape_and_clipping_bounds_them():
    cfg = walk_config(speed=1.2, lift_height=0.095)
    shape = so.shape_trajectory(so.ShapeParams(x_law=1.0, x_skew=0.3, stance_law=0.3), cfg.gait)
    delta = tool.shape_offsets(shape, cfg)
    g = cfg.gait
    phase = np.arange(len(delta)) / len(delta)
    args = (g.step_length, g.lift_height, g.swing_time, g.stance_time)
    cycloid, _ = CompositeCycloid().position_velocity(phase, *args)
    target, _ = shape.position_velocity(phase, *args)
    np.testing.assert_allclose(cycloid + delta, target, atol=1e-12)
    assert np.abs(delta[:, 0]).max() > 0.03  # this shape needs more than the presets' ±3 cm along x
    path = tool.offset_path(delta, g.period, 0.03)
    assert path.offsets.shape == (4, len(delta), 3)
    assert np.abs(path.offsets).max() == pytest.approx(0.03) and not path.offsets[:, :, 1].any()
    np.testing.assert_array_equal(path.offsets[0], path.offsets[3])  # the same on every leg
    free = tool.offset_path(delta, g.period, None)
    np.testing.assert_allclose(free.offsets[2, :, [0, 2]].T, delta)


def test_the_cycloid_itself_needs_no_offset():
    cfg = walk_config(speed=1.0, lift_height=0.10)
    assert np.abs(tool.shape_offsets(so.shape_trajectory(so.CYCLOID_PARAMS, cfg.gait), cfg)).max() < 1e-9
