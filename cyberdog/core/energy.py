"""Energy model: the paper's mechanical energy (Eq. 7), an electrical model beyond it, and the battery (Eq. 13).

Pure numpy. Arrays of joint values have 12 joints on the last axis, leg-major (LF abad, hip, knee, RF …).

Paper (Section 2.2). Mechanical power per joint P_ij = |τ_ij · θ̇_ij| (W) and E = Σ_ij ∫ P_ij dt (J), Eq. (7).
Negative work (a joint braking) counts as spent, as the absolute value says.

Beyond the paper (its own omissions, Section 4.2: "thermal power and joint friction loss"). Per joint:
    τ_m   = τ + b·ω + f_c·tanh(ω/0.01)  if friction is NOT simulated (the real motor must also overcome it;
                                   the law the simulated joint feels, `cyberdog.core.actuator.joint_friction`);
            τ                      if friction IS simulated (ActuatorConfig.friction): the applied torque
                                   already includes what overcomes friction, adding it again would count twice;
    P_out = τ_m·ω + (τ_m / (N·K_T))²·R    shaft power + copper loss (motor current i = τ_m / (N·K_T));
    P_in  = P_out / η if P_out > 0, P_out·η if P_out < 0 (driver efficiency η both ways);
    P_in  clipped to ≥ 0 per joint unless `regeneration` (no energy flows back, nor between joints: an upper
          bound; with regeneration the signed powers are summed on the bus and may recharge the pack).
    Robot: P_el = Σ_joints P_in + idle_power.
Constants: gear ratio N, K_T, R, b, f_c from ActuatorConfig (Xiaomi's controller files; K_T and R are Mini
Cheetah values, low confidence); η, idle power, pack capacity from EnergyConfig (assumptions [G] there).

Integration: the rectangle rule at the sample step dt, E += P_k·dt with τ_k the torque applied during step k
and ω_k the joint's speed over it. The simulation loop (`cyberdog.loop.walker`) passes every physics step's
torque, constant over the step, and the joint's mean speed over it, ω̄_k = Δq_k / dt (the speed PyBullet
reports after the step): then τ_k·ω̄_k·dt = τ_k·Δq_k is the joint's work exactly.
"""
from __future__ import annotations

from typing import Any

import numpy as np

from cyberdog.config import JOINT_NAMES, LEG_NAMES, ActuatorConfig, EnergyConfig
from cyberdog.core.actuator import joint_friction

N_JOINTS = len(LEG_NAMES) * len(JOINT_NAMES)  # 12
J_PER_WH = 3600.0


def _joint_arrays(tau: Any, omega: Any) -> tuple[np.ndarray, np.ndarray]:
    tau, omega = np.asarray(tau, dtype=float), np.asarray(omega, dtype=float)
    if tau.shape != omega.shape or tau.shape[-1:] != (N_JOINTS,):
        raise ValueError(f"tau and omega must have the same shape (..., {N_JOINTS}), got {tau.shape}, "
                         f"{omega.shape}")
    return tau, omega


# ---------------------------------------------------------------------------------------------------------
# Paper: mechanical power and energy, Eq. (7)
# ---------------------------------------------------------------------------------------------------------

def mechanical_power(tau: Any, omega: Any) -> np.ndarray:
    """Eq. (7): per-joint mechanical power |τ·ω|, W, shape of the inputs (..., 12)."""
    tau, omega = _joint_arrays(tau, omega)
    return np.abs(tau * omega)


def joint_energy(tau: Any, omega: Any, dt: float) -> np.ndarray:
    """Eq. (7): (12,) energy per joint, J, of samples tau, omega (n, 12) taken every dt s (rectangle rule)."""
    _check_dt(dt)
    return mechanical_power(tau, omega).reshape(-1, N_JOINTS).sum(axis=0) * dt


def positive_work(tau: Any, omega: Any, dt: float) -> float:
    """J, Σ_ij ∫ max(τ·ω, 0) dt: the work the motors put into the robot (Eq. 7 also counts braking, τ·ω < 0,
    as spent), samples (n, 12) every dt s."""
    _check_dt(dt)
    tau, omega = _joint_arrays(tau, omega)
    return float(np.maximum(tau * omega, 0.0).sum() * dt)


