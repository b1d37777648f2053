"""Prototype experiment in simulation (paper Section 4.2): hardware-like robot options, distance walks, battery."""
import dataclasses
import json
import math

import numpy as np
import pytest

from cyberdog import config as C
from conftest import commanded, learned_set
from cyberdog.analysis import prototype as proto
from cyberdog.analysis import prototype_summary as summary
from cyberdog.analysis.stats import mean_ci
from cyberdog.control.trot import BodyFeedback, TrotController
from cyberdog.loop.walker import Walker
from cyberdog.sim.hardware_model import CommandDelay, draw_mass_scale, hardware_walk_config
from cyberdog.analysis.walk import walk
from cyberdog.core import energy as en
from cyberdog.sim.robot import Robot

CFG = C.WalkConfig()
SHORT_S = 1.5  # s of walking for the direction tests (includes the 1 s start-up ramp)


@pytest.fixture(scope="module")
def ideal_walk():
    return walk(CFG, duration=SHORT_S, record=True)


# ---- HardwareConfig ---------------------------------------------------------------------------------------

def test_hardware_config_defaults_are_the_ideal_robot_and_bad_values_raise():
    assert C.HardwareConfig().ideal and not C.HARDWARE_LIKE.ideal
    assert C.HARDWARE_LIKE.latency_s == 0.0025 and C.HARDWARE_LIKE.mass_uncertainty == 0.05
    for field, value, match in [("latency_s", -0.001, "latency_s"), ("latency_s", 0.5, "latency_s"),
                                ("mass_uncertainty", 0.6, "mass_uncertainty"), ("seed", -1, "seed"),
                                ("joint_angle_noise_std", float("nan"), "joint_angle_noise_std"),
                                ("imu_noise", True, "imu_noise")]:
        with pytest.raises(ValueError, match=match):
            C.HardwareConfig(**{field: value})
    with pytest.raises(ValueError, match="whole multiple"):
        walk(CFG, duration=0.01, hardware=C.HardwareConfig(latency_s=0.003))
    with pytest.raises(ValueError, match="distance"):
        walk(CFG, duration=1.0, distance=-1.0)
    with pytest.raises(TypeError, match="HardwareConfig"):
        walk(CFG, duration=0.01, hardware={"friction": True})


def test_all_off_hardware_path_reproduces_the_ideal_walk_exactly(ideal_walk):
    r = walk(CFG, duration=SHORT_S, hardware=C.HardwareConfig(seed=5))
    assert r.energy == ideal_walk.energy and r.electrical_energy == ideal_walk.electrical_energy
    assert r.distance == ideal_walk.distance and r.mass_scale == 1.0


# ---- each effect, in the expected direction -------------------------------------------------------------

def test_latency_delays_the_command_and_the_drivers_pd_acts_on_the_state_on_arrival():
    delay = CommandDelay(3)
    assert [delay.push(k) for k in range(1, 7)] == [None, None, None, 1, 2, 3]
    assert CommandDelay(0).push("now") == "now"
    with pytest.raises(ValueError, match="latency"):
        CommandDelay(-1)
    # in a walk: 7.5 ms at 400 Hz = no command for the first 3 periods; then in period k the drivers apply
    # the command of period k - 3 with their PD on the joint state at each physics step of period k
    dt, n = CFG.sim.controller_dt, CFG.sim.physics_substeps
    with Walker(CFG, hardware=C.HardwareConfig(latency_s=3 * dt)) as late:
        sent, command = [], late.controller.command
        late.controller.command = lambda *a, **k: sent.append(command(*a, **k)) or sent[-1]
        assert all(np.all(late.step() == 0) for _ in range(3))
        for _ in range(38):
            late.step()
        p, q = late.physics_traces(), late.physics_q.view()
        pd, actuator = late.controller.driver_torque, late.robot.actuator

        def applied(k, row):  # the motor torque of the command sent in period k, at physics step `row`
            dq = p["dq"][row - 1]  # the speed at the step's start: PyBullet's after the step before
            return np.array(actuator.joint_torque(pd(sent[k], q[row], dq), dq.tolist())[0])

        for row in range(40 * n, 41 * n):  # period 40
            np.testing.assert_allclose(p["tau"][row], applied(37, row), rtol=1e-12, atol=1e-12)
            assert not np.allclose(p["tau"][row], applied(40, row), atol=1e-3)  # not the newest command


