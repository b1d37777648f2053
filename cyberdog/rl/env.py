"""`CyberDog-v0` as a TorchRL environment, with per-step reward terms, energy and speed exposed as keys.

The gymnasium env returns nested dicts in `info`; `FlatInfo` flattens the few numbers the trainer logs into
scalars, and TorchRL's `default_info_dict_reader` copies them into the collected tensordicts under "next".
"""
from __future__ import annotations

import gymnasium as gym
import numpy as np
import torch
from torchrl.data import Unbounded
from torchrl.envs import GymWrapper, InitTracker, TransformedEnv
from torchrl.envs.gym_like import default_info_dict_reader

from cyberdog.config import REWARD_TERM_NAMES, EnvConfig, RewardConfig
from cyberdog.envs.cyberdog_env import CyberDogEnv

INFO_KEYS = tuple(f"reward_{n}" for n in REWARD_TERM_NAMES) + ("energy_J", "forward_speed")


class FlatInfo(gym.Wrapper):
    """Replaces `info` with flat float entries: weighted reward terms, step energy (J) and forward speed."""

    def _flat(self, info: dict) -> dict:
        weighted = info.get("reward_weighted", {})
        flat = {f"reward_{n}": weighted.get(n, 0.0) for n in REWARD_TERM_NAMES}
        # the step energy the reward's energy term measured (Eq. 7, or electrical: RewardConfig.energy_model),
        # stored per transition so that rewards can be relabelled with another energy weight
        flat["energy_J"] = info.get("reward_terms", {}).get("energy", 0.0)
        flat["forward_speed"] = info.get("forward_speed", 0.0)
        return {k: np.float32(v) for k, v in flat.items()}

    def reset(self, **kwargs):
        obs, info = self.env.reset(**kwargs)
        return obs, self._flat({})

    def step(self, action):
        obs, reward, terminated, truncated, info = self.env.step(action)
        return obs, reward, terminated, truncated, self._flat(info)


def make_gym_env(env_cfg: EnvConfig, reward: str | RewardConfig) -> gym.Env:
    """The gymnasium env with the paper's time limit (`EnvConfig.max_episode_steps`) and flat info."""
    env = CyberDogEnv(config=env_cfg, reward=reward)
    env = gym.wrappers.TimeLimit(env, max_episode_steps=env_cfg.max_episode_steps)
    return FlatInfo(env)


def make_env(env_cfg: EnvConfig, reward: str | RewardConfig, seed: int, device: str = "cpu",
             track_init: bool = False) -> TransformedEnv:
    """TorchRL env; `track_init` adds the "is_init" flag Ornstein–Uhlenbeck noise needs."""
    base = GymWrapper(make_gym_env(env_cfg, reward), device=device)
    spec = {k: Unbounded(shape=(), dtype=torch.float32, device=device) for k in INFO_KEYS}
    base.set_info_dict_reader(default_info_dict_reader(list(INFO_KEYS), spec=spec))
    env = TransformedEnv(base)
    if track_init:
        env.append_transform(InitTracker())
    env.set_seed(seed)
    return env
