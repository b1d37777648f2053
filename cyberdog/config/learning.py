"""Settings of the learning agent and its training: networks and losses (Section 3, Table 4), the two stages, the
loop; and the experiment that joins them with the environment (`cyberdog.config.env`)."""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from typing import Optional, Tuple

from cyberdog.config._validate import _check, _non_negative, _positive
from cyberdog.config.env import STAGE1_REWARD, STAGE2_REWARD, EnvConfig, RewardConfig
from cyberdog.config.walk_settings import GaitConfig, WalkConfig


# ---------------------------------------------------------------------------------------------------------
# The learning agent and its training (paper Section 3, Table 4)
# ---------------------------------------------------------------------------------------------------------

ALGORITHMS = ("td3", "ddpg")
EXPLORATION_NOISES = ("gaussian", "ou")
DEVICES = ("cpu", "cuda", "auto")
BUFFER_POLICIES = ("clear", "keep", "relabel")
COLLECTION_MODES = ("sync", "async")
UNREAD_AGENT_FIELDS = ("fast_update",)  # what saved agent configs may hold that no setting reads: dropped
RELABELLED_TERMS = ("energy", "keep_moving")  # the reward terms a relabel recomputes at the start of stage 2


@dataclass(frozen=True)
class AgentConfig:
    """Actor–critic agent (paper Section 3: three hidden layers of 128 ReLU units; Table 4 learning rates)."""

    algorithm: str = "td3"  # "td3": twin critics, clipped double-Q, delayed actor; "ddpg": one critic
    hidden_sizes: Tuple[int, ...] = (128, 128, 128)  # units per hidden layer, actor and critic alike
    actor_lr: float = 4e-4  # Adam learning rate of the actor (Table 4)
    critic_lr: float = 2e-3  # Adam learning rate of the critic(s) (Table 4)
    gamma: float = 0.99  # discount per agent step (Ts = 25 ms)
    tau: float = 0.005  # soft (Polyak) target update rate per target update
    policy_delay: int = 2  # TD3: actor and target update every d-th critic update (DDPG: ignored, d = 1)
    policy_noise: float = 0.2  # TD3 target smoothing: std of the noise added to the target action (action units)
    noise_clip: float = 0.5  # TD3 target smoothing: clip of that noise (action units)
    exploration: str = "gaussian"  # one of EXPLORATION_NOISES: "gaussian" additive, or "ou" Ornstein–Uhlenbeck
    exploration_sigma: float = 0.1  # std of the exploration noise at the start (action units, actions in [−1, 1])
    exploration_sigma_end: float = 0.1  # std after `exploration_annealing_steps` env steps (linear annealing)
    exploration_annealing_steps: int = 100_000  # env steps over which sigma goes from start to end
    ou_theta: float = 0.15  # OU mean reversion rate (per OU step)
    ou_dt: float = 0.025  # OU time step (s); the agent step Ts
    max_grad_norm: float = 0.0  # gradient-norm clip of each optimizer step; 0 = off
    action_l2: float = 0.0  # actor loss += action_l2 · mean(μ(s)²): keeps a residual policy near the trot controller
    action_smoothness: float = 0.0  # actor loss += action_smoothness · mean((μ(s') − μ(s))²), the temporal
    #                                 smoothness term of CAPS (Mysore et al. 2021): a foot-mode policy that
    #                                 changes its offsets from step to step makes the PID jerk, which costs energy
    action_spatial_smoothness: float = 0.0  # actor loss += this · mean((μ(s̃) − μ(s))²), s̃ = s moved by
    #                                         spatial_smoothness_sigma of each entry's typical magnitude: CAPS's
    #                                         spatial term, a brake on the policy's feedback (0 = off)
    spatial_smoothness_sigma: float = 0.05  # s̃'s spread, in typical magnitudes of each observation entry
    trot_imitation: float = 0.0  # actor loss += trot_imitation · mean((μ(s) − (1 − w)·a_trot(s))²): a torque
    #                             policy pulled toward the share of the trot controller's torque (in action
    #                             units, EnvConfig.trot_reference) that the prior of weight w leaves out
    #                             (TD3+BC's regulariser, the trot as the behaviour); 0 = off
    actor_observation: Tuple[str, ...] = ()  # the observation groups the actor sees (names of CyberDog-v0's
    #                                          layout, e.g. ("target_speed", "gait_phase")); () = all. The
    #                                          critics always see the whole observation. An actor that sees
    #                                          only the command and the gait phase is a foot trajectory per
    #                                          speed by construction: what it learns is what extraction replays

    @staticmethod
    def upgrade_fields(data: dict) -> dict:
        """Read by `from_dict` before the fields: a saved agent without `UNREAD_AGENT_FIELDS`, so that the runs
        and actor files that hold them resume and load."""
        return {k: v for k, v in data.items() if k not in UNREAD_AGENT_FIELDS} if isinstance(data, dict) else data

    def __post_init__(self) -> None:
        _check(all(isinstance(g, str) and g for g in self.actor_observation)
               and len(set(self.actor_observation)) == len(self.actor_observation),
               "AgentConfig.actor_observation", "distinct observation group names (() = all)",
               self.actor_observation)
        _check(self.algorithm in ALGORITHMS, "AgentConfig.algorithm", f"one of {ALGORITHMS}", self.algorithm)
        _check(self.exploration in EXPLORATION_NOISES, "AgentConfig.exploration", f"one of {EXPLORATION_NOISES}",
               self.exploration)
        _check(len(self.hidden_sizes) >= 1 and all(int(h) == h and h >= 1 for h in self.hidden_sizes),
               "AgentConfig.hidden_sizes", "one or more positive integers", self.hidden_sizes)
        _positive(self, "actor_lr", "critic_lr", "tau", "ou_dt")
        _non_negative(self, "policy_noise", "noise_clip", "exploration_sigma", "exploration_sigma_end",
                      "ou_theta", "max_grad_norm", "action_l2", "action_smoothness", "action_spatial_smoothness",
                      "spatial_smoothness_sigma", "trot_imitation")
        _check(0 <= self.gamma < 1, "AgentConfig.gamma", "in [0, 1)", self.gamma)
        _check(self.tau <= 1, "AgentConfig.tau", "in (0, 1]", self.tau)
        _check(int(self.policy_delay) == self.policy_delay and self.policy_delay >= 1, "AgentConfig.policy_delay",
               "an integer >= 1", self.policy_delay)
        _check(self.exploration_annealing_steps >= 1, "AgentConfig.exploration_annealing_steps", ">= 1",
               self.exploration_annealing_steps)


