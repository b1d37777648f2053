"""Settings of the learning problem: reward (Eq. 10-11), state estimator, environment (Tables 3-4), agent, training."""
from __future__ import annotations

import dataclasses
import functools
import math
from dataclasses import dataclass, field
from typing import Optional, Tuple

from cyberdog.config._validate import _check, _non_negative, _positive

from cyberdog.config.robot import GaitConfig, HardwareConfig, RandomizationConfig, WalkConfig


REWARD_TERM_NAMES = ("speed", "y_offset", "fuselage", "keep_moving", "energy")  # Eq. (10) order: A … E


ENERGY_MODELS = ("mechanical", "electrical")  # what the reward's energy term measures


@dataclass(frozen=True)
class RewardConfig:
    """Weights of the reward terms, Eq. (10); defaults are the paper's Eq. (11): A…E = −2, −20, −50, 25, −0.2.

    Each weight multiplies an unweighted term of `cyberdog.core.rewards`; a weight of 0 turns its term off.
    Penalties (speed, y_offset, fuselage, energy) must be ≤ 0 and the keep-moving bonus ≥ 0, so that a sign
    slip cannot reward the robot for drifting. Stage 1 of the paper's training ignores energy (E = 0,
    `STAGE1_REWARD`); stage 2 adds it (`STAGE2_REWARD`).
    """

    speed: float = -2.0  # A, per (m/s)², on r_v = (v_target − v_x)²
    y_offset: float = -20.0  # B, per m², on r_yoffset = y²
    fuselage: float = -50.0  # C, per m², on r_Fuselage stable = (z − z_nominal)²
    keep_moving: float = 25.0  # D, on r_Keep moving = Ts / Tf (sums to D over a full episode)
    energy: float = -0.2  # E, per J, on r_E = Σ_ij ∫|τ_ij · θ̇_ij| dt over the step (Eq. 7)
    z_nominal: float = 0.30  # m, body height the fuselage term measures from (= RobotConfig.body_height)
    # what r_E measures: "mechanical" (Eq. 7, the paper's) or "electrical" (what the battery pays: copper loss,
    # friction and driver efficiency of `cyberdog.core.energy.electrical_power`, about 3.5x Eq. 7 at 1 m/s)
    energy_model: str = "mechanical"

    @functools.cached_property
    def weights(self) -> dict[str, float]:
        """Weights by term name, in the order of Eq. (10) (made once: the config is frozen; do not modify)."""
        return {n: getattr(self, n) for n in REWARD_TERM_NAMES}

    def __post_init__(self) -> None:
        for n in REWARD_TERM_NAMES:
            v = getattr(self, n)
            rule = ">= 0 and finite (a bonus)" if n == "keep_moving" else "<= 0 and finite (a penalty)"
            ok = math.isfinite(v) and (v >= 0 if n == "keep_moving" else v <= 0)
            _check(ok, f"RewardConfig.{n}", rule, v)
        _check(0 < self.z_nominal <= 0.5 and math.isfinite(self.z_nominal), "RewardConfig.z_nominal",
               "in (0, 0.5] m", self.z_nominal)
        _check(self.energy_model in ENERGY_MODELS, "RewardConfig.energy_model", f"one of {ENERGY_MODELS}",
               self.energy_model)


STAGE1_REWARD = RewardConfig(energy=0.0)  # paper Section 3: stage 1 learns speed and direction, E = 0
STAGE2_REWARD = RewardConfig()  # stage 2: Eq. (11) with the energy term, E = −0.2


# ---------------------------------------------------------------------------------------------------------
# The learning environment (paper Section 3, Tables 3-4)
# ---------------------------------------------------------------------------------------------------------

ACTION_MODES = ("torque", "residual", "foot")


