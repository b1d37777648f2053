"""`Walker`: robot + trot controller + hardware model, advanced one controller period at a time.

Every loop of the project that steps the simulated CyberDog runs through the walker's one controller period
(`Walker._period`; `step` runs one, `run(n)` n of them): the learning environment (`CyberDog-v0`, 10 periods
per agent step at the default 400 Hz, in one `run` call), the scripted walks of the trajectory comparison and
the prototype (`cyberdog.analysis.walk`), the videos and the policy rollouts. One step is one period of the
joint controller (`SimConfig.controller_dt`, 2.5 ms by default), the same stages on every robot, each present
or absent for this one:

1. the robot's software reads its sensors (the hardware model: encoder noise, Kalman speed; the truth on the
   ideal robot) and the trot controller computes its command to the motor drivers (joint targets and
   speeds, gains, feedforward; `cyberdog.core.drivers.JointCommand`), unless the controller is off (the
   paper's torque-mode env); an extra torque (a policy's) is added to it;
2. the virtual end stop of Table 4's joint range adds its torque, if one is given;
3. the command waits out the actuation latency and is held over the period's `SimConfig.physics_substeps`
   physics steps (`SimConfig.physics_dt`, made finer for stiff or strongly damped gains: `driver_rate_config`);
   at each, the motor drivers close their PD on the joint state then (and the torque-mode
   drivers' damping acts on the joint speed then), the actuator model clips and shapes the torque, and
   PyBullet steps once (`Robot.drive`). The drivers read their own encoders, the true joint state: the
   hardware model's encoder noise is on what the locomotion controller reads (`HardwareConfig`). A PID's
   integral term is the controller's, advanced once per period and sent with the command;
4. the torque applied at each physics step and the joint angles after it are kept for Eq. (7) and the
   electrical energy, with `body_trace` the body's speed, attitude and height, and with `record` the state,
   contacts, the controller's foot targets and the feedforward torque the drivers ran; with `gait_metrics` the
   non-foot ground contacts and the feet's positions for foot slip are sampled.

Energy and traces: `cyberdog.loop.books.WalkBooks`, read from the rows the period keeps.

Time is `steps · dt` since the reset.
"""
from __future__ import annotations

import dataclasses

import numpy as np

from cyberdog.config import EnvConfig, HardwareConfig, WalkConfig
from cyberdog.control.joint_stop import JointStop
from cyberdog.control.trot import BodyFeedback, TrotController
from cyberdog.core import kinematics as kin
from cyberdog.core.drivers import driver_physics_dt
from cyberdog.loop.books import WalkBooks
from cyberdog.loop.rows import PeriodEnds, PeriodMean, Rows
from cyberdog.sim.hardware_model import (CommandDelay, HardwareSensing, RobotDraw, draw_mass_scale, hardware_walk_config,
                                   seeded_streams, whole_steps)
from cyberdog.sim import make_robot
from cyberdog.sim.robot import Robot, RobotState

# "fallen" means the same everywhere (EnvConfig's defaults; the env passes its own)
FALL_HEIGHT = EnvConfig.fall_height  # m, body centre below this
FALL_TILT = np.deg2rad(EnvConfig.fall_tilt_deg)  # rad, |roll| or |pitch| above this
CONTACT_CHECK_PERIOD = 0.010  # s between checks of which links touch the ground
SLIP_SAMPLE_PERIOD = 0.005  # s between samples of the feet's positions and contacts (foot slip)



