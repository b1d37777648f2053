"""The closed-loop check of trained policies: what counts as walking, and the stage-2 reduction."""
import dataclasses
import math
from pathlib import Path

import pytest

from cyberdog import config as C
from cyberdog.analysis.policy_check import check_jobs, parse_robot, robot_env, stage_reductions


def row(label, stage, speed, energy, walks=True, duration=10.0, distance=10.0, robot="ideal", electrical=None):
    electrical = 4.0 * energy if electrical is None else electrical
    return {"label": label, "stage": stage, "robot": robot, "speed_command_mps": speed, "energy_J": energy,
            "walks": walks, "duration_s": duration, "energy_per_metre_J": energy / distance,
            "electrical_per_metre_J": electrical / distance}


def test_the_reduction_is_stage2_against_stage1_at_the_same_speed():
    rows = [row("s0", 1, 1.0, 1000.0), row("s0", 2, 1.0, 900.0), row("s0", 1, 1.4, 2000.0),
            row("s0", 2, 1.4, 2500.0, walks=False), row("s1", 1, 1.0, 800.0)]  # s1 has no stage 2
    got = {(r["label"], r["speed_command_mps"]): r for r in stage_reductions(rows)}
    assert set(got) == {("s0", 1.0), ("s0", 1.4)}
    assert got["s0", 1.0]["reduction_pct"] == pytest.approx(10.0) and got["s0", 1.0]["both_walk"]
    assert got["s0", 1.4]["reduction_pct"] == pytest.approx(-25.0) and not got["s0", 1.4]["both_walk"]


def test_the_reduction_per_metre_does_not_credit_walking_slower():
    """Stage 2 spends 10 % less over the same 10 s but walks 20 % less far: per metre it spends more."""
    (got,) = stage_reductions([row("s0", 1, 1.0, 1000.0, distance=10.0), row("s0", 2, 1.0, 900.0, distance=8.0)])
    assert got["reduction_pct"] == pytest.approx(10.0)
    assert got["reduction_per_metre_pct"] == pytest.approx(100.0 * (1.0 - (900.0 / 8.0) / (1000.0 / 10.0)))
    assert got["reduction_per_metre_pct"] < 0


def test_the_electrical_reduction_is_per_metre_and_robots_are_not_mixed():
    """Stage 2 against stage 1 on the same robot only; the battery's energy per metre beside Eq. 7's."""
    rows = [row("s0", 1, 1.0, 1000.0, electrical=5000.0), row("s0", 2, 1.0, 1000.0, electrical=4000.0, distance=8.0),
            row("s0", 1, 1.0, 1000.0, robot="hardware:0"), row("s0", 2, 1.0, 700.0, robot="hardware:1")]
    (got,) = stage_reductions(rows)
    assert got["robot"] == "ideal"
    assert got["electrical_reduction_per_metre_pct"] == pytest.approx(100.0 * (1.0 - (4000.0 / 8.0) / 500.0))


def test_a_robot_is_the_ideal_one_or_a_hardware_like_draw():
    env = C.EnvConfig(hardware=C.HardwareConfig(friction=True), randomization=C.RandomizationConfig(
        mass_scale=(0.9, 1.1)))
    ideal, hardware_robot = robot_env(env, "ideal")
    assert ideal.hardware.ideal and not ideal.randomization.enabled and not hardware_robot
    draw, hardware_robot = robot_env(env, "hardware:1")
    assert draw.hardware == dataclasses.replace(C.HARDWARE_LIKE, seed=1) and hardware_robot
    assert not draw.randomization.enabled and parse_robot("hardware:12") == 12 and parse_robot("ideal") is None
    for bad in ("hardware", "hardware:x", "real", "hardware:-1"):
        with pytest.raises(ValueError, match="'ideal' or 'hardware:N'"):
            parse_robot(bad)


