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
  set-point leans back toward the straight path in proportion to the lateral drift.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cyberdog.config import WalkConfig
from cyberdog.core import kinematics as kin
from cyberdog.core.gait import GaitScheduler, diagonal_trot
from cyberdog.core.pid import JointPID
from cyberdog.core.trajectories import FootTrajectory, make_trajectory


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

    `torque(t, q, dq, yaw, lateral_offset)` returns the joint torque command (12,) in N·m.
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

    def reset(self) -> None:
        self.pid.reset()

    def set_speed(self, speed: float) -> None:
        if not np.isfinite(speed) or speed < 0:
            raise ValueError(f"speed must be >= 0 and finite, got {speed!r}")
        self.speed = float(speed)

    def step_lengths(self, yaw: float, lateral_offset: float, forward_speed: float | None) -> np.ndarray:
        """(4,) step length S per leg, m: S = v·stance_time, skewed left/right to hold the heading."""
        c = self.cfg.controller
        S = self.speed * self.gait.stance_time
        if forward_speed is not None and c.speed_gain > 0:
            S += c.speed_gain * (self.speed - forward_speed) * self.gait.stance_time
        # heading set-point turns back toward the path (y = 0); positive yaw error → lengthen left steps
        heading_error = yaw + c.lateral_gain * lateral_offset
        skew = np.clip(c.heading_gain * heading_error, -0.5, 0.5)
        return np.maximum(S * (1.0 + skew * kin.LEFT_RIGHT), 0.0)

    def targets(self, t: float, yaw: float = 0.0, lateral_offset: float = 0.0,
                forward_speed: float | None = None) -> TrotTargets:
        g = self.gait
        phases = self.scheduler.leg_phases(t)
        S = self.step_lengths(yaw, lateral_offset, forward_speed)
        xz = np.empty((4, 2))
        vxz = np.empty((4, 2))
        for leg in range(4):  # legs may have different step lengths (heading correction)
            p, v = self.trajectory.position_velocity(phases[leg], S[leg], g.lift_height, g.swing_time,
                                                     g.stance_time)
            xz[leg], vxz[leg] = np.ravel(p), np.ravel(v)
        foot = np.stack([xz[:, 0], kin.LEFT_RIGHT * self.robot.l1, xz[:, 1] - self.stand_height], axis=-1)
        foot_vel = np.stack([vxz[:, 0], np.zeros(4), vxz[:, 1]], axis=-1)
        q = kin.inverse_kinematics(foot, self.robot)
        if self.cfg.controller.velocity_feedforward:
            dq = np.linalg.solve(kin.jacobian(q, self.robot), foot_vel[..., None])[..., 0]
        else:
            dq = np.zeros((4, 3))
        return TrotTargets(foot, foot_vel, q.ravel(), dq.ravel(), self.scheduler.in_swing(t))

    def torque(self, t: float, q: np.ndarray, dq: np.ndarray, yaw: float = 0.0, lateral_offset: float = 0.0,
               forward_speed: float | None = None) -> np.ndarray:
        """Joint torque command (12,), N·m: PID on the IK targets plus the feedforward terms."""
        tgt = self.targets(t, yaw, lateral_offset, forward_speed)
        tau = self.pid.torque(tgt.joint_angles, q, tgt.joint_velocities, dq)
        if self.cfg.controller.gravity_compensation:
            tau = tau + self.gravity_feedforward(q, ~tgt.in_swing)
        return tau

    def gravity_feedforward(self, q: np.ndarray, stance: np.ndarray) -> np.ndarray:
        """τ = Jᵀ f per stance leg, f = (0, 0, −m g / n_stance): the stance legs carry the body."""
        n = int(np.count_nonzero(stance))
        if n == 0:
            return np.zeros(12)
        J = kin.jacobian(np.reshape(q, (4, 3)), self.robot)
        f = np.array([0.0, 0.0, -self.body_weight / n])
        tau = np.einsum("lij,i->lj", J, f) * stance[:, None]
        return tau.ravel()