def driver_rate_config(cfg: WalkConfig, joint_damping: float = 0.0, drive: bool = True) -> WalkConfig:
    """`cfg` with the physics step at which the drivers' law converges (`cyberdog.core.drivers.driver_physics_dt`;
    unchanged at the default gains): a user who doubles kd gets the energy of the drivers' law, not of the
    step's size. The law is the PID's PD where the trot drives the joints (`drive`), and the drivers' damping
    `joint_damping` (N·m·s/rad, the torque-mode env's `EnvConfig.joint_damping`, kd with kp = 0) where it is
    on: its 3 N·m·s/rad walks at 1.6 kHz. The gains a robot draw scales at a reset (`RandomizationConfig`) are
    not counted: the step is the configured robot's."""
    kp = list(cfg.pid.kp) if drive else []
    kd = (list(cfg.pid.kd) if drive else []) + [joint_damping]
    h = driver_physics_dt(cfg.sim.physics_dt, kp, kd, cfg.robot.reflected_rotor_inertia)
    if h == cfg.sim.physics_dt:
        return cfg
    return dataclasses.replace(cfg, sim=dataclasses.replace(cfg.sim, physics_dt=h))


_NO_TARGET = [(float("nan"),) * 3] * 4
_NO_OFFSET = [(0.0, 0.0, 0.0)] * 4
_NO_TORQUE = [0.0] * 12