def test_latency_on_the_command_costs_little_energy(ideal_walk):
    """The drivers close the PD on fresh readings: a 5 ms command delay only shifts the targets in time
    (measured: within a few per cent of the ideal robot's Eq. 7, where a delay inside the PD loop cost +8 %)."""
    late = walk(CFG, duration=SHORT_S, hardware=C.HardwareConfig(latency_s=0.005))
    assert not late.fell and abs(late.energy / ideal_walk.energy - 1.0) < 0.05


def test_friction_is_simulated_and_counted_once(ideal_walk):
    hw = C.HardwareConfig(friction=True)
    assert hardware_walk_config(CFG, hw).actuator.friction and not CFG.actuator.friction
    r = walk(CFG, duration=SHORT_S, hardware=hw, record=True)
    assert np.abs(r.traces["tau"] - ideal_walk.traces["tau"]).max() > 1.0  # the physics changed
    # Ideal: friction added analytically to the electrical power; hardware-like: in the physics. Both count it
    # once, so they agree closely; counting it twice (analytic on top of simulated) would add about 3 %.
    assert r.electrical_energy == pytest.approx(ideal_walk.electrical_energy, rel=0.015)
    twice = en.electrical_energy(r.traces["tau"], r.traces["dq"], CFG.sim.controller_dt, CFG.actuator, CFG.energy)
    assert twice > r.electrical_energy * 1.015
    with pytest.raises(ValueError, match="ActuatorConfig"):  # a robot built without friction is refused
        with Robot(CFG.robot, CFG.actuator, CFG.sim) as robot:
            walk(CFG, duration=0.01, robot=robot, hardware=hw)


def test_mass_scale_is_within_5_percent_reproducible_and_applied(ideal_walk):
    draws = [draw_mass_scale(C.HardwareConfig(mass_uncertainty=0.05, seed=s)) for s in range(200)]
    assert all(0.95 <= d <= 1.05 for d in draws) and min(draws) < 0.96 and max(draws) > 1.04
    assert len(set(draws)) == 200
    assert draws[7] == draw_mass_scale(C.HardwareConfig(mass_uncertainty=0.05, seed=7))
    # the sensors do not shift the mass draw (independent streams of one seed)
    assert draws[0] == draw_mass_scale(C.HARDWARE_LIKE)
    heavy_seed = next(s for s, d in enumerate(draws) if d > 1.03)
    hw = C.HardwareConfig(mass_uncertainty=0.05, seed=heavy_seed)
    with Robot(CFG.robot, CFG.actuator, CFG.sim) as robot:
        r = walk(CFG, duration=SHORT_S, robot=robot, hardware=hw)
        assert robot.total_mass() == pytest.approx(CFG.robot.total_mass * draws[heavy_seed], rel=1e-3)
    assert r.mass_scale == draws[heavy_seed]
    assert r.electrical_energy > 1.03 * ideal_walk.electrical_energy  # heavier robot, same gait


def test_estimated_speed_feedback_with_noise_still_walks():
    r = walk(CFG, duration=3.0, distance=1.5, hardware=C.HardwareConfig(
        estimated_velocity=True, imu_noise=True, joint_angle_noise_std=0.002, joint_velocity_noise_std=0.05))
    assert r.reached and r.distance >= 1.5


# ---- distance walks -----------------------------------------------------------------------------------------

def test_distance_walk_stops_at_the_goal_or_at_the_time_cap():
    r = walk(CFG, duration=5.0, distance=0.5)
    assert r.reached and 0.5 <= r.distance < 0.502 and r.duration < 5.0
    capped = walk(CFG, duration=0.3, distance=100.0)
    assert not capped.reached and capped.duration == pytest.approx(0.3)


# ---- the prototype rows --------------------------------------------------------------------------------------

@pytest.fixture(scope="module")
def rows():
    return proto.run_prototype({"cycloid": None}, speeds=(1.0,), distance_m=2.0, workers=2, draws=1, run_up_s=0.0,
                               log=lambda _: None)


