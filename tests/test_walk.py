"""The robot walks: scripted trot in PyBullet, its metrics, and evaluate.py baselines."""
import dataclasses
import json

import numpy as np
import pytest

from cyberdog import config as C
from cyberdog.analysis.walk import walk
from cyberdog.control.trot import BodyFeedback, TrotController


def walk_cfg(trajectory: str, speed: float) -> C.WalkConfig:
    cfg = C.WalkConfig()
    return dataclasses.replace(cfg, gait=dataclasses.replace(cfg.gait, trajectory=trajectory, speed=speed))


@pytest.mark.parametrize("trajectory", ["cycloid", "straight"])
def test_trot_walks_10_s_at_1_mps_on_its_feet(trajectory):
    r = walk(walk_cfg(trajectory, 1.0), duration=10.0)
    assert not r.fell
    assert abs(r.mean_speed - 1.0) <= 0.05, r.mean_speed
    assert r.lateral_drift < 0.3
    assert 0.9 * 10.0 < r.distance < 1.1 * 10.0
    assert r.non_foot_contacts == [], r.non_foot_contacts
    assert r.max_roll < 0.2 and r.max_pitch < 0.2


def test_recorded_power_integrates_to_the_reported_energy():
    r = walk(walk_cfg("cycloid", 1.0), duration=1.0, record=True)
    dt = C.SimConfig().controller_dt
    assert r.traces["power"].sum() * dt == pytest.approx(r.energy, rel=1e-9)
    assert r.energy_per_joint.sum() == pytest.approx(r.energy, rel=1e-12)
    assert r.electrical_energy > 0
    assert r.cost_of_transport == pytest.approx(r.energy / (13.573 * 9.81 * r.distance), rel=1e-9)


def test_standing_still_costs_almost_nothing_and_walking_faster_costs_more():
    still = walk(walk_cfg("cycloid", 0.0), duration=2.0)
    slow = walk(walk_cfg("cycloid", 1.0), duration=2.0)
    assert not still.fell and abs(still.distance) < 0.2
    assert slow.energy > still.energy


def test_controller_targets_follow_the_trajectory_through_ik():
    ctrl = TrotController(walk_cfg("cycloid", 1.0))
    tgt = ctrl.targets(0.05, BodyFeedback())
    from cyberdog.core import kinematics as kin
    feet = kin.foot_position(tgt.joint_angles.reshape(4, 3), ctrl.robot)
    assert np.allclose(feet, tgt.foot_position, atol=1e-9)
    assert tgt.in_swing.tolist() == [True, False, False, True]  # LF + RH swing first (Figure 9)
    with pytest.raises(ValueError, match="speed"):
        ctrl.set_speed(-1.0)


def test_evaluate_baselines_writes_results(tmp_path, capsys):
    import evaluate
    out = tmp_path / "eval"
    assert evaluate.main(["baselines", "--speeds", "1.0", "--trajectories", "cycloid", "--duration", "1",
                          "--out", str(out)]) == 0
    rows = json.loads((out / "baselines.json").read_text())
    assert len(rows) == 1 and rows[0]["speed_command_mps"] == 1.0
    assert (out / "baselines.csv").exists() and (out / "config.yaml").exists()
    assert "energy_J" in capsys.readouterr().out


@pytest.mark.parametrize("field, value, match", [
    ("speed", -1.0, "speed"), ("period", -0.4, "period"), ("lift_height", 0.0, "lift_height"),
    ("swing_time", 0.5, "swing_time"), ("trajectory", "spline", "trajectory"),
])
def test_bad_gait_inputs_raise(field, value, match):
    with pytest.raises(ValueError, match=match):
        C.GaitConfig(**{field: value})


def test_config_yaml_round_trip_and_overrides(tmp_path):
    cfg = C.override(C.WalkConfig(), ["gait.speed=1.2", "pid.kp=[70, 60, 60]"])
    C.save(cfg, tmp_path / "w.yaml")
    assert C.load(C.WalkConfig, tmp_path / "w.yaml") == cfg
    with pytest.raises(ValueError, match="no field"):
        C.override(cfg, ["gait.speeed=1"])
    with pytest.raises(ValueError, match="unknown"):
        C.from_dict(C.GaitConfig, {"sped": 1})