@dataclass(frozen=True)
class EnvConfig:
    """`CyberDog-v0`: the paper's MDP. Degrees appear only here, at the edge, and are converted once."""

    # robot, actuator, sim, gait, PID, controller, energy; the lift height is 0.10 m (not the paper's 0.15 m)
    # so that the trot stays inside Table 4's ±45° joint range around the standing pose
    walk: WalkConfig = field(default_factory=lambda: WalkConfig(gait=GaitConfig(lift_height=0.10)))
    reward: RewardConfig = field(default_factory=RewardConfig)  # Eq. (11) weights (stage 2 by default)
    control_dt: float = 0.025  # s, agent sample time Ts (paper Section 3)
    episode_time: float = 10.0  # s, Tf; 400 steps at Ts = 25 ms (Table 4 "max steps")
    # "torque": the paper's, the action is the joint torque; "residual": torque added to the trot controller's;
    # "foot": offsets of the trot controller's foot targets (the controller's IK + PID then track them)
    action_mode: str = "residual"
    action_scale: float = 25.0  # N·m per unit action (Table 4 torque command limit); torque, residual modes
    foot_offset_scale: float = 0.03  # m per unit action in action_mode="foot" (offset of each foot target)
    foot_offset_scale_z: Optional[float] = None  # m per unit action on the vertical axis; None = foot_offset_scale
    observe_last_action: bool = False  # append the previous action (12) to Table 3's observation (50 -> 62):
    #                                    in foot mode it is the offset the next action ramps from, which sets
    #                                    the step's jerk and energy; without it the critics cannot see that cost
    joint_range_deg: float = 45.0  # ± around the standing pose (Table 4 "joint control range")
    joint_stop_stiffness: float = 200.0  # N·m/rad, virtual end stop beyond the joint range
    joint_stop_damping: float = 2.0  # N·m·s/rad, damping of the virtual end stop (only while beyond it)
    target_speed: float = 1.0  # m/s, commanded forward speed v_x (fixed unless a range is given)
    target_speed_range: Tuple[float, ...] = ()  # (low, high) m/s: sample the command per episode; () = fixed
    # the robot's hardware effects (joint friction, actuation latency, encoder and IMU noise, Kalman speed
    # feedback, mass draw): the same model as the prototype walks'. In the env the mass is drawn per episode
    # from the env's seed and the sensors are seeded per episode too (`HardwareConfig.seed` is not used)
    hardware: HardwareConfig = field(default_factory=HardwareConfig)
    # domain randomisation: the ranges each episode's robot is drawn from (friction, latency, mass, motor
    # strength, PID gains, ground friction); the default is the nominal robot, every episode the same
    randomization: RandomizationConfig = field(default_factory=RandomizationConfig)
    fall_height: float = 0.15  # m, body centre below this = fallen
    fall_tilt_deg: float = 45.0  # |roll| or |pitch| above this = fallen

    @property
    def decimation(self) -> int:
        """Controller periods (`walk.sim.controller_dt`) per agent step."""
        return int(round(self.control_dt / self.walk.sim.controller_dt))

    @property
    def max_episode_steps(self) -> int:
        return int(round(self.episode_time / self.control_dt))

    def __post_init__(self) -> None:
        _positive(self, "control_dt", "episode_time", "action_scale", "foot_offset_scale", "joint_range_deg",
                  "fall_height", "fall_tilt_deg")
        _non_negative(self, "target_speed", "joint_stop_stiffness", "joint_stop_damping")
        dt = self.walk.sim.controller_dt
        _check(abs(self.control_dt / dt - round(self.control_dt / dt)) < 1e-6 and self.control_dt >= dt,
               "EnvConfig.control_dt", f"a whole multiple of walk.sim.controller_dt ({dt} s)", self.control_dt)
        hw_dt = self.hardware.estimator_dt
        _check(abs(hw_dt / dt - round(hw_dt / dt)) < 1e-6 and hw_dt >= dt,
               "EnvConfig.hardware.estimator_dt", f"a whole multiple of walk.sim.controller_dt ({dt} s)", hw_dt)
        _check(abs(self.hardware.latency_s / dt - round(self.hardware.latency_s / dt)) < 1e-6,
               "EnvConfig.hardware.latency_s", f"a whole multiple of walk.sim.controller_dt ({dt} s)",
               self.hardware.latency_s)
        _check(self.action_mode in ACTION_MODES, "EnvConfig.action_mode", f"one of {ACTION_MODES}",
               self.action_mode)
        _check(self.randomization.joint_friction_scale == (1.0, 1.0) or self.hardware.friction,
               "EnvConfig.randomization.joint_friction_scale", "(1, 1) unless hardware.friction is on (the scale "
               "acts on the simulated joint friction)", self.randomization.joint_friction_scale)
        r = self.target_speed_range
        _check(len(r) == 0 or (len(r) == 2 and 0 <= r[0] <= r[1]), "EnvConfig.target_speed_range",
               "() or (low, high) with 0 <= low <= high (m/s)", r)
        _check(self.foot_offset_scale_z is None or (math.isfinite(self.foot_offset_scale_z)
                                                     and self.foot_offset_scale_z > 0),
               "EnvConfig.foot_offset_scale_z", "None or a finite number > 0 (m)", self.foot_offset_scale_z)
        _check(self.joint_range_deg <= 180, "EnvConfig.joint_range_deg", "in (0, 180]", self.joint_range_deg)


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
                      "ou_theta", "max_grad_norm", "action_l2", "action_smoothness")
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
    y_offset_weight: Optional[float] = None  # B of Eq. (10) per m² for this stage; None = the preset's (−20).
    #                                          An actor that does not see the lateral offset cannot hold the
    #                                          line (the trot controller's heading correction does), so for it
    #                                          the term is noise in the return. With "relabel" both stages
    #                                          must have the same B (TrainConfig checks)
    energy_model: Optional[str] = None  # what this stage's energy term measures (RewardConfig.energy_model);
    #                                     None = "mechanical" (Eq. 7). With buffer_between_stages="relabel" both
    #                                     stages must name the same model: the stored step energy is the model's
    action_l2: Optional[float] = None  # the actor's action penalty in this stage; None = agent.action_l2
    actor_lr: Optional[float] = None  # the actor's learning rate in this stage; None = agent.actor_lr
    fresh_actor_optimizer: bool = False  # start the stage with a new Adam for the actor: the moments it kept
    #                                      were scaled to the previous stage's loss, and a larger gradient now
    #                                      (a new reward, a weaker action penalty) would take ~|g|/sqrt(v)
    #                                      times the learning rate per step until they catch up
    critic_warmup_updates: int = 0  # the stage's first updates train the critics only (actor and targets
    #                                 wait), so that the critics learn this stage's reward before the actor
    #                                 follows them

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
        for n in ("stop_score", "save_score"):
            _check(not math.isnan(getattr(self, n)), f"StageConfig.{n}", "a number (.inf allowed)",
                   getattr(self, n))


def stage_reward(stage: StageConfig) -> RewardConfig:
    """The reward weights one training stage uses: its preset, with `energy_weight`, `keep_moving_weight`,
    `speed_weight`, `y_offset_weight` and `energy_model` if set."""
    preset = STAGE1_REWARD if stage.reward == "stage1" else STAGE2_REWARD
    changes = {}
    if stage.energy_weight is not None:
        changes["energy"] = float(stage.energy_weight)
    if stage.keep_moving_weight is not None:
        changes["keep_moving"] = float(stage.keep_moving_weight)
    if stage.speed_weight is not None:
        changes["speed"] = float(stage.speed_weight)
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