@dataclass(frozen=True)
class StageConfig:
    """One stage of the paper's two-stage training (Section 3). Scores are in *our* reward units: one
    episode's summed reward, whose keep-moving bonus adds up to at most +25 (see configs/paper.yaml)."""

    reward: RewardConfig = field(default_factory=lambda: STAGE1_REWARD)  # Eq. (10)'s weights in this stage, by
    #                 the env's term names (speed, y_offset, fuselage, keep_moving, energy, energy_model, ...); a
    #                 partial mapping in YAML changes the named terms of the stage's default: stage 1 Eq. (11)
    #                 with E = 0 (STAGE1_REWARD), stage 2 Eq. (11) (STAGE2_REWARD). Training uses these, never
    #                 env.reward (ExperimentConfig refuses a changed one). With buffer_between_stages="relabel"
    #                 the two stages must agree on every term but energy and keep_moving (TrainConfig checks)
    max_episodes: int = 20_000  # episode budget of this stage (Table 4 "max episodes")
    max_env_steps: int = 0  # env-step budget of this stage; 0 = no step budget (episodes only)
    stop_score: float = 19.0  # stop when the mean score over `score_window` episodes reaches this; .inf = never
    save_score: float = 20.0  # save the agent whenever an episode's score reaches this (Table 4 "save agent")
    action_l2: Optional[float] = None  # the actor's action penalty in this stage; None = agent.action_l2
    trot_imitation: Optional[float] = None  # the pull toward the trot's torque in this stage; None = the agent's
    actor_anchor: float = 0.0  # actor loss += actor_anchor · mean((μ(s) − μ₀(s))²), μ₀ the actor this stage
    #                            started from (frozen): a continuation of a trained actor under critics that
    #                            have not yet learned its returns stays near it instead of following their
    #                            early action gradients (0 = none)
    actor_lr: Optional[float] = None  # the actor's learning rate in this stage; None = agent.actor_lr
    fresh_actor_optimizer: bool = False  # start the stage with a new Adam for the actor: the moments it kept
    #                                      were scaled to the previous stage's loss, and a larger gradient now
    #                                      (a new reward, a weaker action penalty) would take ~|g|/sqrt(v)
    #                                      times the learning rate per step until they catch up
    critic_warmup_updates: int = 0  # the stage's first updates train the critics only (actor and targets
    #                                 wait), so that the critics learn this stage's reward before the actor
    #                                 follows them
    critic_warmup_targets: bool = False  # during that warm-up the target networks follow (every policy_delay
    #                                      updates), so that the critics evaluate the actor as it is over many
    #                                      steps; False: they wait too (one step's reward over frozen targets)
    fresh_critics: bool = False  # a stage started from an agent (--init-from, a recipe's previous phase) keeps
    #                              only its actor: critics, optimizers and exploration noise start anew, as from an
    #                              actor file, so that a phase continued from shipped actor files and the same
    #                              phase in a lineage train alike

    @staticmethod
    def upgrade_fields(data: dict) -> dict:
        """Read by `from_dict` before the fields: a stage in its preset-name form, as a mapping (`upgrade_stage`)."""
        return upgrade_stage(data)

    def __post_init__(self) -> None:
        _check(isinstance(self.reward, RewardConfig), "StageConfig.reward", "a RewardConfig", self.reward)
        _check(self.max_episodes >= 1, "StageConfig.max_episodes", ">= 1", self.max_episodes)
        _check(self.max_env_steps >= 0, "StageConfig.max_env_steps", ">= 0 (0 = no step budget)",
               self.max_env_steps)
        _check(self.actor_lr is None or (math.isfinite(self.actor_lr) and self.actor_lr > 0),
               "StageConfig.actor_lr", "None (agent.actor_lr) or a finite number > 0", self.actor_lr)
        _check(self.critic_warmup_updates >= 0, "StageConfig.critic_warmup_updates", ">= 0",
               self.critic_warmup_updates)
        _check(self.action_l2 is None or (math.isfinite(self.action_l2) and self.action_l2 >= 0),
               "StageConfig.action_l2", "None (agent.action_l2) or a finite number >= 0", self.action_l2)
        _check(self.trot_imitation is None or (math.isfinite(self.trot_imitation) and self.trot_imitation >= 0),
               "StageConfig.trot_imitation", "None (agent.trot_imitation) or a finite number >= 0",
               self.trot_imitation)
        _check(math.isfinite(self.actor_anchor) and self.actor_anchor >= 0, "StageConfig.actor_anchor",
               "a finite number >= 0", self.actor_anchor)
        for n in ("stop_score", "save_score"):
            _check(not math.isnan(getattr(self, n)), f"StageConfig.{n}", "a number (.inf allowed)",
                   getattr(self, n))


