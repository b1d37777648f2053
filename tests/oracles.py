"""The array laws the package's per-period code is checked against (imported as `from oracles import ...`).

The package writes each law of the controller period once, in Python floats (12 joints and 4 legs are too few
for numpy's call overhead). Here are the same laws written the plain way, with numpy arrays, as they read in
the sources they come from; the tests compare the package's floats with them. Nothing in the package imports
this module.
"""
from __future__ import annotations

import numpy as np

from cyberdog.core import kinematics as kin
from cyberdog.core.actuator import DRY_FRICTION_SMOOTHING, ActuatorModel
from cyberdog.core.gait import GaitScheduler


def torque_envelope(model: ActuatorModel, joint_velocity) -> np.ndarray:
    """Largest |τ| (N·m) available while motoring at joint speed ω: torque_limit up to full_torque_speed,
    linearly down to 0 at zero_torque_speed, 0 beyond (cyberdog.hpp n1, n2)."""
    c = model.config
    speed = np.abs(np.asarray(joint_velocity, dtype=float))
    fraction = np.clip((c.zero_torque_speed - speed) / (c.zero_torque_speed - c.full_torque_speed), 0.0, 1.0)
    return model.torque_limit * fraction


def motor_torque(model: ActuatorModel, torque_command, joint_velocity) -> np.ndarray:
    """Clip to ±torque_limit; while motoring (τ·ω > 0) limit |τ| to the envelope; × the drawn strength."""
    limit = model.torque_limit
    tau = np.clip(np.asarray(torque_command, dtype=float), -limit, limit)
    if model.config.torque_speed_curve:
        omega = np.asarray(joint_velocity, dtype=float)
        envelope = torque_envelope(model, omega)
        tau = np.where(tau * omega > 0.0, np.clip(tau, -envelope, envelope), tau)
    return tau * model.strength


def friction_torque(model: ActuatorModel, joint_velocity) -> np.ndarray:
    """−(b·ω + f·tanh(ω / 0.01 rad/s)) × the drawn friction scale; zeros with friction off."""
    omega = np.asarray(joint_velocity, dtype=float)
    if not model.config.friction:
        return np.zeros_like(omega)
    c, k = model.config, model.friction_scale
    return -(k * c.viscous_damping * omega + k * c.dry_friction * np.tanh(omega / DRY_FRICTION_SMOOTHING))


def joint_torque(model: ActuatorModel, torque_command, joint_velocity) -> tuple[np.ndarray, np.ndarray]:
    """(motor torque, motor torque + friction torque)."""
    motor = motor_torque(model, torque_command, joint_velocity)
    return motor, motor + friction_torque(model, joint_velocity)


def stance_feedforward(q, stance, robot, body_weight: float) -> np.ndarray:
    """(12,) N·m: τ = Jᵀ f per stance leg, f = (0, 0, −m g / n_stance): the stance legs carry the body."""
    stance = np.asarray(stance, dtype=bool)
    n = int(np.count_nonzero(stance))
    if n == 0:
        return np.zeros(12)
    J = kin.jacobian(np.reshape(q, (4, 3)), robot)
    return (J[:, 2, :] * (-body_weight / n * stance)[:, None]).ravel()


def leg_phases(scheduler: GaitScheduler, t) -> np.ndarray:
    """(…, 4) each leg's phase (t / period + offset) mod 1, rounded to 1e-12, 1.0 wrapped to 0."""
    t = np.asarray(t, dtype=float)[..., None]
    phase = np.round(np.mod(t / scheduler.period + scheduler.gait.offsets, 1.0), 12)
    return np.where(phase >= 1.0, 0.0, phase)


def foot_offsets(table, leg: int, phase) -> np.ndarray:
    """(m, 3) one leg's offsets at the phases `phase` (m,): periodic linear interpolation of its (n, 3) rows."""
    table = np.asarray(table, dtype=float)[leg]
    n = len(table)
    phi = np.mod(np.asarray(phase, dtype=float), 1.0) * n
    k = np.minimum(phi.astype(int), n - 1)
    f = (phi - k)[:, None]
    return table[k] + (table[(k + 1) % n] - table[k]) * f
