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
(docs/design.md, "The controller's rate"). At the physics rate it converges (the same section's table) when
the physics step is short beside the joint's own time scales: `driver_physics_dt` halves the configured step
until it is, for the gains the walk sets.
"""
from __future__ import annotations

import math
from typing import NamedTuple

# The drivers' PD is explicit (computed on the joint state at the start of each physics step), so its energy
# converges in the step h only while h is short beside the joint's time scales, with J the least inertia a
# joint can have (its rotor's reflected inertia, RobotConfig.reflected_rotor_inertia):
#   damping    kd·h / J        (the velocity error's decay per step; continuous: e^(−kd·t/J))
#   stiffness  kp·h² / J       ((ω_n·h)², ω_n = √(kp/J))
# The bounds are read off the convergence table of docs/design.md ("The drivers' rate"): every gain walked at
# a step within them costs within 1 % of the same walk at half the step (the default PD, kp 60 N·m/rad and kd
# 2 N·m·s/rad at 1.25 ms, is 0.013 and 0.35; kd 4 at 1.25 ms, 0.69, was 2.6–5.8 % off).
MAX_DAMPING_STEP = 0.42  # kd·h / J: kd ≤ 2.42 N·m·s/rad at 800 Hz
MAX_STIFFNESS_STEP = 0.0183  # kp·h² / J: kp ≤ 84.4 N·m/rad at 800 Hz
MAX_HALVINGS = 6  # a configured step at most 64 times finer: beyond, the gains are not a robot's (an error)


class JointCommand(NamedTuple):
    """One controller period's command to the twelve motor drivers, joint order (lists of 12 floats): CyberDog's
    (q_des, qd_des, kp, kd, tau_ff), and the PID's integral term. A named tuple, built at every controller
    period (half the time of a frozen dataclass)."""

    q_target: list  # rad, q_des
    dq_target: list  # rad/s, qd_des
    feedforward: list  # N·m, tau_ff (stance gravity compensation, a foot path's torque), added after the PD's clamp
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


def driver_physics_dt(physics_dt: float, kp, kd, joint_inertia: float) -> float:
    """s: the physics step at which the drivers' PD with gains `kp`, `kd` (N·m/rad, N·m·s/rad; any numbers)
    converges: `physics_dt` halved until kd·h/J ≤ MAX_DAMPING_STEP and kp·h²/J ≤ MAX_STIFFNESS_STEP (the
    module's constants; J = `joint_inertia`, kg·m², the joints' least inertia). Halving keeps a controller
    period a whole number of physics steps. `joint_inertia` 0 (no rotor modelled) leaves `physics_dt` as it is:
    the bound has no scale then. ValueError for gains that need more than MAX_HALVINGS halvings."""
    if not (joint_inertia >= 0 and math.isfinite(joint_inertia)):
        raise ValueError(f"joint_inertia must be >= 0 kg·m² and finite, got {joint_inertia!r}")
    if joint_inertia == 0:
        return physics_dt
    kp_max, kd_max = max(kp, default=0.0), max(kd, default=0.0)
    h = physics_dt
    for _ in range(MAX_HALVINGS + 1):
        if kd_max * h / joint_inertia <= MAX_DAMPING_STEP and kp_max * h * h / joint_inertia <= MAX_STIFFNESS_STEP:
            return h
        h /= 2
    raise ValueError(f"joint gains kp {kp_max:g} N·m/rad, kd {kd_max:g} N·m·s/rad need a physics step under "
                     f"{physics_dt / 2 ** MAX_HALVINGS:.3g} s to converge (joint inertia {joint_inertia:g} kg·m²): "
                     f"not a gain a CyberDog driver runs")
