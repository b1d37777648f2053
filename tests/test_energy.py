"""Energy model: Eq. (7) against a closed form, breakdowns, CoT, electrical losses, battery consistency."""
import numpy as np
import pytest

from cyberdog.config import ActuatorConfig, EnergyConfig
from cyberdog.core.energy import (battery_capacity_J, battery_percent_used, copper_loss,
                                  cost_of_transport, electrical_energy, electrical_joint_power,
                                  electrical_power, energy_per_100m, joint_energy, mechanical_power,
                                  per_joint_type, per_leg, power_consumption, range_at_full_charge,
                                  remaining_percent)

DT = 0.001  # s
DURATION = 2.0  # s


def _sinusoids():
    """τ_j = A_j sin(w_j t), ω_j = B_j cos(w_j t) with whole periods in DURATION; closed-form energy per joint.

    ∫|A B sin(wt) cos(wt)| dt = |A B|/2 ∫|sin 2wt| dt = |A B|/2 · (2/π) · DURATION over whole periods.
    """
    rng = np.random.default_rng(7)
    A, B = rng.uniform(-20, 20, 12), rng.uniform(-8, 8, 12)
    w = 2 * np.pi * np.arange(1, 13) / DURATION  # rad/s, 1 … 12 periods in DURATION
    t = np.arange(int(round(DURATION / DT)))[:, None] * DT
    tau, omega = A * np.sin(w * t), B * np.cos(w * t)
    exact = np.abs(A * B) / 2 * (2 / np.pi) * DURATION
    return tau, omega, exact


def test_joint_energy_matches_closed_form():
    tau, omega, exact = _sinusoids()
    np.testing.assert_allclose(joint_energy(tau, omega, DT), exact, rtol=1e-3)


def test_breakdowns_sum_to_total():
    tau, omega, _ = _sinusoids()
    e = joint_energy(tau, omega, DT)
    legs, types = per_leg(e), per_joint_type(e)
    assert legs.shape == (4,) and types.shape == (3,)
    assert legs.sum() == pytest.approx(e.sum()) and types.sum() == pytest.approx(e.sum())
    np.testing.assert_allclose(legs, [e[0:3].sum(), e[3:6].sum(), e[6:9].sum(), e[9:12].sum()])
    np.testing.assert_allclose(types, [e[0::3].sum(), e[1::3].sum(), e[2::3].sum()])
    np.testing.assert_allclose(per_leg(mechanical_power(tau, omega)).sum(axis=1),
                               np.abs(tau * omega).sum(axis=1))  # batched


def test_cost_of_transport_and_per_100m():
    m, g, d, e = 13.573, 9.81, 12.5, 1600.0
    assert cost_of_transport(e, m, g, d) * m * g * d == pytest.approx(e)
    assert cost_of_transport(2 * e, m, g, d) == pytest.approx(2 * cost_of_transport(e, m, g, d))
    assert energy_per_100m(e, d) == pytest.approx(e / d * 100)
    with pytest.raises(ValueError, match="distance"):
        cost_of_transport(e, m, g, 0.0)
    with pytest.raises(ValueError, match="distance"):
        energy_per_100m(e, -1.0)


def _ideal(**kw):
    return EnergyConfig(**({"driver_efficiency": 1.0, "idle_power": 0.0} | kw))


def test_copper_loss_closed_form():
    act = ActuatorConfig(gear_ratio=9.0, motor_kt=0.05, motor_resistance=0.173, friction=True)
    current = 9.0 / (9.0 * 0.05)  # A for 9 N·m at the joint
    assert copper_loss(9.0, act) == pytest.approx(current ** 2 * 0.173)
    assert copper_loss(-9.0, act) == pytest.approx(copper_loss(9.0, act))
    # holding torque at zero speed: electrical power is copper loss alone
    tau = np.full(12, 9.0)
    np.testing.assert_allclose(electrical_joint_power(tau, np.zeros(12), act, _ideal()), current ** 2 * 0.173)