def stage_reward(stage: StageConfig) -> RewardConfig:
    """The reward weights one training stage uses (its `reward`)."""
    return stage.reward


# A stage's reward in its preset-name form (`reward: stage1|stage2` and `<term>_weight` fields), as saved configs and
# actor files may hold it: read as the same reward, so that those runs resume and those actors load.
_STAGE_TERM_FIELDS = {"energy_weight": "energy", "keep_moving_weight": "keep_moving", "speed_weight": "speed",
                       "y_offset_weight": "y_offset", "speed_window": "speed_window",
                       "speed_deadband": "speed_deadband", "speed_at_nominal_stride": "speed_at_nominal_stride",
                       "energy_model": "energy_model"}


def upgrade_stage(data: dict) -> dict:
    """A stage mapping in the preset-name form (`reward: stage1|stage2` and `<term>_weight` fields) in the mapping
    form (`reward: {term: weight}`); the mapping form is returned unchanged."""
    if not isinstance(data, dict) or not (isinstance(data.get("reward"), str)
                                          or any(k in data for k in _STAGE_TERM_FIELDS)):
        return data
    out = {k: v for k, v in data.items() if k not in _STAGE_TERM_FIELDS}
    preset = data.get("reward", "stage1")
    if preset not in ("stage1", "stage2"):
        raise ValueError(f"StageConfig.reward must be a mapping of reward terms (or the preset name 'stage1' or "
                         f"'stage2'), got {preset!r}")
    base = STAGE1_REWARD if preset == "stage1" else STAGE2_REWARD
    reward = {f.name: getattr(base, f.name) for f in dataclasses.fields(base)}
    reward.update({term: data[k] for k, term in _STAGE_TERM_FIELDS.items() if data.get(k) is not None})
    out["reward"] = reward
    return out


