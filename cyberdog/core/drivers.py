"""The motor drivers: what CyberDog's joint drivers do with the locomotion controller's command. Pure Python.

CyberDog's locomotion controller sends each joint's driver, once per controller period, the command
(q_des, qd_des, kp, kd, tau_ff) (MiRoboticsLab cyberdog_motor_sdk); the driver closes the PD on its own
encoder, far faster than that period. The simulated drivers do the same (`cyberdog.loop.walker.Walker`): the
command (`JointCommand`) is held over the controller period (`SimConfig.controller_dt`), after the latency of
`HardwareConfig.latency_s`, and `driver_torque` is evaluated at every physics step (`SimConfig.physics_dt`) on
the joint state then:

    τ = clamp(kp·(q_des − q) + kd·(q̇_des − q̇) + τ_I, ±torque_limit) + τ_ff

τ_I is the integral term of the paper's joint PID (Figure 8): the drivers have no integrator, so the
locomotion controller computes it at its own rate (`cyberdog.core.pid.JointPID.integral_from_lists`) and
sends it with the command; it is None without integral action (ki = 0, the default gains). The actuator law
(`cyberdog.core.actuator.ActuatorModel`) then clips the sum and applies the torque–speed envelope.

Held over a 2.5 ms period, the PD torque was a discrete loop that rang at kd = 4 N·m·s/rad (kd·dt / J ≈ 1 for
the knee with its rotor's reflected inertia): Eq. (7) energy of a 1.4 m/s cycloid walk +43 % over kd = 2
(docs/design.md, "The controller's rate"). At the physics rate it converges (the same section's table).
"""
from __future__ import annotations

from typing import NamedTuple


class JointCommand(NamedTuple):
    """One controller period's command to the twelve motor drivers, joint order (lists of 12 floats): CyberDog's
    (q_des, qd_des, kp, kd, tau_ff), and the PID's integral term. A named tuple, built at every controller
    period (half the time of a frozen dataclass)."""

    q_target: list  # rad, q_des
    dq_target: list  # rad/s, qd_des
    feedforward: list  # N·m, tau_ff (the stance legs' gravity compensation), added after the PD's clamp
    kp: list  # N·m/rad
    kd: list  # N·m·s/rad
    integral: list | None = None  # N·m, the PID's integral term, inside the PD's clamp; None: no integral action


def driver_torque(command: JointCommand, q: list, dq: list, torque_limit: float) -> list:
    """N·m, 12 floats: the drivers' law (module docstring) for `command` on the joint state q (rad), q̇ (rad/s),
    12 floats each, as read now; `torque_limit` (N·m) the PD's clamp. In floats, one comprehension: at 12
    values numpy's call overhead exceeds the arithmetic, and this runs at every physics step. A non-finite
    state gives a non-finite torque (the robot refuses it with a message)."""
    c, hi, lo = command, torque_limit, -torque_limit
    if c.integral is None:
        return [(hi if (p := kp * (qt - qm) + kd * (dqt - dqm)) > hi else lo if p < lo else p) + f
                for kp, kd, qt, qm, dqt, dqm, f in zip(c.kp, c.kd, c.q_target, q, c.dq_target, dq, c.feedforward)]
    return [(hi if (p := kp * (qt - qm) + kd * (dqt - dqm) + i) > hi else lo if p < lo else p) + f
            for kp, kd, qt, qm, dqt, dqm, i, f in zip(c.kp, c.kd, c.q_target, q, c.dq_target, dq, c.integral,
                                                     c.feedforward)]