def test_2m_prototype_gives_ideal_and_hardware_rows(rows):
    assert [(r["trajectory"], r["speed_mps"], r["robot"]) for r in rows] == [
        ("cycloid", 1.0, "ideal"), ("cycloid", 1.0, "hardware")]
    ideal, hw = rows
    assert ideal["reached"] and hw["reached"] and not ideal["fell"] and not hw["fell"]
    assert ideal["mass_scale"] == 1.0 and hw["mass_scale"] == draw_mass_scale(C.HARDWARE_LIKE)
    assert hw["electrical_energy_J"] > ideal["electrical_energy_J"]  # measured: about +12 %
    expected_gap = 100 * ((hw["electrical_energy_J"] / hw["distance_m"])
                          / (ideal["electrical_energy_J"] / ideal["distance_m"]) - 1)
    assert hw["electrical_gap_pct"] == pytest.approx(expected_gap)
    text = proto.prototype_table(rows)
    assert "ASSUMPTION" in text and "3600" in text and "electrical_gap_pct" in text
    # how much the body rocked, in every row: a steady trot from a stand rocks by a few degrees, not by none
    for r in rows:
        assert 0.0 < r["max_roll_rad"] < 0.15 and 0.0 < r["max_pitch_rad"] < 0.15, r


def test_battery_percent_is_eq13_and_range_is_consistent(rows):
    e = CFG.energy
    assert len(rows) == 2  # the ideal and the hardware-like walk
    for r in rows:
        assert r["battery_start_pct"] == pytest.approx(95.0)
        assert r["battery_used_pct"] == pytest.approx(r["battery_start_pct"] - r["battery_end_pct"])  # Eq. (13)
        assert r["battery_used_pct"] == pytest.approx(100 * r["electrical_energy_J"] / (e.battery_capacity_wh * 3600))
        assert r["range_full_charge_m"] == pytest.approx(r["distance_m"] * 95.0 / r["battery_used_pct"])
        assert r["range_full_charge_m"] == pytest.approx(
            en.range_at_full_charge(r["electrical_energy_J"], r["distance_m"], e))


def test_eq12_reductions_and_gap_table_from_synthetic_rows(tmp_path):
    """Every reduction in prototype_gaps is against the cheaper common trajectory on the same robot (never the
    searched reference shape, even when it is cheaper), and the sim-to-real gap compares one quantity (battery
    per metre) on the two robots. Read back from the written report."""
    def row(name, robot, e_mech, pct):
        return {"trajectory": name, "speed_mps": 1.0, "robot": robot, "distance_m": 100.0, "energy_J": e_mech,
                "electrical_energy_J": 10 * e_mech, "battery_used_pct": pct, "range_full_charge_m": 9500 / pct,
                "fell": False, "reached": True, "mean_speed_mps": 1.0}
    rows = proto.add_gaps([row("learned", "ideal", 880.0, 2.0), row("learned", "hardware", 900.0, 2.73),
                           row("cycloid", "ideal", 1000.0, 2.5), row("cycloid", "hardware", 1100.0, 3.0),
                           row("straight", "ideal", 1200.0, 2.4), row("straight", "hardware", 1300.0, 3.3),
                           row("searched", "ideal", 700.0, 1.5), row("searched", "hardware", 750.0, 1.9)])
    proto.write_prototype(rows, tmp_path)
    gaps = {g["trajectory"]: g for g in json.loads((tmp_path / "prototype_gaps.json").read_text())}
    learned = gaps["learned"]
    assert (learned["reference_ideal"], learned["reference_hardware"]) == ("straight", "cycloid")
    assert learned["battery_reduction_ideal_pct"] == pytest.approx(100 * (2.4 - 2.0) / 2.4)
    assert learned["battery_reduction_hardware_pct"] == pytest.approx(9.0)  # (3.0 − 2.73) / 3.0
    assert learned["sim_to_real_gap_pp"] == pytest.approx(100 * (2.4 - 2.0) / 2.4 - 9.0)
    assert learned["eq7_reduction_ideal_pct"] == pytest.approx(12.0)  # (1000 − 880) / 1000, Table 5's measure
    assert gaps["searched"]["battery_reduction_hardware_pct"] == pytest.approx(100 * (3.0 - 1.9) / 3.0)
    assert gaps["cycloid"]["battery_reduction_hardware_pct"] == pytest.approx(0.0)  # the reference itself
    assert gaps["cycloid"]["mechanical_gap_pct"] == pytest.approx(10.0)
    assert en.energy_reduction(1845.1, 1623.6) == pytest.approx(0.12, abs=0.001)  # Table 5 at 1 m/s


