"""A robot drawn with stiffer or more damped gains steps at the physics rate its drivers' law needs, when the
randomisation asks for it (`RandomizationConfig.drivers_rate_per_robot`); the configured robot's rate otherwise."""
import dataclasses

import numpy as np
import pytest

from cyberdog import config as C
from cyberdog.core.drivers import MAX_DAMPING_STEP, driver_physics_dt
from cyberdog.envs.cyberdog_env import CyberDogEnv

CONFIGURED_DT = C.SimConfig().physics_dt


def _env(kd: tuple, per_robot: bool) -> CyberDogEnv:
    ranges = C.RandomizationConfig(kd_factor=kd, drivers_rate_per_robot=per_robot)
    return CyberDogEnv(config=C.EnvConfig(randomization=ranges), reward="stage1")


@pytest.mark.parametrize("kd, per_robot", [((2.0, 2.0), True), ((2.0, 2.0), False), ((0.5, 0.5), True)])
def test_the_physics_step_follows_the_drawn_gains_only_when_asked(kd, per_robot):
    env = _env(kd, per_robot)
    try:
        env.reset(seed=0)
        w = env.walker
        walk = C.WalkConfig()
        drawn_kd = [g * kd[0] for g in walk.pid.kd]
        need = driver_physics_dt(CONFIGURED_DT, list(walk.pid.kp), drawn_kd, walk.robot.reflected_rotor_inertia)
        want = need if per_robot else CONFIGURED_DT
        assert w.physics_dt == pytest.approx(want) and w.robot.physics_dt == w.physics_dt
        assert w.substeps == round(walk.sim.controller_dt / want)
        if kd[0] > 1.5 and per_robot:
            assert want < CONFIGURED_DT  # doubled damping is beyond the default rate's bound
        _, _, terminated, _, info = env.step(np.zeros(12, np.float32))
        # one agent step's books: 10 controller periods of `substeps` physics steps each, whose Eq. 7 sums to
        # the step's energy
        p = w.physics_traces()
        assert len(p["tau"]) == env.cfg.decimation * w.substeps
        assert float(np.abs(p["tau"] * p["dq"]).sum() * w.physics_dt) == pytest.approx(info["step_energy_J"])
        assert p["t"][1] - p["t"][0] == pytest.approx(want)
    finally:
        env.close()


def test_a_later_softer_draw_returns_to_the_configured_step():
    ranges = C.RandomizationConfig(kd_factor=(0.5, 2.0), drivers_rate_per_robot=True)
    env = CyberDogEnv(config=C.EnvConfig(randomization=ranges), reward="stage1")
    try:
        steps = set()
        for seed in range(8):
            _, info = env.reset(seed=seed)
            factor = info["robot_draw"]["kd_factor"]
            steps.add(env.walker.physics_dt)
            damping_step = factor * C.PIDConfig().kd[0] * CONFIGURED_DT / C.RobotConfig().reflected_rotor_inertia
            assert (env.walker.physics_dt < CONFIGURED_DT) == (damping_step > MAX_DAMPING_STEP), factor
        assert steps == {CONFIGURED_DT, CONFIGURED_DT / 2}
    finally:
        env.close()


def test_the_setting_is_refused_where_no_gain_is_drawn():
    with pytest.raises(ValueError, match="drivers_rate_per_robot"):
        C.RandomizationConfig(drivers_rate_per_robot=True)
    assert dataclasses.replace(C.RandomizationConfig(kp_factor=(1.0, 2.0)), drivers_rate_per_robot=True)