def foot_slip(foot_xy: Any, contacts: Any) -> np.ndarray:
    """(4,) m: per foot, the horizontal distance it slid while on the ground, from samples of the foot
    positions foot_xy (n, 4, 2) m (world x, y) and contacts (n, 4) bool; a move between two samples counts
    when the foot touched the ground at both. Eq. (7) does not see the energy lost in slip (friction work)."""
    xy = np.asarray(foot_xy, dtype=float)
    c = np.asarray(contacts, dtype=bool)
    if xy.ndim != 3 or xy.shape[1:] != (4, 2) or c.shape != xy.shape[:2]:
        raise ValueError(f"foot_xy must be (n, 4, 2) and contacts (n, 4), got {xy.shape}, {c.shape}")
    if len(xy) < 2:
        return np.zeros(4)
    step = np.linalg.norm(np.diff(xy, axis=0), axis=-1)  # (n − 1, 4)
    return (step * (c[1:] & c[:-1])).sum(axis=0)


def per_leg(joint_values: Any) -> np.ndarray:
    """(..., 4) sums over each leg's 3 joints (LF, RF, LH, RH) of (..., 12) values."""
    v = np.asarray(joint_values, dtype=float)
    return v.reshape(v.shape[:-1] + (len(LEG_NAMES), len(JOINT_NAMES))).sum(axis=-1)


def per_joint_type(joint_values: Any) -> np.ndarray:
    """(..., 3) sums over the 4 legs per joint type (abad, hip, knee) of (..., 12) values."""
    v = np.asarray(joint_values, dtype=float)
    return v.reshape(v.shape[:-1] + (len(LEG_NAMES), len(JOINT_NAMES))).sum(axis=-2)


def energy_per_100m(energy_J: float, distance_m: float) -> float:
    """Energy per 100 m travelled, J (the paper's prototype walks 100 m, Section 4.2)."""
    _check_distance(distance_m)
    return energy_J * 100.0 / distance_m


def cost_of_transport(energy_J: float, mass_kg: float, gravity: float, distance_m: float) -> float:
    """Dimensionless cost of transport E / (m·g·d)."""
    _check_distance(distance_m)
    if not (mass_kg > 0 and gravity > 0):
        raise ValueError(f"mass and gravity must be > 0, got {mass_kg!r} kg, {gravity!r} m/s²")
    return energy_J / (mass_kg * gravity * distance_m)


def _check_dt(dt: float) -> None:
    if not (np.isfinite(dt) and dt > 0):
        raise ValueError(f"dt must be > 0 s and finite, got {dt!r}")


def _check_distance(distance_m: float) -> None:
    if not (np.isfinite(distance_m) and distance_m > 0):
        raise ValueError(f"distance must be > 0 m and finite, got {distance_m!r}")


# ---------------------------------------------------------------------------------------------------------
# Beyond the paper: electrical power (copper loss, friction, driver efficiency, idle power)
# ---------------------------------------------------------------------------------------------------------

def copper_loss(tau: Any, actuator: ActuatorConfig) -> np.ndarray:
    """Winding (Joule) loss (τ / (N·K_T))²·R, W, for joint torque τ (N·m) through gear ratio N."""
    current = np.asarray(tau, dtype=float) / (actuator.gear_ratio * actuator.motor_kt)  # A
    return current * current * actuator.motor_resistance


def drive_torque(tau: Any, omega: Any, actuator: ActuatorConfig) -> np.ndarray:
    """Torque the real motor must produce for the joint torque τ: τ itself when the simulation modelled the
    joint friction (the applied torque already overcame it), else τ plus the friction of `joint_friction`."""
    tau, omega = _joint_arrays(tau, omega)
    if actuator.friction:
        return tau
    return tau + joint_friction(omega, actuator.viscous_damping, actuator.dry_friction)


