"""The foot-path shape parameterisation (cyberdog.core.path_shape) and a tiny objective run."""
import math

import numpy as np
import pytest

from cyberdog.core import path_shape as so
from cyberdog.analysis import shape_search as search
from cyberdog.config import HARDWARE_LIKE
from cyberdog.config import GaitConfig
from cyberdog.core.trajectories import CompositeCycloid, SampledTrajectory

BETA = 0.5  # the default trot's swing fraction (0.2 s swing of a 0.4 s cycle)


def random_params(n: int, seed: int = 0) -> list[so.ShapeParams]:
    rng = np.random.default_rng(seed)
    return [so.from_unit(rng.random(len(so.PARAM_NAMES))) for _ in range(n)]


def test_cycloid_params_are_the_composite_cycloid_exactly_in_closed_form():
    phase = np.linspace(0.0, 1.0, 2001)[:-1]
    x_hat, z_hat = so.normalised_cycle(phase, so.CYCLOID_PARAMS, BETA)
    S, H = 0.24, 0.10
    xz, _ = CompositeCycloid().position_velocity(phase, S, H, 0.2, 0.2)
    np.testing.assert_allclose(S * x_hat, xz[:, 0], atol=1e-12)
    np.testing.assert_allclose(H * z_hat, xz[:, 1], atol=1e-12)


@pytest.mark.parametrize("speed, lift", [(1.0, 0.10), (1.4, 0.10), (1.2, 0.15)])
def test_sampled_start_is_within_a_millimetre_of_the_cycloid(speed, lift):
    gait = GaitConfig(speed=speed, lift_height=lift)
    traj = so.shape_trajectory(so.CYCLOID_PARAMS, gait)
    assert isinstance(traj, SampledTrajectory)
    phase = np.linspace(0.0, 1.0, 8001)[:-1]
    args = (gait.step_length, lift, gait.swing_time, gait.stance_time)
    ours, _ = traj.position_velocity(phase, *args)
    cyc, _ = CompositeCycloid().position_velocity(phase, *args)
    assert np.max(np.abs(ours - cyc)) < 1e-3  # m
    assert traj.provenance["shape_params"] == so.CYCLOID_PARAMS.as_dict()


@pytest.mark.parametrize("p", random_params(25))
def test_lift_height_and_continuity_hold_for_any_parameters(p):
    tau = np.linspace(0.0, 1.0, 20001)
    z = so.swing_z_hat(tau, p)
    assert so.swing_z_hat(p.z_peak, p) == pytest.approx(1.0, abs=1e-12)  # the apex is exactly H …
    assert z.max() <= 1.0 + 1e-12 and z.min() >= 0.0  # … and nothing is above it or below the ground
    x = so.swing_x_hat(tau, p)
    assert np.all(np.diff(x) >= -1e-12)  # the swing foot never moves backward
    # swing ends meet the stance ends: lift-off at (−½, 0), touch-down at (+½, 0)
    assert so.swing_x_hat(0.0, p) == pytest.approx(-0.5, abs=1e-12)
    assert so.swing_x_hat(1.0, p) == pytest.approx(0.5, abs=1e-12)
    assert so.stance_x_hat(0.0, p) == pytest.approx(0.5, abs=1e-12)
    assert so.stance_x_hat(1.0, p) == pytest.approx(-0.5, abs=1e-12)
    assert so.swing_z_hat(0.0, p) == pytest.approx(0.0, abs=1e-12)
    assert so.swing_z_hat(1.0, p) == pytest.approx(0.0, abs=1e-12)
    # no jump across the switches of the full cycle (positions continuous, velocities bounded)
    eps = 1e-7
    for a, b in ((BETA - eps, BETA), (1.0 - eps, 0.0)):
        (xa, za), (xb, zb) = (np.asarray(so.normalised_cycle(np.array([ph]), p, BETA)).ravel() for ph in (a, b))
        assert abs(xa - xb) < 1e-5 and abs(za - zb) < 1e-5
    # the replayed spline keeps the lift height (within 0.1 % where the apex falls between samples)
    traj = so.shape_trajectory(p, GaitConfig(speed=1.2, lift_height=0.10))
    xz, _ = traj.position_velocity(np.linspace(0.0, 1.0, 20001)[:-1], 0.24, 0.10, 0.2, 0.2)
    assert xz[:, 1].max() == pytest.approx(0.10, rel=1e-3)
    assert xz[:, 1].min() > -1e-4
    # ±S/2: the C² spline overshoots a velocity jump at a switch by a fraction of a millimetre
    assert xz[:, 0].min() == pytest.approx(-0.12, abs=5e-4) and xz[:, 0].max() == pytest.approx(0.12, abs=5e-4)


def test_unit_coordinates_round_trip():
    for p in random_params(5, seed=1) + [so.CYCLOID_PARAMS]:
        q = so.from_unit(so.to_unit(p))
        np.testing.assert_allclose(q.as_array(), p.as_array(), atol=1e-12)
    assert np.all((so.to_unit(so.CYCLOID_PARAMS) >= 0) & (so.to_unit(so.CYCLOID_PARAMS) <= 1))


