"""action_mode="foot": the policy shifts the trot controller's foot targets (controller and env); "foot_torque": it
also sends a joint torque through the drivers, and the path extracted from it carries that torque as its own
feedforward."""
import numpy as np
import pytest

from cyberdog import config as C
from cyberdog.control.trot import TrotController
from cyberdog.envs.cyberdog_env import CyberDogEnv
from cyberdog.envs.observation import observation_size


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


# ---- foot_torque: the foot shifts and a joint torque ----------------------------------------------------------
TORQUE = np.linspace(-0.6, 0.6, 12)  # action units of the torque half: N·m per unit × action_scale


def test_the_action_and_the_observed_last_action_are_24_wide():
    cfg = C.EnvConfig(action_mode="foot_torque")
    env = CyberDogEnv(config=cfg, reward="stage2")
    assert env.action_space.shape == (24,) and cfg.action_size == 24
    assert env.observation_space.shape == (observation_size(cfg),) == (50 + 24,)
    with pytest.raises(ValueError, match=r"shape \(24,\)"):
        env.reset(seed=0)
        env.step(np.zeros(12, dtype=np.float32))
    env.close()


def test_a_zero_torque_half_walks_exactly_like_foot_mode():
    shift = np.tile([0.2, -0.1, 0.3], 4).astype(np.float32)
    foot, e_foot = _episode(shift, 40, action_mode="foot")
    both, e_both = _episode(np.concatenate([shift, np.zeros(12, np.float32)]), 40, action_mode="foot_torque")
    np.testing.assert_array_equal(both[:, :50], foot[:, :50])  # Table 3's entries; the last action is wider
    assert e_both == e_foot


def test_the_torque_half_is_added_to_the_commands_feedforward_times_action_scale():
    env = CyberDogEnv(action_mode="foot_torque", action_scale=5.0, target_speed_range=())
    env.reset(seed=0)
    action = np.concatenate([np.zeros(12), TORQUE * 2.5]).astype(np.float32)  # clipped to ±1 first
    env.step(action)
    c = env.walker.controller
    expected = np.clip(action[12:].astype(float), -1.0, 1.0) * 5.0
    np.testing.assert_allclose(c.last_joint_torque, expected, rtol=1e-6)
    # the command carries it on top of the trot's own feedforward, and nothing else changes
    q = env.walker.reading.q
    with_torque = c.command(env.t, q)
    c.set_joint_torque(None)
    without = c.command(env.t, q)
    np.testing.assert_allclose(np.subtract(with_torque.feedforward, without.feedforward), expected, atol=1e-12)
    assert with_torque.q_target == without.q_target
    env.close()


def test_the_trot_adds_a_set_joint_torque_until_reset():
    c = TrotController(C.EnvConfig().walk)
    q = np.zeros(12)
    plain = c.command(0.3, q).feedforward
    c.set_joint_torque(list(TORQUE))
    np.testing.assert_allclose(np.subtract(c.command(0.3, q).feedforward, plain), TORQUE, atol=1e-12)
    c.reset()
    assert c.command(0.3, q).feedforward == plain and c.last_joint_torque is None


def _constant_actor_file(path, action, **env_changes):
    """An actor file whose policy outputs `action` whatever it sees (zero weights, bias atanh(action))."""
    torch = pytest.importorskip("torch")
    from cyberdog.envs.observation import observation_typical_magnitude
    from cyberdog.rl.networks import TanhActor

    cfg = C.ExperimentConfig()
    cfg = C.replace(cfg, env=C.replace(cfg.env, target_speed_range=(), **env_changes),
                    agent=C.replace(cfg.agent, hidden_sizes=(8,)))
    scale = observation_typical_magnitude(cfg.env)
    actor = TanhActor(len(scale), cfg.env.action_size, (8,), scale)
    with torch.no_grad():
        actor.net[-1].weight.zero_()
        actor.net[-1].bias.copy_(torch.atanh(torch.as_tensor(action, dtype=torch.float32)))
    torch.save({"actor": {f"module.{k}": v for k, v in actor.state_dict().items()}, "config": C.to_dict(cfg),
                "stage": 2, "episode": 1}, path)
    return path


def test_the_extracted_path_carries_the_policys_torque_as_its_feedforward(tmp_path):
    pytest.importorskip("torch")
    from cyberdog.analysis.extract import commanded_from_rollout
    from cyberdog.rl.rollout import load_actor, rollout

    action = np.concatenate([np.zeros(12), TORQUE * 0.5])  # ±1.5 N·m at action_scale 5
    actor = load_actor(_constant_actor_file(tmp_path / "actor.pt", action, action_mode="foot_torque",
                                            action_scale=5.0))
    r = rollout(actor, speed=1.0, duration=6.0)
    assert not r.fell
    path = commanded_from_rollout(r, actor.config.env).path
    table = path.offsets.feedforward
    assert table is not None and table.shape == (4, path.offsets.n, 3)
    # a constant torque at every phase of every leg, as sent (float32 actions)
    np.testing.assert_allclose(table, np.broadcast_to((TORQUE * 0.5 * 5.0).reshape(4, 1, 3), table.shape), atol=1e-5)
    np.testing.assert_allclose(path.provenance["feedforward_rms_Nm"], np.abs(TORQUE * 2.5).reshape(4, 3), atol=1e-3)
    # and a foot-mode policy's path carries none
    plain = load_actor(_constant_actor_file(tmp_path / "plain.pt", np.zeros(12), action_mode="foot"))
    assert commanded_from_rollout(rollout(plain, speed=1.0, duration=6.0), plain.config.env).path.offsets.feedforward \
        is None


def test_the_exported_layout_names_shifts_then_torques():
    torch = pytest.importorskip("torch")  # noqa: F841 (policy_export imports torch)
    from cyberdog.rl.policy_export import action_layout

    layout = action_layout(C.EnvConfig(action_mode="foot_torque", action_scale=5.0, foot_offset_scale=0.02))
    assert [e["index"] for e in layout] == list(range(24))
    assert [e["unit"] for e in layout] == ["m"] * 12 + ["N·m"] * 12
    assert layout[0]["name"] == "LF_dx" and layout[0]["scale"] == 0.02
    assert layout[12]["joint"] == layout[12]["name"] and layout[12]["leg"] == "LF" and layout[12]["scale"] == 5.0
    assert layout[23]["leg"] == "RH"