def test_a_check_walks_in_the_engine_asked_for_or_the_actors_own():
    """`check --runs --set sim.engine=mujoco`: every job carries the engine, and the env it builds names it; without
    it the actor's env keeps its own."""
    env = C.EnvConfig()
    assert robot_env(env, "hardware:0", "mujoco")[0].walk.sim.engine == "mujoco"
    assert robot_env(env, "ideal")[0].walk.sim == env.walk.sim
    jobs = check_jobs({"s0": {1: __file__}}, [1.0, 1.2], 10.0, engine="mujoco")
    assert [job[-1] for job in jobs] == ["mujoco", "mujoco"]
    assert check_jobs({"s0": {1: __file__}}, [1.0], 10.0)[0][-1] is None


def test_the_trot_reference_row_walks_the_controller_at_the_speed():
    """The reference row is the trot controller's own walk: it keeps the speed and does not fall."""
    from cyberdog.analysis.policy_check import COLUMNS, check_trot
    from cyberdog.config import EnvConfig
    r = check_trot((1.2, 3.0, EnvConfig().walk, "ideal"))
    assert set(COLUMNS) <= set(r) and r["label"] == "trot" and r["stage"] == 0
    assert not r["fell"] and abs(r["mean_speed_mps"] - 1.2) < 0.1 and r["energy_J"] > 0
    hw = check_trot((1.2, 3.0, EnvConfig().walk, "hardware:0"))  # friction: the joints' losses cost more
    assert hw["robot"] == "hardware:0" and not hw["fell"] and hw["electrical_per_metre_J"] > r["electrical_per_metre_J"]


def test_walks_of_different_durations_give_no_reduction():
    """A walk that fell is shorter: its energy is not comparable."""
    got = stage_reductions([row("s0", 1, 1.0, 1000.0), row("s0", 2, 1.0, 300.0, walks=False, duration=2.5)])
    assert math.isnan(got[0]["reduction_pct"]) and not got[0]["both_walk"]


def test_bad_requests_fail_before_any_walk(tmp_path):
    actor = tmp_path / "stage1_final_actor.pt"
    actor.write_bytes(b"")
    with pytest.raises(ValueError, match="speeds"):
        check_jobs({"s0": {1: actor}}, [0.0], 10.0)
    with pytest.raises(ValueError, match="duration"):
        check_jobs({"s0": {1: actor}}, [1.0], -1.0)
    with pytest.raises(FileNotFoundError, match="stage 2"):
        check_jobs({"s0": {1: actor, 2: tmp_path / "missing.pt"}}, [1.0], 10.0)
    with pytest.raises(ValueError, match="hardware:N"):
        check_jobs({"s0": {1: actor}}, [1.0], 10.0, robots=["hardware-0"])
    assert len(check_jobs({"s0": {1: actor}}, [1.0, 1.2, 1.4], 10.0)) == 3
    assert len(check_jobs({"s0": {1: actor}}, [1.0, 1.2], 10.0, robots=["ideal", "hardware:0", "hardware:1"])) == 6


def test_the_prototype_walks_a_policy_in_the_walk_configs_engine(monkeypatch):
    """`prototype --closed-loop --set sim.engine=mujoco`: the policy walks in its own env, in the paths' engine,
    with their PD and their payload (the rollout itself is stubbed: only the env it is given is checked)."""
    import cyberdog.rl.rollout as rollout_module
    from cyberdog.analysis import prototype as proto

    seen = {}
    monkeypatch.setattr(rollout_module, "rollout", lambda actor, speed, cap, env_config, **kw: seen.update(
        env=env_config))
    cfg = C.override(C.WalkConfig(), ["sim.engine=mujoco", "pid.kp=[70,70,70]", "robot.payload=3"])
    job = proto._Job("policy", None, 1.2, "hardware", cfg, C.HARDWARE_LIKE, 20.0,
                     policy=str(Path(__file__).resolve().parents[1] / "results/battery/policy/seed0/stage2_actor.pt"))
    proto._policy_walk(job, C.HARDWARE_LIKE, 30.0)
    assert seen["env"].walk.sim.engine == "mujoco" and seen["env"].walk.pid == cfg.pid
    assert seen["env"].walk.robot.payload == 3.0  # the policy carries the paths' payload
