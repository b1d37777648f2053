"""A path re-commanded for another joint PD (`cyberdog.core.pd_match_solver`,
`cyberdog.analysis.pd_match_recording`): along the same motion the new PD gives the old torque, and walked so
the robot executes the motion it executed under its own PD, where the plain command under a stiffer PD does
not."""
from __future__ import annotations

import math

import numpy as np
import pytest

from cyberdog import config as C
from cyberdog.analysis import prototype as proto
from cyberdog.analysis.pd_match_recording import SETTLE_S, pd_matched_foot_offsets
from cyberdog.analysis.walk import walk
from cyberdog.core.foot_offsets import FootOffsetPath
from cyberdog.core.gait import GaitScheduler
from cyberdog.core.pd_match_solver import pd_matched_command, pd_matched_offsets, phase_means

PERIOD = 0.4  # s
N = 64
PHASE = np.arange(N) / N
W = 2.0 * math.pi / PERIOD  # rad/s, the gait frequency


def _signals():
    """A periodic motion q and command c over one cycle (3 joints), with their exact time derivatives."""
    amp = np.array([0.3, 0.5, 0.7])
    x = 2.0 * math.pi * PHASE[:, None]
    q = amp * np.sin(x + np.array([0.0, 1.0, 2.0])) + 0.2 * np.cos(3 * x)
    dq = amp * W * np.cos(x + np.array([0.0, 1.0, 2.0])) - 0.6 * W * np.sin(3 * x)
    d = 0.05 * np.cos(x + 0.3) + 0.02 * np.sin(2 * x + np.array([0.1, 0.2, 0.3]))
    dd = -0.05 * W * np.sin(x + 0.3) + 0.04 * W * np.cos(2 * x + np.array([0.1, 0.2, 0.3]))
    return q, dq, q + d, dq + dd


def _derivative(x):
    """Periodic time derivative of samples over one cycle, from the discrete Fourier series."""
    k = np.fft.fftfreq(N, d=1.0 / N)
    return np.real(np.fft.ifft(np.fft.fft(x, axis=0) * (1j * W * k)[:, None], axis=0))


KP, KD = np.array([60.0, 50.0, 40.0]), np.array([2.0, 1.5, 3.0])


@pytest.mark.parametrize("scale", [0.7, 1.4, 2.0])
def test_the_scaled_pd_gives_the_old_torque_along_the_same_motion(scale):
    q, dq, c, dc = _signals()
    torque = KP * (c - q) + KD * (dc - dq)
    matched = pd_matched_command(q, c, PERIOD, KP, KD, scale * KP, math.sqrt(scale) * KD)
    torque_new = scale * KP * (matched - q) + math.sqrt(scale) * KD * (_derivative(matched) - dq)
    np.testing.assert_allclose(torque_new, torque, atol=1e-9)
    plain = scale * KP * (c - q) + math.sqrt(scale) * KD * (dc - dq)  # the command left as it was
    assert np.max(np.abs(plain - torque)) > 0.1  # N·m: what the re-solving corrects
    # stiffer: the command sits closer to the motion, by between 1/s and 1/√s
    gap, new_gap = np.sqrt(np.mean((c - q) ** 2)), np.sqrt(np.mean((matched - q) ** 2))
    assert min(1 / scale, 1 / math.sqrt(scale)) - 1e-9 <= new_gap / gap <= max(1 / scale, 1 / math.sqrt(scale)) + 1e-9


def test_without_velocity_feedforward_the_damping_acts_on_the_joint_speed_alone():
    q, dq, c, _ = _signals()
    scale = 1.4
    matched = pd_matched_command(q, c, PERIOD, KP, KD, scale * KP, math.sqrt(scale) * KD, velocity_feedforward=False)
    torque = KP * (c - q) - KD * dq
    np.testing.assert_allclose(scale * KP * (matched - q) - math.sqrt(scale) * KD * dq, torque, atol=1e-9)


def test_at_the_same_pd_the_command_is_unchanged():
    q, _, c, _ = _signals()
    np.testing.assert_allclose(pd_matched_command(q, c, PERIOD, KP, KD, KP, KD), c, atol=1e-12)
    with pytest.raises(ValueError, match="new kp"):
        pd_matched_command(q, c, PERIOD, KP, KD, 0.0, KD)
    with pytest.raises(ValueError, match="same shape"):
        pd_matched_command(q, c[:, :2], PERIOD, KP, KD, KP, KD)


def test_any_new_gains_give_the_old_torque_not_only_a_scaled_pd():
    q, dq, c, dc = _signals()
    new_kp, new_kd = np.array([90.0, 40.0, 70.0]), np.array([1.0, 2.5, 2.0])  # stiffer, softer, less damped
    matched = pd_matched_command(q, c, PERIOD, KP, KD, new_kp, new_kd)
    np.testing.assert_allclose(new_kp * (matched - q) + new_kd * (_derivative(matched) - dq),
                               KP * (c - q) + KD * (dc - dq), atol=1e-9)


