"""Foot trajectories: boundary conditions, closed forms, derivatives, sampled replay and bad inputs."""
import types

import numpy as np
import pytest

from cyberdog.config import GaitConfig
from cyberdog.core.trajectories import (CompositeCycloid, SampledTrajectory, StraightLine, make_trajectory,
                                        swing_fraction)

S, H = 0.2, 0.15  # m, the paper's Section 2.3 parameters
T_SWING, T_STANCE = 0.2, 0.2  # s

SHAPES = ("rectangle", "trapezoid", "triangle")
SWING_TRAJECTORIES = [CompositeCycloid()] + [StraightLine(s) for s in SHAPES]


def test_cycloid_boundary_conditions():
    cyc = CompositeCycloid()
    x, z, dx, dz = cyc.swing_path(np.array([0.0, 0.5, 1.0]), S, H)
    np.testing.assert_allclose(x, [-S / 2, 0.0, S / 2], atol=1e-12)
    np.testing.assert_allclose(z, [0.0, H, 0.0], atol=1e-12)
    np.testing.assert_allclose([dx[0], dx[2], dz[0], dz[2]], 0.0, atol=1e-12)
    # acceleration from one-sided differences of the velocity: vanishes like h at both ends
    for h in (1e-3, 1e-4):
        _, _, dx0, dz0 = cyc.swing_path(np.array([0.0, h]), S, H)
        _, _, dx1, dz1 = cyc.swing_path(np.array([1.0 - h, 1.0]), S, H)
        for acc in (np.diff(dx0) / h, np.diff(dz0) / h, np.diff(dx1) / h, np.diff(dz1) / h):
            assert abs(acc[0]) < 100 * h  # the acceleration itself would be O(1)
    tau = np.linspace(0, 1, 2001)
    x, z, _, _ = cyc.swing_path(tau, S, H)
    assert x.max() - x.min() == pytest.approx(S, abs=1e-12)
    assert z.max() == pytest.approx(H, abs=1e-12) and tau[np.argmax(z)] == pytest.approx(0.5)
    assert np.all(np.diff(x) >= 0) and np.all(z >= -1e-15)


@pytest.mark.parametrize("traj", SWING_TRAJECTORIES, ids=lambda t: getattr(t, "shape", t.name))
def test_swing_derivative_matches_finite_difference(traj):
    h = 1e-6
    tau = np.linspace(0.013, 0.987, 97)
    x, z, dx, dz = traj.swing_path(tau, S, H)
    xp, zp, _, _ = traj.swing_path(tau + h, S, H)
    xm, zm, _, _ = traj.swing_path(tau - h, S, H)
    fd_x, fd_z = (xp - xm) / (2 * h), (zp - zm) / (2 * h)
    smooth = np.isclose(fd_x, (xp - x) / h, atol=1e-4) & np.isclose(fd_z, (zp - z) / h, atol=1e-4)
    assert smooth.sum() > 90  # only samples within h of a straight-line corner are excused
    np.testing.assert_allclose(dx[smooth], fd_x[smooth], atol=1e-5)
    np.testing.assert_allclose(dz[smooth], fd_z[smooth], atol=1e-5)


@pytest.mark.parametrize("traj", SWING_TRAJECTORIES, ids=lambda t: getattr(t, "shape", t.name))
@pytest.mark.parametrize("swing_time,stance_time", [(0.2, 0.2), (0.15, 0.25)])
def test_time_velocity_matches_finite_difference(traj, swing_time, stance_time):
    period = swing_time + stance_time
    dt = 1e-7
    phase = np.random.default_rng(0).uniform(0, 1, 200)
    pos, vel = traj.position_velocity(phase, S, H, swing_time, stance_time)
    plus, _ = traj.position_velocity(phase + dt / period, S, H, swing_time, stance_time)
    minus, _ = traj.position_velocity(phase - dt / period, S, H, swing_time, stance_time)
    fd = (plus - minus) / (2 * dt)
    one_sided = (plus - pos) / dt
    smooth = np.all(np.isclose(fd, one_sided, atol=1e-3), axis=-1)
    assert smooth.sum() > 190
    np.testing.assert_allclose(vel[smooth], fd[smooth], atol=1e-4)