class Walker(WalkBooks):
    """The CyberDog under the trot controller at the controller rate, its drivers at the physics rate (see the
    module docstring).

    cfg: the walk (robot, actuator, sim, gait, PID, controller, energy).
    controller: the trot controller (default: `TrotController(cfg)`), or a command source with its `command` and
        `reset` (`cyberdog.control.gait_table.TablePlayer`: a joint table's frames); `drive=False` leaves it off.
    hardware: the hardware model (None: the ideal robot). With friction on, a given `robot` must have been
        built with `hardware_walk_config(cfg, hardware).actuator`.
    joint_stop: the virtual end stop of the env's joint range (None: only the URDF limits).
    record: keep the state, contacts and foot targets of every step (`traces`); gait_metrics: sample non-foot
        contacts and foot slip; body_trace: keep the body's speed, attitude and height at every step (what
        `cyberdog.loop.result.walk_result` reads; the env, which reads none of it, leaves it off).
    fall_height, fall_tilt: m, rad: what `fallen` means.
    joint_damping: N·m·s/rad, the motor drivers' damping −c·q̇ added at every physics step on the joint speed
        then (the drivers' kd with kp = 0: the torque-mode env's `EnvConfig.joint_damping`); motor torque, so
        the energy books its work. A drawn robot's `kd_factor` scales it, as it scales the PID's kd.
    rate_per_robot: a robot drawn at `reset` with other gains steps at the physics rate its gains need
        (`RandomizationConfig.drivers_rate_per_robot`); False: at the configured robot's.

    After each step, `reading` holds the robot's state in floats (`Robot.read`, what the controller's per-period
    path uses) and `state` the same as a `RobotState` of arrays, built when first asked.
    """

    def __init__(self, cfg: WalkConfig, controller: TrotController | None = None, robot: Robot | None = None,
                 hardware: HardwareConfig | None = None, joint_stop: JointStop | None = None, drive: bool = True,
                 record: bool = False, gait_metrics: bool = False, gui: bool = False,
                 fall_height: float = FALL_HEIGHT, fall_tilt: float = FALL_TILT, body_trace: bool = True,
                 joint_damping: float = 0.0, rate_per_robot: bool = False) -> None:
        if hardware is not None and not isinstance(hardware, HardwareConfig):
            raise TypeError(f"hardware must be a HardwareConfig or None, got {type(hardware).__name__}")
        if not (joint_damping >= 0 and np.isfinite(joint_damping)):
            raise ValueError(f"joint_damping must be >= 0 N·m·s/rad and finite, got {joint_damping!r}")
        self.cfg = cfg = driver_rate_config(hardware_walk_config(cfg, hardware), joint_damping, drive)
        if robot is not None and robot.actuator_config != cfg.actuator:
            raise ValueError("robot was built with another ActuatorConfig than the walk needs (friction="
                             f"{cfg.actuator.friction}); build it from hardware_walk_config(cfg, hardware)")
        self.own_robot = robot is None
        self.robot = robot or make_robot(cfg.robot, cfg.actuator, cfg.sim, gui=gui)
        self.controller = controller or TrotController(cfg)
        self.hardware = hardware
        self.joint_stop, self.drive = joint_stop, drive
        self.nominal_joint_damping = float(joint_damping)  # N·m·s/rad, the configured robot's
        self.joint_damping = self.nominal_joint_damping  # N·m·s/rad, the drivers' damping on the joint speed now
        self.record, self.gait_metrics, self.body_trace = record, gait_metrics, body_trace
        self.rate_per_robot = rate_per_robot  # a drawn robot steps at the rate its gains need
        self.fall_height, self.fall_tilt = fall_height, fall_tilt
        self.dt = cfg.sim.controller_dt  # s, one `step`
        if self.robot.dt != self.dt:
            raise ValueError(f"robot was built with another controller period ({self.robot.dt} s) than the walk's "
                             f"SimConfig.controller_dt ({self.dt} s)")
        if self.robot.physics_dt > cfg.sim.physics_dt * (1 + 1e-9):
            raise ValueError(f"robot was built with a physics step of {self.robot.physics_dt} s; the walk's gains "
                             f"need {cfg.sim.physics_dt} s (build it from driver_rate_config(cfg).sim)")
        self.substeps, self.physics_dt = self.robot.substeps, self.robot.physics_dt  # per period; s, one each
        self.contact_check_every = max(1, int(round(CONTACT_CHECK_PERIOD / self.dt)))  # steps
        self.slip_sample_every = max(1, int(round(SLIP_SAMPLE_PERIOD / self.dt)))  # steps
        self.latency_steps = (whole_steps(hardware.latency_s, self.dt, "HardwareConfig.latency_s")
                              if hardware is not None else 0)  # periods, of the configured hardware
        self.delay = CommandDelay(self.latency_steps)
        self.sensing: HardwareSensing | None = None
        self.foot_link_names = set(self.robot.foot_link_names)
        self.reset()

    # ------------------------------------------------------------------------------------------------------
    def reset(self, mass_scale: float | None = None, sensor_rng: np.random.Generator | None = None,
              draw: RobotDraw | None = None):
        """Robot at rest in its standing pose, controller and hardware model reset, traces cleared.

        mass_scale: the link-mass scale to walk with; None = the hardware's seeded draw (1 on the ideal
            robot). sensor_rng: the sensors' generator; None = the stream seeded by `HardwareConfig.seed`.
        draw: a robot drawn from a `RandomizationConfig` (`cyberdog.sim.hardware_model.draw_robot`): its joint
            friction and motor strength, latency, mass (instead of `mass_scale`), PID gains and ground
            friction; None = the configured robot.
        Returns the state (a RobotState)."""
        hw = self.hardware
        if hw is not None:
            mass_rng, seeded_sensor_rng = seeded_streams(hw)
            if mass_scale is None and draw is None:
                mass_scale = draw_mass_scale(hw, mass_rng)
            sensing = not hw.ideal or hw.imu_noise
            self.sensing = (HardwareSensing(hw, self.cfg, sensor_rng if sensor_rng is not None
                                            else seeded_sensor_rng) if sensing else None)
        self.draw = draw
        d = draw if draw is not None else RobotDraw(latency_periods=self.latency_steps)
        if draw is not None:
            mass_scale = draw.mass_scale
        self.robot.set_mass_scale(1.0 if mass_scale is None else mass_scale)  # the ideal robot: its own mass
        self.robot.actuator.set_scales(d.joint_friction_scale, d.motor_strength)
        self.robot.set_ground_friction(self.cfg.sim.ground_friction * d.ground_friction_scale)
        self.joint_damping = self.nominal_joint_damping * d.kd_factor  # the drivers' kd, drawn as the PID's is
        if self.rate_per_robot:
            self._step_for_gains(d.kp_factor, d.kd_factor)
        self.robot.reset()
        self.controller.reset(d.kp_factor, d.kd_factor)
        self.delay.reset(d.latency_periods)
        self.reading = self.robot.read()
        self._state = None
        if self.sensing is not None:
            self.sensing.reset(self.state)
        self.start = self.state.base_position.copy()
        self._start_y = float(self.start[1])
        self.steps = 0
        self.physics_tau = Rows((12,))  # motor torque applied over each physics step, N·m
        self.physics_q = Rows((12,))  # joint angles, rad, at the reset and after each physics step
        self.physics_q.append(self.reading.q)
        self.tau = PeriodMean(self.physics_tau, self.substeps)  # per step: its mean applied motor torque, N·m
        self.q_rows = PeriodEnds(self.physics_q, self.substeps)  # joint angles at the reset and after each step
        self.body = Rows((5,))  # body state at the step start: forward speed (m/s), roll, pitch, yaw (rad), z (m)
        # with body_trace, the trot's speed integral per driven period after its command: (correction, its bound),
        # m/s: what the speed loop added to the commanded stride and how near its limit it ran (`walk_result`)
        self.speed_loop = Rows((2,))
        self._traces: dict[str, Rows] = {}
        self.non_foot_contacts: set[str] = set()
        self.slip_xy: list[np.ndarray] = []  # (4, 2) m, every SLIP_SAMPLE_PERIOD
        self.slip_contacts: list[np.ndarray] = []
        return self.state

    def _step_for_gains(self, kp_factor: float, kd_factor: float) -> None:
        """The physics step at which the drivers' law converges for the PID's gains × the factors (and the
        drivers' damping × `kd_factor`): the configured step, halved as `driver_physics_dt` needs."""
        c = self.cfg
        kp = [g * kp_factor for g in c.pid.kp] if self.drive else []
        kd = ([g * kd_factor for g in c.pid.kd] if self.drive else []) + [self.joint_damping]
        h = driver_physics_dt(c.sim.physics_dt, kp, kd, c.robot.reflected_rotor_inertia)
        if h != self.robot.physics_dt:
            self.robot.set_physics_dt(h)
        self.substeps, self.physics_dt = self.robot.substeps, self.robot.physics_dt

    @property
    def time(self) -> float:
        """s since the reset."""
        return self.steps * self.dt

    @property
    def state(self) -> RobotState:
        """The robot's state after the last step (as arrays; built from `reading` when first asked)."""
        s = self._state
        if s is None:
            s = self._state = RobotState.from_reading(self.reading)
        return s

    # ------------------------------------------------------------------------------------------------------
    def body_feedback(self, state, v_world: np.ndarray | None) -> BodyFeedback:
        """What the controller knows of the body: the truth, or the forward and sideways speed of the
        Kalman estimate `v_world` (yaw and lateral offset stay true: on the robot they come from the IMU's
        attitude filter and the operator's steering)."""
        if v_world is None:
            return BodyFeedback.from_state(state, self.start)
        v_body = state.rotation_matrix.T @ v_world
        return BodyFeedback(yaw=float(state.base_rpy[2]), lateral_offset=float(state.base_position[1] - self.start[1]),
                            forward_speed=float(v_world[0]), lateral_speed=float(v_body[1]))

    def sensed_joints(self, state=None) -> tuple[np.ndarray, np.ndarray]:
        """(q, dq) as the robot's encoders read them now (a fresh noise draw on the hardware-like robot)."""
        s = self.state if state is None else state
        return (s.q, s.dq) if self.sensing is None or not self.sensing.noisy else self.sensing.joints(s.q, s.dq)

    @property
    def velocity_estimate_world(self) -> np.ndarray | None:
        """(3,) m/s, the Kalman estimate of the body velocity; None unless the hardware estimates it."""
        if self.sensing is None or not self.hardware.estimated_velocity:
            return None
        return self.sensing.velocity_estimate_world

    # what a task (the env) asks of the loop: the command, the gait's clock, the drivers' stiffness, the view
    def set_speed(self, speed: float) -> None:
        """Set the trot's speed (m/s) for the next walk: it ramps up to it after the reset."""
        self.controller.set_speed(speed)

    @property
    def commanded_speed(self) -> float:
        """m/s, the trot's command now: the set speed, reached by its start-up ramp."""
        return self.controller.commanded_speed(self.time)

    @property
    def speed_correction(self) -> float:
        """m/s, what the trot's speed loop adds to the commanded stride now."""
        return self.controller.speed_correction

    @property
    def gait_phase(self) -> float:
        """LF's gait phase now, in [0, 1): 0 at its lift-off."""
        return self.controller.scheduler.phases_at(self.time)[0]

    @property
    def hip_kp(self) -> float:
        """N·m/rad, the hip joints' PD stiffness the drivers run now (the robot's draw included)."""
        return float(self.controller.pid.kp[1])

    def ramp_foot_offsets_to(self, end: list, duration: float) -> None:
        """Shift the trot's foot targets by offsets ramping from the last ramp's end to `end` (4 × (x, y, z), m)
        over the next `duration` s (`TrotController.ramp_foot_offsets_to`)."""
        self.controller.ramp_foot_offsets_to(end, duration, self.time)

    def render(self, width: int, height: int, **camera) -> np.ndarray:
        """An RGB image (height, width, 3) of the robot now (`Robot.render`'s camera options)."""
        return self.robot.render(width, height, **camera)

    def trot_torque(self, periods: int = 1) -> np.ndarray:
        """N·m (12,): the trot controller's torque (trajectory + IK + PD + feedforward) at the state the robot's
        software reads now, without stepping; `periods`: the controller periods it will be held (the torque-mode
        env's prior, held over an agent step: its speed integral advances by as many)."""
        s = self.state
        q, dq = self.sensed_joints(s)
        command = self.controller.command(self.time, q, self.body_feedback(s, self.velocity_estimate_world), periods,
                                          dq=dq)
        return np.array(self.controller.driver_torque(command, q, dq))

    def run(self, periods: int, extra_torque: np.ndarray | float | None = None) -> np.ndarray:
        """`periods` controller periods (≥ 1), each the one period of `step` with the same `extra_torque`;
        returns the motor torque applied in the last (12,), its mean over the period. The env's loop: 10 periods
        per agent step."""
        if periods < 1:
            raise ValueError(f"periods must be >= 1, got {periods!r}")
        period = self._period
        for _ in range(periods):
            period(extra_torque)
        return self.tau.view(self.steps - 1)[0]

    def step(self, extra_torque: np.ndarray | float | None = None) -> np.ndarray:
        """One controller period; `extra_torque` (N·m, (12,)) is added to the controller's command. Returns the
        motor torque applied (12,), its mean over the period."""
        self._period(extra_torque)
        return self.tau.view(self.steps - 1)[0]

    def _period(self, extra_torque) -> None:
        """The controller period, written once: sense → command → joint stop → delay → actuate → record (the
        module docstring). What this robot lacks (sensors' noise and filter, controller, end stop, latency,
        damping, traces) is skipped; the usual period (the truth, the controller alone) stays in floats."""
        r, k, sensing = self.reading, self.steps, self.sensing
        command = None
        if self.drive:  # sense, then command (torque mode: no controller; only the velocity filter runs)
            if sensing is None:  # the truth, in floats
                q, dq = r.q, r.dq
                feedback = BodyFeedback(r.base_rpy[2], r.base_position[1] - self._start_y,
                                        r.base_linear_velocity_world[0],
                                        kin.lateral_velocity_body(r.base_quaternion, r.base_linear_velocity_world))
            else:
                s = self.state
                q, dq, v_world = sensing.read(k, s, self.robot.foot_contacts)
                feedback = self.body_feedback(s, v_world)
            command = self.controller.command(k * self.dt, q, feedback, dq=dq)
            if self.body_trace:
                self.speed_loop.append((self.controller.speed_correction, self.controller.speed_correction_limit))
        elif sensing is not None and sensing.estimator_due(k):  # torque mode: no controller, but the robot's
            sensing.update_estimator(self.state, self.robot.foot_contacts)  # velocity filter runs all the same
        stop = self.joint_stop.torque(r.q, r.dq) if self.joint_stop is not None else None
        # the latency holds the whole command (targets, gains, feedforward, the added torques)
        arrived = (command, extra_torque, stop)
        if self.delay.steps:
            arrived = self.delay.push(arrived)
        s = self.state if self.body_trace or self.record else None  # this period's start, before the step
        self._actuate(arrived)
        if self.body_trace:
            rpy = s.base_rpy
            self.body.append((s.base_linear_velocity_world[0], rpy[0], rpy[1], rpy[2], s.base_position[2]))
        if self.record:
            self._record(s, arrived)
        if self.gait_metrics:
            if k % self.contact_check_every == 0:
                self.non_foot_contacts |= self.robot.ground_contact_links() - self.foot_link_names
            if k % self.slip_sample_every == 0:
                self.slip_xy.append(self.robot.foot_positions_world()[:, :2])
                self.slip_contacts.append(self.robot.foot_contacts())
        self.steps = k + 1
        self.reading = self.robot.read()
        self._state = None

    def _actuate(self, arrived) -> None:
        """The motor drivers over the period's physics steps (`Robot.drive`), for the command that has arrived
        (None: none yet, zero torque): at each, their PD + feedforward on the joint state then (the truth: their
        own encoders), plus the command's added torques (an extra torque, the end stop), minus their damping on
        the joint speed then; the torque applied over each physics step and the joint angles after it are
        kept."""
        command = added = None
        if arrived is not None:
            command, extra, stop = arrived
            if extra is not None or stop is not None:
                added = np.broadcast_to(0.0 if extra is None else extra, (12,)) + (0.0 if stop is None else stop)
                added = added.tolist()
        taus, angles = self.robot.drive(command, added, self.joint_damping)
        self.physics_tau.extend(taus)
        self.physics_q.extend(angles)

    def _record(self, s, arrived) -> None:
        traces = self._traces
        if not traces:
            traces.update(base_position=Rows((3,)), contacts=Rows((4,), bool),
                          foot_targets=Rows((4, 3)), foot_offsets=Rows((4, 3)), feedforward=Rows((12,)),
                          joint_torque=Rows((12,)))
        traces["base_position"].append(s.base_position)
        traces["contacts"].append(self.robot.foot_contacts())  # after the step
        c = self.controller  # its last call computed this step's torque (torque mode: it does not run)
        traces["foot_targets"].append(c.last_foot_targets if self.drive and c.last_foot_targets else _NO_TARGET)
        traces["foot_offsets"].append(c.last_foot_offsets if self.drive and c.last_foot_offsets else _NO_OFFSET)
        traces["joint_torque"].append(c.last_joint_torque if self.drive and c.last_joint_torque else _NO_TORQUE)
        command = arrived[0] if arrived is not None else None  # what the drivers ran this step (after the latency)
        traces["feedforward"].append(command.feedforward if command is not None else _NO_TORQUE)

    # ------------------------------------------------------------------------------------------------------
    def fallen(self, state=None) -> bool:
        """The body is below `fall_height` or tilted beyond `fall_tilt` in roll or pitch."""
        s = self.state if state is None else state
        roll, pitch, _ = s.base_rpy.tolist()
        tilt = self.fall_tilt
        return bool(s.base_position[2] < self.fall_height or abs(roll) > tilt or abs(pitch) > tilt)

    def close(self) -> None:
        if self.own_robot:
            self.robot.close()

    def __enter__(self) -> "Walker":
        return self

    def __exit__(self, *exc) -> None:
        self.close()