def test_a_walk_whose_trot_asks_for_a_foot_beyond_reach_ends_as_a_fall(monkeypatch):
    """A robot going down can make the trot ask for a foot target the leg cannot reach (the kinematics raise
    UnreachableFootTarget, a ValueError): the walk ends there as a fall, with the periods walked so far,
    instead of aborting a run of many walks. Any other error still propagates."""
    from cyberdog.core import kinematics as kin

    with pytest.raises(kin.UnreachableFootTarget):
        kin.leg_inverse_kinematics(0.0, 0.1, -0.6, 1.0, 0.1, 0.2, 0.2)
    assert issubclass(kin.UnreachableFootTarget, ValueError)
    original, calls = TrotController.command, []

    def command(self, *args, error=kin.UnreachableFootTarget, **kwargs):
        calls.append(1)
        if len(calls) == 100:
            raise error("unreachable foot target [-0.273, 0.131, -0.282]: outside the leg's reach")
        return original(self, *args, **kwargs)

    monkeypatch.setattr(TrotController, "command", command)
    cfg = C.WalkConfig()
    r = walk(cfg, duration=1.0)
    assert r.fell and r.duration == pytest.approx(99 * cfg.sim.controller_dt)
    calls.clear()
    monkeypatch.setattr(TrotController, "command", lambda self, *a, **k: command(self, *a, error=RuntimeError, **k))
    with pytest.raises(RuntimeError):
        walk(cfg, duration=1.0)


def test_a_run_up_is_walked_but_left_out_of_the_result():
    """walk(run_up=r): the same robot motion as a walk from a stand, with the first r seconds' time, energies
    and distance left out of the result; a distance goal counts from the run-up's end."""
    from conftest import walk_config
    cfg = walk_config(speed=1.2)
    whole, first = walk(cfg, 3.0, record=True), walk(cfg, 1.5)
    rest = walk(cfg, 3.0, run_up=1.5, record=True)
    assert rest.duration == pytest.approx(1.5) and not rest.fell
    assert rest.energy == pytest.approx(whole.energy - first.energy, rel=1e-9)
    assert rest.electrical_energy == pytest.approx(whole.electrical_energy - first.electrical_energy, rel=1e-9)
    k = int(round(1.5 / cfg.sim.controller_dt))
    x = whole.traces["base_position"][:, 0]  # at each period's start
    assert rest.distance == pytest.approx(whole.distance - (x[k] - x[0]), abs=1e-12)
    assert np.array_equal(rest.traces["tau"], whole.traces["tau"])  # the traces are the whole walk's
    goal = walk(cfg, 20.0, distance=2.0, run_up=1.5)
    assert 2.0 <= goal.distance < 2.0 + 1.2 * 2 * cfg.sim.controller_dt and goal.reached
    assert goal.duration == pytest.approx(2.0 / 1.2, rel=0.1)  # at speed from the start of the measured part
    for bad in (-0.1, 3.0, float("nan")):
        with pytest.raises(ValueError, match="run_up"):
            walk(cfg, 3.0, run_up=bad)


def test_a_long_walk_reports_each_simulated_second_and_a_replay_check_logs_a_heartbeat(monkeypatch):
    """A 100 m check walk is 20 s or more of wall time: `walk` calls `progress` once per simulated second (with
    the distance so far), and the replay check's heartbeat turns that into a line once its wall interval passed."""
    from cyberdog.analysis import replay_check as rc
    calls = []
    r = walk(walk_cfg("cycloid", 1.0), duration=3.0, progress=lambda t, x: calls.append((t, x)))
    assert [round(t, 6) for t, _ in calls] == [1.0, 2.0, 3.0]
    xs = [x for _, x in calls]
    assert xs == sorted(xs) and 0.5 < xs[-1] - xs[0] < 3.0  # forward, about 1 m/s after the ramp
    assert xs[-1] == pytest.approx(r.distance, abs=0.3)
    clock = iter([0.0, 4.0, 11.0, 12.0, 25.0])  # wall seconds: begin, then one reading per progress call
    monkeypatch.setattr(rc.time, "monotonic", lambda: next(clock))
    lines = []
    beat = rc.heartbeat(lines.append, "ideal robot, 100 m", 100.0, every_s=10.0)
    for t, x in [(1.0, 0.4), (2.0, 1.3), (3.0, 2.2), (4.0, 3.2)]:
        beat(t, x)
    assert lines == ["replay check, ideal robot, 100 m: 1 m of 100 (2 s walked)",
                     "replay check, ideal robot, 100 m: 3 m of 100 (4 s walked)"]