@pytest.mark.parametrize("shape", SHAPES)
def test_straight_line_reaches_height_spans_step_at_constant_speed(shape):
    traj = StraightLine(shape, trapezoid_fraction=0.3)
    tau = np.linspace(0, 1, 4001)
    x, z, dx, dz = traj.swing_path(tau, S, H)
    assert z.max() == pytest.approx(H) and z[0] == 0 and z[-1] == pytest.approx(0, abs=1e-12)
    assert x[0] == pytest.approx(-S / 2) and x[-1] == pytest.approx(S / 2)
    assert np.all(np.diff(x) >= -1e-12)
    path_length = {"rectangle": 2 * H + S, "triangle": 2 * np.hypot(S / 2, H),
                   "trapezoid": 2 * np.hypot(0.3 * S, H) + S - 2 * 0.3 * S}[shape]
    np.testing.assert_allclose(np.hypot(dx, dz), path_length, rtol=1e-12)  # |dp/dτ| = L everywhere
    # equal τ steps cover equal path lengths (the chord only cuts the corners)
    chords = np.hypot(np.diff(x), np.diff(z))
    assert np.median(chords) == pytest.approx(path_length / 4000, rel=1e-9)
    assert chords.sum() == pytest.approx(path_length, rel=1e-4)


def test_straight_line_with_zero_step_goes_up_and_down():
    x, z, dx, dz = StraightLine("rectangle").swing_path(np.linspace(0, 1, 11), 0.0, H)
    np.testing.assert_allclose(x, 0.0)
    np.testing.assert_allclose(z, H * (1 - np.abs(np.linspace(-1, 1, 11))), atol=1e-12)
    np.testing.assert_allclose(np.abs(dz), 2 * H)


@pytest.mark.parametrize("traj", SWING_TRAJECTORIES, ids=lambda t: getattr(t, "shape", t.name))
@pytest.mark.parametrize("swing_time,stance_time", [(0.2, 0.2), (0.15, 0.25), (0.3, 0.1)])
def test_stance_moves_back_at_constant_speed(traj, swing_time, stance_time):
    beta = swing_fraction(swing_time, stance_time)
    phase = np.linspace(beta, 1, 50, endpoint=False)
    pos, vel = traj.position_velocity(phase, S, H, swing_time, stance_time)
    np.testing.assert_allclose(vel[:, 0], -S / stance_time)
    np.testing.assert_allclose(vel[:, 1], 0.0)
    np.testing.assert_allclose(pos[:, 1], 0.0)
    np.testing.assert_allclose(pos[:, 0], S / 2 - S * (phase - beta) / (1 - beta), atol=1e-12)
    # the swing is continuous with the stance: lift-off at −S/2, touch-down at +S/2
    start, _ = traj.position_velocity(0.0, S, H, swing_time, stance_time)
    end, _ = traj.position_velocity(beta - 1e-12, S, H, swing_time, stance_time)
    np.testing.assert_allclose(start, [-S / 2, 0.0], atol=1e-9)
    np.testing.assert_allclose(end, [S / 2, 0.0], atol=1e-9)


def test_scalar_phase_and_wrapping():
    cyc = CompositeCycloid()
    pos, vel = cyc.position_velocity(0.25, S, H, T_SWING, T_STANCE)
    assert pos.shape == (2,) and vel.shape == (2,)
    pos2, vel2 = cyc.position_velocity(1.25, S, H, T_SWING, T_STANCE)
    np.testing.assert_allclose(pos, pos2, atol=1e-12)
    np.testing.assert_allclose(vel, vel2, atol=1e-9)


def _learned_like_points(n=60):
    """A smooth closed curve standing in for an extracted trajectory (not produced by the code under test)."""
    phase = np.arange(n) / n
    x = S * (0.5 * np.sin(2 * np.pi * phase) + 0.1 * np.cos(4 * np.pi * phase))
    z = H * np.maximum(np.sin(2 * np.pi * phase), 0) ** 2
    return phase, x, z


