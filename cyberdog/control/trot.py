"""Diagonal trot controller (paper Figures 8–9): scheduler + foot trajectory + IK + PID + feedforward.

Pure numpy: once per controller period (`SimConfig.controller_dt`, 400 Hz by default) it maps time and the
measured robot state to the motor drivers' command (`command`: joint targets and speeds, the PID's gains,
the feedforward torque; `cyberdog.core.drivers.JointCommand`); the drivers close their PD on it at every
physics step (`cyberdog.loop.walker.Walker`). `torque` is command and drivers at one instant.

What is added on top of the paper's joint PID, and why (each switchable in `ControllerConfig`; the
docs/robot.md: on a similar robot plain PD tracking reached only about half the commanded speed):
- joint-velocity feedforward: the trajectory's foot velocity mapped through the inverse leg Jacobian, so the
  D term tracks the motion instead of braking it;
- stance gravity compensation: each stance foot pushes down with the body weight shared among the stance
  feet, τ = Jᵀ f with f = (0, 0, −m g / n_stance) (virtual work: τ·q̇ = f·ṗ, f the force the foot exerts);
- heading correction: left and right step lengths differ in proportion to the yaw error, and the heading
  set-point leans back toward the straight path in proportion to the lateral drift;
- speed integral: the step length is corrected by the integral of the forward-speed error, because the
  feet slip and the body sags, so S = v·T_stance alone walks a few per cent off the command;
- sideways foot placement in proportion to the body's sideways speed (Raibert's foot-placement idea), which
  damps the roll/sway that otherwise topples the trot at 1.2–1.4 m/s;
- sagittal foot placement, off by default (`sagittal_placement_gain`): each touchdown moved ahead by
  k·(v − v_cmd), Raibert's rule for the forward speed; a stabiliser of replayed paths, not the paper's trot;
- a start-up ramp of the commanded speed (`speed_ramp_time`, 1 s): stepping from rest to full speed at once
  rolled the body by up to 0.8 rad and toppled the straight-line trot at 1.4 m/s. A learned path's per-leg
  shift (`foot_offset_path`), and its joint torque where it carries one, are blended in over the same ramp, in
  proportion to the commanded speed.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
import numpy as np

from cyberdog.config import WalkConfig
from cyberdog.core import kinematics as kin
from cyberdog.core.drivers import JointCommand, driver_torque
from cyberdog.core.foot_offsets import FootOffsetPath
from cyberdog.core.gait import GaitScheduler, diagonal_trot
from cyberdog.core.pid import JointPID
from cyberdog.core.trajectories import FootTrajectory, check_gait_args, make_trajectory, point_evaluator

SIDES = (np.array([0, 2]), np.array([1, 3]))  # leg indices of the left (LF, LH) and right (RF, RH) legs
MAX_ATTITUDE_SHIFT = 0.03  # m, bound on each foot-placement shift of the foot targets (sideways, and sagittal)
LEG_SIDE = tuple(float(s) for s in kin.LEFT_RIGHT)  # +1 left, −1 right, per leg LF, RF, LH, RH
LEG_IS_LEFT = tuple(s > 0 for s in LEG_SIDE)


@dataclass
class BodyFeedback:
    """What the controller measures of the body (true or estimated), world-aligned where it matters."""

    yaw: float = 0.0  # rad
    lateral_offset: float = 0.0  # m, y from the straight line
    forward_speed: float | None = None  # m/s; None: no speed feedback
    lateral_speed: float = 0.0  # m/s, body-frame y velocity

    @classmethod
    def from_state(cls, state, start: np.ndarray, forward_speed: float | None = None) -> "BodyFeedback":
        """From a robot state (`cyberdog.sim.robot.RobotState`); `forward_speed` replaces the true speed
        (e.g. by the Kalman estimate); `start` is the body position the straight line starts from."""
        v = float(state.base_linear_velocity_world[0]) if forward_speed is None else float(forward_speed)
        return cls(yaw=float(state.base_rpy[2]), lateral_offset=float(state.base_position[1] - start[1]),
                   forward_speed=v, lateral_speed=state.lateral_velocity_body)


_NO_FEEDBACK = BodyFeedback()


@dataclass
class TrotTargets:
    """What the controller asked for at one instant (for logging and tests)."""

    foot_position: np.ndarray  # (4, 3) m, leg frame
    foot_velocity: np.ndarray  # (4, 3) m/s, leg frame
    joint_angles: np.ndarray  # (12,) rad
    joint_velocities: np.ndarray  # (12,) rad/s
    in_swing: np.ndarray  # (4,) bool


class TrotController:
    """Diagonal trot (LF+RH, then RF+LH) that walks straight at `cfg.gait.speed`.

    `torque(t, q, dq, body)` returns the joint torque command (12,) in N·m.
    A custom trajectory (e.g. the learned one) can replace the one named in the config.

    It runs at every controller period, so its path works on Python floats leg by leg (scalar IK, closed-form
    Jacobian solve; on 4-element arrays numpy's call overhead exceeds the arithmetic): the arithmetic of
    `cyberdog.core.kinematics`' array functions, which tests/test_fast_paths.py checks it against.
    """

    def __init__(self, cfg: WalkConfig, trajectory: FootTrajectory | None = None,
                 foot_offset_path: FootOffsetPath | None = None):
        self.cfg = cfg
        self.robot = cfg.robot
        self.gait = cfg.gait
        self.trajectory = trajectory if trajectory is not None else make_trajectory(cfg.gait)
        self.scheduler = GaitScheduler(diagonal_trot(cfg.gait), cfg.gait.period)
        self.pid = JointPID.from_config(cfg.pid, cfg.sim.controller_dt, cfg.actuator.torque_limit)
        self.stand_height = self.robot.body_height - self.robot.foot_radius  # m, hip joint → foot centre
        self.body_weight = self.robot.carried_mass * cfg.sim.gravity  # N, with the payload it knows it carries
        self.speed = cfg.gait.speed
        self.speed_correction = 0.0  # m/s, integral of the speed error × speed_gain
        self.speed_correction_limit = 0.0  # m/s, ± the integral's bound at the last command (0: none yet)
        self.dropped_shifts = 0  # leg-periods whose shifted foot target was out of reach (see reset)
        self.foot_offsets: list[tuple[float, float, float]] | None = None  # m, see set_foot_offsets
        self.foot_offset_rates: list[tuple[float, float, float]] | None = None  # m/s
        self.foot_offset_time: float | None = None  # s, when the offsets held `foot_offsets` (None: held still)
        self.joint_torque: list[float] | None = None  # N·m, 12 added to the feedforward until changed (a policy's)
        self.last_joint_torque: list[float] | None = None  # N·m, what the last command added (for recording)
        self._ramp_end = [(0.0, 0.0, 0.0)] * 4  # m, where the last foot-offset ramp ended
        # a periodic shift of each foot target over its phase (a learned trajectory's), on top of the above
        self.foot_offset_path = foot_offset_path
        # what the last call of the per-period path commanded: foot targets (4 × (x, y, z)) m, leg frame, and the
        # offsets in them (None: unshifted); kept for recording, not used by the controller
        self.last_foot_targets: list[tuple[float, float, float]] | None = None
        self.last_foot_offsets: list[tuple[float, float, float]] | None = None
        self._point_for = (None, None)  # (trajectory, its float evaluator or None), see _foot_points
        # the per-period path's constants as floats (the configs are frozen): gait timing, link lengths
        g, r = cfg.gait, cfg.robot
        self._swing_time, self._stance_time = g.swing_time, g.stance_time  # s
        self._swing_fraction = self.scheduler.gait.swing_fraction
        self._links = (r.l1, r.l2, r.l3)  # m
        # sagittal foot placement (ControllerConfig.sagittal_placement_gain): per leg, the x shift its stance
        # holds (set at touchdown) and the one its swing reached last period, m; whether it was swinging
        self._placement_held = [0.0] * 4
        self._placement_swing = [0.0] * 4
        self._was_swinging = [False] * 4

    def reset(self, kp_factor: float = 1.0, kd_factor: float = 1.0) -> None:
        """Start a walk: the PID's gains kp × `kp_factor`, kd × `kd_factor` of the configured ones (a robot drawn
        with other gains; 1 and 1: the configured robot), its integral cleared, no speed correction or shift."""
        self.pid.set_gain_factors(kp_factor, kd_factor)
        self.pid.reset()
        self._ramp_end = [(0.0, 0.0, 0.0)] * 4
        self.speed_correction = 0.0
        self.speed_correction_limit = 0.0  # m/s, ± the speed integral's bound at the last command
        self.dropped_shifts = 0  # leg-periods whose shifted foot target was out of reach (the unshifted one went)
        self.foot_offsets = self.foot_offset_rates = self.foot_offset_time = None
        self.last_foot_targets = self.last_foot_offsets = None
        self.joint_torque = self.last_joint_torque = None
        self._placement_held, self._placement_swing, self._was_swinging = [0.0] * 4, [0.0] * 4, [False] * 4

    def set_foot_offsets(self, offsets: np.ndarray | None, rates: np.ndarray | None = None,
                         at_time: float | None = None) -> None:
        """Shift each foot target by `offsets` (4, 3), m, leg frame (x forward, y left, z up), legs LF, RF, LH,
        RH, moving at `rates` (4, 3), m/s (added to the velocity feedforward; None = still), until the next
        call; None removes the shift. With `at_time` (s) the shift is a ramp: `offsets` at that time, then
        offsets + rates·(t − at_time) at time t; without it the shift stays at `offsets`. A shifted target the
        leg cannot reach falls back to the unshifted one."""
        self.foot_offset_time = None
        if offsets is None:
            self.foot_offsets = self.foot_offset_rates = None
            return
        offsets = np.asarray(offsets, dtype=float)
        if offsets.shape != (4, 3) or not np.all(np.isfinite(offsets)):
            raise ValueError(f"foot offsets must be a finite (4, 3) array in m, got {offsets!r}")
        self.foot_offsets = [tuple(row) for row in offsets.tolist()]
        if rates is None:
            self.foot_offset_rates = None
        else:
            rates = np.asarray(rates, dtype=float)
            if rates.shape != (4, 3) or not np.all(np.isfinite(rates)):
                raise ValueError(f"foot offset rates must be a finite (4, 3) array in m/s, got {rates!r}")
            self.foot_offset_rates = [tuple(row) for row in rates.tolist()]
        if at_time is not None:
            if self.foot_offset_rates is None or not np.isfinite(at_time):
                raise ValueError(f"a foot offset ramp needs rates and a finite at_time (s), got {at_time!r}")
            self.foot_offset_time = float(at_time)

    def ramp_foot_offsets_to(self, end: list, duration: float, at_time: float) -> None:
        """Shift the foot targets by offsets that ramp linearly from where the last ramp ended (zero after a
        reset) to `end` (4 tuples of (x, y, z), m, leg frame) over `duration` s from `at_time` s: the first-order
        hold of a policy's foot targets (`CyberDogEnv`'s foot mode), so that the target path stays continuous.
        Controller period k after `at_time` holds the ramp's value at its own end, start + rate·(k + 1)·dt, so
        the last period of the ramp reaches `end`. Unchecked floats: the per-agent-step path, whose action was
        checked."""
        start, dt = self._ramp_end, self.cfg.sim.controller_dt
        rates = [((x1 - x0) / duration, (y1 - y0) / duration, (z1 - z0) / duration)
                 for (x0, y0, z0), (x1, y1, z1) in zip(start, end)]  # m/s
        self.foot_offsets = [(x0 + rx * dt, y0 + ry * dt, z0 + rz * dt)
                             for (x0, y0, z0), (rx, ry, rz) in zip(start, rates)]
        self.foot_offset_rates, self.foot_offset_time, self._ramp_end = rates, at_time, end

    def set_joint_torque(self, torque: list[float] | None) -> None:
        """Add `torque` (12 floats, N·m, joints leg-major) to each command's feedforward until the next call (None:
        none): a foot_torque policy's force, sent as a path's own torque is, so the gains do not scale it."""
        self.joint_torque = torque

    def set_speed(self, speed: float) -> None:
        if not np.isfinite(speed) or speed < 0:
            raise ValueError(f"speed must be >= 0 and finite, got {speed!r}")
        self.speed = float(speed)

    def commanded_speed(self, t: float) -> float:
        """m/s: the set speed, reached by a linear ramp over `speed_ramp_time` after a reset (t in s)."""
        ramp = self.cfg.controller.speed_ramp_time
        return self.speed if ramp <= 0 else self.speed * min(1.0, t / ramp)

    def _path_blend(self, t: float) -> float:
        """The share of `foot_offset_path` applied at time t: the commanded speed's share of the set speed, so
        that over the start-up ramp the trot blends from its plain path into the learned one (a learned path
        is a steady-state path: replayed whole from a stand, some toppled within 1.5 s), then 1."""
        if self.speed <= 0:
            return 1.0
        return min(1.0, self.commanded_speed(t) / self.speed)

    def step_lengths(self, t: float, body: BodyFeedback) -> np.ndarray:
        """(4,) step length S per leg, m: S = v·stance_time, corrected for speed, skewed to hold the heading."""
        left, right = self._side_step_lengths(t, body)
        return np.array([left if is_left else right for is_left in LEG_IS_LEFT])

    def _side_step_lengths(self, t: float, body: BodyFeedback, periods: int = 1) -> tuple[float, float]:
        """(S_left, S_right), m; advances the speed integral by `periods` controller periods (once per call, as
        `step_lengths`)."""
        # (min and max as conditional expressions, with the builtins' choice on ties: a per-period path)
        c = self.cfg.controller
        ramp = c.speed_ramp_time
        v = self.speed
        if ramp > 0:
            share = t / ramp
            v = v * (share if share < 1.0 else 1.0)  # commanded_speed(t)
        if body.forward_speed is not None and c.speed_gain > 0:
            limit = c.max_speed_correction * v
            correction = self.speed_correction + c.speed_gain * (v - body.forward_speed) * (
                self.cfg.sim.controller_dt if periods == 1 else periods * self.cfg.sim.controller_dt)
            correction = -limit if -limit > correction else correction  # np.clip on a scalar
            self.speed_correction = float(limit if limit < correction else correction)
            self.speed_correction_limit = limit  # m/s, what the integral may add or remove at this command
        S = (v + self.speed_correction) * self._stance_time
        # heading set-point turns back toward the path (y = 0); positive yaw error → lengthen left steps
        skew = c.heading_gain * (body.yaw + c.lateral_gain * body.lateral_offset)
        skew = -0.5 if -0.5 > skew else 0.5 if 0.5 < skew else skew
        left, right = S * (1.0 + skew), S * (1.0 - skew)
        return (0.0 if 0.0 > left else left), (0.0 if 0.0 > right else right)

    def _foot_points(self, phases: list[float], S: tuple[float, float]) -> list[tuple[float, float, float, float]]:
        """Per leg (x, z, vx, vz) of the trajectory at its phase (in [0, 1)) and side's step length."""
        lift, swing, stance = self.gait.lift_height, self._swing_time, self._stance_time
        traj = self.trajectory
        if self._point_for[0] is not traj:
            self._point_for = (traj, point_evaluator(traj))
        point = self._point_for[1]
        if point is not None:
            S_left, S_right = S
            if not (0.0 <= S_left < math.inf and 0.0 <= S_right < math.inf):  # NaN feedback: the usual message
                check_gait_args(min(S_left, S_right), lift, swing, stance)
            beta = self._swing_fraction
            return [point(phase, beta, S_left if is_left else S_right, lift, swing, stance)
                    for phase, is_left in zip(phases, LEG_IS_LEFT)]
        points = [None] * 4  # any other trajectory: its array method, once per side
        for side, legs in enumerate(SIDES):
            xz, vxz = traj.position_velocity(np.array([phases[i] for i in legs]), S[side], lift, swing, stance)
            for row, i in enumerate(legs):
                points[i] = (float(xz[row, 0]), float(xz[row, 1]), float(vxz[row, 0]), float(vxz[row, 1]))
        return points

    def _shift(self, t: float, phases: list[float]):
        """(offsets, rates) of the foot targets at time t: the policy's ramp and the learned path's shift (each
        4 × (x, y, z), m and m/s), or (None, None) for the plain trot; rates may be None (a still shift)."""
        offsets, rates = self.foot_offsets, self.foot_offset_rates
        if self.foot_offset_time is not None:  # a ramp: the offsets have moved on at their rates
            e = t - self.foot_offset_time
            offsets = [(a + d * e, b + f * e, c + g * e) for (a, b, c), (d, f, g) in zip(offsets, rates)]
        if self.foot_offset_path is not None:
            path_offsets, path_rates = self.foot_offset_path.at(phases)
            blend = self._path_blend(t)
            if blend < 1.0:  # starting from a stand: the learned shift grows with the commanded speed
                path_offsets = [(a * blend, b * blend, c * blend) for a, b, c in path_offsets]
                path_rates = [(a * blend, b * blend, c * blend) for a, b, c in path_rates]
            if offsets is None:
                offsets, rates = path_offsets, path_rates
            else:  # both: the sum (a policy acting on a learned path)
                offsets = [(a + d, b + e, c + f) for (a, b, c), (d, e, f) in zip(offsets, path_offsets)]
                rates = path_rates if rates is None else [
                    (a + d, b + e, c + f) for (a, b, c), (d, e, f) in zip(rates, path_rates)]
        return offsets, rates

    def _sagittal_placement(self, t: float, body: BodyFeedback, phases: list[float]):
        """Per leg (x shift m, its rate m/s) of the sagittal foot placement, or None when it is off: each swing
        moves the foot's touchdown by k·(v − v_cmd) (Raibert 1986: a body faster than commanded steps further
        ahead, which brakes it), from the shift its last stance held, linearly over the swing; the stance holds
        the shift it touched down with, so the stance stroke, and with it the commanded speed, is unchanged."""
        k = self.cfg.controller.sagittal_placement_gain
        if k <= 0 or body.forward_speed is None:
            return None
        dx = k * (body.forward_speed - self.commanded_speed(t))
        dx = -MAX_ATTITUDE_SHIFT if -MAX_ATTITUDE_SHIFT > dx else MAX_ATTITUDE_SHIFT if MAX_ATTITUDE_SHIFT < dx else dx
        beta, swing_time = self._swing_fraction, self._swing_time
        out = []
        for leg, phase in enumerate(phases):
            held = self._placement_held[leg]
            if phase < beta:  # swing: from the held shift toward today's, reached at touchdown
                shift = held + (dx - held) * (phase / beta)
                self._placement_swing[leg], self._was_swinging[leg] = shift, True
                out.append((shift, (dx - held) / swing_time))
            else:
                if self._was_swinging[leg]:  # touchdown: the stance keeps where the swing put the foot
                    held = self._placement_held[leg] = self._placement_swing[leg]
                    self._was_swinging[leg] = False
                out.append((held, 0.0))
        return out

    def _leg_targets(self, t: float, body: BodyFeedback, periods: int = 1):
        """Foot targets (4 × (x, y, z)), foot velocities (4 × (vx, vy, vz)), joint targets and joint speed
        targets (12 floats each) and the swing flags (4 bools) at time t, in plain Python values."""
        c = self.cfg.controller
        phases = self.scheduler.phases_at(t)
        S = self._side_step_lengths(t, body, periods)
        # sideways foot placement against the body's sideways speed
        dy = c.lateral_placement_gain * body.lateral_speed
        dy = -MAX_ATTITUDE_SHIFT if -MAX_ATTITUDE_SHIFT > dy else MAX_ATTITUDE_SHIFT if MAX_ATTITUDE_SHIFT < dy else dy
        l1, l2, l3 = self._links
        width = l1 - self.trajectory.foot_inset  # m, each foot's y from its abad axis (l1: below the hip)
        stand, feedforward = self.stand_height, c.velocity_feedforward
        placement = self._sagittal_placement(t, body, phases)
        offsets, rates = self._shift(t, phases)
        applied = offsets  # the shifts the robot gets (a copy is made only if one is dropped)
        ik = kin.leg_inverse_kinematics_velocity
        feet, foot_vels, q_t, dq_t = [], [], [], []
        for leg, (x, z, vx, vz) in enumerate(self._foot_points(phases, S)):
            side = LEG_SIDE[leg]
            y, z = side * width + dy, z - stand
            if placement is not None:
                x, vx = x + placement[leg][0], vx + placement[leg][1]
            vy = 0.0
            if offsets is None:
                fx, fy, fz, wx, wy, wz = x, y, z, vx, vy, vz
            else:
                ox, oy, oz = offsets[leg]
                fx, fy, fz, wx, wy, wz = x + ox, y + oy, z + oz, vx, vy, vz
                if rates is not None:
                    rx, ry, rz = rates[leg]
                    wx, wy, wz = vx + rx, vy + ry, vz + rz
            try:
                a, h, k, da, dh, dk = ik(fx, fy, fz, wx, wy, wz, side, l1, l2, l3)
            except ValueError:
                if offsets is None:  # unreachable: the array function raises with its full message
                    kin.inverse_kinematics(np.array([(p[0], s * width + dy, p[1] - stand) for p, s in
                                                     zip(self._foot_points(phases, S), LEG_SIDE)]), self.robot)
                    raise
                # a shifted target out of reach: the unshifted one, at the unshifted speed; the record says so
                fx, fy, fz, wx, wy, wz = x, y, z, vx, vy, vz
                a, h, k, da, dh, dk = ik(fx, fy, fz, wx, wy, wz, side, l1, l2, l3)
                applied = list(offsets) if applied is offsets else applied
                applied[leg] = (0.0, 0.0, 0.0)
                self.dropped_shifts += 1
            feet.append((fx, fy, fz))
            foot_vels.append((wx, wy, wz))
            q_t += (a, h, k)
            dq_t += (da, dh, dk) if feedforward else (0.0, 0.0, 0.0)
        self.last_foot_targets, self.last_foot_offsets = feet, applied
        beta = self._swing_fraction
        return feet, foot_vels, q_t, dq_t, [phase < beta for phase in phases]

    def targets(self, t: float, body: BodyFeedback | None = None) -> TrotTargets:
        """Foot and joint targets at time t (s) for the measured body state."""
        feet, foot_vels, q_t, dq_t, in_swing = self._leg_targets(t, body or _NO_FEEDBACK)
        return TrotTargets(np.array(feet), np.array(foot_vels), np.array(q_t), np.array(dq_t), np.array(in_swing))

    def torque(self, t: float, q: np.ndarray, dq: np.ndarray, body: BodyFeedback | None = None) -> np.ndarray:
        """Joint torque command (12,), N·m: PID on the IK targets plus the feedforward terms (`command` then
        `driver_torque` on the same q, q̇: the controller without a delay between the two)."""
        q = np.asarray(q, dtype=float)
        dq = np.asarray(dq, dtype=float)
        if q.shape != (12,) or dq.shape != (12,):
            raise ValueError(f"q and dq must have shape (12,), got {q.shape} and {dq.shape}")
        return np.array(self.driver_torque(self.command(t, q, body, dq=dq), q, dq))

    def command(self, t: float, q: np.ndarray | list, body: BodyFeedback | None = None, periods: int = 1,
                dq: np.ndarray | list | None = None) -> JointCommand:
        """What the controller sends to the motor drivers at time t (s) for the measured joint angles q (12 floats, an
        array or a list): joint targets and speeds from the trajectory and IK, the stance feedforward torque (and a
        foot path's own), the PID's gains and, with integral action, its integral term advanced on (q, dq) (dq,
        rad/s, is needed then). `periods`: the controller periods until the next call (the speed integral's time
        step): 1 in the walker's loop, 10 for a command held over a 25 ms agent step (the torque-mode prior)."""
        _, _, q_t, dq_t, in_swing = self._leg_targets(t, body or _NO_FEEDBACK, periods)
        feedforward = [0.0] * 12
        if self.cfg.controller.gravity_compensation:
            kin.add_stance_weight_torque(feedforward, q if type(q) is list else q.tolist(), in_swing, self.robot,
                                         self.body_weight)
        path = self.foot_offset_path
        if path is not None and path.feedforward is not None:  # the path's own torque, blended in as its shift
            path.add_feedforward(feedforward, self.scheduler.phases_at(t), self._path_blend(t))
        added = self.last_joint_torque = self.joint_torque
        if added is not None:  # a policy's joint torque (foot_torque mode)
            feedforward = [f + a for f, a in zip(feedforward, added)]
        pid, integral = self.pid, None
        if pid.integrates:
            if dq is None:
                raise ValueError("TrotController.command needs the joint speeds dq (rad/s) when the PID has "
                                 "integral action (PIDConfig.ki > 0)")
            integral = pid.integral_from_lists(q_t, q, dq_t, dq)
        return JointCommand(q_t, dq_t, feedforward, pid.kp_list, pid.kd_list, integral)

    def driver_torque(self, command: JointCommand, q: np.ndarray | list, dq: np.ndarray | list) -> list:
        """The motor drivers' law (`cyberdog.core.drivers.driver_torque`), N·m, as 12 floats, on the joint state
        (q, q̇: arrays or lists of floats) read now, with the PID's clamp: the torque of one instant, for
        callers outside the loop (the walker's drivers apply it at every physics step)."""
        q = q if type(q) is list else q.tolist()
        dq = dq if type(dq) is list else dq.tolist()
        return driver_torque(command, q, dq, self.pid.torque_limit)
