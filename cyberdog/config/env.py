"""Settings of the learning environment `CyberDog-v0`: the reward (Eq. 10-11) and the MDP (Tables 3-4), with the
torque mode's documented departures (the drivers' damping, the decaying trot prior)."""
from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field
from typing import Optional, Tuple

from cyberdog.config._validate import _check, _non_negative, _positive

from cyberdog.config.hardware import HardwareConfig, RandomizationConfig, check_controller_periods
from cyberdog.config.walk_settings import GaitConfig, WalkConfig


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
    # s over which r_v compares the speed with the command: both are averaged over the last `speed_window` s
    # (the steps since the reset while fewer). 0 = each step's own speed, the paper's. A trot's body surges and
    # slows within each stride (about 0.04 m/s rms at 1.0 m/s), so a per-step r_v with a large A also pays the
    # gait for a smoother surge; one gait period (0.4 s) leaves only the error of the speed the robot walks
    speed_window: float = 0.0
    # share of the command within which r_v is 0: r_v = max(0, |v_cmd − v_x| − speed_deadband·v_cmd)² (on the
    # window's means with speed_window > 0). 0 = the paper's term. A share inside the evaluation's ±5 % band
    # leaves the gait free to walk anywhere near the command and pays it only for walking off it
    speed_deadband: float = 0.0
    # r_v on the speed the gait walks at the stride its command asks for: v_x · v_cmd / (v_cmd + c), with c (m/s)
    # the trot's speed-loop correction (ControllerConfig.max_speed_correction bounds it), which lengthens the
    # stride when the body falls behind. False = v_x, the paper's. A foot-mode gait that leans on the loop walks
    # the command where training drew its robots and leaves the loop no margin for a robot that needs more (a
    # stiffer joint PD); paid for that lean, it carries the speed in its own foot path
    speed_at_nominal_stride: bool = False
    # r_v on the error as a share of the episode's set speed, ((v_cmd − v_x) / v_set)², unitless (A per share²;
    # A = −300 in m/s at 1.2 m/s is −432 here). False = in m/s, the paper's. The evaluation's band is a share
    # (±5 %): in m/s a 5 % error at 1.0 m/s is paid half what it is at 1.4 m/s, and an energy term pulls the
    # lowest command's walk slowest
    speed_relative: bool = False
    # share of the command beyond which r_v stops growing: the error counts up to speed_cap·v_cmd (after the
    # deadband). 0 = no cap, the paper's. The episode ends at a fall, so an unbounded r_v makes a fall the better
    # end of a walk far off the command once A·r_v per step exceeds the keep-moving bonus D·Ts/Tf: capped, a
    # walk with D·Ts/Tf > |A|·r_v(cap) + |E|·r_E always scores above a fall
    speed_cap: float = 0.0

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
        _check(0 <= self.speed_window <= 10 and math.isfinite(self.speed_window), "RewardConfig.speed_window",
               "in [0, 10] s (0 = per step, the paper's)", self.speed_window)
        _check(0 <= self.speed_deadband < 1 and math.isfinite(self.speed_deadband), "RewardConfig.speed_deadband",
               "in [0, 1) (a share of the command; 0 = the paper's)", self.speed_deadband)
        _check(isinstance(self.speed_at_nominal_stride, bool), "RewardConfig.speed_at_nominal_stride",
               "True or False", self.speed_at_nominal_stride)
        _check(isinstance(self.speed_relative, bool), "RewardConfig.speed_relative", "True or False",
               self.speed_relative)
        _check(0 <= self.speed_cap < 10 and math.isfinite(self.speed_cap), "RewardConfig.speed_cap",
               "in [0, 10) (a share of the command; 0 = no cap, the paper's)", self.speed_cap)


STAGE1_REWARD = RewardConfig(energy=0.0)  # paper Section 3: stage 1 learns speed and direction, E = 0
STAGE2_REWARD = RewardConfig()  # stage 2: Eq. (11) with the energy term, E = −0.2


# ---------------------------------------------------------------------------------------------------------
# The learning environment (paper Section 3, Tables 3-4)
# ---------------------------------------------------------------------------------------------------------

ACTION_MODES = ("torque", "residual", "foot", "foot_torque")
FOOT_MODES = ("foot", "foot_torque")  # the modes whose action shifts the trot's foot targets (a commanded path)


# what saved env configs may hold at these values, which leave the trot prior's decay as it is: the trainer's
# progress (env steps done, per step of one env), which the env gets at run time, not from its config
TRAINING_PROGRESS_FIELDS = {"prior_steps_done": 0, "prior_step_stride": 1}


