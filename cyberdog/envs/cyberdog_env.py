"""`CyberDog-v0`: the paper's MDP (Section 3, Eq. 10–11, Tables 3–4) as a gymnasium environment."""
from __future__ import annotations

import dataclasses
import math
import warnings
from typing import Any

import gymnasium as gym
import numpy as np

from cyberdog import config as C
from cyberdog.control.joint_stop import JointStop
from cyberdog.control.trot import TrotController
from cyberdog.core import rewards
from cyberdog.core.kinematics import UnreachableFootTarget
from cyberdog.envs.observation import (DEFAULT_KP, LAST_ACTION_LAYOUT, OBSERVATION_LAYOUT,  # noqa: F401 (re-exported)
                                      PD_STIFFNESS_LAYOUT, actor_observation_scale, observation_layout,
                                      observation_size, observation_typical_magnitude)
from cyberdog.loop.walker import Walker
from cyberdog.sim.hardware_model import draw_mass_scale, draw_robot, resolve_draw

REWARD_PRESETS = {"stage1": C.STAGE1_REWARD, "stage2": C.STAGE2_REWARD}
# CyberDog-v0's reward: Eq. 11 with the presets' keep-moving bonus D = 300, under which walking (+70 over an
# episode) scores above falling (−47); with Eq. 11's D = 25 falling early scores higher (PAPER_REWARD_WARNING)
TASK_REWARD = C.RewardConfig(keep_moving=300.0)
PAPER_REWARD_WARNING = (
    "CyberDog-v0 with the paper's stage-2 reward (Eq. 11: keep-moving bonus D = 25, energy E = -0.2 per J; "
    "EnvConfig's default) has no fall penalty, and with it falling early scores higher than walking: a policy "
    "trained on it learns to fall. Train with reward='stage1' first, or with a larger keep-moving bonus "
    "(RewardConfig(keep_moving=300), the task's own, as configs/table5.yaml's stage 2); see docs/environment.md")

