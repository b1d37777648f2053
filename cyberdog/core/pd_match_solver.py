"""A foot path re-commanded for another joint PD: the same executed motion, the same joint torques. Pure numpy.

A path is walked by commanding joint targets c(t) (IK of the foot targets) to the motor drivers' PD,

    τ = kp·(c − q) + kd·(ċ − q̇)         (velocity feedforward on: ċ from the path's foot velocity, J⁻¹ v)
    τ = kp·(c − q) − kd·q̇               (off: the speed target is zero)

plus the same feedforward torques (gravity compensation) whatever the gains. What the robot *does* is the
executed motion q(t); the gap d = c − q between command and motion is what a soft PD needs to produce the torque
the gait takes. With other gains (kp', kd'), e.g. the PD s times as stiff (kp × s, kd × √s:
`PIDConfig.stiffness_scaled`), the same command is followed more or less closely, the torques change and the
gait is another one: a learned path found under one PD can then lose its saving (docs/results.md).
Here the command is re-solved so that the new PD gives, along the same periodic motion q(φ), the torque the old
one gave:

    kp'·d' + kd'·ḋ' = kp·d + kd·ḋ        (feedforward on; per harmonic k of the gait frequency, ω_k = 2πk / T:
                                          D'_k = D_k·(kp + iω_k·kd) / (kp' + iω_k·kd'))
    kp'·d' − kd'·q̇  = kp·d − kd·q̇        (off: d' = (kp·d + (kd' − kd)·q̇) / kp')

and c' = q + d'. If the new PD gets the same torque on the same motion, that motion is again a solution of the
robot's dynamics: the gait is the same one, and so is its energy. What is matched is the cycle's mean motion;
the trot's feedback (speed loop, foot placement) still acts on top, and an integral term (ki ≠ 0) holds a
state that is not a function of the phase, so it is refused.

`phase_means` averages a recorded walk over its gait cycles, `pd_matched_command` solves the equations above,
and `pd_matched_offsets` turns the change of command back into a shift of each foot target (forward kinematics,
Eq. 1-2) added to a path's `FootOffsetPath`. Recording the walk is the analysis layer's
(`cyberdog.analysis.pd_match_recording`).
"""
from __future__ import annotations

import math

import numpy as np

from cyberdog.config import PIDConfig, RobotConfig
from cyberdog.core import kinematics as kin
from cyberdog.core.foot_offsets import FootOffsetPath


def _spectral_derivative(x: np.ndarray, period: float) -> np.ndarray:
    """d/dt of a periodic signal sampled at n equal phases over `period` s (axis 0)."""
    n = x.shape[0]
    spectrum = np.fft.rfft(x, axis=0)
    omega = 2.0 * np.pi * np.arange(spectrum.shape[0]) / period
    if n % 2 == 0:
        omega[-1] = 0.0  # the Nyquist harmonic has no defined slope on n samples
    return np.fft.irfft(spectrum * (1j * omega)[:, None], n=n, axis=0)


def pd_matched_command(q: np.ndarray, command: np.ndarray, period: float, kp, kd, new_kp, new_kd,
                       velocity_feedforward: bool = True) -> np.ndarray:
    """Joint targets c' (n, j), rad, that give with the PD (new_kp, new_kd) the torque the PD (kp, kd) gives with
    the targets `command` along the periodic motion `q`.

    q, command: (n, j) rad, the executed joint angles and the commanded targets at n equal phases of one gait
        cycle of `period` s (n ≥ 4).
    kp, kd, new_kp, new_kd: N·m/rad and N·m·s/rad, each a scalar or one per joint (j,); kp and new_kp > 0.
    velocity_feedforward: the drivers get the target's speed (ċ) as well; False: a zero speed target.
    """
    q = np.asarray(q, dtype=float)
    command = np.asarray(command, dtype=float)
    if q.ndim != 2 or q.shape != command.shape or q.shape[0] < 4:
        raise ValueError(f"q and command must have the same shape (n >= 4, joints), got {q.shape} and "
                         f"{command.shape}")
    if not (np.all(np.isfinite(q)) and np.all(np.isfinite(command))):
        raise ValueError("q and command must be finite")
    if not (math.isfinite(period) and period > 0):
        raise ValueError(f"period must be > 0 s and finite, got {period!r}")
    kp, kd, new_kp, new_kd = (np.broadcast_to(np.asarray(g, dtype=float), q.shape[1:])
                              for g in (kp, kd, new_kp, new_kd))
    for name, g, low in (("kp", kp, 0), ("new kp", new_kp, 0), ("kd", kd, None), ("new kd", new_kd, None)):
        if not np.all(np.isfinite(g)) or (np.any(g <= 0) if low == 0 else np.any(g < 0)):
            raise ValueError(f"{name} must be finite and {'> 0' if low == 0 else '>= 0'}, got {g.tolist()}")
    error = command - q
    if not velocity_feedforward:
        dq = _spectral_derivative(q, period)
        return q + (kp * error + (new_kd - kd) * dq) / new_kp
    spectrum = np.fft.rfft(error, axis=0)
    omega = (2.0 * np.pi * np.arange(spectrum.shape[0]) / period)[:, None]
    gain = (kp + 1j * omega * kd) / (new_kp + 1j * omega * new_kd)
    return q + np.fft.irfft(spectrum * gain, n=q.shape[0], axis=0)