def test_run_prototype_rejects_bad_input_before_walking():
    for kwargs, match in [(dict(speeds=()), "speeds"), (dict(speeds=(-1.0,)), "speeds"),
                          (dict(distance_m=0.0), "distance_m"), (dict(modes=("real",)), "modes"),
                          (dict(workers=0), "workers"), (dict(trajectories={}), "trajectories")]:
        with pytest.raises(ValueError, match=match):
            proto.run_prototype(**kwargs, log=lambda _: None)
    with pytest.raises(ValueError, match="run_up_s"):
        proto.run_prototype(run_up_s=-1.0, log=lambda _: None)
    with pytest.raises(TypeError, match="FootTrajectory"):
        proto.run_prototype({"x": "cycloid"}, log=lambda _: None)
    assert math.isfinite(proto.time_cap(100.0, 1.0, CFG))
    assert dataclasses.replace(C.HARDWARE_LIKE, seed=3).seed == 3


def test_a_run_up_is_walked_before_the_measured_distance():
    """With run_up_s the measured walk starts at speed: its distance, time and battery use are those after the
    run-up."""
    kw = dict(speeds=(1.2,), distance_m=2.0, modes=("ideal",), workers=1, log=lambda _: None)
    (stand,), (run_up,) = proto.run_prototype({"cycloid": None}, run_up_s=0.0, **kw), proto.run_prototype(
        {"cycloid": None}, run_up_s=1.5, **kw)
    assert stand["run_up_s"] == 0.0 and run_up["run_up_s"] == 1.5 and run_up["reached"]
    assert 2.0 <= run_up["distance_m"] < 2.01
    assert run_up["time_s"] == pytest.approx(2.0 / 1.2, rel=0.1)  # at speed throughout
    assert run_up["time_s"] < stand["time_s"] - 0.4  # the ramp from a stand is left out


# ---- the prototype at scale: every learned seed, several hardware-like robots -------------------------------

def test_every_seed_walks_with_the_common_trajectories_at_its_lift_on_each_draw():
    learned = learned_set(seed0=[commanded(1.0, -0.01, 0)], seed1=[commanded(1.0, -0.03, 1)])
    rows = proto.run_prototype(speeds=(1.0,), distance_m=0.5, modes=("ideal", "hardware"), workers=2, draws=2,
                               run_up_s=0.0, learned=learned, log=lambda _: None)
    assert len(rows) == 2 * 3 * (1 + 2)  # seeds × trajectories × (ideal + 2 draws)
    for seed, lift in (("seed0", 0.09), ("seed1", 0.07)):
        mine = [r for r in rows if r["seed"] == seed]
        assert {r["trajectory"] for r in mine} == {"learned", "cycloid", "straight"}
        assert all(r["lift_height_m"] == pytest.approx(lift, abs=2e-3) for r in mine if r["trajectory"] != "learned")
    hw = [r for r in rows if r["robot"] == "hardware"]
    scales = {r["draw"]: r["mass_scale"] for r in hw}
    assert sorted(scales) == [0, 1] and scales[0] != scales[1]  # two robots, each shared by every trajectory
    assert all(r["mass_scale"] == scales[r["draw"]] for r in hw)
    assert {r["draw"] for r in rows if r["robot"] == "ideal"} == {0}


def proto_row(trajectory: str, seed: str, draw: int, battery_pct: float, **kw) -> dict:
    """A synthetic 20 m hardware walk using `battery_pct` of the pack."""
    row = {"trajectory": trajectory, "seed": seed, "draw": draw, "speed_mps": 1.0, "robot": "hardware",
           "reached": True, "fell": False, "mean_speed_mps": 1.0, "distance_m": 20.0,
           "battery_used_pct": battery_pct, "energy_J": 2000.0, "electrical_energy_J": 7000.0,
           "electrical_cost_of_transport": 2.5, "range_full_charge_m": 20.0 * 95 / battery_pct}
    return {**row, **kw}


