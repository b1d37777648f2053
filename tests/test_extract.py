"""Extraction of the learned foot trajectory (paper Section 3, after Figure 6) from recorded rollout traces."""
import json

import numpy as np
import pytest

from cyberdog import config as C
from cyberdog.analysis.extract import ExtractionError, cycle_rows
from cyberdog.analysis.extract_measured import debounce, extract_trajectory, foot_paths, touch_downs
from cyberdog.core import kinematics as kin
from cyberdog.core.trajectories import CompositeCycloid, SampledTrajectory

DT = 0.001  # s
PERIOD = 0.4  # s, 0.2 s swing + 0.2 s stance
S, H = 0.2, 0.10  # m, the synthetic gait's step length and lift height (v = 1 m/s)


def synthetic_traces(levels, speeds, bounce_at=None):
    """A trot whose LF foot follows the composite cycloid exactly (phase 0 = lift-off at t = k·PERIOD).

    Cycle k (touch-down to touch-down, t ∈ [k·0.4 + 0.2, k·0.4 + 0.6)) has joint power 12·levels[k] W and
    body speed speeds[k] m/s, so its Eq. (7) energy is 12·levels[k]·0.4 J.
    """
    robot = C.RobotConfig()
    n_cycles = len(levels)
    n = int(round((n_cycles + 1) * PERIOD / DT))
    t = np.arange(n) * DT
    phase = np.mod(t / PERIOD, 1.0)
    pos, _ = CompositeCycloid().position_velocity(phase, S, H, 0.2, 0.2)
    stand = robot.body_height - robot.foot_radius
    feet = np.zeros((n, 4, 3))
    feet[..., 0] = pos[:, None, 0]
    feet[..., 1] = kin.LEFT_RIGHT * robot.l1
    feet[..., 2] = pos[:, None, 1] - stand
    q = kin.inverse_kinematics(feet, robot, np.broadcast_to(kin.LEFT_RIGHT, (n, 4))).reshape(n, 12)
    contacts = np.zeros((n, 4), dtype=bool)
    contacts[:, 0] = contacts[:, 3] = phase >= 0.5
    contacts[:, 1] = contacts[:, 2] = phase < 0.5
    if bounce_at is not None:  # a 3 ms bounce just after a touch-down
        contacts[bounce_at:bounce_at + 3, 0] = False
    cycle = np.floor((t - 0.2) / PERIOD + 1e-9).astype(int)  # −1 before the first touch-down
    level = np.where(cycle >= 0, np.asarray(levels)[np.clip(cycle, 0, n_cycles - 1)], 1.0)
    speed = np.where(cycle >= 0, np.asarray(speeds)[np.clip(cycle, 0, n_cycles - 1)], 1.0)
    base = np.zeros((n, 3))
    base[:, 0] = np.concatenate([[0.0], np.cumsum(speed[:-1] * DT)])
    base[:, 2] = 0.3
    return {"t": t, "q": q, "dq": np.ones((n, 12)), "tau": level[:, None] * np.ones((n, 12)),
            "contacts": contacts, "base_position": base}


def test_debounce_removes_short_runs_only():
    x = np.array([1, 1, 1, 1, 0, 1, 1, 1, 0, 0, 0, 0, 1, 0, 0, 0], dtype=bool)
    assert debounce(x, 3).tolist() == [True] * 8 + [False] * 8
    assert debounce(x, 1).tolist() == x.tolist()
    assert touch_downs(x, 3).tolist() == []
    assert touch_downs(np.array([0, 0, 1, 1, 0, 0, 1], dtype=bool)).tolist() == [2, 6]


def test_foot_paths_invert_the_controllers_ik():
    tr = synthetic_traces([1.0], [1.0])
    xz = foot_paths(tr["q"], C.RobotConfig())
    pos, _ = CompositeCycloid().position_velocity(np.mod(tr["t"] / PERIOD, 1.0), S, H, 0.2, 0.2)
    assert np.allclose(xz[:, 0, :], pos, atol=1e-9) and np.allclose(xz[:, 3, :], pos, atol=1e-9)