def phase_means(phases: np.ndarray, values: np.ndarray, n: int) -> np.ndarray:
    """(4, n, k): per leg, the mean of `values` (steps, 4, k) over the steps whose phase (steps, 4) is nearest
    to each of n equal phases i / n. Every bin must hold a step (record more cycles or use fewer phases)."""
    phases = np.asarray(phases, dtype=float)
    values = np.asarray(values, dtype=float)
    if phases.ndim != 2 or phases.shape[1] != 4 or values.shape[:2] != phases.shape or values.ndim != 3:
        raise ValueError(f"phases must be (steps, 4) and values (steps, 4, k), got {phases.shape} and "
                         f"{values.shape}")
    bins = np.rint(phases * n).astype(int) % n
    out = np.empty((4, n, values.shape[2]))
    for leg in range(4):
        counts = np.bincount(bins[:, leg], minlength=n)
        if np.any(counts == 0):
            raise ValueError(f"leg {leg}: {int(np.sum(counts == 0))} of {n} phases hold no recorded step; record "
                             "a longer walk")
        for axis in range(values.shape[2]):
            out[leg, :, axis] = np.bincount(bins[:, leg], weights=values[:, leg, axis], minlength=n) / counts
    return out


def pd_matched_offsets(phases: np.ndarray, q: np.ndarray, foot_targets: np.ndarray, offsets: FootOffsetPath,
                       pid: PIDConfig, new_pid: PIDConfig, robot: RobotConfig, velocity_feedforward: bool = True
                       ) -> FootOffsetPath:
    """`offsets` plus the shift of each foot target that re-commands a recorded walk under `pid` for `new_pid`
    (`pd_matched_command` at each of the offset table's phases).

    phases: (steps, 4) each leg's gait phase; q: (steps, 12) rad, the joint angles the drivers read;
    foot_targets: (steps, 4, 3) m, the foot targets commanded at those steps (leg frame), from a walk under
    `pid` itself with `offsets` applied. The walk's cycles are averaged (`phase_means`).
    """
    for which, gains in (("", pid), ("new ", new_pid)):
        if any(g != 0 for g in gains.ki):
            raise ValueError(f"a PD-matched command needs ki = 0 (the integral holds a state that is not a function "
                             f"of the gait phase), got the {which}PID's ki = {gains.ki}")
    q = np.asarray(q, dtype=float)
    foot_targets = np.asarray(foot_targets, dtype=float)
    steps = q.shape[0]
    if q.shape != (steps, 12) or foot_targets.shape != (steps, 4, 3):
        raise ValueError(f"q must be (steps, 12) and foot_targets (steps, 4, 3), got {q.shape} and "
                         f"{foot_targets.shape}")
    command = kin.inverse_kinematics(foot_targets, robot)  # (steps, 4, 3), the trot's IK, legs LF, RF, LH, RH
    n = offsets.n
    q_mean = phase_means(phases, q.reshape(steps, 4, 3), n)
    c_mean = phase_means(phases, command, n)
    table = offsets.offsets.copy()
    for leg in range(4):  # the gains are per joint type (abad, hip, knee), the same on every leg
        matched = pd_matched_command(q_mean[leg], c_mean[leg], offsets.period, pid.kp, pid.kd, new_pid.kp,
                                     new_pid.kd, velocity_feedforward)
        side = np.full(n, kin.LEFT_RIGHT[leg])
        table[leg] += kin.foot_position(matched, robot, side=side) - kin.foot_position(c_mean[leg], robot, side=side)
    return FootOffsetPath(table, offsets.period, offsets.feedforward)  # a carried torque is the same under any gains


__all__ = ["pd_matched_command", "pd_matched_offsets", "phase_means"]