class CyberDogEnv(gym.Env):
    """The CyberDog walks forward at a commanded speed; the paper's reward (Eq. 10) trades speed, straightness,
    body height, survival and energy. `CyberDogEnv()` is the registered `CyberDog-v0`.

    **Timing.** The agent acts every Ts = 25 ms (`control_dt`); the joint controller's command is held per
    2.5 ms period (`walk.sim.controller_dt`, 10 per agent step); the motor drivers close their PD at every
    physics step (`walk.sim.physics_dt`, 800 Hz at the default gains). An episode is Tf = 10 s = 400 steps
    (the registration's `max_episode_steps`, Table 4). All of it runs in `cyberdog.loop.walker.Walker`, the
    loop of every scripted walk too.

    **Action** (12,) ((24,) in foot_torque), float32 in [−1, 1], legs LF, RF, LH, RH × joints (abad, hip, knee):

    | mode | the action is | scale |
    |---|---|---|
    | `foot` (default) | a shift of the trot controller's foot targets (Δx, Δy, Δz) per leg, ramped from the last action's over the step; IK + PID track the shifted path | ±`foot_offset_scale` 0.03 m per axis (z: `foot_offset_scale_z` if set) |
    | `foot_torque` | the foot shifts (the first 12, as `foot`) and a joint torque the trot adds to its feedforward, held over the step (the last 12) | as `foot`; × `action_scale` N·m |
    | `residual` | a torque added to the trot controller's | × `action_scale` N·m |
    | `torque` | the joint torque, held over the step (the paper's, Table 3) | × `action_scale` 25 N·m |

    In torque mode two departures are available, both off by default (docs/training.md): the drivers' damping
    `joint_damping` and a trot prior τ = 25·a + w·τ_trot whose weight w decays to 0 over training
    (`prior_weight`, `prior_decay_steps`); `info["prior_weight"]` is the step's w, `info["trot_action"]` τ_trot
    in action units with `trot_reference`. Table 4's ±45° joint range is a virtual end stop around the standing
    pose (`joint_stop_stiffness`, `joint_stop_damping`); the default lift height, 0.10 m, keeps the trot inside it.

    **Observation** (50,), (62,) or (63,), float32, clipped to finite bounds (`OBSERVATION_LAYOUT`):

    | slice | content | unit |
    |---|---|---|
    | 0, 1 | body height z, lateral offset y | m |
    | 2:5 | roll, pitch, yaw | rad |
    | 5:8 | body linear velocity, body frame (true, or the Kalman estimate) | m/s |
    | 8:11 | body angular velocity, body frame | rad/s |
    | 11:23, 23:35, 35:47 | joint angles, joint velocities, joint torques (last period) | rad, rad/s, N·m |
    | 47 | commanded speed (ramped from 0 over `walk.controller.speed_ramp_time`, then the set speed) | m/s |
    | 48:50 | sin, cos of LF's gait phase | – |
    | 50:62 (50:74) | the previous action (`observe_last_action`, on by default) | action units |
    | last | hip PD stiffness / 60 N·m/rad (`observe_pd_stiffness`) | – |

    One entry per physical quantity of the paper's groups (Section 2; its 111-entry list is not given), no
    forward position (unbounded), plus the command and phase a speed- and gait-aware policy needs.

    **Reward**, Eq. 10: r = A·(v_cmd − v_x)² + B·y² + C·(z − z_nom)² + D·Ts/Tf + E·Σ∫|τ·ω|dt, weights from
    `reward` (a `RewardConfig`: Eq. 11's (−2, −20, −50, 25, −0.2) by default; `TASK_REWARD`, D = 300, for
    `CyberDogEnv()`; "stage1" sets E = 0). With Eq. 11's D = 25 falling early scores above walking, and a
    warning says so unless a reward is chosen. `info["reward_terms"]` (unweighted) and
    `info["reward_weighted"]` sum to the reward; `step_energy_J` is Eq. 7, `step_electrical_energy_J` the
    battery's draw when `reward.energy_model="electrical"` puts it in the energy term. The speed term's
    options (`speed_window`, `speed_deadband`, `speed_at_nominal_stride`, `speed_relative`, `speed_cap`) are
    documented where `RewardConfig` declares them; `forward_speed`, `forward_speed_used` and
    `forward_speed_paid` are the true speed, the one the robot's software knows and the one paid.

    **Episode end.** `terminated`: the body below `fall_height` (0.15 m) or tilted beyond `fall_tilt_deg`
    (45°), a non-finite state, or a foot target beyond the leg's reach (`info["fall_reason"]`). `truncated`:
    only the registration's time limit.

    **Options.** `config` (an `EnvConfig`, taken as it is), `reward` ("stage1", "stage2" or a `RewardConfig`),
    `render_mode` ("rgb_array", or "human": a PyBullet window), and any top-level `EnvConfig` field as a
    keyword (`target_speed=1.2` alone fixes the command). `reset(options={"target_speed": v})` sets one
    episode's command; `{"hardware_robot": True}` walks the scripted walks' robot (`hardware.seed`'s draws).

    **Robots.** `hardware` (a `HardwareConfig`, off by default): joint friction, latency, encoder and IMU
    noise, the Kalman speed, a mass draw, what the prototype walks use; the controller, the observation and
    the reward's v_x see what the sensors read. `randomization` (a `RandomizationConfig`, off by default): each
    episode's robot drawn from ranges of friction, latency, mass, motor strength, PID gains and ground friction
    (`info["robot_draw"]` of `reset`). All randomness comes from the env's generator: the same seed, the same
    episodes.
    """

    metadata = {"render_modes": ["rgb_array", "human"], "render_fps": 40}

    def __init__(self, config: C.EnvConfig | None = None, reward: str | C.RewardConfig | None = None,
                 render_mode: str | None = None, **overrides: Any):
        if config is None and reward is None:  # the registered task: EnvConfig's defaults, TASK_REWARD
            reward = TASK_REWARD
        cfg = config or C.EnvConfig()
        reward_chosen = reward is not None
        if reward is not None:
            if isinstance(reward, str):
                if reward not in REWARD_PRESETS:
                    raise ValueError(f"reward must be one of {sorted(REWARD_PRESETS)} or a RewardConfig, "
                                     f"got {reward!r}")
                reward = REWARD_PRESETS[reward]
            overrides["reward"] = reward
        unknown = sorted(set(overrides) - {f.name for f in dataclasses.fields(C.EnvConfig)})
        if unknown:
            raise ValueError(f"unknown CyberDog-v0 option(s) {unknown}")
        if "target_speed" in overrides:  # a speed given alone fixes the command (the drawn range would win)
            overrides.setdefault("target_speed_range", ())
        self.cfg = cfg = dataclasses.replace(cfg, **overrides) if overrides else cfg
        if not reward_chosen and cfg.reward == C.STAGE2_REWARD:  # the default, taken without a word
            warnings.warn(PAPER_REWARD_WARNING, UserWarning, stacklevel=2)
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(f"render_mode must be one of {self.metadata['render_modes']}, got {render_mode!r}")
        self.render_mode = render_mode
        walk = cfg.walk
        self.dt = walk.sim.controller_dt
        self.decimation = cfg.decimation
        # the one simulation loop: robot + trot controller + hardware model; the controller is off in the
        # paper's torque mode; virtual end stops at ±joint_range around the standing pose (Table 4)
        self.walker = Walker(walk, TrotController(walk), hardware=None if cfg.hardware.ideal else cfg.hardware,
                             joint_stop=JointStop(walk.robot, np.deg2rad(cfg.joint_range_deg),
                                                  cfg.joint_stop_stiffness, cfg.joint_stop_damping),
                             drive=cfg.action_mode != "torque", gui=(render_mode == "human"),
                             fall_height=cfg.fall_height, fall_tilt=np.deg2rad(cfg.fall_tilt_deg),
                             body_trace=False,  # the env reads the state, not the walk's per-period body trace
                             joint_damping=cfg.joint_damping,
                             rate_per_robot=cfg.randomization.drivers_rate_per_robot)
        layout = observation_layout(cfg)
        low = np.concatenate([np.full(n, lo_, dtype=np.float32) for _, n, lo_, _, _ in layout])
        high = np.concatenate([np.full(n, hi_, dtype=np.float32) for _, n, _, hi_, _ in layout])
        self.observation_space = gym.spaces.Box(low, high, dtype=np.float32)
        self.action_space = gym.spaces.Box(-1.0, 1.0, (cfg.action_size,), dtype=np.float32)
        z_scale = cfg.foot_offset_scale if cfg.foot_offset_scale_z is None else cfg.foot_offset_scale_z
        self._foot_offset_scale = np.array([cfg.foot_offset_scale, cfg.foot_offset_scale, z_scale])  # m, x y z
        self._state = None
        # r_v over the last reward.speed_window s (None: each step's own speed, the paper's)
        self._speed_window = (rewards.SpeedWindow(max(1, round(cfg.reward.speed_window / cfg.control_dt)))
                              if cfg.reward.speed_window > 0 else None)
        self._steps_taken = 0  # env steps since `set_training_progress` (all episodes): the prior's decay counts them
        self._training_steps, self._steps_per_step = 0, 1  # the trainer's progress (`set_training_progress`)

    # ----------------------------------------------------------------------------------------------------
    def reset(self, *, seed: int | None = None, options: dict | None = None):
        super().reset(seed=seed)
        cfg = self.cfg
        options = options or {}
        if "target_speed" in options:
            self.target_speed = float(options["target_speed"])
            if not (np.isfinite(self.target_speed) and self.target_speed >= 0):
                raise ValueError(f"target_speed must be >= 0 m/s, got {options['target_speed']!r}")
        elif cfg.target_speed_range:
            self.target_speed = float(self.np_random.uniform(*cfg.target_speed_range))
        else:
            self.target_speed = cfg.target_speed
        hw = cfg.hardware  # per episode: a mass draw and sensor noise seeded from the env's generator
        if options.get("hardware_robot"):  # the robot of hw.seed, as a scripted walk with this `hw` draws it
            mass_scale = sensor_rng = draw = None
        else:
            mass_scale = draw_mass_scale(hw, self.np_random) if hw.mass_uncertainty > 0 else None
            sensor_rng = np.random.default_rng(self.np_random.integers(2 ** 63))
            # domain randomisation drawn last: an env without it repeats its episodes exactly as before
            draw = draw_robot(cfg.randomization, self.np_random) if cfg.randomization.enabled else None
        if draw is not None:  # one robot: the ranges left nominal keep the hardware's latency and mass draw
            draw = resolve_draw(draw, cfg.randomization, self.walker.latency_steps, mass_scale)
        self.walker.set_speed(self.target_speed)
        self._state = self.walker.reset(mass_scale=mass_scale, sensor_rng=sensor_rng, draw=draw)
        self.last_torque = np.zeros(12)
        self._last_action = np.zeros(cfg.action_size)  # the previous action, observed with `observe_last_action`
        if self._speed_window is not None:
            self._speed_window.reset()
        info = {"target_speed": self.target_speed}
        if draw is not None:
            info["robot_draw"] = dataclasses.asdict(draw)
        return self._observation(), info

    @property
    def t(self) -> float:
        """s since the reset."""
        return self.walker.time

    def _forward_speed_used(self, s) -> float:
        """m/s, the forward speed the robot's software knows: the Kalman estimate on hardware that estimates
        it, else the simulator's truth."""
        v = self.walker.velocity_estimate_world
        return float(s.base_linear_velocity_world[0] if v is None else v[0])

    def step(self, action):
        if self._state is None:
            raise RuntimeError("call reset() before step()")
        a = np.asarray(action, dtype=np.float64)
        if a.shape != self.action_space.shape:
            raise ValueError(f"action must have shape {self.action_space.shape}, got {a.shape}")
        values = a.tolist()  # the action's checks and the foot offsets in floats: too few numbers for numpy
        if not math.isfinite(sum(values)) and not all(map(math.isfinite, values)):
            raise ValueError(f"action must be finite, got {values}")
        clipped = [1.0 if x > 1.0 else -1.0 if x < -1.0 else x for x in values]  # np.clip to [-1, 1]
        self._last_action = np.array(clipped)
        w = self.walker
        if self.cfg.action_mode in C.FOOT_MODES:  # the action moves the foot targets; the controller's torque is as is
            # a first-order hold over the agent step, from the last action's offsets to this one's: a staircase
            # of targets makes the PID jerk (docs/design.md)
            sx, sy, sz = self._foot_offset_scale.tolist()
            w.ramp_foot_offsets_to([(clipped[i] * sx, clipped[i + 1] * sy, clipped[i + 2] * sz)
                                    for i in range(0, 12, 3)], self.cfg.control_dt)  # m, 4 × (x, y, z)
            if self.cfg.action_mode == "foot_torque":  # and sends a force through the drivers, held over the step
                scale = self.cfg.action_scale
                w.controller.set_joint_torque([x * scale for x in clipped[12:]])  # N·m
            tau_action = None
        else:
            tau_action = self._last_action * self.cfg.action_scale
        prior_weight = self.prior_weight
        self._steps_taken += 1
        k0 = w.steps
        trot_action = None
        try:
            if prior_weight > 0 or self.cfg.trot_reference:  # the trot's torque at this step's state, held
                trot = self._trot_torque_or_none(must=prior_weight > 0)
                if trot is not None:
                    trot_action = np.clip(trot / self.cfg.action_scale, -1.0, 1.0)
                    if prior_weight > 0:
                        tau_action = tau_action + prior_weight * trot
            applied = w.run(self.decimation, tau_action)  # the controller periods (bench/env_throughput.py)
        except UnreachableFootTarget as e:  # the trot asks for a foot beyond the leg's reach: the robot is going down
            return self._end_unreachable(k0, str(e), prior_weight)
        s = self._state = w.state
        self.last_torque = applied
        step_energy = w.energy(since=k0)  # Eq. (7)
        step_electrical = w.electrical_energy(since=k0) if self.cfg.reward.energy_model == "electrical" else None
        obs, reward, terminated, truncated, info = self._finish_step(s, step_energy, step_electrical, prior_weight)
        if trot_action is not None:
            info["trot_action"] = trot_action
        return obs, reward, terminated, truncated, info

    def _trot_torque_or_none(self, must: bool) -> np.ndarray | None:
        """N·m (12,), the trot controller's torque at the state read now, for the agent step (its speed integral
        advances by the step's periods). A foot target out of reach raises if the torque `must` act (the prior),
        else gives None (a reference only: the robot is not driven by it)."""
        try:
            return self.walker.trot_torque(self.decimation)
        except UnreachableFootTarget:
            if must:
                raise
            return None

    def set_training_progress(self, training_steps: int, steps_per_step: int = 1) -> None:
        """The trainer's progress, which the trot prior's weight decays over: `training_steps` env steps of training
        are done, and each step of this env from now on adds `steps_per_step` (the envs that collect in lock step)."""
        if training_steps < 0 or steps_per_step < 1:
            raise ValueError(f"training_steps must be >= 0 and steps_per_step >= 1, got {training_steps}, "
                             f"{steps_per_step}")
        self._training_steps, self._steps_per_step, self._steps_taken = int(training_steps), int(steps_per_step), 0

    @property
    def prior_weight(self) -> float:
        """The trot prior's weight for the next step (torque mode; `EnvConfig.prior_weight_at`): 0 without one."""
        return self.cfg.prior_weight_at(self._training_steps + self._steps_per_step * self._steps_taken)

    def _end_unreachable(self, k0: int, why: str, prior_weight: float):
        """The step in which the trot controller asked for a foot beyond the leg's reach: the episode ends as a
        fall (`terminated`, `info["fall_reason"]`), with the energy of the periods that did run."""
        s = self._state = self.walker.state
        step_energy = self.walker.energy(since=k0)
        electrical = (self.walker.electrical_energy(since=k0) if self.cfg.reward.energy_model == "electrical"
                      else None)
        obs, reward, _, truncated, info = self._finish_step(s, step_energy, electrical, prior_weight)
        info.update(fallen=True, fall_reason=f"unreachable foot target ({why})")
        return obs, reward, True, truncated, info

    def _finish_step(self, s, step_energy: float, step_electrical: float | None = None, prior_weight: float = 0.0):
        cfg = self.cfg
        v_true = float(s.base_linear_velocity_world[0])
        v_used = self._forward_speed_used(s)
        y = float(s.base_position[1] - self.walker.start[1])
        v_cmd = self.walker.commanded_speed  # the ramped command (see the class docstring)
        v_paid = v_used
        if cfg.reward.speed_at_nominal_stride:  # the speed at the command's own stride
            stride = v_cmd + self.walker.speed_correction  # m/s: the speed the trot's stride is set for
            if stride > 0:
                v_paid = v_used * v_cmd / stride
        window = self._speed_window
        v_reward, v_cmd_reward = (v_paid, v_cmd) if window is None else window.add(v_paid, v_cmd)
        terms = rewards.reward_terms(v_x=v_reward, v_target=v_cmd_reward, y=y, z=float(s.base_position[2]),
                                     z_nominal=cfg.reward.z_nominal, sample_time=cfg.control_dt,
                                     episode_time=cfg.episode_time,
                                     step_energy_J=step_energy if step_electrical is None else step_electrical,
                                     speed_deadband=cfg.reward.speed_deadband,
                                     speed_per=self.target_speed if cfg.reward.speed_relative else None,
                                     speed_cap=cfg.reward.speed_cap)
        weighted = rewards.weighted_terms(terms, cfg.reward)
        reward = float(sum(weighted.values()))
        finite = math.isfinite(sum(s.q.tolist()) + sum(s.base_position.tolist()))  # a NaN or inf anywhere
        fallen = self.walker.fallen(s)
        terminated = bool(fallen or not finite)
        info = {"reward_terms": terms, "reward_weighted": weighted, "step_energy_J": step_energy,
                "step_electrical_energy_J": step_electrical,
                "forward_speed": v_true, "forward_speed_used": v_used, "forward_speed_paid": v_paid,
                "speed_loop_correction": self.walker.speed_correction, "target_speed": self.target_speed,
                "velocity_estimate": self.walker.velocity_estimate_world, "fallen": bool(fallen),
                "time": self.t, "prior_weight": prior_weight}
        if terminated:
            info["fall_reason"] = "fell (body height or tilt)" if fallen else "non-finite state"
        if self.render_mode == "human":
            self.render()
        return self._observation(), reward, terminated, False, info

    # ----------------------------------------------------------------------------------------------------
    def _observation(self) -> np.ndarray:
        s = self._state
        q, dq = self.walker.sensed_joints(s)
        v_world = self.walker.velocity_estimate_world
        v_body = s.base_linear_velocity_body if v_world is None else s.rotation_matrix.T @ v_world
        w = self.walker
        phase = 2 * np.pi * w.gait_phase
        obs = np.concatenate([
            [s.base_position[2], s.base_position[1] - self.walker.start[1]], s.base_rpy, v_body,
            s.base_angular_velocity_body, q, dq, self.last_torque, [w.commanded_speed],
            [np.sin(phase), np.cos(phase)]]
            + ([self._last_action] if self.cfg.observe_last_action else [])
            + ([[w.hip_kp / DEFAULT_KP]] if self.cfg.observe_pd_stiffness else [])
        ).astype(np.float32)
        if not np.isfinite(obs).all():  # rare (a blown-up state): NaN → 0, ±inf → the extremes, then clipped
            obs = np.nan_to_num(obs, nan=0.0)
        return np.minimum(np.maximum(obs, self.observation_space.low, out=obs), self.observation_space.high, out=obs)

    def render(self):
        if self.render_mode == "rgb_array":
            return self.walker.render(320, 240)
        return None

    def close(self):
        if getattr(self, "walker", None) is not None:
            self.walker.close()
            self.walker = None
