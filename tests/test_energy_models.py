"""What Eq. (7) does not see: positive work, foot slip, and the electrical energy as the reward's energy term."""
import dataclasses

import gymnasium as gym
import numpy as np
import pytest

import cyberdog  # noqa: F401 - registers CyberDog-v0
from cyberdog import config as C
from cyberdog.core import energy as en


def test_positive_work_counts_only_driving_power():
    tau = np.zeros((3, 12))
    omega = np.zeros((3, 12))
    tau[:, 0], omega[:, 0] = [2.0, 2.0, -2.0], [1.0, -1.0, -1.0]  # +2 W, −2 W (braking), +2 W
    assert en.positive_work(tau, omega, 0.5) == pytest.approx(2.0)  # (2 + 2) W · 0.5 s
    assert en.joint_energy(tau, omega, 0.5).sum() == pytest.approx(3.0)  # Eq. (7) counts the braking too


def test_foot_slip_adds_the_horizontal_moves_of_feet_on_the_ground():
    xy = np.zeros((4, 4, 2))
    xy[:, 0, 0] = [0.0, 0.003, 0.007, 0.5]  # LF slides 3 + 4 mm on the ground, then jumps in the air
    xy[:, 1, 1] = [0.0, 0.1, 0.2, 0.3]  # RF moves 0.3 m, always in the air
    contacts = np.zeros((4, 4), dtype=bool)
    contacts[:3, 0] = True
    slip = en.foot_slip(xy, contacts)
    assert slip == pytest.approx([0.007, 0.0, 0.0, 0.0])
    with pytest.raises(ValueError, match="foot_xy"):
        en.foot_slip(np.zeros((4, 4, 3)), contacts)


def make_env(**reward_changes):
    reward = dataclasses.replace(C.STAGE2_REWARD, **reward_changes)
    return gym.make("CyberDog-v0", action_mode="foot", reward=reward)


def test_the_electrical_energy_model_changes_only_the_energy_term():
    steps = 20
    infos = {}
    for model in C.ENERGY_MODELS:
        env = make_env(energy_model=model)
        env.reset(seed=0)
        infos[model] = [env.step(np.full(12, 0.2))[4] for _ in range(steps)]
        env.close()
    mech, elec = infos["mechanical"], infos["electrical"]
    for m, e in zip(mech, elec):
        assert m["step_energy_J"] == e["step_energy_J"]  # the same physics: Eq. (7) unchanged
        assert m["reward_terms"]["energy"] == m["step_energy_J"] and m["step_electrical_energy_J"] is None
        assert e["reward_terms"]["energy"] == pytest.approx(e["step_electrical_energy_J"])
        assert e["step_electrical_energy_J"] > e["step_energy_J"]  # copper loss and driver losses on top
        assert {k: v for k, v in e["reward_terms"].items() if k != "energy"} == \
            {k: v for k, v in m["reward_terms"].items() if k != "energy"}


def test_reward_and_stage_energy_model_are_checked():
    with pytest.raises(ValueError, match="RewardConfig.energy_model"):
        C.RewardConfig(energy_model="thermal")
    electrical = C.StageConfig(reward=C.replace(C.STAGE2_REWARD, energy_model="electrical"))
    assert C.stage_reward(electrical).energy_model == "electrical"
    with pytest.raises(ValueError, match="stage1.reward.energy_model"):  # the relabelled buffer needs one model
        C.TrainConfig(stage2=electrical, buffer_between_stages="relabel")
    C.TrainConfig(stage2=electrical, buffer_between_stages="clear")  # fine without relabelling


def test_vertical_foot_offset_authority():
    env = gym.make("CyberDog-v0", action_mode="foot", foot_offset_scale=0.03, foot_offset_scale_z=0.10)
    env.reset(seed=0)
    env.step(np.tile([1.0, 1.0, -1.0], 4))
    offsets = np.array(env.unwrapped.walker.controller.last_foot_offsets)  # at the step's last controller period
    assert offsets[:, :2] == pytest.approx(0.03) and offsets[:, 2] == pytest.approx(-0.10)
    with pytest.raises(ValueError, match="foot_offset_scale_z"):
        C.EnvConfig(foot_offset_scale_z=-0.1)


def test_the_electrical_models_friction_is_what_the_simulated_joint_feels():
    """One friction law: with friction left out of the physics, the electrical model adds to the motor's
    torque exactly the friction a joint moving at ω feels when the physics models it."""
    from cyberdog.core.actuator import ActuatorModel
    from cyberdog.core import energy as en
    omega = np.linspace(-5.0, 5.0, 12)
    omega[:3] = [0.0, 0.004, -0.02]  # at rest and inside the dry friction's smoothing
    tau = np.full(12, 3.0)
    simulated = C.ActuatorConfig(friction=True)
    felt = ActuatorModel(simulated).joint_torque(tau, omega)
    felt_friction = np.subtract(felt[1], felt[0])  # joint torque minus motor torque: the friction on the joint
    added = en.drive_torque(tau, omega, C.ActuatorConfig(friction=False)) - tau
    np.testing.assert_allclose(added, -felt_friction, rtol=1e-12, atol=1e-15)
    assert en.drive_torque(tau, omega, simulated) is not None
    np.testing.assert_array_equal(en.drive_torque(tau, omega, simulated), tau)  # counted once: in the physics
