"""Table 4's joint control range (±45° around the standing pose) as a virtual end stop."""
from __future__ import annotations

import numpy as np

from cyberdog.config import RobotConfig
from cyberdog.core import kinematics as kin


class JointStop:
    """Spring-damper torque that pushes a joint back inside ±`range_rad` of the standing pose (and inside the
    URDF limits): τ = −k·overshoot − c·q̇ for each joint beyond its range, nothing inside it."""

    def __init__(self, robot: RobotConfig, range_rad: float, stiffness: float, damping: float) -> None:
        q_stand = kin.standing_joint_angles(robot).ravel()
        lo, hi = kin.joint_limits(robot)
        self.q_low, self.q_high = np.maximum(q_stand - range_rad, lo), np.minimum(q_stand + range_rad, hi)
        self.stiffness, self.damping = float(stiffness), float(damping)
        self._bounds = list(zip(self.q_low.tolist(), self.q_high.tolist()))

    def torque(self, q: np.ndarray | list, dq: np.ndarray | list) -> np.ndarray | None:
        """N·m (12,); None while every joint is inside its range (almost always: checked by a loop over
        floats, under half the time of the array comparisons, and no generator for all() to build). q, q̇ (12,)
        as arrays or lists of floats."""
        for x, (lo, hi) in zip(q if type(q) is list else q.tolist(), self._bounds):
            if not lo <= x <= hi:
                break
        else:
            return None
        q, dq = np.asarray(q, dtype=float), np.asarray(dq, dtype=float)
        over = np.minimum(q - self.q_low, 0.0) + np.maximum(q - self.q_high, 0.0)
        if not over.any():
            return None
        return -self.stiffness * over - self.damping * dq * (over != 0)
