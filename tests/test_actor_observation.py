"""An actor that sees only some observation groups (`agent.actor_observation`): the trajectory policy.

An actor that sees only the commanded speed and the gait phase is a foot trajectory per speed; these tests
check that it stays blind to everything else through TD3 updates (both loss implementations), in the file
the trainer writes and in the actor `load_actor` rebuilds, while its critics still see the whole state."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import torch
from tensordict import TensorDict

from cyberdog import config as C
from cyberdog.envs.cyberdog_env import actor_observation_scale, observation_layout, observation_typical_magnitude
from cyberdog.rl.td3 import TD3, UpdateSettings
from cyberdog.rl.trainer import Trainer

ROOT = Path(__file__).resolve().parents[1]
SEEN = ("target_speed", "gait_phase")


def seen_mask(env_cfg=None) -> np.ndarray:
    mask = []
    for name, n, *_ in observation_layout(env_cfg):
        mask += [name in SEEN] * n
    return np.array(mask)


def with_hidden_entries_redrawn(obs: torch.Tensor, mask: np.ndarray, seed: int) -> torch.Tensor:
    g = torch.Generator().manual_seed(seed)
    other = obs.clone()
    hidden = torch.as_tensor(~mask)
    other[..., hidden] = torch.randn(other[..., hidden].shape, generator=g) * 3
    return other


def test_the_scale_hides_exactly_the_other_groups():
    scale = actor_observation_scale(None, SEEN)
    mask = seen_mask()
    assert mask.sum() == 3  # the command and sin, cos of the phase
    assert np.all(np.isinf(scale[~mask]))
    np.testing.assert_array_equal(scale[mask], observation_typical_magnitude()[mask])
    np.testing.assert_array_equal(actor_observation_scale(None, ()), observation_typical_magnitude())


def test_unknown_group_names_are_refused_with_the_valid_ones():
    with pytest.raises(ValueError, match="gait_phase"):
        actor_observation_scale(None, ("target_speed", "phase"))
    with pytest.raises(ValueError, match="actor_observation"):
        C.AgentConfig(actor_observation=("gait_phase", "gait_phase"))


def test_updates_leave_the_actor_blind_and_the_critics_seeing():
    torch.manual_seed(0)
    n_obs = len(observation_typical_magnitude())
    cfg = C.AgentConfig(hidden_sizes=(16, 16), policy_delay=1, actor_lr=1e-2,
                        action_smoothness=1.0, actor_observation=SEEN)
    agent = TD3(cfg, n_obs, 12, observation_scale=observation_typical_magnitude(),
                actor_observation_scale=actor_observation_scale(None, SEEN))
    g = torch.Generator().manual_seed(1)
    n = 64
    data = TensorDict({"observation": torch.randn(n, n_obs, generator=g), "action": torch.rand(n, 12) * 2 - 1,
                       "next": {"observation": torch.randn(n, n_obs, generator=g), "reward": torch.randn(n, 1),
                                "done": torch.zeros(n, 1, dtype=torch.bool),
                                "terminated": torch.zeros(n, 1, dtype=torch.bool)}}, [n])
    for _ in range(20):
        metrics = agent.update(data, UpdateSettings.of(cfg))
    assert all(torch.isfinite(v) for v in metrics.values())
    obs = data["observation"][:8]
    mask = seen_mask()
    other = with_hidden_entries_redrawn(obs, mask, seed=2)
    with torch.no_grad():
        a, a_other = (agent.actor(TensorDict({"observation": o}, [8]))["action"] for o in (obs, other))
        seen_changed = obs.clone()
        seen_changed[..., torch.as_tensor(mask)] += 0.5
        a_seen = agent.actor(TensorDict({"observation": seen_changed}, [8]))["action"]
    torch.testing.assert_close(a, a_other, rtol=0, atol=0)
    assert (a - a_seen).abs().max() > 1e-4, "the actor still reacts to what it sees"
    # the critics (and their targets) read the whole observation
    for critics in (agent.critic, agent.target_critic):
        assert torch.isfinite(critics.scale).all()


def test_a_trained_trajectory_actor_is_blind_after_loading(tmp_path):
    """The trainer end to end with `actor_observation` (tiny budget): the actor file keeps the hidden entries
    hidden when `load_actor` rebuilds it, so rollouts and extraction use the same trajectory policy."""
    from cyberdog.rl.rollout import load_actor
    cfg = C.override(C.load(C.ExperimentConfig, ROOT / "configs/tiny.yaml"),
                     ["train.stage1.max_env_steps=300", "env.action_mode=foot", "env.observe_last_action=true",
                      "agent.actor_observation=[target_speed, gait_phase]"])
    summary = Trainer(cfg, tmp_path, stages=(1,), progress=False).run()
    assert summary["updates"] > 0
    actor = load_actor(tmp_path / "stage1_final_actor.pt")
    assert actor.config.agent.actor_observation == SEEN
    mask = seen_mask(actor.config.env)
    obs = torch.randn(8, len(mask))
    obs[:, ~torch.as_tensor(mask)] = 0.0
    np.testing.assert_array_equal(actor(obs.numpy()), actor(with_hidden_entries_redrawn(obs, mask, 3).numpy()))


def test_a_stage_can_drop_the_lateral_offset_term_and_relabel_needs_the_same_in_both():
    """A stage's `reward.y_offset` sets B of Eq. (10) for a stage (a trajectory actor cannot hold the line):
    the env's reward then differs from the paper's by exactly B·y² per step, and relabelling refuses stages
    whose B differ (only the stored energy and the constant keep-moving term can be recomputed)."""
    from cyberdog.envs.cyberdog_env import CyberDogEnv
    stage = C.StageConfig(reward=C.replace(C.STAGE1_REWARD, y_offset=0.0))
    assert C.stage_reward(stage).y_offset == 0.0 and C.stage_reward(C.StageConfig()).y_offset == -20.0
    with pytest.raises(ValueError, match="RewardConfig.y_offset"):
        C.RewardConfig(y_offset=5.0)
    env_cfg = C.load(C.ExperimentConfig, ROOT / "configs/tiny.yaml").env
    steps = []
    for s in (C.StageConfig(), stage):
        env = CyberDogEnv(config=env_cfg, reward=C.stage_reward(s))
        env.reset(seed=1)
        steps.append([env.step(np.full(12, 0.3 * (-1) ** k))[1:5:3] for k in range(5)])
        env.close()
    for (r_paper, info), (r_no_y, _) in zip(*steps):
        y_term = info["reward_terms"]["y_offset"]
        assert y_term > 0
        assert r_no_y == pytest.approx(r_paper + 20.0 * y_term, abs=1e-9)
    no_y = C.StageConfig(reward=C.replace(C.STAGE2_REWARD, y_offset=0.0))
    with pytest.raises(ValueError, match="stage1.reward.y_offset"):
        C.TrainConfig(buffer_between_stages="relabel", stage2=no_y)
    with pytest.raises(ValueError, match="stage1.reward.speed"):
        C.TrainConfig(buffer_between_stages="relabel", stage2=C.StageConfig(reward=C.replace(C.STAGE2_REWARD,
                                                                                             speed=-40.0)))
    with pytest.raises(ValueError, match="RewardConfig.speed"):
        C.RewardConfig(speed=1.0)
    C.TrainConfig(buffer_between_stages="relabel", stage1=stage, stage2=no_y)  # the same B in both: accepted
