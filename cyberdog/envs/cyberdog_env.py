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
PAPER_REWARD_WARNING = (
    "CyberDog-v0 with the paper's stage-2 reward (Eq. 11: keep-moving bonus D = 25, energy E = -0.2 per J; the "
    "default) has no fall penalty, and with it falling early scores higher than walking: a policy trained on it "
    "learns to fall. Train with reward='stage1' first, or with a larger keep-moving bonus (RewardConfig("
    "keep_moving=300), as configs/table5.yaml's stage 2); see docs/environment.md")

class CyberDogEnv(gym.Env):
    """The CyberDog walks forward at a commanded speed; the paper's reward trades speed, straightness,
    body height, survival and energy.

    **Timing.** The joint controller runs at 400 Hz (`walk.sim.controller_dt`): its command (targets, target
    speeds, gains, feed-forward) is held over the period, and the motor drivers close their PD on the joint
    state at every physics step (800 Hz, `walk.sim.physics_dt`); the agent acts every Ts = 25 ms
    (`control_dt`, 10 controller periods); an episode lasts Tf = 10 s = 400 steps (registered
    `max_episode_steps=400`, Table 4). All of it runs in the project's one simulation loop
    (`cyberdog.loop.walker.Walker`, the same as the scripted walks').

    **Action** (12,), float32 in [−1, 1], joint order LF, RF, LH, RH × (abad, hip, knee), scaled by
    `action_scale` = 25 N·m (Table 4), then through the actuator model (clip, torque–speed curve):
    - `action_mode="torque"` (the paper's, Table 3): the action is the joint torque, held over the agent step;
      two documented departures can be switched on (both off by default; docs/training.md, the torque recipe):
      the drivers' damping `joint_damping` (−c·q̇ at every physics step, motor torque that Eq. 7 books), and a
      prior from the trot controller whose weight decays to exactly 0 during training (`prior_weight`,
      `prior_decay_steps`; DecAP): τ = 25·a + w·τ_trot, τ_trot computed at the agent step's state and held.
      `info["prior_weight"]` is the weight the step used; with `trot_reference` (or a prior) `info["trot_action"]`
      is τ_trot in action units (clipped to ±1), what a learner may pull its actor toward;
    - `action_mode="residual"` (default): the action is added to the torque of the diagonal trot controller
      (trajectory + IK + PID), so that a policy learns corrections to a walking gait — practical on a CPU;
    - `action_mode="foot"`: the action shifts the trot controller's foot targets by up to
      ±`foot_offset_scale` (0.03 m) per axis (z: `foot_offset_scale_z` if set), (Δx, Δy, Δz) per leg in the
      same leg order, reached by a linear ramp over the agent step from the last action's; the controller's
      IK + PID track the shifted
      path. The policy reshapes the foot trajectory itself (a trajectory-modulating policy, cf. Iscen et al.
      2018, "Policies Modulating Trajectory Generators"), which a torque residual barely can: the joint PID
      (60 N·m/rad) pulls the joints back to the path, and the residual policies stayed within 0.5 % of the
      controller's energy (README).
    Table 4's joint control range (±45°) is enforced around the standing pose by a virtual end stop: beyond
    the range a spring-damper torque (`joint_stop_stiffness`, `joint_stop_damping`) pushes the joint back.
    (The default lift height in the env is 0.10 m so that the trot stays inside that range; the paper's
    0.15 m needs about 51° of knee flexion.)

    **Observation** (50,), (62,) or (63,), float32, clipped to finite bounds (`OBSERVATION_LAYOUT`):

    | slice | content | unit |
    |---|---|---|
    | 0 | body height z | m |
    | 1 | lateral offset y | m |
    | 2:5 | roll, pitch, yaw | rad |
    | 5:8 | body linear velocity, body frame (true, or Kalman estimate) | m/s |
    | 8:11 | body angular velocity, body frame | rad/s |
    | 11:23 | joint angles | rad |
    | 23:35 | joint velocities | rad/s |
    | 35:47 | joint torques (last controller period) | N·m |
    | 47 | commanded speed (ramped up over the first `speed_ramp_time`, then the set speed) | m/s |
    | 48:50 | sin, cos of the gait phase | – |
    | 50:62 | the previous action, only with `observe_last_action` | action units |
    | next | the joint PD's stiffness (hip kp / 60 N·m/rad), only with `observe_pd_stiffness` | – |

    The paper's model has 111 observations in these groups (torso position, orientation, joint angles,
    3-D velocities, angular velocities, joint velocities, joint torques, Section 2); its full list is not
    given. We keep one entry per physical quantity (no forward position x, which is unbounded) and add the
    command and phase the policy needs to be speed- and gait-aware.

    **Commanded speed.** The robot starts from rest, so the command ramps linearly from 0 to the set speed
    over `walk.controller.speed_ramp_time` (1 s), as in the scripted walks; the reward's v_cmd and the
    observed command are that ramped value. (With the set speed in the reward from t = 0, the start-up ramp
    alone cost about −40 of a 400-step episode's score, and a policy learned to fight the ramp instead of
    walking straight: measured in `configs/quick_residual.yaml` runs.)

    **Reward**, Eq. (10): r = A·(v_cmd − v_x)² + B·y² + C·(z − z_nom)² + D·Ts/Tf + E·Σ∫|τ·ω|dt, with
    (A, B, C, D, E) = (−2, −20, −50, 25, −0.2) (Eq. 11; `reward="stage1"` sets E = 0). `info` carries every
    term unweighted (`reward_terms`) and weighted (`reward_weighted`), which sum to the reward, plus
    `step_energy_J` (Eq. 7), `forward_speed` (true) and `forward_speed_used` (what the reward saw). With
    `reward.energy_model="electrical"` the energy term is the electrical energy drawn over the step (copper
    loss, friction, driver efficiency: `cyberdog.core.energy.electrical_power`), also in
    `step_electrical_energy_J` (None otherwise). With `reward.speed_window` > 0, r_v compares the means of the
    speed and of the command over the last `speed_window` s (the steps since the reset while fewer), so that
    the within-stride surge of a trot is not paid for (`forward_speed_used` stays the step's own speed); with
    `reward.speed_deadband`, only the error beyond that share of the command; with
    `reward.speed_at_nominal_stride`, on the speed the gait would walk at the stride its command asks for
    (`forward_speed_paid`: v · v_cmd / (v_cmd + the trot's speed-loop correction, `speed_loop_correction`)); with
    `reward.speed_relative`, on the error as a share of the episode's set speed (`target_speed`); with
    `reward.speed_cap`, the error counted only up to that share of the command.

    **Training on the default task.** The registered default is the paper's stage-2 reward, which has no fall
    penalty: with D = 25 and E = −0.2 per J, the walking trot scores about −205 over 400 steps and an
    all-ones action that falls after 38 steps about −73, so falling early is the better policy (a warning says
    so, unless a reward is passed). Train with `reward="stage1"` (walking +18, falling −50) or a larger keep-moving bonus,
    `RewardConfig(keep_moving=300)` as the presets' stage 2 (walking +70, falling −47).

    **Episode end.** `terminated` when the body falls below `fall_height` (0.15 m), tilts beyond
    `fall_tilt_deg` (45°) in roll or pitch, the state is not finite, or the trot controller (residual mode, or
    the torque mode's prior) asks for a foot beyond the leg's reach (a robot going down); `info["fall_reason"]`
    says which. `truncated` only by the time limit of the registration.

    **Options** (keyword arguments of `gymnasium.make("CyberDog-v0", ...)`): `config` (an `EnvConfig`),
    `reward` ("stage1", "stage2" or a `RewardConfig`), `render_mode` ("rgb_array", or "human": a PyBullet window;
    on a machine without a display it runs without one, with a warning), and any top-level `EnvConfig` field,
    e.g. `action_mode="torque"`, `target_speed=1.2` (a speed given alone fixes the command: the task's drawn
    1.0–1.4 m/s would otherwise win), `hardware=C.HARDWARE_LIKE`.

    **Domain randomisation** (`randomization`, a `RandomizationConfig`, off by default): each episode's robot
    is drawn from ranges of joint friction, actuation latency, link masses, motor strength, PID gains and
    ground friction, from the env's generator (same seed, same robots; `info["robot_draw"]` of `reset` says
    which). `configs/battery.yaml` switches it on around the hardware-like robot.

    **Hardware model** (`hardware`, a `HardwareConfig`, all off by default): joint friction, actuation
    latency, encoder noise, Kalman speed feedback (simulated IMU + leg odometry) and a mass draw, the same model
    the prototype walks use. The robot's software sees what its sensors read: with `estimated_velocity` the
    trot controller, the observation and the reward's v_x use the Kalman estimate; encoder noise reaches the
    controller and the observation. The mass is drawn per episode; `reset(options={"hardware_robot": True})`
    walks a scripted walk's robot instead (`hardware.seed`'s mass and sensor streams, no randomisation draw).
    """

    metadata = {"render_modes": ["rgb_array", "human"], "render_fps": 40}

    def __init__(self, config: C.EnvConfig | None = None, reward: str | C.RewardConfig | None = None,
                 render_mode: str | None = None, **overrides: Any):
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
                             joint_damping=cfg.joint_damping)
        self.robot, self.controller = self.walker.robot, self.walker.controller
        layout = observation_layout(cfg)
        low = np.concatenate([np.full(n, lo_, dtype=np.float32) for _, n, lo_, _, _ in layout])
        high = np.concatenate([np.full(n, hi_, dtype=np.float32) for _, n, _, hi_, _ in layout])
        self.observation_space = gym.spaces.Box(low, high, dtype=np.float32)
        self.action_space = gym.spaces.Box(-1.0, 1.0, (12,), dtype=np.float32)
        z_scale = cfg.foot_offset_scale if cfg.foot_offset_scale_z is None else cfg.foot_offset_scale_z
        self._foot_offset_scale = np.array([cfg.foot_offset_scale, cfg.foot_offset_scale, z_scale])  # m, x y z
        self._state = None
        # r_v over the last reward.speed_window s (None: each step's own speed, the paper's)
        self._speed_window = (rewards.SpeedWindow(max(1, round(cfg.reward.speed_window / cfg.control_dt)))
                              if cfg.reward.speed_window > 0 else None)
        self._steps_taken = 0  # env steps since construction (all episodes): the trot prior's decay counts them

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
        self.controller.set_speed(self.target_speed)
        self._state = self.walker.reset(mass_scale=mass_scale, sensor_rng=sensor_rng, draw=draw)
        self.last_torque = np.zeros(12)
        self._foot_offset = [(0.0, 0.0, 0.0)] * 4  # m, 4 × (x, y, z): the last action's foot offsets (foot mode)
        self._last_action = np.zeros(12)  # the previous action, observed with `observe_last_action`
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
        if a.shape != (12,):
            raise ValueError(f"action must have shape (12,), got {a.shape}")
        values = a.tolist()  # the action's checks and the foot offsets in floats: 12 numbers are too few for numpy
        if not math.isfinite(sum(values)) and not all(map(math.isfinite, values)):
            raise ValueError(f"action must be finite, got {values}")
        clipped = [1.0 if x > 1.0 else -1.0 if x < -1.0 else x for x in values]  # np.clip to [-1, 1]
        self._last_action = np.array(clipped)
        w, controller, dt = self.walker, self.controller, self.dt
        if self.cfg.action_mode == "foot":  # the action moves the foot targets; the controller's torque is as is
            # first-order hold: the offset ramps from the last action's to this one's over the agent step, so
            # that the target path stays continuous (a 25 ms staircase of targets made the PID jerk: lowering
            # the swing feet by 1-3 cm that way cost 10-75 % more energy, measured)
            sx, sy, sz = self._foot_offset_scale.tolist()
            start, control_dt = self._foot_offset, self.cfg.control_dt
            self._foot_offset = end = [(clipped[i] * sx, clipped[i + 1] * sy, clipped[i + 2] * sz)
                                       for i in range(0, 12, 3)]  # m, 4 × (x, y, z)
            rates = [((x1 - x0) / control_dt, (y1 - y0) / control_dt, (z1 - z0) / control_dt)
                     for (x0, y0, z0), (x1, y1, z1) in zip(start, end)]  # m/s
            # the offset of controller period k (from 0) is start + rate·(k + 1)·dt: this action's at the last
            controller.ramp_foot_offsets([(x0 + rx * dt, y0 + ry * dt, z0 + rz * dt)
                                          for (x0, y0, z0), (rx, ry, rz) in zip(start, rates)], rates, w.time)
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

    @property
    def prior_weight(self) -> float:
        """The trot prior's weight for the next step (torque mode; `EnvConfig.prior_weight_at`): 0 without one."""
        cfg = self.cfg
        return cfg.prior_weight_at(cfg.prior_steps_done + cfg.prior_step_stride * self._steps_taken)

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
        v_cmd = self.controller.commanded_speed(self.t)  # the ramped command (see the class docstring)
        v_paid = v_used
        if cfg.reward.speed_at_nominal_stride:  # the speed at the command's own stride
            stride = v_cmd + self.controller.speed_correction  # m/s: the speed the trot's stride is set for
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
                "speed_loop_correction": self.controller.speed_correction, "target_speed": self.target_speed,
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
        t = self.t
        phase = 2 * np.pi * self.controller.scheduler.phases_at(t)[0]
        obs = np.concatenate([
            [s.base_position[2], s.base_position[1] - self.walker.start[1]], s.base_rpy, v_body,
            s.base_angular_velocity_body, q, dq, self.last_torque, [self.controller.commanded_speed(t)],
            [np.sin(phase), np.cos(phase)]]
            + ([self._last_action] if self.cfg.observe_last_action else [])
            + ([[self.controller.pid.kp[1] / DEFAULT_KP]] if self.cfg.observe_pd_stiffness else [])
        ).astype(np.float32)
        if not np.isfinite(obs).all():  # rare (a blown-up state): NaN → 0, ±inf → the extremes, then clipped
            obs = np.nan_to_num(obs, nan=0.0)
        return np.minimum(np.maximum(obs, self.observation_space.low, out=obs), self.observation_space.high, out=obs)

    def render(self):
        if self.render_mode == "rgb_array":
            return self.robot.render(320, 240)
        return None

    def close(self):
        if getattr(self, "walker", None) is not None:
            self.walker.close()
            self.walker = self.robot = None
