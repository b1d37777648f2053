"""Diagonal trot controller (paper Figures 8–9): scheduler + foot trajectory + IK + PID + feedforward.

Pure numpy: it maps time and the measured robot state to 12 joint torque commands, once per physics step
(1 kHz by default). The simulator applies the actuator model to whatever it returns.

What is added on top of the paper's joint PID, and why (each switchable in `ControllerConfig`; the
NOTES' measurement on a similar robot found plain PD tracking reached only about half the commanded speed):
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
- a start-up ramp of the commanded speed (`speed_ramp_time`, 1 s): stepping from rest to full speed at once
  rolled the body by up to 0.8 rad and toppled the straight-line trot at 1.4 m/s.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cyberdog.config import WalkConfig
from cyberdog.core import kinematics as kin
from cyberdog.core.gait import GaitScheduler, diagonal_trot
from cyberdog.core.pid import JointPID
from cyberdog.core.trajectories import FootTrajectory, make_trajectory

SIDES = (np.array([0, 2]), np.array([1, 3]))  # leg indices of the left (LF, LH) and right (RF, RH) legs
MAX_ATTITUDE_SHIFT = 0.03  # m, bound on the sideways foot-placement shift of the foot targets


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
                   forward_speed=v, lateral_speed=float(state.base_linear_velocity_body[1]))


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
    """

    def __init__(self, cfg: WalkConfig, trajectory: FootTrajectory | None = None):
        self.cfg = cfg
        self.robot = cfg.robot
        self.gait = cfg.gait
        self.trajectory = trajectory if trajectory is not None else make_trajectory(cfg.gait)
        self.scheduler = GaitScheduler(diagonal_trot(cfg.gait), cfg.gait.period)
        self.pid = JointPID.from_config(cfg.pid, cfg.sim.physics_dt, cfg.actuator.torque_limit)
        self.stand_height = self.robot.body_height - self.robot.foot_radius  # m, hip joint → foot centre
        self.body_weight = self.robot.total_mass * cfg.sim.gravity  # N
        self.speed = cfg.gait.speed
        self.speed_correction = 0.0  # m/s, integral of the speed error × speed_gain

    def reset(self) -> None:
        self.pid.reset()
        self.speed_correction = 0.0

    def set_speed(self, speed: float) -> None:
        if not np.isfinite(speed) or speed < 0:
            raise ValueError(f"speed must be >= 0 and finite, got {speed!r}")
        self.speed = float(speed)

    def commanded_speed(self, t: float) -> float:
        """m/s: the set speed, reached by a linear ramp over `speed_ramp_time` after a reset (t in s)."""
        ramp = self.cfg.controller.speed_ramp_time
        return self.speed if ramp <= 0 else self.speed * min(1.0, t / ramp)

    def step_lengths(self, t: float, body: BodyFeedback) -> np.ndarray:
        """(4,) step length S per leg, m: S = v·stance_time, corrected for speed, skewed to hold the heading."""
        c = self.cfg.controller
        v = self.commanded_speed(t)
        if body.forward_speed is not None and c.speed_gain > 0:
            limit = c.max_speed_correction * v
            self.speed_correction = float(np.clip(
                self.speed_correction + c.speed_gain * (v - body.forward_speed) * self.cfg.sim.physics_dt,
                -limit, limit))
        S = (v + self.speed_correction) * self.gait.stance_time
        # heading set-point turns back toward the path (y = 0); positive yaw error → lengthen left steps
        heading_error = body.yaw + c.lateral_gain * body.lateral_offset
        skew = np.clip(c.heading_gain * heading_error, -0.5, 0.5)
        return np.maximum(S * (1.0 + skew * kin.LEFT_RIGHT), 0.0)

    def targets(self, t: float, body: BodyFeedback | None = None) -> TrotTargets:
        """Foot and joint targets at time t (s) for the measured body state."""
        g, c = self.gait, self.cfg.controller
        body = body or BodyFeedback()
        phases = self.scheduler.leg_phases(t)
        S = self.step_lengths(t, body)
        xz = np.empty((4, 2))
        vxz = np.empty((4, 2))
        for legs in SIDES:  # left and right legs differ in step length (heading correction)
            xz[legs], vxz[legs] = self.trajectory.position_velocity(phases[legs], S[legs[0]], g.lift_height,
                                                                    g.swing_time, g.stance_time)
        # sideways foot placement against the body's sideways speed
        dy = float(np.clip(c.lateral_placement_gain * body.lateral_speed, -MAX_ATTITUDE_SHIFT,
                           MAX_ATTITUDE_SHIFT))
        foot = np.stack([xz[:, 0], kin.LEFT_RIGHT * self.robot.l1 + dy, xz[:, 1] - self.stand_height],
                        axis=-1)
        foot_vel = np.stack([vxz[:, 0], np.zeros(4), vxz[:, 1]], axis=-1)
        q = kin.inverse_kinematics(foot, self.robot)
        if c.velocity_feedforward:
            dq = np.linalg.solve(kin.jacobian(q, self.robot), foot_vel[..., None])[..., 0]
        else:
            dq = np.zeros((4, 3))
        return TrotTargets(foot, foot_vel, q.ravel(), dq.ravel(), self.scheduler.in_swing(t))

    def torque(self, t: float, q: np.ndarray, dq: np.ndarray, body: BodyFeedback | None = None) -> np.ndarray:
        """Joint torque command (12,), N·m: PID on the IK targets plus the feedforward terms."""
        tgt = self.targets(t, body)
        tau = self.pid.torque(tgt.joint_angles, q, tgt.joint_velocities, dq)
        if self.cfg.controller.gravity_compensation:
            tau = tau + self.stance_feedforward(q, ~tgt.in_swing)
        return tau

    def stance_feedforward(self, q: np.ndarray, stance: np.ndarray) -> np.ndarray:
        """τ = Jᵀ f per stance leg, f = (0, 0, −m g / n_stance): the stance legs carry the body."""
        n = int(np.count_nonzero(stance))
        if n == 0:
            return np.zeros(12)
        J = kin.jacobian(np.reshape(q, (4, 3)), self.robot)
        tau = J[:, 2, :] * (-self.body_weight / n * stance)[:, None]  # Jᵀ (0, 0, f_z)
        return tau.ravel()
