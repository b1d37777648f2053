"""Deterministic rollouts of a trained actor in `CyberDog-v0`, recorded at the physics rate.

This is how a policy is judged (does the stage-1 policy walk at 1.0 m/s, does the stage-2
policy use less energy per metre) and where the learned foot trajectory is extracted from (paper Section 3,
after Figure 6): the actor acts without exploration noise, and every controller period's joint angles, velocities,
applied torques and foot contacts are kept, so that gait cycles can be cut at touch-down and their energy
integrated by Eq. (7) exactly as in the scripted walks.

    actor = load_actor("results/table5/policy/seed0/stage2_actor.pt")
    r = rollout(actor, speed=1.0, duration=10.0)
    r.mean_speed, r.energy_per_metre, r.fell  # a WalkResult, as a scripted walk's
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import torch

from cyberdog import config as C
from cyberdog.core.foot_offsets import FootOffsetPath
from cyberdog.envs.cyberdog_env import CyberDogEnv, actor_observation_scale
from cyberdog.loop.result import WalkResult, walk_result
from cyberdog.rl.checkpoint import CheckpointError, check_shapes, load_torch_file, saved_config
from cyberdog.rl.networks import TanhActor


@dataclass
class LoadedActor:
    """A deterministic policy μ(s) and the experiment it was trained in."""

    module: TanhActor
    config: C.ExperimentConfig
    meta: dict = field(default_factory=dict)  # stage, episode, env_steps, score, trained_at of the saved actor

    @torch.no_grad()
    def __call__(self, observation: np.ndarray) -> np.ndarray:
        obs = torch.as_tensor(observation, dtype=torch.float32)
        return self.module(obs).numpy().astype(np.float32)


def load_actor(path: str | Path) -> LoadedActor:
    """Load an actor file written by the trainer (`stage<N>_final_actor.pt`, `stage<N>_best_actor.pt`,
    `saved/*.pt`): its weights, and the experiment config saved beside them (needed for the env)."""
    path = Path(path)
    state = load_torch_file(path, "actor file")
    if not isinstance(state, dict) or "actor" not in state or "config" not in state:
        raise CheckpointError(f"{path} is not an actor file (expected keys 'actor' and 'config')")
    cfg = saved_config(state["config"])
    # TensorDictModule wraps TanhActor: its parameters are stored under "module."
    weights = {k.removeprefix("module."): v for k, v in state["actor"].items()}
    scale = actor_observation_scale(cfg.env, cfg.agent.actor_observation)  # the saved buffer is loaded below
    module = TanhActor(len(scale), cfg.env.action_size, cfg.agent.hidden_sizes, scale)
    check_shapes(weights, module.state_dict(), "the actor", path)
    module.load_state_dict(weights)
    module.eval()
    meta = {k: state[k] for k in ("stage", "episode", "env_steps", "score", "trained_at") if k in state}
    return LoadedActor(module, cfg, meta)


def _check_walk(speed: float, duration: float, distance: float | None, run_up: float) -> None:
    """`rollout`'s walk, or a ValueError naming the argument and its allowed range."""
    if not (np.isfinite(speed) and speed >= 0):
        raise ValueError(f"speed must be >= 0 m/s, got {speed!r}")
    if not duration > 0:
        raise ValueError(f"duration must be > 0 s, got {duration!r}")
    if distance is not None and not (np.isfinite(distance) and distance > 0):
        raise ValueError(f"distance must be None or > 0 m and finite, got {distance!r}")
    if not (0.0 <= run_up < duration):
        raise ValueError(f"run_up must be >= 0 s and shorter than duration ({duration!r} s), got {run_up!r}")


