"""action_mode="foot": the policy shifts the trot controller's foot targets (controller and env)."""
import numpy as np
import pytest

from cyberdog import config as C
from cyberdog.control.trot import TrotController
from cyberdog.envs.cyberdog_env import CyberDogEnv


@pytest.fixture()
def controller():
    return TrotController(C.EnvConfig().walk)


def test_offsets_shift_the_foot_targets_and_rates_the_velocities(controller):
    t = 0.37  # mid-gait, some legs in swing
    plain = controller.targets(t)
    offsets = np.array([[0.01, -0.005, 0.02], [0.0, 0.0, -0.01], [-0.02, 0.01, 0.0], [0.005, 0.0, 0.015]])
    rates = np.array([[0.1, 0.0, -0.2], [0.0, 0.3, 0.0], [0.0, 0.0, 0.0], [-0.1, 0.0, 0.05]])
    controller.set_foot_offsets(offsets, rates)
    shifted = controller.targets(t)
    np.testing.assert_allclose(shifted.foot_position - plain.foot_position, offsets, atol=1e-12)
    np.testing.assert_allclose(shifted.foot_velocity - plain.foot_velocity, rates, atol=1e-12)
    assert not np.allclose(shifted.joint_angles, plain.joint_angles)
    controller.reset()  # a reset removes the shift
    np.testing.assert_array_equal(controller.targets(t).foot_position, plain.foot_position)


def test_unreachable_shifted_target_falls_back_to_the_path(controller):
    t = 0.37
    plain = controller.targets(t)
    offsets = np.zeros((4, 3))
    offsets[1, 2] = -1.0  # 1 m below the hip: out of reach
    controller.set_foot_offsets(offsets)
    shifted = controller.targets(t)
    np.testing.assert_allclose(shifted.foot_position[1], plain.foot_position[1])
    np.testing.assert_allclose(shifted.joint_angles[3:6], plain.joint_angles[3:6])


@pytest.mark.parametrize("offsets", [np.zeros((3, 3)), np.full((4, 3), np.nan)])
def test_bad_offsets_raise(controller, offsets):
    with pytest.raises(ValueError, match="foot offsets"):
        controller.set_foot_offsets(offsets)


def _episode(action, steps, **options):
    env = CyberDogEnv(**options)
    env.reset(seed=0)
    observations, energy = [], 0.0
    for _ in range(steps):
        obs, _, terminated, _, info = env.step(action)
        observations.append(obs)
        energy += info["step_energy_J"]
        assert not terminated
    env.close()
    return np.array(observations), energy


def test_zero_action_walks_exactly_like_the_zero_residual():
    foot, e_foot = _episode(np.zeros(12, dtype=np.float32), 40, action_mode="foot")
    residual, e_residual = _episode(np.zeros(12, dtype=np.float32), 40, action_mode="residual")
    np.testing.assert_array_equal(foot, residual)
    assert e_foot == e_residual


def test_raising_every_foot_target_lowers_the_body():
    """Feet 3 cm higher relative to the hips (Δz = +1 × foot_offset_scale) put the body ≈3 cm lower."""
    up = np.tile([0.0, 0.0, 1.0], 4).astype(np.float32)
    shifted, _ = _episode(up, 40, action_mode="foot", foot_offset_scale=0.03)
    plain, _ = _episode(np.zeros(12, dtype=np.float32), 40, action_mode="foot")
    drop = float(np.mean(plain[-20:, 0] - shifted[-20:, 0]))  # body height z, last 0.5 s
    assert 0.02 < drop < 0.04, drop


def test_foot_action_ramps_each_offset_to_the_clipped_action_times_the_scale():
    """A foot-mode step ramps the targets' offsets from the last action's to this one's (clipped to ±1, times
    the scale per axis) over the agent step, reaching this one's at the step's last controller period."""
    env = CyberDogEnv(action_mode="foot", foot_offset_scale=0.03, foot_offset_scale_z=0.02)
    env.reset(seed=0)
    scale = np.array([0.03, 0.03, 0.02])
    period, agent_dt = env.walker.dt, env.cfg.control_dt
    c, previous = env.walker.controller, np.zeros((4, 3))
    for action in (np.linspace(-1.5, 1.5, 12, dtype=np.float32), np.linspace(0.9, -0.4, 12, dtype=np.float32)):
        start_time = env.walker.time
        env.step(action)
        target = np.clip(action.astype(float), -1.0, 1.0).reshape(4, 3) * scale
        rates = np.array(c.foot_offset_rates)
        assert c.foot_offset_time == start_time
        np.testing.assert_allclose(rates, (target - previous) / agent_dt, rtol=1e-12, atol=1e-12)
        # the ramp's value at the step's last period (k = decimation − 1) is this action's offset
        last = np.array(c.foot_offsets) + rates * (agent_dt - period)
        np.testing.assert_allclose(last, target, atol=1e-12)
        previous = target
    env.close()
