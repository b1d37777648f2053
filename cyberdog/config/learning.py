"""Settings of the learning agent and its training: networks and losses (Section 3, Table 4), the two stages, the
loop; and the experiment that joins them with the environment (`cyberdog.config.env`)."""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from typing import Optional, Tuple

from cyberdog.config._validate import _check, _non_negative, _positive
from cyberdog.config.env import ENERGY_MODELS, STAGE1_REWARD, STAGE2_REWARD, EnvConfig, RewardConfig
from cyberdog.config.robot import GaitConfig, WalkConfig


# ---------------------------------------------------------------------------------------------------------
# The learning agent and its training (paper Section 3, Table 4)
# ---------------------------------------------------------------------------------------------------------

ALGORITHMS = ("td3", "ddpg")
EXPLORATION_NOISES = ("gaussian", "ou")
DEVICES = ("cpu", "cuda", "auto")
BUFFER_POLICIES = ("clear", "keep", "relabel")
COLLECTION_MODES = ("sync", "async")


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
    fast_update: bool = True  # TD3: losses computed directly over the loss's parameters (cyberdog.rl.fast_td3,
    #                           checked against TorchRL's TD3Loss); False = TD3Loss's own (vmap over tensordicts)
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
    #                             units, EnvConfig.trot_reference) that the prior of weight w no longer gives
    #                             (TD3+BC's regulariser, the trot as the behaviour); 0 = off
    actor_observation: Tuple[str, ...] = ()  # the observation groups the actor sees (names of CyberDog-v0's
    #                                          layout, e.g. ("target_speed", "gait_phase")); () = all. The
    #                                          critics always see the whole observation. An actor that sees
    #                                          only the command and the gait phase is a foot trajectory per
    #                                          speed by construction: what it learns is what extraction replays

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

    reward: str = "stage1"  # reward preset of CyberDog-v0: "stage1" (E = 0) or "stage2" (Eq. 11)
    max_episodes: int = 20_000  # episode budget of this stage (Table 4 "max episodes")
    max_env_steps: int = 0  # env-step budget of this stage; 0 = no step budget (episodes only)
    stop_score: float = 19.0  # stop when the mean score over `score_window` episodes reaches this; .inf = never
    save_score: float = 20.0  # save the agent whenever an episode's score reaches this (Table 4 "save agent")
    energy_weight: Optional[float] = None  # E of Eq. (10) per J for this stage; None = the preset's (0 or −0.2)
    keep_moving_weight: Optional[float] = None  # D of Eq. (10) for this stage; None = the preset's (25): the
    #                                             survival bonus per episode, which must outweigh the energy
    #                                             cost of walking or falling at once becomes the best policy
    speed_weight: Optional[float] = None  # A of Eq. (10) per (m/s)² for this stage; None = the preset's (−2).
    #                                       With E = −0.2 per J, walking Δv slower saves ~0.9·Δv per step
    #                                       (the trot's power rises ~185 W per m/s) and costs |A|·Δv², so the
    #                                       reward's optimum is Δv = 0.9 / (2|A|): 0.23 m/s below the command
    #                                       with A = −2, 0.011 m/s with A = −40. With "relabel" both stages
    #                                       must have the same A (TrainConfig checks)
    speed_window: Optional[float] = None  # s over which the speed term averages speed and command
    #                                       (RewardConfig.speed_window); None = per step, the paper's. With
    #                                       "relabel" both stages must have the same window (TrainConfig checks)
    speed_deadband: Optional[float] = None  # share of the command within which the speed term is 0
    #                                         (RewardConfig.speed_deadband); None = the paper's term. With
    #                                         "relabel" both stages must have the same (TrainConfig checks)
    speed_at_nominal_stride: Optional[bool] = None  # the speed term on the speed at the commanded stride
    #                                                 (RewardConfig.speed_at_nominal_stride); None = the
    #                                                 preset's (False). With "relabel" both stages must agree
    y_offset_weight: Optional[float] = None  # B of Eq. (10) per m² for this stage; None = the preset's (−20).
    #                                          An actor that does not see the lateral offset cannot hold the
    #                                          line (the trot controller's heading correction does), so for it
    #                                          the term is noise in the return. With "relabel" both stages
    #                                          must have the same B (TrainConfig checks)
    energy_model: Optional[str] = None  # what this stage's energy term measures (RewardConfig.energy_model);
    #                                     None = "mechanical" (Eq. 7). With buffer_between_stages="relabel" both
    #                                     stages must name the same model: the stored step energy is the model's
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

    def __post_init__(self) -> None:
        _check(self.reward in ("stage1", "stage2"), "StageConfig.reward", "'stage1' or 'stage2'", self.reward)
        _check(self.max_episodes >= 1, "StageConfig.max_episodes", ">= 1", self.max_episodes)
        _check(self.max_env_steps >= 0, "StageConfig.max_env_steps", ">= 0 (0 = no step budget)",
               self.max_env_steps)
        _check(self.energy_weight is None or (math.isfinite(self.energy_weight) and self.energy_weight <= 0),
               "StageConfig.energy_weight", "None (the preset's) or a finite number <= 0 (per J)",
               self.energy_weight)
        _check(self.keep_moving_weight is None or (math.isfinite(self.keep_moving_weight)
                                                    and self.keep_moving_weight >= 0),
               "StageConfig.keep_moving_weight", "None (the preset's) or a finite number >= 0",
               self.keep_moving_weight)
        _check(self.speed_weight is None or (math.isfinite(self.speed_weight) and self.speed_weight <= 0),
               "StageConfig.speed_weight", "None (the preset's) or a finite number <= 0 (per (m/s)²)",
               self.speed_weight)
        _check(self.speed_window is None or (math.isfinite(self.speed_window) and 0 <= self.speed_window <= 10),
               "StageConfig.speed_window", "None (per step) or in [0, 10] s", self.speed_window)
        _check(self.speed_deadband is None or (math.isfinite(self.speed_deadband) and 0 <= self.speed_deadband < 1),
               "StageConfig.speed_deadband", "None (the paper's term) or in [0, 1)", self.speed_deadband)
        _check(self.speed_at_nominal_stride is None or isinstance(self.speed_at_nominal_stride, bool),
               "StageConfig.speed_at_nominal_stride", "None (the preset's), True or False",
               self.speed_at_nominal_stride)
        _check(self.y_offset_weight is None or (math.isfinite(self.y_offset_weight) and self.y_offset_weight <= 0),
               "StageConfig.y_offset_weight", "None (the preset's) or a finite number <= 0 (per m²)",
               self.y_offset_weight)
        _check(self.energy_model is None or self.energy_model in ENERGY_MODELS, "StageConfig.energy_model",
               f"None or one of {ENERGY_MODELS}", self.energy_model)
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
    """The reward weights one training stage uses: its preset, with `energy_weight`, `keep_moving_weight`,
    `speed_weight`, `speed_window`, `speed_deadband`, `speed_at_nominal_stride`, `y_offset_weight` and
    `energy_model` if set."""
    preset = STAGE1_REWARD if stage.reward == "stage1" else STAGE2_REWARD
    changes = {}
    if stage.energy_weight is not None:
        changes["energy"] = float(stage.energy_weight)
    if stage.keep_moving_weight is not None:
        changes["keep_moving"] = float(stage.keep_moving_weight)
    if stage.speed_weight is not None:
        changes["speed"] = float(stage.speed_weight)
    if stage.speed_window is not None:
        changes["speed_window"] = float(stage.speed_window)
    if stage.speed_deadband is not None:
        changes["speed_deadband"] = float(stage.speed_deadband)
    if stage.speed_at_nominal_stride is not None:
        changes["speed_at_nominal_stride"] = stage.speed_at_nominal_stride
    if stage.y_offset_weight is not None:
        changes["y_offset"] = float(stage.y_offset_weight)
    if stage.energy_model is not None:
        changes["energy_model"] = stage.energy_model
    return dataclasses.replace(preset, **changes) if changes else preset