def test_the_summary_pairs_each_learned_walk_with_the_cheaper_common_one_on_the_same_robot():
    rows = [proto_row("learned", "s0", 0, 0.9), proto_row("cycloid", "s0", 0, 1.0), proto_row("straight", "s0", 0, 1.2),
            proto_row("learned", "s0", 1, 0.8), proto_row("cycloid", "s0", 1, 1.0), proto_row("straight", "s0", 1, 0.9),
            proto_row("learned", "s1", 0, 1.1), proto_row("cycloid", "s1", 0, 1.0), proto_row("straight", "s1", 0, 1.3),
            proto_row("learned", "s1", 1, 0.5, fell=True, reached=False, distance_m=3.0),
            proto_row("cycloid", "s1", 1, 1.0), proto_row("straight", "s1", 1, 1.3)]
    learned = next(r for r in summary.summary_rows(rows) if r["trajectory"] == "learned")
    # s0: 10 % (draw 0, against the cycloid) and 100·(1 − 0.8/0.9) (draw 1, against the straight line);
    # s1: −10 % (draw 0); its fallen walk of draw 1 does not count but is reported
    s0 = (10.0 + 100 * (1 - 0.8 / 0.9)) / 2
    assert summary.battery_savings(rows, "hardware", 1.0) == pytest.approx([s0, -10.0])
    mean, half = mean_ci([s0, -10.0])
    assert learned["battery_saving_pct_mean"] == pytest.approx(mean)
    assert learned["battery_saving_pct_ci95"] == pytest.approx(half)
    assert (learned["walks"], learned["counted"], learned["fell"], learned["seeds"]) == (4, 3, 1, 2)
    per_100m = [(4.5 + 4.0) / 2, 5.5]  # battery % per 100 m, per seed (s1: its counting walk only)
    assert learned["battery_pct_per_100m_mean"] == pytest.approx(np.mean(per_100m))
    text = summary.summary_markdown(summary.summary_rows(rows), "hardware")
    assert "3 of 4 / 1" in text and "(2 seeds)" in text


def test_the_searched_shape_is_a_reference_row_not_a_common_trajectory():
    """A "searched" walk cheaper than both common ones leaves the saving against the common trajectories as it
    was, and adds the learned path's saving against the searched shape alone (negative: the shape is cheaper)."""
    rows = [proto_row("learned", "s0", 0, 0.9), proto_row("cycloid", "s0", 0, 1.0), proto_row("straight", "s0", 0, 1.2),
            proto_row("searched", "s0", 0, 0.6),
            proto_row("learned", "s1", 0, 0.8), proto_row("cycloid", "s1", 0, 1.0), proto_row("straight", "s1", 0, 1.1),
            proto_row("searched", "s1", 0, 1.0)]
    learned = next(r for r in summary.summary_rows(rows) if r["trajectory"] == "learned")
    assert summary.battery_savings(rows, "hardware", 1.0) == pytest.approx([10.0, 20.0])
    assert learned["battery_saving_pct_mean"] == pytest.approx(15.0)
    vs_searched = [100 * (1 - 0.9 / 0.6), 100 * (1 - 0.8 / 1.0)]
    assert learned["battery_vs_searched_pct_mean"] == pytest.approx(np.mean(vs_searched))
    assert "vs the searched shape" in summary.summary_markdown(summary.summary_rows(rows), "hardware")
    without = [r for r in rows if r["trajectory"] != "searched"]
    assert "battery_vs_searched_pct_mean" not in next(
        r for r in summary.summary_rows(without) if r["trajectory"] == "learned")


def test_a_learned_rows_lift_height_is_its_paths_own_like_its_baselines():
    """One meaning per column: a learned row's lift_height_m is the path's own lift, the same as the common
    trajectories matched to it; the trot under a commanded path has its H in trot_lift_height_m."""
    learned = learned_set(seed0=[commanded(1.0, -0.01, 0)])
    rows = proto.run_prototype(speeds=(1.0,), distance_m=0.3, modes=("ideal",), learned=learned, run_up_s=0.0,
                               trajectories={"cycloid": None}, workers=1, log=lambda *_: None)
    own = learned.path("seed0", 1.0).lift_height
    by = {r["trajectory"]: r for r in rows}
    assert by["learned"]["lift_height_m"] == pytest.approx(own) == by["cycloid"]["lift_height_m"]
    assert own < 0.1 and by["learned"]["trot_lift_height_m"] == pytest.approx(0.1)
    assert by["cycloid"]["trot_lift_height_m"] is None