def test_friction_added_only_when_not_simulated():
    tau, omega = np.full(12, 3.0), np.full(12, -4.0)
    simulated = ActuatorConfig(friction=True, viscous_damping=0.01, dry_friction=0.246)
    not_simulated = ActuatorConfig(friction=False, viscous_damping=0.01, dry_friction=0.246)
    cu = 0.173 / (9 * 0.05) ** 2  # copper loss per N·m²
    p_sim = electrical_joint_power(tau, omega, simulated, _ideal(regeneration=True))
    np.testing.assert_allclose(p_sim, 3.0 * -4.0 + cu * 3.0 ** 2)
    tau_m = 3.0 + 0.01 * -4.0 - 0.246  # friction opposes the motion
    p_not = electrical_joint_power(tau, omega, not_simulated, _ideal(regeneration=True))
    np.testing.assert_allclose(p_not, tau_m * -4.0 + cu * tau_m ** 2)
    # friction is a loss: τ_m·ω = τ·ω + b·ω² + f_c·|ω|
    assert (tau_m * -4.0) == pytest.approx(3.0 * -4.0 + 0.01 * 16 + 0.246 * 4)


def test_efficiency_regeneration_and_idle_power():
    act = ActuatorConfig(friction=True, motor_resistance=0.0)
    tau, omega = np.full(12, 2.0), np.array([3.0] * 6 + [-3.0] * 6)
    eta = 0.8
    regen = electrical_joint_power(tau, omega, act, EnergyConfig(driver_efficiency=eta, regeneration=True))
    np.testing.assert_allclose(regen, [6.0 / eta] * 6 + [-6.0 * eta] * 6)
    no_regen = electrical_joint_power(tau, omega, act, EnergyConfig(driver_efficiency=eta, regeneration=False))
    np.testing.assert_allclose(no_regen, [6.0 / eta] * 6 + [0.0] * 6)
    cfg = EnergyConfig(driver_efficiency=eta, idle_power=30.0)
    assert electrical_power(tau, omega, act, cfg) == pytest.approx(6 * 6.0 / eta + 30.0)
    samples = np.tile(tau, (500, 1)), np.tile(omega, (500, 1))
    assert electrical_energy(*samples, DT, act, cfg) == pytest.approx(0.5 * (36.0 / eta + 30.0))


def test_electrical_exceeds_mechanical_without_regeneration():
    tau, omega, _ = _sinusoids()
    act = ActuatorConfig(friction=False)
    cfg = EnergyConfig(driver_efficiency=0.9)
    e_el = electrical_energy(tau, omega, DT, act, cfg)
    # per sample P_in >= max(τ·ω, 0) / η: friction and copper loss only add, braking is not recovered
    positive_work = np.maximum(tau * omega, 0).sum() * DT
    assert e_el >= positive_work / 0.9 > 0


def test_battery_percent_range_and_eq13_consistent():
    cfg = EnergyConfig(battery_capacity_wh=200.0, usable_fraction=0.95)
    assert battery_capacity_J(cfg) == pytest.approx(200.0 * 3600)
    e, d = 36_000.0, 100.0  # J over 100 m
    assert battery_percent_used(e, cfg) == pytest.approx(100 * e / (200.0 * 3600))
    r = range_at_full_charge(e, d, cfg)
    # walking the whole range at the same rate drains exactly the usable share of the pack
    assert battery_percent_used(e * r / d, cfg) == pytest.approx(100 * cfg.usable_fraction)
    assert remaining_percent(e * r / d, cfg) == pytest.approx(0.0, abs=1e-9)
    # Eq. (13): P_C = E_f − E_n with E_f = 95 %
    assert power_consumption(95.0, remaining_percent(e, cfg)) == pytest.approx(battery_percent_used(e, cfg))
    # halving the energy per metre doubles the range
    assert range_at_full_charge(e / 2, d, cfg) == pytest.approx(2 * r)
    with pytest.raises(ValueError, match="energy"):
        range_at_full_charge(0.0, d, cfg)


def test_bad_inputs_raise():
    with pytest.raises(ValueError, match="same shape"):
        mechanical_power(np.zeros(12), np.zeros(11))
    with pytest.raises(ValueError, match="dt"):
        joint_energy(np.zeros((3, 12)), np.zeros((3, 12)), 0.0)
