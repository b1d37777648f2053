"""Deterministic rollouts of a trained actor in `CyberDog-v0`, recorded at the physics rate.

This is how a policy is judged (issue "Training": does the stage-1 policy walk at 1.0 m/s, does the stage-2
policy use less energy per metre) and where the learned foot trajectory is extracted from (paper Section 3,
after Figure 6): the actor acts without exploration noise, and every physics step's joint angles, velocities,
applied torques and foot contacts are kept, so that gait cycles can be cut at touch-down and their energy
integrated by Eq. (7) exactly as in the scripted walks.

    actor = load_actor("results/policy_speeds/stage2_actor.pt")
    r = rollout(actor, speed=1.0, duration=10.0)
    r.mean_speed, r.energy_per_metre, r.fell
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import torch

from cyberdog import config as C
from cyberdog.core import energy as en
from cyberdog.envs.cyberdog_env import CyberDogEnv, observation_typical_magnitude
from cyberdog.rl.checkpoint import CheckpointError, check_shapes
from cyberdog.rl.networks import TanhActor


@dataclass
class LoadedActor:
    """A deterministic policy μ(s) and the experiment it was trained in."""

    module: TanhActor
    config: C.ExperimentConfig
    meta: dict = field(default_factory=dict)  # stage, episode, env_steps, score of the saved actor

    @torch.no_grad()
    def __call__(self, observation: np.ndarray) -> np.ndarray:
        obs = torch.as_tensor(observation, dtype=torch.float32)
        return self.module(obs).numpy().astype(np.float32)


def load_actor(path: str | Path) -> LoadedActor:
    """Load an actor file written by the trainer (`stage<N>_final_actor.pt`, `stage<N>_best_actor.pt`,
    `saved/*.pt`): its weights, and the experiment config saved beside them (needed for the env)."""
    path = Path(path)
    if not path.is_file():
        raise CheckpointError(f"actor file {path} does not exist")
    try:
        state = torch.load(path, map_location="cpu", weights_only=True)
    except Exception as e:
        raise CheckpointError(f"actor file {path} is corrupt or unreadable ({type(e).__name__}: {e})") from e
    if not isinstance(state, dict) or "actor" not in state or "config" not in state:
        raise CheckpointError(f"{path} is not an actor file (expected keys 'actor' and 'config')")
    cfg = C.from_dict(C.ExperimentConfig, state["config"])
    # TensorDictModule wraps TanhActor: its parameters are stored under "module."
    weights = {k.removeprefix("module."): v for k, v in state["actor"].items()}
    scale = observation_typical_magnitude(cfg.env)
    module = TanhActor(len(scale), 12, cfg.agent.hidden_sizes, scale)
    check_shapes(weights, module.state_dict(), "the actor", path)
    module.load_state_dict(weights)
    module.eval()
    meta = {k: state[k] for k in ("stage", "episode", "env_steps", "score") if k in state}
    return LoadedActor(module, cfg, meta)


@dataclass
class Rollout:
    """One deterministic episode; traces at the physics rate (dt = `physics_dt`)."""

    speed_command: float  # m/s
    duration: float  # s walked (shorter than asked if the robot fell)
    fell: bool
    mean_speed: float  # m/s, forward, over the second half of the rollout (the last 5 s of 10 s)
    distance: float  # m, forward displacement of the body
    lateral_drift: float  # m, |y| at the end
    energy: float  # J, Eq. (7) over the whole rollout
    score: float  # sum of the env's rewards (the reward the env was built with)
    physics_dt: float  # s
    traces: dict  # t, q, dq, tau (applied motor torque), contacts (4 feet), base_position; (n, ...) arrays;
    # foot_targets, foot_offsets (n, 4, 3) m: the trot controller's commanded foot targets and the policy's
    # shift in them (leg frame; action_mode "foot"; zeros without a shift, nan targets in torque mode)

    @property
    def energy_per_metre(self) -> float:
        """J/m over the whole rollout; nan without forward travel."""
        return self.energy / self.distance if self.distance > 0 else float("nan")

    @property
    def speed_ok(self) -> bool:
        """Mean speed within ±5 % of the command."""
        return abs(self.mean_speed - self.speed_command) <= 0.05 * self.speed_command

    def summary(self) -> dict:
        return {"speed_command_mps": self.speed_command, "mean_speed_mps": self.mean_speed,
                "fell": self.fell, "duration_s": self.duration, "distance_m": self.distance,
                "lateral_drift_m": self.lateral_drift, "energy_J": self.energy,
                "energy_per_m_J": self.energy_per_metre, "score": self.score}


_NO_TARGET = [(float("nan"),) * 3] * 4
_NO_OFFSET = [(0.0, 0.0, 0.0)] * 4


class _PhysicsRecorder:
    """Wraps the env's robot so that each physics step's state and applied torque are kept.

    The env reads the state after every physics step (`read_state`) and applies torques with `step`; both
    are intercepted on the instance only, so the env's own code path is the one being measured.
    """

    def __init__(self, robot, controller):
        self.robot, self.controller = robot, controller
        self._step, self._read = robot.step, robot.read_state
        self.q, self.dq, self.tau, self.contacts, self.base = [], [], [], [], []
        self.foot_targets, self.foot_offsets = [], []  # what the trot controller commanded (leg frame, m)
        self._last_state = None
        robot.step = self.step
        robot.read_state = self.read_state

    def read_state(self):
        self._last_state = self._read()
        return self._last_state

    def step(self, tau):
        applied = self._step(tau)
        s = self._last_state  # the state the torque acted on (Eq. 7 uses ω at the start of the step)
        self.q.append(s.q.copy())
        self.dq.append(s.dq.copy())
        self.tau.append(np.array(applied, dtype=float))
        self.base.append(s.base_position.copy())
        self.contacts.append(np.asarray(self.robot.foot_contacts(), dtype=bool))
        c = self.controller  # its last call computed this step's torque (torque mode: it does not run)
        self.foot_targets.append(c.last_foot_targets or _NO_TARGET)
        self.foot_offsets.append(c.last_foot_offsets or _NO_OFFSET)
        return applied

    def clear(self) -> None:
        for trace in (self.q, self.dq, self.tau, self.contacts, self.base, self.foot_targets, self.foot_offsets):
            trace.clear()

    def traces(self, dt: float) -> dict:
        n = len(self.tau)
        stack = (lambda xs, w: np.array(xs, dtype=float).reshape(n, w))
        return {"t": np.arange(n) * dt, "q": stack(self.q, 12), "dq": stack(self.dq, 12),
                "tau": stack(self.tau, 12), "base_position": stack(self.base, 3),
                "contacts": np.array(self.contacts, dtype=bool).reshape(n, 4),
                "foot_targets": np.array(self.foot_targets, dtype=float).reshape(n, 4, 3),
                "foot_offsets": np.array(self.foot_offsets, dtype=float).reshape(n, 4, 3)}


def rollout(actor: LoadedActor, speed: float = 1.0, duration: float = 10.0, seed: int = 0,
            env_config: C.EnvConfig | None = None, reward: str | C.RewardConfig = "stage2") -> Rollout:
    """Run the actor deterministically for `duration` s at `speed` m/s in the env it was trained in
    (or `env_config`), recording every physics step. Stops early if the robot falls."""
    if not (np.isfinite(speed) and speed >= 0):
        raise ValueError(f"speed must be >= 0 m/s, got {speed!r}")
    if not duration > 0:
        raise ValueError(f"duration must be > 0 s, got {duration!r}")
    cfg = env_config or actor.config.env
    cfg = dataclasses.replace(cfg, episode_time=max(cfg.episode_time, duration), target_speed_range=())
    env = CyberDogEnv(config=cfg, reward=reward)
    try:
        obs, _ = env.reset(seed=seed, options={"target_speed": float(speed)})
        rec = _PhysicsRecorder(env.robot, env.controller)
        start = env.robot.read_state().base_position.copy()
        rec.clear()
        n_steps = int(round(duration / cfg.control_dt))
        score, fell = 0.0, False
        for _ in range(n_steps):
            obs, reward_t, terminated, _, info = env.step(actor(obs))
            score += float(reward_t)
            if terminated:
                fell = True
                break
        dt = cfg.walk.sim.physics_dt
        traces = rec.traces(dt)
        end = env.robot.read_state().base_position
    finally:
        env.close()
    n = len(traces["t"])
    vx = np.gradient(traces["base_position"][:, 0], dt) if n > 1 else np.zeros(n)
    return Rollout(speed_command=float(speed), duration=n * dt, fell=fell,
                   mean_speed=float(np.mean(vx[n // 2:])) if n else 0.0,
                   distance=float(end[0] - start[0]), lateral_drift=float(abs(end[1] - start[1])),
                   energy=float(en.joint_energy(traces["tau"], traces["dq"], dt).sum()), score=score,
                   physics_dt=dt, traces=traces)