def test_sampled_reproduces_points_is_periodic_and_c1():
    phase, x, z = _learned_like_points()
    traj = SampledTrajectory.from_points(phase, x, z, S, H, {"source": "test"})
    pos, vel = traj.position_velocity(phase, S, H, T_SWING, T_STANCE)
    np.testing.assert_allclose(pos[:, 0], x, atol=1e-12)
    np.testing.assert_allclose(pos[:, 1], z, atol=1e-12)
    eps = 1e-9
    for p in (0.0, phase[7], 0.5 * (phase[3] + phase[4])):
        lo, vlo = traj.position_velocity(p - eps, S, H, T_SWING, T_STANCE)
        hi, vhi = traj.position_velocity(p + eps, S, H, T_SWING, T_STANCE)
        np.testing.assert_allclose(lo, hi, atol=1e-8)
        np.testing.assert_allclose(vlo, vhi, atol=1e-5)
    a, _ = traj.position_velocity(0.3, S, H, T_SWING, T_STANCE)
    b, _ = traj.position_velocity(1.3, S, H, T_SWING, T_STANCE)
    np.testing.assert_allclose(a, b, atol=1e-12)
    # velocity is the time derivative over the full cycle
    period, dt = T_SWING + T_STANCE, 1e-7
    q = np.linspace(0, 1, 37, endpoint=False)
    plus, _ = traj.position_velocity(q + dt / period, S, H, T_SWING, T_STANCE)
    minus, _ = traj.position_velocity(q - dt / period, S, H, T_SWING, T_STANCE)
    _, v = traj.position_velocity(q, S, H, T_SWING, T_STANCE)
    np.testing.assert_allclose(v, (plus - minus) / (2 * dt), atol=1e-5)


def test_sampled_replays_scaled_at_other_step_and_height():
    phase, x, z = _learned_like_points()
    traj = SampledTrajectory.from_points(phase, x, z, S, H)
    q = np.linspace(0, 1, 41, endpoint=False)
    pos, vel = traj.position_velocity(q, S, H, T_SWING, T_STANCE)
    pos2, vel2 = traj.position_velocity(q, 2.5 * S, 0.5 * H, T_SWING, 2 * T_STANCE)
    np.testing.assert_allclose(pos2, pos * [2.5, 0.5], atol=1e-12)
    period_ratio = (T_SWING + T_STANCE) / (T_SWING + 2 * T_STANCE)
    np.testing.assert_allclose(vel2, vel * [2.5, 0.5] * period_ratio, atol=1e-12)


@pytest.mark.parametrize("suffix", [".json", ".csv"])
def test_sampled_save_load_round_trip(tmp_path, suffix):
    phase, x, z = _learned_like_points(25)
    prov = {"source": "unit test", "speed_m_s": 1.0, "cycle": 3}
    traj = SampledTrajectory.from_points(phase, x, z, S, H, prov)
    back = SampledTrajectory.load(traj.save(tmp_path / f"traj{suffix}"))
    assert back.provenance == prov
    assert (back.step_length, back.lift_height) == (S, H)
    q = np.linspace(0, 1, 101)
    for a, b in zip(traj.position_velocity(q, S, H, T_SWING, T_STANCE),
                    back.position_velocity(q, S, H, T_SWING, T_STANCE)):
        np.testing.assert_array_equal(a, b)
    # the factory loads it too
    made = make_trajectory(GaitConfig(trajectory="sampled", sampled_file=str(tmp_path / f"traj{suffix}")))
    assert isinstance(made, SampledTrajectory)


