"""Stage 2 starting from stage 1's experience: each stored reward relabelled with stage 2's weights."""
from __future__ import annotations

import numpy as np
import pytest
import torch

from cyberdog import config as C
from cyberdog.rl.replay import make_replay_buffer, relabel_rewards
from cyberdog.rl.trainer import Trainer
from rl_helpers import batch, changed, snapshot, tiny_config


def test_relabel_adds_the_weight_changes_to_each_stored_reward():
    rb = make_replay_buffer(10)
    data = batch(6, reward=1.0)
    data["next", "energy_J"] = torch.arange(6.0).reshape(6, 1)
    rb.extend(data)
    relabel_rewards(rb, -0.5, 0.25)
    assert torch.allclose(rb[:6]["next", "reward"].reshape(-1), 1.25 - 0.5 * torch.arange(6.0))
    relabel_rewards(make_replay_buffer(10), -0.5)  # an empty buffer is left as it is


def test_relabelled_buffer_carries_stage1_experience_with_stage2_rewards(tmp_path):
    """buffer_between_stages="relabel": stage 2 starts with stage 1's transitions, each reward recomputed with
    stage 2's energy weight; critic_warmup_updates holds the actor for the stage's first updates."""
    e2, d2 = -0.05, 40.0
    cfg = C.override(tiny_config(), ["train.buffer_between_stages=relabel", f"train.stage2.reward.energy={e2}",
                               f"train.stage2.reward.keep_moving={d2}",
                               "train.stage1.max_env_steps=100", "train.stage2.max_env_steps=100",
                               "train.init_random_frames=0", "train.stage2.critic_warmup_updates=1000"])
    trainer = Trainer(cfg, tmp_path, progress=False)
    stored = {}
    carry = trainer._carry_buffer

    def recording_carry(old, new):
        stored["before"] = trainer.rb[:len(trainer.rb)].clone()
        stored["actor"] = snapshot(trainer.agent)
        carry(old, new)
        stored["after"] = trainer.rb[:len(trainer.rb)].clone()

    trainer._carry_buffer = recording_carry
    trainer.run()
    trainer.logger.close()
    before, after = stored["before"], stored["after"]
    assert len(before) == len(after) == 100 and len(trainer.rb) == 200
    energy = before["next", "energy_J"].reshape(-1)
    assert (energy > 0).all(), "every stored step carries its energy (J)"
    per_step = (d2 - 25.0) * cfg.env.control_dt / cfg.env.episode_time  # stage 1 keeps the paper's D = 25
    assert torch.allclose(after["next", "reward"].reshape(-1),
                          before["next", "reward"].reshape(-1) + e2 * energy + per_step)
    assert trainer.progress.stage_updates > 0
    assert not changed(stored["actor"], snapshot(trainer.agent), "actor_network_params"), \
        "within critic_warmup_updates the actor waits"
    with pytest.raises(ValueError, match="buffer_between_stages"):
        C.TrainConfig(buffer_between_stages="relabel-all")
    with pytest.raises(ValueError, match="critic_warmup_updates"):
        C.StageConfig(critic_warmup_updates=-1)
    with pytest.raises(ValueError, match="RewardConfig.keep_moving"):
        C.RewardConfig(keep_moving=-1.0)


def test_relabel_formula_gives_the_reward_the_next_stage_would_have_given():
    """The same steps (same seed, same actions) under the stage-1 and the stage-2 reward differ by exactly
    ΔE · energy + ΔD · Ts/Tf, the correction `relabel_rewards` applies."""
    from cyberdog.envs.cyberdog_env import CyberDogEnv
    s1 = C.StageConfig()
    s2 = C.StageConfig(reward=C.replace(C.STAGE2_REWARD, energy=-0.05, keep_moving=40.0))
    w1, w2 = C.stage_reward(s1).weights, C.stage_reward(s2).weights
    assert (w2["energy"], w2["keep_moving"]) == (-0.05, 40.0) and w1["energy"] == 0.0
    env_cfg = tiny_config().env
    runs = []
    for stage in (s1, s2):
        env = CyberDogEnv(config=env_cfg, reward=C.stage_reward(stage))
        env.reset(seed=3)
        steps = [env.step(np.full(12, 0.2 * (-1) ** k))[1:5:3] for k in range(5)]
        env.close()
        runs.append([(r, info["step_energy_J"]) for r, info in steps])
    per_step = (40.0 - 25.0) * env_cfg.control_dt / env_cfg.episode_time
    for (r1, e1), (r2, e2) in zip(*runs):
        assert e1 == e2 > 0
        assert r2 == pytest.approx(r1 - 0.05 * e1 + per_step, abs=1e-9)
