"""Sagittal foot placement (ControllerConfig.sagittal_placement_gain): the touchdown shift k·(v − v_cmd)."""
import dataclasses

import numpy as np
import pytest

from cyberdog import config as C
from cyberdog.analysis.walk import walk
from cyberdog.control.trot import MAX_ATTITUDE_SHIFT, BodyFeedback, TrotController

SPEED = 1.0  # m/s, the set speed (reached after the 1 s start-up ramp)
T0 = 2.0  # s: LF's phase is 0 here, the start of its swing (phase offset 0, period 0.4 s)


def controller(gain: float) -> TrotController:
    cfg = C.WalkConfig()
    cfg = dataclasses.replace(cfg, gait=dataclasses.replace(cfg.gait, speed=SPEED),
                              controller=dataclasses.replace(cfg.controller, sagittal_placement_gain=gain))
    return TrotController(cfg)


def x_difference(gain: float, speeds, t0: float = T0):
    """LF's foot-target x (m) with the placement on, minus the same controller's with it off, and the same for
    the foot velocity target, per controller period from t0 with body speeds `speeds` (m/s, one per period)."""
    on, off = controller(gain), controller(0.0)
    dt = on.cfg.sim.controller_dt
    dx, dvx, swinging = [], [], []
    for k, v in enumerate(speeds):
        body = BodyFeedback(forward_speed=v)
        a, b = on.targets(t0 + k * dt, body), off.targets(t0 + k * dt, body)
        dx.append(a.foot_position[0, 0] - b.foot_position[0, 0])
        dvx.append(a.foot_velocity[0, 0] - b.foot_velocity[0, 0])
        swinging.append(bool(a.in_swing[0]))
    return np.array(dx), np.array(dvx), np.array(swinging), dt


def test_off_by_default_and_silent_at_the_commanded_speed():
    assert C.ControllerConfig().sagittal_placement_gain == 0.0  # the paper's trot, Table 5's walks
    dx, dvx, _, _ = x_difference(0.2, [SPEED] * 320)  # two gait cycles at exactly the command
    assert np.all(dx == 0.0) and np.all(dvx == 0.0)


def test_a_faster_body_steps_further_ahead_and_the_stance_holds_it():
    k, excess = 0.2, 0.1  # s, m/s: 20 mm
    n_swing = 80  # controller periods of a 0.2 s swing at 400 Hz
    dx, dvx, swinging, dt = x_difference(k, [SPEED + excess] * (2 * n_swing))
    assert swinging[:n_swing].all() and not swinging[n_swing:].any()
    # the swing moves the foot from the stance's shift (none yet) to k·Δv, linearly, at the matching rate
    phase_share = np.arange(n_swing) / n_swing
    np.testing.assert_allclose(dx[:n_swing], k * excess * phase_share, atol=1e-9)
    np.testing.assert_allclose(dvx[:n_swing], k * excess / 0.2, atol=1e-9)
    # touchdown: the stance keeps where the swing put the foot, still, so its stroke is the unshifted one's
    np.testing.assert_allclose(dx[n_swing:], dx[n_swing - 1], atol=1e-12)
    assert dx[n_swing - 1] == pytest.approx(k * excess, rel=dt / 0.2 + 1e-9)
    np.testing.assert_allclose(dvx[n_swing:], 0.0, atol=1e-12)


def test_back_at_the_command_the_next_swing_returns_the_foot_and_a_slower_body_steps_short():
    k, n_swing = 0.2, 80
    dx, _, _, _ = x_difference(k, [SPEED + 0.1] * (2 * n_swing) + [SPEED] * (2 * n_swing))
    assert dx[2 * n_swing - 1] > 0.019  # held through the first stance
    assert abs(dx[3 * n_swing - 1]) < 0.02 / n_swing + 1e-12  # the second swing brings it back to the line
    slow, _, _, _ = x_difference(k, [SPEED - 0.1] * (2 * n_swing))
    assert slow[-1] == pytest.approx(-0.02, rel=0.02)


def test_the_shift_is_bounded():
    dx, _, _, _ = x_difference(1.0, [SPEED + 1.0] * 160)  # asks for 1 m
    assert abs(dx).max() <= MAX_ATTITUDE_SHIFT + 1e-12
    assert dx[-1] == pytest.approx(MAX_ATTITUDE_SHIFT, rel=0.02)


def test_a_reset_forgets_the_held_shift():
    ctrl = controller(0.2)
    dt = ctrl.cfg.sim.controller_dt
    for k in range(160):
        ctrl.targets(T0 + k * dt, BodyFeedback(forward_speed=SPEED + 0.1))
    ctrl.reset()
    fresh = controller(0.2)
    body = BodyFeedback(forward_speed=SPEED)
    t = T0 + 0.25  # LF in stance: a held shift would show
    np.testing.assert_array_equal(ctrl.targets(t, body).foot_position, fresh.targets(t, body).foot_position)


def test_the_trot_walks_with_it_at_the_command():
    cfg = controller(0.2).cfg
    r = walk(cfg, duration=6.0)
    assert not r.fell
    assert abs(r.mean_speed - SPEED) <= 0.05 * SPEED, r.mean_speed