@dataclass(frozen=True)
class TrainConfig:
    """Training loop: collection, replay, updates, stopping, checkpoints and logs."""

    seed: int = 0  # seeds torch, numpy, python and the environment
    device: str = "cpu"  # "cpu", "cuda" or "auto" (cuda if available); networks and updates
    stage1: StageConfig = field(default_factory=StageConfig)  # speed and direction, no energy term
    stage2: StageConfig = field(default_factory=lambda: StageConfig(reward=STAGE2_REWARD, stop_score=math.inf))
    score_window: int = 250  # episodes averaged for the stop test (Table 4 "score averaging window length")
    buffer_size: int = 1_000_000  # transitions kept in the replay buffer
    buffer_between_stages: str = "clear"  # "clear": rewards change at stage 2, so old transitions are dropped;
    #                                       "keep": kept with their old rewards; "relabel": kept, each reward
    #                                       recomputed with the new stage's energy weight (from the step's stored
    #                                       energy) and keep-moving weight
    batch_size: int = 256  # transitions per update
    init_random_frames: int = 5_000  # env steps with uniform random actions before learning starts (stage 1)
    learning_starts: int = 0  # env steps of the stage's first policy (+ noise) before the first update; lets
    #                           the critic see the walking controller before the actor moves (residual mode)
    frames_per_batch: int = 200  # env steps collected between rounds of updates
    updates_per_frame: float = 1.0  # critic updates per collected env step once learning has started
    checkpoint_every: int = 10_000  # env steps between periodic checkpoints (rounded up to frames_per_batch)
    deterministic: bool = False  # torch.use_deterministic_algorithms (bit-identical reruns, slower)
    num_threads: int = 0  # torch CPU threads of the updates; 0 = torch's default ("async": one core fewer)
    collection: str = "sync"  # "sync": env steps and updates take turns in this process (bit-identical reruns
    #                           and resumes); "async": the env runs in a worker process while the
    #                           updates run here, one batch ahead (~1.7x the env steps/s of "sync" on 2 idle
    #                           cores at 1 update per step, bench/train_throughput.py; the policy that collects
    #                           lags one batch of updates; reruns with a seed are identical too, but differ
    #                           from "sync"). See cyberdog/rl/collect.py
    num_envs: int = 1  # envs that collect, each in a process of its own (TorchRL ParallelEnv, stepped in lock
    #                    step; 1: one env in the collecting process): more env steps/s with more
    #                    cores. frames_per_batch must be a multiple of it; a seed repeats a run for a fixed
    #                    num_envs only. See cyberdog/rl/collect.py

    def __post_init__(self) -> None:
        _check(isinstance(self.seed, int) and 0 <= self.seed < 2 ** 32, "TrainConfig.seed",
               "an integer in [0, 2**32)", self.seed)
        _check(self.device in DEVICES, "TrainConfig.device", f"one of {DEVICES}", self.device)
        _check(self.collection in COLLECTION_MODES, "TrainConfig.collection", f"one of {COLLECTION_MODES}",
               self.collection)
        _check(self.buffer_between_stages in BUFFER_POLICIES, "TrainConfig.buffer_between_stages",
               f"one of {BUFFER_POLICIES}", self.buffer_between_stages)
        if self.buffer_between_stages == "relabel":  # a stored reward is recomputed from its step's energy and
            #                                          bonus only: every other term must be the same in both stages
            one, two = self.stage1.reward, self.stage2.reward
            for f in dataclasses.fields(RewardConfig):
                if f.name not in RELABELLED_TERMS:
                    _check(getattr(one, f.name) == getattr(two, f.name), f"TrainConfig.stage1.reward.{f.name}",
                           f"the same as stage2's ({getattr(two, f.name)!r}) with buffer_between_stages='relabel' "
                           "(only energy and keep_moving are recomputed)", getattr(one, f.name))
        for n in ("score_window", "buffer_size", "batch_size", "frames_per_batch", "checkpoint_every"):
            _check(getattr(self, n) >= 1, f"TrainConfig.{n}", ">= 1", getattr(self, n))
        _check(type(self.num_envs) is int and self.num_envs >= 1, "TrainConfig.num_envs", "an integer >= 1",
               self.num_envs)
        _check(self.frames_per_batch % self.num_envs == 0, "TrainConfig.frames_per_batch",
               f"a multiple of num_envs ({self.num_envs}): each env takes frames_per_batch / num_envs steps "
               "per batch", self.frames_per_batch)
        for n in ("init_random_frames", "learning_starts", "num_threads"):
            _check(getattr(self, n) >= 0, f"TrainConfig.{n}", ">= 0", getattr(self, n))
        _check(self.updates_per_frame > 0 and math.isfinite(self.updates_per_frame),
               "TrainConfig.updates_per_frame", "> 0 and finite", self.updates_per_frame)
        _check(self.batch_size <= self.buffer_size, "TrainConfig.batch_size",
               f"<= buffer_size ({self.buffer_size})", self.batch_size)


