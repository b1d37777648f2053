"""The learned path set: one loader, one rule for "the path at this speed", and a table and its figure that
show the same path."""
import numpy as np
import pytest

from conftest import commanded, learned_set
from cyberdog import config as C
from cyberdog.analysis import compare as cmp
from cyberdog.core.learned_set import SPEED_BAND, LearnedPath, LearnedSet, LearnedSetError
from cyberdog.core.trajectories import CompositeCycloid, SampledTrajectory
from plots import results


def sampled(seed: int, lift: float = 0.09) -> SampledTrajectory:
    phase = np.arange(100) / 100
    pos, _ = CompositeCycloid().position_velocity(phase, 0.2, lift, 0.2, 0.2)
    return SampledTrajectory.from_points(phase, pos[:, 0], pos[:, 1], 0.2, lift, {"seed": seed})


def test_files_round_trip_with_labels_from_the_seed_and_cycle_tables_left_out(tmp_path):
    learned = learned_set(seed10=[commanded(1.2, -0.02, 10), commanded(1.0, -0.01, 10)],
                          seed2=[commanded(1.0, -0.03, 2)])
    files = learned.save(tmp_path / "learned")
    assert sorted(f.name for f in files) == ["seed10_1.2mps.json", "seed10_1mps.json", "seed2_1mps.json"]
    (tmp_path / "learned" / "seed2_1mps_cycles.json").write_text("[]")  # extraction's per-cycle table
    back = LearnedSet.load([tmp_path / "learned"])
    assert back.labels == ["seed2", "seed10"] and back.speeds() == [1.0, 1.2]  # seeds in numeric order
    assert len(back.paths()) == len(learned.paths()) == 3
    for p, q in zip(learned.paths(), back.paths()):
        assert (p.label, p.speed) == (q.label, q.speed)
        assert q.lift_height == pytest.approx(p.lift_height, abs=1e-5)
    one = LearnedSet.load([tmp_path / "learned" / "seed10_1mps.json"])  # a file as given
    assert one.labels == ["seed10"] and len(one.paths()) == 1


def test_the_path_at_a_speed_is_the_nearest_within_the_band_else_an_error():
    learned = learned_set(seed0=[commanded(1.0, -0.01, 0), commanded(1.2, -0.02, 0)], seed1=[sampled(1)])
    assert learned.path("seed0", 1.0).speed == 1.0
    assert learned.path("seed0", 1.0 * (1 + 0.9 * SPEED_BAND)).speed == 1.0  # inside ±5 %
    assert learned.path("seed0", 1.16).speed == 1.2
    with pytest.raises(LearnedSetError, match=r"seed0 has no learned path at 1.1 m/s \(its paths are at 1, 1.2"):
        learned.at(1.1)
    assert not learned.covers(1.1) and learned.covers(1.2)
    assert learned.path("seed1", 3.0).speed is None  # a sampled path serves every speed
    with pytest.raises(LearnedSetError, match="no learned paths labelled 'seed7'"):
        learned.subset(["seed7"])
    assert learned.subset(["seed1"]).labels == ["seed1"]


def test_a_label_holds_one_sampled_path_or_commanded_paths_at_distinct_speeds():
    with pytest.raises(LearnedSetError, match="two learned paths for seed0 at 1 m/s"):
        learned_set(seed0=[commanded(1.0, -0.01, 0), commanded(1.0, -0.02, 0)])
    with pytest.raises(LearnedSetError, match="sampled path"):
        learned_set(seed0=[commanded(1.0, -0.01, 0), sampled(0)])
    with pytest.raises(TypeError, match="LearnedPath"):
        LearnedSet([commanded(1.0, -0.01, 0)])


def test_unreadable_or_missing_files_are_named(tmp_path):
    bad = tmp_path / "bad.json"
    bad.write_text("{not json")
    with pytest.raises(LearnedSetError, match="bad.json is unreadable"):
        LearnedSet.load([bad])
    with pytest.raises(LearnedSetError, match="does not exist"):
        LearnedSet.load([tmp_path / "missing.json"])
    (tmp_path / "empty").mkdir()
    with pytest.raises(LearnedSetError, match="holds no JSON file"):
        LearnedSet.load([tmp_path / "empty"])


def test_both_kinds_replay_through_one_interface():
    cfg = C.WalkConfig()
    c_cfg, c_traj, c_offsets = LearnedPath("seed0", commanded(1.2, -0.02, 0)).walk_args(cfg, 1.2)
    assert c_traj is None and c_offsets is not None and c_cfg.gait.lift_height == 0.10  # its own base trot
    s = LearnedPath("seed1", sampled(1, lift=0.09))
    s_cfg, s_traj, s_offsets = s.walk_args(cfg, 1.4)
    assert s_traj is s.path and s_offsets is None and s_cfg.gait.lift_height == 0.09 and s_cfg.gait.speed == 1.4
    with pytest.raises(LearnedSetError, match="does not walk at 1.4 m/s"):
        LearnedPath("seed0", commanded(1.2, -0.02, 0)).walk_args(cfg, 1.4)


def test_a_table_row_and_its_figure_use_the_same_path(tmp_path):
    """Table 5's learned walk at 1 m/s and Figure 7's drawn path come from the same file through one rule,
    even where the seed has another path at a nearby speed."""
    learned = learned_set(seed0=[commanded(1.0, -0.01, 0), commanded(1.2, -0.03, 0)],
                          seed1=[commanded(1.0, -0.02, 1), commanded(1.2, -0.04, 1)])
    folder = tmp_path / "results"
    learned.save(folder / "learned")
    jobs = cmp.comparison_jobs(C.WalkConfig(), LearnedSet.load([folder / "learned"]), speeds=(1.0,))
    walked = {j.seed: j.learned for j in jobs if j.trajectory == "learned"}
    assert sorted(walked) == ["seed0", "seed1"]
    drawn = results.load_results(folder)
    assert drawn.learned_speed == results.FIGURE7_SPEED == 1.0
    for label, path in walked.items():
        fig = drawn.learned[label]
        assert np.allclose(fig.z, path.figure_path().z) and np.allclose(fig.x, path.figure_path().x)
        other = learned.path(label, 1.2).figure_path()
        assert not np.allclose(fig.z, other.z)  # the 1.2 m/s path differs: the match above is not by chance
    # a set without 1 m/s: the figure names the speed it draws, the lowest one, and the table's path there
    only_fast = tmp_path / "fast"
    learned_set(seed0=[commanded(1.2, -0.03, 0), commanded(1.4, -0.01, 0)]).save(only_fast / "learned")
    fast = results.load_results(only_fast)
    assert fast.learned_speed == 1.2
    assert np.allclose(fast.learned["seed0"].z, LearnedSet.load([only_fast / "learned"]).path("seed0", 1.2)
                       .figure_path().z)


def test_a_figure_draws_the_seeds_that_have_a_path_at_its_speed():
    """A seed whose extraction found no path at 1 m/s (walked with --skip-missing-paths) is left out of the
    figure at 1 m/s, not an error; a speed no seed has is refused."""
    learned = learned_set(seed0=[commanded(1.2, -0.02, 0)], seed1=[commanded(1.0, -0.01, 1), commanded(1.2, -0.02, 1)])
    assert learned.figure_speed(1.0) == 1.0 and list(learned.figure_paths(1.0)) == ["seed1"]
    assert list(learned.figure_paths(1.2)) == ["seed0", "seed1"]
    assert learned.figure_speed(1.4) == 1.0  # no seed at 1.4 m/s: the lowest recorded speed
    with pytest.raises(LearnedSetError, match="1.4 m/s"):
        learned.figure_paths(1.4)