def test_factory_names():
    assert isinstance(make_trajectory(GaitConfig(trajectory="cycloid")), CompositeCycloid)
    made = make_trajectory(GaitConfig(trajectory="straight", straight_shape="triangle"))
    assert isinstance(made, StraightLine) and made.shape == "triangle"
    with pytest.raises(ValueError, match="cycloid"):
        make_trajectory(types.SimpleNamespace(trajectory="spline"))
    with pytest.raises(ValueError, match="trajectory"):
        GaitConfig(trajectory="spline")
    with pytest.raises(ValueError, match="sampled_file"):
        make_trajectory(GaitConfig(trajectory="sampled"))


@pytest.mark.parametrize("args, match", [
    ((-0.1, H, T_SWING, T_STANCE), "step_length"),
    ((S, 0.0, T_SWING, T_STANCE), "lift_height"),
    ((S, -0.1, T_SWING, T_STANCE), "lift_height"),
    ((S, H, 0.0, T_STANCE), "swing_time"),
    ((S, H, T_SWING, 0.0), "stance_time"),
    ((S, H, T_SWING, -0.1), "stance_time"),
    ((np.nan, H, T_SWING, T_STANCE), "step_length"),
])
def test_bad_gait_arguments_raise(args, match):
    for traj in SWING_TRAJECTORIES:
        with pytest.raises(ValueError, match=match):
            traj.position_velocity(0.3, *args)


def test_bad_config_and_shape_raise():
    with pytest.raises(ValueError, match="swing_time"):
        GaitConfig(period=0.4, swing_time=0.5)  # swing longer than the cycle
    with pytest.raises(ValueError, match="shape"):
        StraightLine("circle")
    with pytest.raises(ValueError, match="trapezoid_fraction"):
        StraightLine("trapezoid", trapezoid_fraction=0.6)
    with pytest.raises(ValueError, match="tau"):
        CompositeCycloid().swing_path(1.5, S, H)
    with pytest.raises(ValueError, match="phase"):
        CompositeCycloid().position_velocity(np.inf, S, H, T_SWING, T_STANCE)


@pytest.mark.parametrize("phase, x, z, kwargs, match", [
    ([0.0, 0.5, 0.3, 0.7], [0] * 4, [0] * 4, {}, "increasing"),
    ([0.0, 0.2, 0.2, 0.7], [0] * 4, [0] * 4, {}, "increasing"),
    ([0.0, 0.5], [0] * 2, [0] * 2, {}, "at least"),
    ([0.0, 0.25, 0.5, 1.0], [0] * 4, [0] * 4, {}, r"\[0, 1\)"),
    ([0.0, 0.25, 0.5, 0.75], [0, np.nan, 0, 0], [0] * 4, {}, "finite"),
    ([0.0, 0.25, 0.5, 0.75], [0] * 3, [0] * 4, {}, "lengths"),
    ([0.0, 0.25, 0.5, 0.75], [0] * 4, [0] * 4, {"step_length": 0.0}, "step_length"),
    ([0.0, 0.25, 0.5, 0.75], [0] * 4, [0] * 4, {"provenance": {"f": object()}}, "JSON"),
])
def test_sampled_bad_inputs_raise(phase, x, z, kwargs, match):
    args = {"step_length": S, "lift_height": H, "provenance": None} | kwargs
    with pytest.raises(ValueError, match=match):
        SampledTrajectory.from_points(phase, x, z, **args)


def test_sampled_missing_file_raises(tmp_path):
    with pytest.raises(ValueError, match="does not exist"):
        SampledTrajectory.load(tmp_path / "missing.json")


@pytest.mark.parametrize("edit, match", [
    (lambda text: text.replace("# lift_height_m", "# lift_m"), "lacks header"),
    (lambda text: text.replace("phase,x_m,z_m\n", "phase,x_m,z_m\n0.0,0.1\n"), "a point is phase,x_m,z_m"),
])
def test_a_broken_csv_file_is_refused_with_what_it_lacks(tmp_path, edit, match):
    phase, x, z = _learned_like_points(8)
    path = SampledTrajectory.from_points(phase, x, z, S, H).save(tmp_path / "traj.csv")
    path.write_text(edit(path.read_text()))
    with pytest.raises(ValueError, match=match):
        SampledTrajectory.load(path)
