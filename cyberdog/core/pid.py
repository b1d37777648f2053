"""Joint-space PID (paper Figure 8) over the 12 joints, with anti-windup. Pure numpy.

Joint order leg-major (LF abad, hip, knee, RF abad, …; `cyberdog.config.JOINT_NAMES`). The law, on the errors
e = q_target − q and ė = dq_target − dq:

    I ← clamp(I + ki·e·dt, ±integral_limit)     (skipped per joint while the output saturates, see below)
    τ = clamp(kp·e + I + kd·ė, ±torque_limit)

On the robot the law is split as CyberDog splits it: the motor drivers close the PD (kp, kd) at every physics
step on the joint state then (`cyberdog.core.drivers`), and the locomotion controller advances the integral
once per controller period of dt on the joint state it reads (`integral_from_lists`) and sends I with its
command. `torque` is the whole law at one instant (the two on the same state).

Anti-windup: the integral term is kept as a torque (N·m) and clamped to ±integral_limit; and a joint does not
integrate while its output, computed with the previous integral, is at or past ±torque_limit in the
direction of its error (conditional integration), so that a long saturation does not store torque that would
overshoot once the error shrinks.
"""
from __future__ import annotations

from typing import Any

import numpy as np

from cyberdog.config import JOINT_NAMES, LEG_NAMES, PIDConfig

N_JOINTS = len(LEG_NAMES) * len(JOINT_NAMES)  # 12


def per_joint(gain: Any, name: str = "gain") -> np.ndarray:
    """(12,) array from a scalar, a per-joint-type triple (abad, hip, knee) tiled over the 4 legs, or (12,)."""
    g = np.asarray(gain, dtype=float)
    if g.ndim == 0:
        g = np.full(N_JOINTS, float(g))
    elif g.shape == (len(JOINT_NAMES),):
        g = np.tile(g, len(LEG_NAMES))
    elif g.shape != (N_JOINTS,):
        raise ValueError(f"{name} must be a scalar, 3 values (abad, hip, knee) or 12 values, got shape {g.shape}")
    if not np.all(np.isfinite(g)) or np.any(g < 0):
        raise ValueError(f"{name} must be non-negative and finite, got {g.tolist()}")
    return g


class JointPID:
    """PID torque for 12 joints; gains in N·m/rad (kp), N·m/(rad·s) (ki), N·m·s/rad (kd)."""

    def __init__(self, kp: Any, ki: Any, kd: Any, integral_limit: float, dt: float,
                 torque_limit: float) -> None:
        self.kp = per_joint(kp, "kp")
        self.ki = per_joint(ki, "ki")
        self.kd = per_joint(kd, "kd")
        self.integral_limit = per_joint(integral_limit, "integral_limit")  # N·m
        if not (np.isfinite(dt) and dt > 0):
            raise ValueError(f"dt must be > 0 s and finite, got {dt!r}")
        if not torque_limit > 0:  # np.inf allowed: no saturation
            raise ValueError(f"torque_limit must be > 0 N·m, got {torque_limit!r}")
        self.dt = float(dt)  # s
        self.torque_limit = float(torque_limit)  # N·m
        self.integral = np.zeros(N_JOINTS)  # N·m, the integral term ki·∫e dt
        self.integrates = bool(np.count_nonzero(self.ki))  # integral action (ki > 0 for some joint)
        self._nominal = (self.kp, self.kd)
        self.set_gain_factors()

    def set_gain_factors(self, kp_factor: float = 1.0, kd_factor: float = 1.0) -> None:
        """Gains kp × `kp_factor` and kd × `kd_factor` of the configured ones (a drawn controller, domain
        randomisation); 1 and 1: the configured gains."""
        if not (np.isfinite(kp_factor) and kp_factor > 0 and np.isfinite(kd_factor) and kd_factor > 0):
            raise ValueError(f"gain factors must be > 0 and finite, got {kp_factor!r}, {kd_factor!r}")
        kp, kd = self._nominal
        self.kp, self.kd = kp * kp_factor, kd * kd_factor
        # the drivers' gains as sent with each command (12 floats each, `cyberdog.core.drivers.JointCommand`)
        self.kp_list, self.kd_list = self.kp.tolist(), self.kd.tolist()

    @classmethod
    def from_config(cls, pid_cfg: PIDConfig, dt: float, torque_limit: float) -> "JointPID":
        """Gains per joint type from `PIDConfig`, controller period dt (s), torque clip (N·m, ActuatorConfig)."""
        return cls(pid_cfg.kp, pid_cfg.ki, pid_cfg.kd, pid_cfg.integral_limit, dt, torque_limit)

    def reset(self) -> None:
        """Clear the integral (start of an episode or walk)."""
        self.integral[:] = 0.0

    def torque(self, q_target: Any, q: Any, dq_target: Any, dq: Any) -> np.ndarray:
        """(12,) joint torque, N·m, for joint targets and measurements (rad, rad/s); advances the integral."""
        arrays = [np.asarray(a, dtype=float) for a in (q_target, q, dq_target, dq)]
        for name, a in zip(("q_target", "q", "dq_target", "dq"), arrays):
            if a.shape != (N_JOINTS,):
                raise ValueError(f"{name} must have shape ({N_JOINTS},), got {a.shape}")
        return self.torque_unchecked(*arrays)

    def integral_from_lists(self, q_target: list, q: list, dq_target: list, dq: list) -> list:
        """The locomotion controller's share of the law, once per controller period: advance the integral on
        the joint state it reads (four lists of 12 floats, or arrays) and return it, N·m, as 12 floats, for the
        drivers' clamp (`cyberdog.core.drivers.driver_torque`); the anti-windup test uses the PD output at
        this state, as `torque` does."""
        self.torque_unchecked(np.array(q_target, dtype=float), np.array(q, dtype=float),
                              np.array(dq_target, dtype=float), np.array(dq, dtype=float))
        return self.integral.tolist()

    def torque_unchecked(self, q_target: np.ndarray, q: np.ndarray, dq_target: np.ndarray,
                         dq: np.ndarray) -> np.ndarray:
        """`torque` for four float arrays of shape (12,) that the caller guarantees (the per-period path)."""
        error = q_target - q  # rad
        error_rate = dq_target - dq  # rad/s
        pd = self.kp * error + self.kd * error_rate
        limit = self.torque_limit
        if not np.count_nonzero(self.ki) and not np.count_nonzero(self.integral) and np.isfinite(pd).all():
            # no integral action and none stored (the default gains): the update below would add ki·e·dt = 0
            # to a zero integral, so skip it; non-finite errors (0·inf = nan) take the full path
            return np.minimum(np.maximum(pd, -limit), limit)  # = np.clip(pd + 0, ±limit), np.clip is slower
        unclipped = pd + self.integral
        saturated = (np.abs(unclipped) >= self.torque_limit) & (np.sign(unclipped) == np.sign(error))
        step = np.where(saturated, 0.0, self.ki * error * self.dt)
        self.integral = np.clip(self.integral + step, -self.integral_limit, self.integral_limit)
        return np.clip(pd + self.integral, -self.torque_limit, self.torque_limit)