@dataclass(frozen=True)
class TrainConfig:
    """Training loop: collection, replay, updates, stopping, checkpoints and logs."""

    seed: int = 0  # seeds torch, numpy, python and the environment
    device: str = "cpu"  # "cpu", "cuda" or "auto" (cuda if available); networks and updates
    stage1: StageConfig = field(default_factory=StageConfig)  # speed and direction, no energy term
    stage2: StageConfig = field(default_factory=lambda: StageConfig(reward="stage2", stop_score=math.inf))
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
    #                           and resumes, as before); "async": the env runs in a worker process while the
    #                           updates run here, one batch ahead (~1.7x the env steps/s of "sync" on 2 idle
    #                           cores at 1 update per step, bench/train_throughput.py; the policy that collects
    #                           lags one batch of updates; reruns with a seed are identical too, but differ
    #                           from "sync"). See cyberdog/rl/collect.py
    num_envs: int = 1  # envs that collect, each in a process of its own (TorchRL ParallelEnv, stepped in lock
    #                    step; 1: one env in the collecting process, as before): more env steps/s with more
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
        models = [s.energy_model or "mechanical" for s in (self.stage1, self.stage2)]
        _check(self.buffer_between_stages != "relabel" or models[0] == models[1], "TrainConfig.stage1.energy_model",
               f"the same as stage2's ({models[1]!r}) with buffer_between_stages='relabel' (the stored step "
               "energy is the model's)", models[0])
        for term in ("speed", "y_offset"):  # a stored reward's speed and lateral terms cannot be recomputed
            w = [stage_reward(s).weights[term] for s in (self.stage1, self.stage2)]
            _check(self.buffer_between_stages != "relabel" or w[0] == w[1], f"TrainConfig.stage1.{term}_weight",
                   f"the same weight as stage2's ({w[1]}) with buffer_between_stages='relabel'", w[0])
        windows = [stage_reward(s).speed_window for s in (self.stage1, self.stage2)]
        _check(self.buffer_between_stages != "relabel" or windows[0] == windows[1], "TrainConfig.stage1.speed_window",
               f"the same window as stage2's ({windows[1]} s) with buffer_between_stages='relabel'", windows[0])
        bands = [stage_reward(s).speed_deadband for s in (self.stage1, self.stage2)]
        _check(self.buffer_between_stages != "relabel" or bands[0] == bands[1], "TrainConfig.stage1.speed_deadband",
               f"the same deadband as stage2's ({bands[1]}) with buffer_between_stages='relabel'", bands[0])
        strides = [stage_reward(s).speed_at_nominal_stride for s in (self.stage1, self.stage2)]
        _check(self.buffer_between_stages != "relabel" or strides[0] == strides[1],
               "TrainConfig.stage1.speed_at_nominal_stride",
               f"the same as stage2's ({strides[1]}) with buffer_between_stages='relabel'", strides[0])
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
