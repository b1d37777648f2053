"""A foot path's stance width (`FootTrajectory.foot_inset`): the trot places every foot that much nearer the body's
midline, the searched shape carries it in its file, and the search walks it."""
import numpy as np
import pytest

from cyberdog import config as C
from cyberdog.analysis import shape_search
from cyberdog.control.trot import TrotController
from cyberdog.core import kinematics as kin
from cyberdog.core.path_shape import CYCLOID_PARAMS, shape_trajectory
from cyberdog.core.trajectories import SampledTrajectory, make_trajectory


def _shape(inset: float = 0.0) -> SampledTrajectory:
    return shape_trajectory(CYCLOID_PARAMS, C.GaitConfig(lift_height=0.10), foot_inset=inset)


def test_the_trot_moves_every_foot_toward_the_midline_by_the_inset():
    cfg = C.WalkConfig(gait=C.GaitConfig(lift_height=0.10))
    t = 0.37  # mid-gait: two legs swing, two stand
    plain = TrotController(cfg, _shape()).targets(t)
    narrow = TrotController(cfg, _shape(0.02)).targets(t)
    side = np.asarray(kin.LEFT_RIGHT, dtype=float)
    np.testing.assert_allclose(narrow.foot_position[:, 1] - plain.foot_position[:, 1], -0.02 * side, atol=1e-12)
    np.testing.assert_array_equal(narrow.foot_position[:, [0, 2]], plain.foot_position[:, [0, 2]])
    # an inset of 0 is the paper's placement, below the hips, to the bit (y = ±l1)
    cycloid = TrotController(cfg, make_trajectory(cfg.gait)).targets(t)
    np.testing.assert_array_equal(plain.foot_position[:, 1], cycloid.foot_position[:, 1])
    np.testing.assert_array_equal(cycloid.foot_position[:, 1], side * cfg.robot.l1)


@pytest.mark.parametrize("suffix", [".json", ".csv"])
def test_the_inset_survives_the_file_and_old_files_have_none(tmp_path, suffix):
    path = _shape(-0.015).save(tmp_path / f"shape{suffix}")
    assert SampledTrajectory.load(path).foot_inset == -0.015
    assert SampledTrajectory.load(_shape().save(tmp_path / f"plain{suffix}")).foot_inset == 0.0
    assert "foot_inset" not in (tmp_path / f"plain{suffix}").read_text()  # files without one are as before


@pytest.mark.parametrize("bad", [0.1, -0.2, float("nan")])
def test_an_inset_beyond_the_leg_is_refused(bad):
    with pytest.raises(ValueError, match="foot_inset"):
        _shape(bad)


def test_the_search_walks_each_shape_at_its_inset(monkeypatch):
    seen = []

    def fake_walk(cfg, duration, trajectory=None, **kw):
        seen.append(trajectory.foot_inset)
        raise RuntimeError("stop before the physics")

    import cyberdog.analysis.walk as walk_module
    monkeypatch.setattr(walk_module, "walk", fake_walk)
    job = shape_search.ShapeWalk(CYCLOID_PARAMS, 1.0, 0.10, 2.0, 1.0, foot_inset=0.02)
    with pytest.raises(RuntimeError, match="stop"):
        shape_search.walk_cost(job)
    assert seen == [0.02]