def _handover(cfg: C.EnvConfig, then_path: tuple[float, FootOffsetPath] | None,
              duration: float) -> tuple[int | None, FootOffsetPath | None]:
    """(agent step at which the walk is handed to the path, the path's offsets) of `rollout`'s `then_path`, or
    (None, None) without one; a ValueError (TypeError) names what does not fit."""
    if then_path is None:
        return None, None
    t_hand, path_offsets = then_path
    if cfg.action_mode not in C.FOOT_MODES:
        raise ValueError(f"then_path hands the walk to a foot path: the policy must act on foot targets, "
                         f"not {cfg.action_mode!r}")
    if not isinstance(path_offsets, FootOffsetPath):
        raise TypeError(f"then_path's offsets must be a FootOffsetPath, got {type(path_offsets).__name__}")
    if not (np.isfinite(t_hand) and 0.0 < t_hand < duration):
        raise ValueError(f"then_path's time must be > 0 s and before the end ({duration!r} s), got {t_hand!r}")
    handover_step = int(round(t_hand / cfg.control_dt))
    if abs(handover_step * cfg.control_dt - t_hand) > 1e-9:
        raise ValueError(f"then_path's time {t_hand!r} s is not a multiple of the agent step "
                         f"({cfg.control_dt:g} s)")
    return handover_step, path_offsets


def rollout(actor: LoadedActor, speed: float = 1.0, duration: float = 10.0, seed: int = 0,
            env_config: C.EnvConfig | None = None, reward: str | C.RewardConfig = "stage2",
            distance: float | None = None, run_up: float = 0.0, hardware_robot: bool = False,
            then_path: tuple[float, FootOffsetPath] | None = None) -> WalkResult:
    """Run the actor deterministically for `duration` s at `speed` m/s in the env it was trained in
    (or `env_config`), recording every controller period. Stops early if the robot falls. The result is the
    same record as a scripted walk's, with the episode's score.

    distance, run_up: as `cyberdog.analysis.walk.walk`'s, so that a policy walks the prototype run's protocol:
    `run_up` s first, left out of the result, then `distance` m (`duration` is then the time cap). The goal is
    checked once per agent step (25 ms), the scripted walk's every period: per-metre values are unaffected.
    hardware_robot: walk the robot of `env_config.hardware.seed` (the env's reset option of that name), the one
    a scripted walk with that `HardwareConfig` walks, instead of one drawn from the env's generator.
    then_path: (t_s, offsets) hands the walk over at t_s (s, a multiple of the agent step) from the policy to a
    fixed commanded path: from then on the actions are zero (the policy's shift ramps out over one agent step)
    and the trot controller shifts its targets by `offsets` (a `FootOffsetPath`, as a replayed path does)."""
    _check_walk(speed, duration, distance, run_up)
    cfg = env_config or actor.config.env
    handover_step, path_offsets = _handover(cfg, then_path, duration)
    # the policy alone: a torque policy trained with the trot prior (EnvConfig.prior_weight) is judged without it,
    # and without the trot's torque computed as an imitation reference (EnvConfig.trot_reference): no trot
    # controller runs at all (the reference never drove the robot: the walk is the same to the last bit)
    cfg = dataclasses.replace(cfg, episode_time=max(cfg.episode_time, duration), target_speed_range=(),
                              prior_weight=0.0, prior_decay_steps=0, trot_reference=False)
    env = CyberDogEnv(config=cfg, reward=reward)
    try:
        # the env's simulation loop keeps every controller period: state, body, applied torque, contacts, and the
        # trot controller's commanded foot targets and the policy's shift of them; and samples foot slip
        env.walker.record = env.walker.gait_metrics = env.walker.body_trace = True
        obs, _ = env.reset(seed=seed, options={"target_speed": float(speed), "hardware_robot": hardware_robot})
        n_steps = int(round(duration / cfg.control_dt))
        run_up_steps = int(round(run_up / cfg.control_dt))
        walker = env.walker
        score, fell, since, since_x, goal_x = 0.0, False, 0, None, None
        for k in range(n_steps):
            if k == run_up_steps:  # the measured walk starts here
                x = float(walker.state.base_position[0])
                since, since_x = (walker.steps, x) if k > 0 else (0, None)
                goal_x = None if distance is None else x + distance
            if goal_x is not None and walker.state.base_position[0] >= goal_x:
                break
            if k == handover_step:
                walker.controller.foot_offset_path = path_offsets  # the path's shift, at the controller's clock
            policy_acts = handover_step is None or k < handover_step
            action = actor(obs) if policy_acts else np.zeros(cfg.action_size, np.float32)
            obs, reward_t, terminated, _, info = env.step(action)
            score += float(reward_t)
            if terminated:
                fell = True
                break
        return walk_result(walker, float(speed), fell, target_distance=distance, score=score, since=since,
                           since_x=since_x)
    finally:
        env.close()
