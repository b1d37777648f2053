"""Domain randomisation: each episode's robot drawn from ranges, reproducibly, within them, and applied."""
import dataclasses
from pathlib import Path

import numpy as np
import pytest

from cyberdog import config as C
from cyberdog.envs.cyberdog_env import CyberDogEnv
from cyberdog.sim.hardware_model import RobotDraw, draw_robot

ROOT = Path(__file__).resolve().parents[1]
BATTERY = ROOT / "configs/battery.yaml"
WIDE = C.RandomizationConfig(joint_friction_scale=(0.5, 1.5), latency_periods=(0, 2), mass_scale=(0.9, 1.1),
                             motor_strength=(0.9, 1.1), kp_factor=(0.8, 1.2), kd_factor=(0.7, 1.3),
                             ground_friction_scale=(0.7, 1.3))


def test_draws_repeat_with_the_seed_and_stay_in_their_ranges():
    draws = [draw_robot(WIDE, np.random.default_rng(seed)) for seed in range(300)]
    assert draw_robot(WIDE, np.random.default_rng(7)) == draws[7]
    assert len({d.mass_scale for d in draws}) == 300  # they do vary
    for name in C.RandomizationConfig.RANGES:
        lo, hi = getattr(WIDE, name)
        values = [getattr(d, name) for d in draws]
        assert lo <= min(values) and max(values) <= hi, name
    assert {d.latency_periods for d in draws} == {0, 1, 2}  # every whole value of the range, both ends included
    assert all(isinstance(d.latency_periods, int) for d in draws)


def test_the_env_draws_one_robot_per_episode_from_its_generator():
    env = CyberDogEnv(action_mode="foot", hardware=C.HARDWARE_LIKE, randomization=WIDE)
    try:
        first = [env.reset(seed=3)[1]["robot_draw"]] + [env.reset()[1]["robot_draw"] for _ in range(3)]
        again = [env.reset(seed=3)[1]["robot_draw"]] + [env.reset()[1]["robot_draw"] for _ in range(3)]
        assert first == again
        assert len({d["mass_scale"] for d in first}) == 4  # a new robot each episode
        last = RobotDraw(**first[-1])
        # the draw is what the robot walks with
        robot, walker = env.walker.robot, env.walker
        assert robot.mass_scale == last.mass_scale
        assert robot.actuator.friction_scale == last.joint_friction_scale
        assert robot.actuator.strength == last.motor_strength
        assert walker.delay.steps == last.latency_periods
        assert robot.ground_friction == pytest.approx(env.cfg.walk.sim.ground_friction * last.ground_friction_scale)
        plane = robot.client.getDynamicsInfo(robot.plane_id, -1)
        assert plane[1] == pytest.approx(robot.ground_friction)  # lateral friction as PyBullet holds it
        np.testing.assert_allclose(env.walker.controller.pid.kp, np.array(env.cfg.walk.pid.kp * 4) * last.kp_factor)
        np.testing.assert_allclose(env.walker.controller.pid.kd, np.array(env.cfg.walk.pid.kd * 4) * last.kd_factor)
    finally:
        env.close()


def test_without_randomisation_the_env_is_the_configured_robot():
    assert not C.EnvConfig().randomization.enabled
    env = CyberDogEnv(action_mode="foot", hardware=C.HARDWARE_LIKE)
    try:
        _, info = env.reset(seed=0)
        assert "robot_draw" not in info
        assert env.walker.robot.actuator.friction_scale == 1.0 and env.walker.robot.actuator.strength == 1.0
        assert env.walker.delay.steps == 1  # HARDWARE_LIKE's one period
    finally:
        env.close()