def test_phase_means_average_each_legs_cycles_and_refuse_an_empty_phase():
    steps = 400
    t = np.arange(steps) * 0.0025
    phases = np.stack([(t / PERIOD + o) % 1.0 for o in (0.0, 0.5, 0.5, 0.0)], axis=1)
    values = np.stack([np.sin(2 * math.pi * phases), np.cos(2 * math.pi * phases)], axis=-1)  # (steps, 4, 2)
    means = phase_means(phases, values, 16)
    expected = np.stack([np.sin(2 * math.pi * np.arange(16) / 16), np.cos(2 * math.pi * np.arange(16) / 16)], -1)
    for leg in range(4):  # 10 steps per bin spread ±half a bin around its phase: the mean is close to the centre
        np.testing.assert_allclose(means[leg], expected, atol=0.03)
    with pytest.raises(ValueError, match="no recorded step"):
        phase_means(phases[:20], values[:20], 16)


def test_an_integral_term_is_refused():
    offsets = FootOffsetPath(np.zeros((4, 8, 3)), PERIOD)
    with pytest.raises(ValueError, match="ki = 0"):
        pd_matched_offsets(np.zeros((8, 4)), np.zeros((8, 12)), np.zeros((8, 4, 3)), offsets,
                           C.PIDConfig(ki=(1.0, 0.0, 0.0)), C.PIDConfig(), C.RobotConfig())


def _mean_motion(result, cfg, n=50):
    """(4, n, 3) rad: the walk's joint angles averaged over its cycles after the run-up."""
    tr = result.traces
    keep = tr["t"] >= SETTLE_S
    phases = GaitScheduler.from_config(cfg.gait).leg_phases(tr["t"][keep])
    return phase_means(phases, tr["q"][keep].reshape(-1, 4, 3), n)


def test_walked_re_commanded_under_a_stiffer_pd_the_robot_executes_its_old_motion():
    """The cycloid at 1 m/s on the ideal robot: under the PD 1.4x stiffer its re-solved command executes the
    joint motion it executes under its own PD, several times closer than the plain command does."""
    cfg = C.WalkConfig()
    cfg = C.replace(cfg, gait=C.replace(cfg.gait, speed=1.0))
    own = _mean_motion(walk(cfg, 6.0, record=True), cfg)
    stiff = C.replace(cfg, pid=cfg.pid.stiffness_scaled(1.4))
    offsets = pd_matched_foot_offsets(cfg, None, None, stiff.pid)
    assert offsets.n == 100 and np.max(np.abs(offsets.offsets)) > 1e-3  # m: the command moved
    plain = _mean_motion(walk(stiff, 6.0, record=True), cfg)
    matched = _mean_motion(walk(stiff, 6.0, record=True, foot_offsets=offsets), cfg)
    plain_gap, matched_gap = np.sqrt(np.mean((plain - own) ** 2)), np.sqrt(np.mean((matched - own) ** 2))
    assert matched_gap < 0.3 * plain_gap, (matched_gap, plain_gap)
    assert pd_matched_foot_offsets(cfg, None, None, cfg.pid) is None  # the path's own PD: nothing to re-solve


def test_a_pd_matched_prototype_run_re_commands_every_trajectory_and_says_so(monkeypatch):
    """The motion is recorded under the path's own PD (kp 60) and the walk is made under the scaled one (84)."""
    from cyberdog.analysis import pd_match_recording
    from cyberdog.core import pid as pid_module
    built = []
    original = pid_module.JointPID.__init__

    def recording(self, kp, *args, **kwargs):
        original(self, kp, *args, **kwargs)
        built.append(float(self.kp[0]))
    monkeypatch.setattr(pid_module.JointPID, "__init__", recording)
    monkeypatch.setattr(pd_match_recording, "_cache", {})
    rows = proto.run_prototype({"cycloid": None}, speeds=(1.0,), distance_m=0.3, modes=("ideal",), run_up_s=0.0,
                               workers=1, log=lambda *_: None, pd_scale=1.4, pd_matched=True)
    assert [r["pd_matched"] for r in rows] == [True] and rows[0]["pd_scale"] == 1.4
    assert built[0] == pytest.approx(60.0) and built[-1] == pytest.approx(84.0)  # recorded, then walked
    rows = proto.run_prototype({"cycloid": None}, speeds=(1.0,), distance_m=0.3, modes=("ideal",), run_up_s=0.0,
                               workers=1, log=lambda *_: None, pd_scale=1.0, pd_matched=True)
    assert [r["pd_matched"] for r in rows] == [False]  # at its own PD a path walks as it is