@dataclass(frozen=True)
class EnvConfig:
    """`CyberDog-v0`: the paper's MDP (Tables 3-4) on the task the shipped agents learn. Degrees appear only
    here, at the edge, and are converted once.

    The defaults are the registered `CyberDog-v0` task's: the action shifts the trot controller's foot targets
    (±3 cm per axis), the observation appends the previous action (62), and the command is drawn per episode
    from the paper's 1.0-1.4 m/s. The paper's own MDP as written (joint torques, Table 3's 50 observations, a
    fixed command) is `cyberdog.envs.registration.PAPER_TASK` (`CyberDogPaper-v0`, `configs/paper.yaml`).
    """

    # robot, actuator, sim, gait, PID, controller, energy; the lift height is 0.10 m (not the paper's 0.15 m)
    # so that the trot stays inside Table 4's ±45° joint range around the standing pose
    walk: WalkConfig = field(default_factory=lambda: WalkConfig(gait=GaitConfig(lift_height=0.10)))
    reward: RewardConfig = field(default_factory=RewardConfig)  # Eq. (11) weights (stage 2 by default)
    control_dt: float = 0.025  # s, agent sample time Ts (paper Section 3)
    episode_time: float = 10.0  # s, Tf; 400 steps at Ts = 25 ms (Table 4 "max steps")
    # "torque": the paper's, the action is the joint torque; "residual": torque added to the trot controller's;
    # "foot": offsets of the trot controller's foot targets (the controller's IK + PID then track them), the
    # shipped agents' (Table 5, the battery); the paper's torque agent is configs/torque.yaml; "foot_torque": the
    # foot offsets (12) and a joint torque (12) the trot adds to its feedforward, so that a force the path needs
    # is sent as a force, not as a position error the PD's gains scale
    action_mode: str = "foot"
    action_scale: float = 25.0  # N·m per unit action (Table 4 torque limit); torque, residual, foot_torque
    foot_offset_scale: float = 0.03  # m per unit action in action_mode="foot" (offset of each foot target)
    foot_offset_scale_z: Optional[float] = None  # m per unit action on the vertical axis; None = foot_offset_scale
    observe_last_action: bool = True  # append the previous action (12) to Table 3's observation (50 -> 62):
    #                                    in foot mode it is the offset the next action ramps from, which sets
    #                                    the step's jerk and energy; without it the critics cannot see that cost
    observe_pd_stiffness: bool = False  # append the joint PD's stiffness (1 entry, after the previous action):
    #                                     the hip kp the drivers run now over the robot's default 60 N·m/rad,
    #                                     so that a policy may command a path per stiffness a user sets
    # torque mode only: the motor drivers' damping, τ = τ_action − joint_damping·q̇ at every physics step
    # (the drivers' kd with kp = 0). 0 = the paper's pure torque. A documented departure (docs/training.md, the
    # torque recipe): a torque held over Ts = 25 ms cannot damp a light leg, and MathWorks' example, whose settings
    # Table 4 copies, gives every joint 8 N·m·s/rad of damping. Here it is motor torque, so Eq. 7 books its work
    joint_damping: float = 0.0  # N·m·s/rad
    # torque mode only: a prior from the trot controller (trajectory + IK + PD at the state of the agent step,
    # held over Ts like the action), added to the action's torque with a weight that decays linearly from
    # `prior_weight` to exactly 0 over `prior_decay_steps` env steps of training (DecAP, arXiv 2310.05714).
    # 0 = no prior (the paper's). Evaluation always runs without it (`cyberdog.rl.rollout`)
    prior_weight: float = 0.0  # weight at the start of training (1 = the trot's whole torque)
    prior_decay_start: int = 0  # env steps (all envs together) at the full weight before the decay begins
    prior_decay_steps: int = 0  # env steps over which the weight then falls linearly to 0; 0 = it stays
    # torque mode only: report the trot controller's torque at each step's start state, in action units, as
    # info["trot_action"] (computed anyway while the prior acts): what the actor may be pulled toward in training
    # (AgentConfig.trot_imitation). It does not act on the robot
    trot_reference: bool = False
    joint_range_deg: float = 45.0  # ± around the standing pose (Table 4 "joint control range")
    joint_stop_stiffness: float = 200.0  # N·m/rad, virtual end stop beyond the joint range
    joint_stop_damping: float = 2.0  # N·m·s/rad, damping of the virtual end stop (only while beyond it)
    target_speed: float = 1.0  # m/s, commanded forward speed v_x (fixed when target_speed_range is ())
    # (low, high) m/s: the command is drawn per episode and observed, so one policy walks the paper's three
    # speeds (Table 5); () = target_speed every episode (the paper's MDP)
    target_speed_range: Tuple[float, ...] = (1.0, 1.4)
    # the robot's hardware effects (joint friction, actuation latency, encoder and IMU noise, Kalman speed
    # feedback, mass draw): the same model as the prototype walks'. In the env the mass is drawn per episode
    # from the env's seed and the sensors are seeded per episode too (`HardwareConfig.seed` is not used)
    hardware: HardwareConfig = field(default_factory=HardwareConfig)
    # domain randomisation: the ranges each episode's robot is drawn from (friction, latency, mass, motor
    # strength, PID gains, ground friction); the default is the nominal robot, every episode the same
    randomization: RandomizationConfig = field(default_factory=RandomizationConfig)
    fall_height: float = 0.15  # m, body centre below this = fallen
    fall_tilt_deg: float = 45.0  # |roll| or |pitch| above this = fallen

    @staticmethod
    def upgrade_fields(data: dict) -> dict:
        """Read by `from_dict` before the fields: a saved config's `TRAINING_PROGRESS_FIELDS` at the values that
        leave the schedule as it is (0 steps done, 1 per step) are dropped; any other value is refused."""
        if not isinstance(data, dict) or not any(k in data for k in TRAINING_PROGRESS_FIELDS):
            return data
        for name, inert in TRAINING_PROGRESS_FIELDS.items():
            _check(data.get(name, inert) == inert, f"EnvConfig.{name}", f"absent (or {inert}): the trot prior's "
                   "decay counts the trainer's env steps, which the trainer gives the env as it runs "
                   "(CyberDogEnv.set_training_progress)", data.get(name))
        return {k: v for k, v in data.items() if k not in TRAINING_PROGRESS_FIELDS}

    @property
    def decimation(self) -> int:
        """Controller periods (`walk.sim.controller_dt`) per agent step."""
        return int(round(self.control_dt / self.walk.sim.controller_dt))

    @property
    def action_size(self) -> int:
        """Entries of the action: 12 (a torque or a foot shift per joint), 24 in "foot_torque" (both)."""
        return 24 if self.action_mode == "foot_torque" else 12

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
        check_controller_periods(self.hardware, dt, "EnvConfig.hardware", "walk.sim.controller_dt")
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
        r, hw = self.randomization, self.hardware
        periods = int(round(hw.latency_s / dt))
        _check(r.latency_periods == (0, 0) or r.latency_periods[0] <= periods <= r.latency_periods[1],
               "EnvConfig.randomization.latency_periods", f"(0, 0) (the hardware's own latency: EnvConfig.hardware."
               f"latency_s = {hw.latency_s} s, {periods} periods) or a range that contains {periods}: a drawn "
               "latency replaces the hardware's", r.latency_periods)
        _check(r.mass_scale == (1.0, 1.0) or r.mass_scale[0] <= 1 - hw.mass_uncertainty <= 1 + hw.mass_uncertainty
               <= r.mass_scale[1], "EnvConfig.randomization.mass_scale", "(1, 1) (the hardware's own mass draw: "
               f"EnvConfig.hardware.mass_uncertainty = ±{hw.mass_uncertainty}) or a range that contains "
               f"1 ± {hw.mass_uncertainty}: a drawn mass replaces the hardware's", r.mass_scale)
        _non_negative(self, "joint_damping", "prior_weight", "prior_decay_start", "prior_decay_steps")
        for name in ("joint_damping", "prior_weight", "trot_reference"):
            _check(getattr(self, name) == 0 or self.action_mode == "torque", f"EnvConfig.{name}",
                   "0 unless action_mode is 'torque' (the other modes run the trot controller's PD at the "
                   "controller rate)", getattr(self, name))

    def prior_weight_at(self, env_steps: int) -> float:
        """The trot prior's weight after `env_steps` env steps of training (all envs together): `prior_weight`
        for `prior_decay_start` steps, then linear to exactly 0 over `prior_decay_steps` (constant if that is 0)."""
        if self.prior_weight == 0 or self.prior_decay_steps == 0:
            return float(self.prior_weight)
        into = max(0, env_steps - self.prior_decay_start)
        return float(self.prior_weight) * max(0.0, 1.0 - into / self.prior_decay_steps)