@dataclass(frozen=True)
class ExperimentConfig:
    """Everything `train.py` needs: the environment, the agent and the training loop."""

    env: EnvConfig = field(default_factory=lambda: EnvConfig(walk=WalkConfig(gait=GaitConfig(lift_height=0.10))))
    agent: AgentConfig = field(default_factory=AgentConfig)
    train: TrainConfig = field(default_factory=TrainConfig)

    @property
    def imitates_trot(self) -> bool:
        """The actor is pulled toward the trot's torque in some stage (agent or stage `trot_imitation` > 0)."""
        return self.agent.trot_imitation > 0 or any((getattr(self.train, f"stage{n}").trot_imitation or 0) > 0
                                                    for n in (1, 2))

    def __post_init__(self) -> None:
        env, s1 = self.env, self.train.stage1
        _check(env.reward == RewardConfig(), "EnvConfig.reward (env.reward)",
               "left at its default in a training config: each stage trains on its own reward "
               "(train.stage1.reward, train.stage2.reward)", env.reward)
        if env.prior_weight > 0 and env.prior_decay_steps > 0:  # the prior must be gone before stage 1 ends
            end = env.prior_decay_start + env.prior_decay_steps
            _check(0 < s1.max_env_steps and end <= s1.max_env_steps, "EnvConfig.prior_decay_steps",
                   f"such that prior_decay_start + prior_decay_steps <= train.stage1.max_env_steps "
                   f"({s1.max_env_steps}; a step budget is needed): the prior's weight reaches 0 within stage 1, "
                   f"and the policy alone is trained after it", env.prior_decay_steps)
        _check(not self.imitates_trot or env.trot_reference or env.prior_weight > 0, "EnvConfig.trot_reference",
               "true (or a prior) when the actor imitates the trot (agent or stage trot_imitation > 0): the "
               "reference is recorded per transition", env.trot_reference)
        _check(env.prior_weight == 0 or env.prior_decay_steps > 0, "EnvConfig.prior_decay_steps",
               "> 0 when training with a prior (EnvConfig.prior_weight > 0): its weight must decay to 0",
               env.prior_decay_steps)