def test_the_cheapest_cycle_within_the_speed_band_is_extracted():
    # cycle 2 is the cheapest but too slow (0.8 m/s); cycle 4 is the cheapest in the ±5 % band
    levels = [5.0, 4.0, 1.0, 3.0, 2.0, 2.5, 6.0]
    speeds = [1.0, 1.02, 0.8, 0.99, 1.03, 1.0, 1.0]
    tr = synthetic_traces(levels, speeds, bounce_at=int(round((0.2 + 3 * PERIOD) / DT)) + 2)
    ex = extract_trajectory(tr, DT, 1.0, gait=C.GaitConfig(lift_height=H), settle_time=0.0,
                            provenance={"policy": "synthetic", "seed": 7})
    assert ex.chosen.index == 4
    assert ex.chosen.energy == pytest.approx(12 * 2.0 * PERIOD, rel=1e-9)
    assert ex.chosen.speed == pytest.approx(1.03, rel=1e-6)
    # every cycle the trace holds whole: touch-downs at 0.2 + 0.4·k s, the seventh cycle ends at 3.0 s of 3.2 s
    assert [c.index for c in ex.cycles] == list(range(len(levels)))
    assert not ex.cycles[2].speed_ok and ex.cycles[2].energy < ex.chosen.energy
    assert all(c.valid for c in ex.cycles), [c.reason for c in ex.cycles]  # the bounce was debounced
    traj = ex.trajectory
    assert traj.step_length == pytest.approx(S) and traj.lift_height == pytest.approx(H, abs=1e-3)
    # the extracted path replays the recorded one (phase 0 = lift-off)
    phase = np.linspace(0, 1, 200, endpoint=False)
    got, _ = traj.position_velocity(phase, S, traj.lift_height, 0.2, 0.2)
    want, _ = CompositeCycloid().position_velocity(phase, S, H, 0.2, 0.2)
    assert np.max(np.abs(got - want)) < 2e-3
    p = traj.provenance
    assert p["cycle_index"] == 4 and p["policy"] == "synthetic" and p["seed"] == 7
    assert p["cycle_energy_J"] == pytest.approx(ex.chosen.energy)
    rows = cycle_rows(ex)
    assert [r["chosen"] for r in rows].count(True) == 1 and rows[4]["chosen"]
    json.dumps(rows)


def test_skipped_cycles_give_the_next_cheapest_in_band_and_none_left_raises():
    """A cycle whose path was rejected is skipped: the next cheapest in the band is taken, and when every
    in-band cycle was skipped, the error says so (rather than taking one outside the band)."""
    levels = [5.0, 4.0, 1.0, 3.0, 2.0, 2.5]
    speeds = [1.0, 1.02, 0.8, 0.99, 1.03, 1.0]  # in band: 0, 1, 3, 4, 5; by energy 4, 5, 3, 1, 0
    tr = synthetic_traces(levels, speeds)
    gait = C.GaitConfig(lift_height=H)
    order = []
    for _ in range(5):
        ex = extract_trajectory(tr, DT, 1.0, gait=gait, settle_time=0.0, skip_cycles=order)
        assert ex.trajectory.provenance["cycles_skipped"] == sorted(order)
        order.append(ex.chosen.index)
    assert order == [4, 5, 3, 1, 0]
    with pytest.raises(ExtractionError, match="all 5 gait cycles .* replayed and rejected"):
        extract_trajectory(tr, DT, 1.0, gait=gait, settle_time=0.0, skip_cycles=order)


def test_extracted_trajectory_round_trips_with_provenance(tmp_path):
    tr = synthetic_traces([2.0, 1.0, 3.0], [1.0, 1.0, 1.0])
    ex = extract_trajectory(tr, DT, 1.0, gait=C.GaitConfig(lift_height=H), settle_time=0.0,
                            provenance={"policy": "p.pt", "seed": 3})
    for name in ("t.json", "t.csv"):
        back = SampledTrajectory.load(ex.trajectory.save(tmp_path / name))
        assert back.provenance["cycle_index"] == 1 and back.provenance["seed"] == 3
        assert np.allclose(back.x, ex.trajectory.x) and back.lift_height == ex.trajectory.lift_height


def test_settle_time_and_period_mark_cycles_invalid():
    tr = synthetic_traces([1.0, 2.0, 3.0, 4.0, 5.0], [1.0] * 5)
    tr["contacts"][800:1000, 0] = True  # the foot never lifts in [0.8, 1.0) s: one cycle of 0.8 s
    ex = extract_trajectory(tr, DT, 1.0, gait=C.GaitConfig(lift_height=H), settle_time=0.5)
    assert [c.valid for c in ex.cycles] == [False, False, True, True]
    assert "settle" in ex.cycles[0].reason and "duration" in ex.cycles[1].reason
    assert ex.cycles[1].duration == pytest.approx(0.8, abs=2 * DT)
    assert ex.chosen.index == 2  # the first valid one is the cheapest


@pytest.mark.parametrize("kwargs, match", [
    ({"speed_command": 2.0}, "no gait cycle"),
    ({"speed_command": 1.0, "leg": "XX"}, "leg"),
    ({"speed_command": -1.0}, "speed_command"),
    ({"speed_command": 1.0, "speed_tolerance": 1.5}, "speed_tolerance"),
])
def test_bad_input_and_no_qualifying_cycle_raise(kwargs, match):
    tr = synthetic_traces([1.0, 2.0], [1.0, 1.0])
    with pytest.raises(ValueError, match=match):
        extract_trajectory(tr, DT, settle_time=0.0, **kwargs)
    assert issubclass(ExtractionError, ValueError)


def test_too_short_rollout_raises():
    tr = {k: v[:1] for k, v in synthetic_traces([1.0], [1.0]).items()}
    with pytest.raises(ExtractionError, match="samples"):
        extract_trajectory(tr, DT, 1.0)