@pytest.mark.parametrize("field, value", [("x_law", 2.0), ("x_skew", -1.0), ("z_peak", 0.1), ("z_peak", 0.9),
                                          ("z_fullness_log2", 3.0), ("stance_law", -0.1), ("x_law", math.nan)])
def test_bad_parameters_raise_naming_the_field(field, value):
    with pytest.raises(ValueError, match=field):
        so.ShapeParams(**{field: value})


def test_bad_inputs_raise():
    with pytest.raises(ValueError, match="5 values"):
        so.ShapeParams.from_array([0.0, 0.0, 0.5])
    with pytest.raises(ValueError, match="n_points"):
        so.shape_trajectory(so.CYCLOID_PARAMS, n_points=10)
    with pytest.raises(ValueError, match="swing_fraction"):
        so.normalised_cycle([0.1], so.CYCLOID_PARAMS, 1.0)
    with pytest.raises(ValueError, match="phase"):
        so.normalised_cycle([1.0], so.CYCLOID_PARAMS, BETA)
    with pytest.raises(ValueError, match="tau"):
        so.swing_x_hat([1.5], so.CYCLOID_PARAMS)
    with pytest.raises(ValueError, match="lift_height"):
        search.ShapeObjective(lift_height=0.5)
    with pytest.raises(ValueError, match="speeds"):
        search.ShapeObjective(speeds=())
    with pytest.raises(ValueError, match="measure_from"):
        search.ShapeObjective(duration=2.0, measure_from=2.0)
    with pytest.raises(ValueError, match="max_evals"):
        search.optimize_shape(max_evals=1)


def test_objective_smoke_two_evaluations_on_a_short_walk():
    obj = search.ShapeObjective(lift_height=0.10, speeds=(1.0,), duration=1.0, measure_from=0.5, log=None, max_evals=2)
    start = obj(so.to_unit(so.CYCLOID_PARAMS))
    other = obj(so.to_unit(so.ShapeParams(x_law=0.5, stance_law=0.3)))
    assert math.isfinite(start) and math.isfinite(other) and start > 0 and other > 0
    assert obj(so.to_unit(so.CYCLOID_PARAMS)) == start and len(obj.history) == 2  # cached, not walked again
    with pytest.raises(search.EvaluationBudgetSpent):
        obj(so.to_unit(so.ShapeParams(x_skew=0.2)))
    walk = obj.history[0].walks[0]
    assert walk["energy_window_J"] < walk["energy_total_J"]  # the window leaves the start out
    row = obj.history[1].row()
    assert row["x_law"] == pytest.approx(0.5) and "E_window_J@1.00" in row


def test_the_electrical_objective_on_the_hardware_like_robot_counts_what_the_battery_pays():
    """The battery's search: the window's electrical energy (copper loss, friction, driver) of the hardware-like
    robot's walk, which is more than its Eq. (7) energy there; bad objectives are refused by name."""
    kw = dict(lift_height=0.085, speeds=(1.0,), duration=1.0, measure_from=0.5, log=None)
    eq7 = search.ShapeObjective(**kw, hardware=HARDWARE_LIKE)
    battery = search.ShapeObjective(**kw, objective="electrical", hardware=HARDWARE_LIKE)
    u = so.to_unit(so.CYCLOID_PARAMS)
    e_mech, e_el = eq7(u), battery(u)
    assert math.isfinite(e_mech) and math.isfinite(e_el) and e_el > e_mech > 0
    assert eq7.history[0].walks[0]["energy_total_J"] == pytest.approx(battery.history[0].walks[0]["energy_total_J"])
    with pytest.raises(ValueError, match="objective"):
        search.ShapeObjective(objective="mechanical")
    with pytest.raises(TypeError, match="hardware"):
        search.ShapeObjective(hardware="hardware")


def test_a_search_over_the_gains_walks_each_shape_under_each_and_costs_their_mean():
    """`gains`: every speed walked under each (kp, kd) factor pair of the default PID, the objective their mean;
    doubling kd changes the walk (the drivers' damping reaches it); bad pairs are refused by name."""
    kw = dict(lift_height=0.10, speeds=(1.0,), duration=1.0, measure_from=0.5, log=None)
    both = search.ShapeObjective(**kw, gains=((1.0, 1.0), (1.0, 2.0)))
    u = so.to_unit(so.CYCLOID_PARAMS)
    mean = both(u)
    walks = both.history[0].walks
    assert [(w["kp_factor"], w["kd_factor"]) for w in walks] == [(1.0, 1.0), (1.0, 2.0)]
    assert mean == pytest.approx((walks[0]["cost_J"] + walks[1]["cost_J"]) / 2)
    assert walks[0]["energy_window_J"] != pytest.approx(walks[1]["energy_window_J"], rel=1e-6)
    alone = search.ShapeObjective(**kw)(u)
    assert alone == pytest.approx(walks[0]["cost_J"])  # the default pair is the default search's walk
    row = both.history[0].row()
    assert "E_window_J@1.00" in row and "E_window_J@1.00 kp1 kd2" in row
    for bad in ((), ((1.0, 0.1),), ((1.0,),), ((1.0, 1.0), (1.0, 1.0))):
        with pytest.raises(ValueError, match="gains"):
            search.ShapeObjective(**kw, gains=bad)
