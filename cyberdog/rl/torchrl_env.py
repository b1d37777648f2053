"""`CyberDog-v0` as a TorchRL environment, with per-step reward terms, energy and speed exposed as keys.

The gymnasium env returns nested dicts in `info`; `FlatInfo` flattens the few numbers the trainer logs into
scalars, and TorchRL's `default_info_dict_reader` copies them into the collected tensordicts under "next".
`make_batched_env` runs several copies, one per process (`train.num_envs`).
"""
from __future__ import annotations

import functools

import gymnasium as gym
import numpy as np
import torch
from torchrl.data import Unbounded
from torchrl.envs import GymWrapper, InitTracker, ParallelEnv, TransformedEnv
from torchrl.envs.gym_like import default_info_dict_reader

from cyberdog.config import REWARD_TERM_NAMES, EnvConfig, RewardConfig
from cyberdog.envs.cyberdog_env import CyberDogEnv
from cyberdog.rl.stop import ignore_stop_signals

INFO_KEYS = tuple(f"reward_{n}" for n in REWARD_TERM_NAMES) + ("energy_J", "forward_speed", "prior_weight",
                                                                 "trot_action")
INFO_SHAPES = {"trot_action": (12,)}  # the others are scalars
NO_REFERENCE = np.full(12, np.nan, dtype=np.float32)


class FlatInfo(gym.Wrapper):
    """Replaces `info` with flat float entries: weighted reward terms, step energy (J), forward speed and the
    trot prior's weight (torque mode; 0 without one)."""

    def _flat(self, info: dict) -> dict:
        weighted = info.get("reward_weighted", {})
        flat = {f"reward_{n}": weighted.get(n, 0.0) for n in REWARD_TERM_NAMES}
        # the step energy the reward's energy term measured (Eq. 7, or electrical: RewardConfig.energy_model),
        # stored per transition so that rewards can be relabelled with another energy weight
        flat["energy_J"] = info.get("reward_terms", {}).get("energy", 0.0)
        flat["forward_speed"] = info.get("forward_speed", 0.0)
        flat["prior_weight"] = info.get("prior_weight", 0.0)
        flat = {k: np.float32(v) for k, v in flat.items()}
        # the trot controller's torque at the step's start state, in action units (NaN where the env did not
        # compute it: EnvConfig.trot_reference off, a reset, or a foot target out of the leg's reach)
        reference = info.get("trot_action")
        flat["trot_action"] = NO_REFERENCE if reference is None else np.asarray(reference, dtype=np.float32)
        return flat

    def reset(self, **kwargs):
        obs, info = self.env.reset(**kwargs)
        return obs, self._flat({})

    def step(self, action):
        obs, reward, terminated, truncated, info = self.env.step(action)
        return obs, reward, terminated, truncated, self._flat(info)


def make_gym_env(env_cfg: EnvConfig, reward: str | RewardConfig, training_steps: int = 0,
                 steps_per_step: int = 1) -> gym.Env:
    """The gymnasium env with the paper's time limit (`EnvConfig.max_episode_steps`) and flat info; the trot
    prior's decay starts from `training_steps` env steps of training, `steps_per_step` more per step of this env
    (`CyberDogEnv.set_training_progress`)."""
    env = CyberDogEnv(config=env_cfg, reward=reward)
    env.set_training_progress(training_steps, steps_per_step)
    env = gym.wrappers.TimeLimit(env, max_episode_steps=env_cfg.max_episode_steps)
    return FlatInfo(env)


def make_env(env_cfg: EnvConfig, reward: str | RewardConfig, seed: int, device: str = "cpu",
             track_init: bool = False, training_steps: int = 0, steps_per_step: int = 1) -> TransformedEnv:
    """TorchRL env; `track_init` adds the "is_init" flag Ornstein–Uhlenbeck noise needs; `training_steps`,
    `steps_per_step`: as `make_gym_env`'s."""
    base = GymWrapper(make_gym_env(env_cfg, reward, training_steps, steps_per_step), device=device)
    spec = {k: Unbounded(shape=INFO_SHAPES.get(k, ()), dtype=torch.float32, device=device) for k in INFO_KEYS}
    base.set_info_dict_reader(default_info_dict_reader(list(INFO_KEYS), spec=spec))
    env = TransformedEnv(base)
    if track_init:
        env.append_transform(InitTracker())
    env.set_seed(seed)
    return env


def make_worker_env(*args, **kwargs) -> TransformedEnv:
    """`make_env` in an env worker process of `ParallelEnv`: the trainer, not the worker, answers SIGINT and
    SIGTERM (`cyberdog.rl.stop`)."""
    ignore_stop_signals()
    return make_env(*args, **kwargs)


def worker_seed(seed: int, index: int) -> int:
    """Env seed of worker `index` of a batch of envs started with `seed`: numpy's `SeedSequence` of the pair,
    so that the workers draw independent streams (seed + index would give run seed s's worker 1 the stream
    of run seed s + 1's worker 0) and a fixed (seed, index) always gives the same one."""
    return int(np.random.SeedSequence([int(seed), int(index)]).generate_state(1)[0])


def make_batched_env(env_cfg: EnvConfig, reward: str | RewardConfig, seed: int, num_envs: int,
                     track_init: bool = False, training_steps: int = 0) -> ParallelEnv:
    """`num_envs` copies of `make_env`, each in its own process (TorchRL's `ParallelEnv`), worker i seeded
    with `worker_seed(seed, i)`; batch size [num_envs]. The trot prior's decay counts `training_steps` env steps
    of training made, and `num_envs` per step of an env.

    The workers step in lock step (all of them, then the next step) and return their data through shared
    memory, so what a batch holds depends on the seeds only, never on the timing. The processes are spawned
    (a fresh interpreter each: no forked PyBullet or OpenMP state). `num_threads` is given so that TorchRL
    leaves this process's torch threads as they are (by default it lowers them by one per worker).
    """
    if int(num_envs) != num_envs or num_envs < 2:
        raise ValueError(f"make_batched_env needs num_envs >= 2 (one env is make_env), got {num_envs!r}")
    make_one = functools.partial(make_worker_env, env_cfg, reward, track_init=track_init,
                                 training_steps=training_steps, steps_per_step=int(num_envs))
    return ParallelEnv(int(num_envs), make_one, create_env_kwargs=[{"seed": worker_seed(seed, i)}
                                                                  for i in range(num_envs)],
                       mp_start_method="spawn", num_threads=torch.get_num_threads())