def electrical_joint_power(tau: Any, omega: Any, actuator: ActuatorConfig, energy: EnergyConfig) -> np.ndarray:
    """(..., 12) power drawn from the bus per joint, W (see the module docstring); idle power excluded."""
    tau_m = drive_torque(tau, omega, actuator)
    p_out = tau_m * np.asarray(omega, dtype=float) + copper_loss(tau_m, actuator)
    eta = energy.driver_efficiency
    p_in = np.where(p_out > 0, p_out / eta, p_out * eta)
    return p_in if energy.regeneration else np.maximum(p_in, 0.0)


def electrical_power(tau: Any, omega: Any, actuator: ActuatorConfig, energy: EnergyConfig) -> np.ndarray:
    """(...) total electrical power of the robot, W: Σ joints + idle_power."""
    return electrical_joint_power(tau, omega, actuator, energy).sum(axis=-1) + energy.idle_power


def electrical_energy(tau: Any, omega: Any, dt: float, actuator: ActuatorConfig, energy: EnergyConfig) -> float:
    """Electrical energy, J, of samples tau, omega (n, 12) taken every dt s (rectangle rule)."""
    _check_dt(dt)
    return float(np.sum(electrical_power(tau, omega, actuator, energy)) * dt)


# ---------------------------------------------------------------------------------------------------------
# Battery (paper Section 4.2, Eq. 13)
# ---------------------------------------------------------------------------------------------------------

def battery_capacity_J(cfg: EnergyConfig) -> float:
    """Pack energy at full charge, J (EnergyConfig.battery_capacity_wh, an assumption)."""
    return cfg.battery_capacity_wh * J_PER_WH


def battery_percent_used(energy_electrical_J: float, cfg: EnergyConfig) -> float:
    """Share of the full pack, %, that `energy_electrical_J` drains."""
    return 100.0 * energy_electrical_J / battery_capacity_J(cfg)


def power_consumption(initial_percent: float, remaining_percent: float) -> float:
    """Eq. (13): P_C = E_f − E_n, percentage points of charge used (E_f the initial, E_n the remaining)."""
    return initial_percent - remaining_percent


def remaining_percent(energy_electrical_J: float, cfg: EnergyConfig) -> float:
    """E_n, %, after drawing `energy_electrical_J` from a pack starting at E_f = 100·usable_fraction (95 %)."""
    return 100.0 * cfg.usable_fraction - battery_percent_used(energy_electrical_J, cfg)


def range_at_full_charge(energy_J: float, distance_m: float, cfg: EnergyConfig) -> float:
    """Distance, m, walkable on the usable capacity at the measured rate: distance / energy × usable energy.

    Compare: the paper's CyberDog walked 3600 m (cycloid) and 3924 m (learned trajectory) at 1 m/s.
    """
    _check_distance(distance_m)
    if not energy_J > 0:
        raise ValueError(f"energy must be > 0 J to give a range, got {energy_J!r}")
    return distance_m / energy_J * cfg.usable_fraction * battery_capacity_J(cfg)


def energy_reduction(energy_min: float, energy_s: float) -> float:
    """Eq. (12): D_t = (E_min − E_s) / E_min, as a fraction; E_min the cheaper of the other trajectories' energy,
    E_s the evaluated trajectory's (any unit, both the same: J, J/m or % of battery)."""
    if not (np.isfinite(energy_min) and energy_min > 0 and np.isfinite(energy_s)):
        raise ValueError(f"Eq. (12) needs E_min > 0 and a finite E_s, got {energy_min!r}, {energy_s!r}")
    return (energy_min - energy_s) / energy_min


def range_from_percent(distance_m: float, percent_used: float, cfg: EnergyConfig) -> float:
    """Range, m, on the usable pack (E_f = 100·usable_fraction %, drained to 0) at the rate of a walk of
    `distance_m` that used `percent_used` points (Eq. 13): d · 100·usable_fraction / P_C.
    Equal to `range_at_full_charge(E, d, cfg)` when percent_used = battery_percent_used(E, cfg)."""
    _check_distance(distance_m)
    if not (np.isfinite(percent_used) and percent_used > 0):
        raise ValueError(f"percent used must be > 0 and finite to give a range, got {percent_used!r}")
    return distance_m * 100.0 * cfg.usable_fraction / percent_used