def test_a_drawn_actuator_scales_friction_and_torque():
    from cyberdog.core.actuator import ActuatorModel
    model = ActuatorModel(C.ActuatorConfig(friction=True))
    command, omega = np.full(12, 5.0), np.linspace(-3.0, 3.0, 12)
    motor, joint = map(np.array, model.joint_torque(command, omega))
    model.set_scales(friction_scale=2.0, strength=0.9)
    motor2, joint2 = map(np.array, model.joint_torque(command, omega))
    np.testing.assert_allclose(motor2, 0.9 * motor)
    np.testing.assert_allclose(joint2 - motor2, 2.0 * (joint - motor))
    with pytest.raises(ValueError, match="strength"):
        model.set_scales(strength=0.0)


def test_the_battery_preset_contains_the_hardware_like_robot():
    """The prototype's hardware-like robot lies inside the training ranges, so that the evaluation's robot is
    one the policy could have met."""
    cfg = C.load_preset(BATTERY).config  # its stage 2 (the stage1 phase is Table 5's, on the ideal robot)
    r, hw = cfg.env.randomization, cfg.env.hardware
    like = C.HARDWARE_LIKE
    assert r.enabled and hw.friction and hw.estimated_velocity and hw.imu_noise
    assert dataclasses.replace(hw, latency_s=like.latency_s) == like  # its effects are HARDWARE_LIKE's
    nominal = {"joint_friction_scale": 1.0, "motor_strength": 1.0, "kp_factor": 1.0, "kd_factor": 1.0,
               "ground_friction_scale": 1.0}
    for name, value in nominal.items():
        lo, hi = getattr(r, name)
        assert lo <= value <= hi, name
    dt = cfg.env.walk.sim.controller_dt
    assert r.latency_periods[0] <= round(like.latency_s / dt) <= r.latency_periods[1]
    assert r.mass_scale[0] <= 1 - like.mass_uncertainty and 1 + like.mass_uncertainty <= r.mass_scale[1]


def test_bad_ranges_are_refused_with_the_field_named():
    with pytest.raises(ValueError, match="RandomizationConfig.mass_scale"):
        C.RandomizationConfig(mass_scale=(1.2, 1.0))
    with pytest.raises(ValueError, match="RandomizationConfig.latency_periods"):
        C.RandomizationConfig(latency_periods=(-1, 1))
    with pytest.raises(ValueError, match="joint_friction_scale.*hardware.friction"):
        C.EnvConfig(randomization=C.RandomizationConfig(joint_friction_scale=(0.5, 1.5)))


def test_a_range_left_nominal_keeps_the_hardwares_latency_and_mass_and_a_set_range_must_contain_them():
    """One robot by one rule: randomising only the PD gains keeps HARDWARE_LIKE's 2.5 ms latency and its mass
    draw (they were silently replaced by the draw's defaults, 0 periods and 1); a set range that would drop the
    hardware's value is refused naming both fields."""
    env = CyberDogEnv(C.EnvConfig(hardware=C.HARDWARE_LIKE, randomization=C.RandomizationConfig(kp_factor=(0.8, 1.2))),
                      reward="stage1")
    _, info = env.reset(seed=0)
    draw = info["robot_draw"]
    assert draw["latency_periods"] == 1 and draw["mass_scale"] != 1.0
    assert abs(draw["mass_scale"] - 1.0) <= C.HARDWARE_LIKE.mass_uncertainty
    assert env.walker.delay.steps == 1 and env.walker.robot.mass_scale == draw["mass_scale"]
    env.close()
    with pytest.raises(ValueError, match="randomization.latency_periods.*hardware.latency_s"):
        C.EnvConfig(hardware=C.HARDWARE_LIKE, randomization=C.RandomizationConfig(latency_periods=(2, 3)))
    with pytest.raises(ValueError, match="randomization.mass_scale.*hardware.mass_uncertainty"):
        C.EnvConfig(hardware=C.HARDWARE_LIKE, randomization=C.RandomizationConfig(mass_scale=(1.0, 1.2)))
    C.EnvConfig(hardware=C.HARDWARE_LIKE, randomization=C.RandomizationConfig(latency_periods=(0, 1),
                                                                              mass_scale=(0.9, 1.15)))  # contains both
