#!/usr/bin/env python3
"""Why does a re-commanded battery path lose its saving at a doubled damping, and not at a doubled stiffness?

A learned path re-commanded for new gains (`cyberdog.analysis.pd_match_recording`) should, if the new PD gives
the old torque along the old motion, walk that motion again. For one shipped battery path at its speed this
script measures, on the ideal robot, how far the re-commanded walk's motion is from the default PD's (RMS over
the joints and the 160 phases of the cycle-mean joint angles, the first 3 s left out), with its Eq. (7) energy
per metre and how far its cycle-mean joint torque is from the default's around each foot's touchdown and over
the rest of the cycle, at kp 2×, kd 2× and kd 0.5× (one gain changed). Then, for `--gain`, it walks the path at the default
gains and re-commanded on robots with one hardware effect of `HARDWARE_LIKE` on at a time (the prototype's robot
draw 0: its mass draw and sensor streams), 12 s after a 3 s run-up: which effect moves the re-commanded gait?
With `--ilc N`, N rounds of a P-type iterative correction on the ideal robot follow (the command moved by
`--ilc-gain` × the motion error's harmonics up to `--ilc-harmonics`), and the corrected path walks the
hardware-like robot (draw 0): does keeping the motion on the model keep it on the robot?

    python notebook/tools/damping_study.py results/battery/paths/seed0_1.4mps.json --ilc 2
"""
from __future__ import annotations

import argparse
import dataclasses

import numpy as np

from cyberdog import config as C
from cyberdog.analysis.pd_match_recording import RECORD_S, SETTLE_S, pd_matched_foot_offsets
from cyberdog.analysis.walk import walk
from cyberdog.config import HARDWARE_LIKE, HardwareConfig
from cyberdog.core import kinematics as kin
from cyberdog.core.foot_offsets import FootOffsetPath
from cyberdog.core.gait import GaitScheduler
from cyberdog.core.learned_set import LearnedSet
from cyberdog.core.pd_match_solver import phase_means
from cyberdog.evaluation.recorded_trot import with_trot

H = HARDWARE_LIKE
TORQUE_BINS = 40  # phases of the cycle-mean torque (10 ms apart): a touchdown falls within one or two
EFFECTS = {  # one effect of HARDWARE_LIKE at a time, the prototype's draw 0 (its seed)
    "none (ideal)": None,
    "latency 2.5 ms": HardwareConfig(latency_s=H.latency_s, seed=H.seed),
    "joint friction": HardwareConfig(friction=True, seed=H.seed),
    "encoder noise": HardwareConfig(joint_angle_noise_std=H.joint_angle_noise_std,
                                    joint_velocity_noise_std=H.joint_velocity_noise_std, seed=H.seed),
    "Kalman speed": HardwareConfig(estimated_velocity=True, imu_noise=True, seed=H.seed),
    "mass draw (±5 %)": HardwareConfig(mass_uncertainty=H.mass_uncertainty, seed=H.seed),
    "all (HARDWARE_LIKE)": H,
}


def cycle_means(cfg, trajectory, table: FootOffsetPath, torque: bool = False):
    """(joint angles, commanded joint targets), each (4, n, 3) rad at the table's n phases, and the walk; with
    `torque`, also the joint torque (4, TORQUE_BINS, 3) N·m and each leg's ground contact share (4,
    TORQUE_BINS) at TORQUE_BINS phases."""
    result = walk(cfg, RECORD_S, trajectory, record=True, foot_offsets=table)
    tr = result.traces
    keep = tr["t"] >= SETTLE_S
    phases = GaitScheduler.from_config(cfg.gait).leg_phases(tr["t"][keep])
    steps = int(keep.sum())
    q = phase_means(phases, tr["q"][keep].reshape(steps, 4, 3), table.n)
    command = phase_means(phases, kin.inverse_kinematics(tr["foot_targets"][keep], cfg.robot), table.n)
    if not torque:
        return q, command, result
    tau = phase_means(phases, tr["tau"][keep].reshape(steps, 4, 3), TORQUE_BINS)
    contact = phase_means(phases, tr["contacts"][keep][:, :, None].astype(float), TORQUE_BINS)[:, :, 0]
    return q, command, result, tau, contact


def touchdown_split(difference: np.ndarray, contact: np.ndarray) -> tuple[float, float]:
    """N·m: the RMS of a cycle-mean torque difference (4, bins, 3) over each leg's touchdown (the bin where its
    contact share rises most, and the bins either side) and over the rest of the cycle."""
    at = np.zeros(difference.shape[:2], dtype=bool)
    for leg in range(4):
        k = int(np.argmax(np.roll(contact[leg], -1) - contact[leg])) + 1  # the first bin in contact
        at[leg, [(k - 1) % at.shape[1], k % at.shape[1], (k + 1) % at.shape[1]]] = True
    return float(np.sqrt(np.mean(difference[at] ** 2))), float(np.sqrt(np.mean(difference[~at] ** 2)))


def with_gain(cfg, gain: str, factor: float):
    pid = dataclasses.replace(cfg.pid, **{gain: tuple(factor * g for g in getattr(cfg.pid, gain))})
    return dataclasses.replace(cfg, pid=pid)


def corrected(table: FootOffsetPath, command, error, robot, gain: float, harmonics: int) -> FootOffsetPath:
    """The table with each leg's command moved by gain × the motion error's harmonics up to `harmonics`."""
    spectrum = np.fft.rfft(error, axis=1)
    spectrum[:, harmonics + 1:] = 0.0
    step = gain * np.fft.irfft(spectrum, n=table.n, axis=1)
    out = table.offsets.copy()
    for leg in range(4):
        side = np.full(table.n, kin.LEFT_RIGHT[leg])
        out[leg] += (kin.foot_position(command[leg] + step[leg], robot, side=side)
                     - kin.foot_position(command[leg], robot, side=side))
    return FootOffsetPath(out, table.period)


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("path", help="a commanded battery path file (results/battery/paths/seedN_<v>mps.json)")
    p.add_argument("--gain", choices=("kp", "kd"), default="kd", help="the gain of the hardware table (default kd)")
    p.add_argument("--factor", type=float, default=2.0, help="its factor over the default (default 2)")
    p.add_argument("--ilc", type=int, default=0, help="rounds of the iterative correction (default 0)")
    p.add_argument("--ilc-gain", type=float, default=0.5, help="its gain (default 0.5)")
    p.add_argument("--ilc-harmonics", type=int, default=4, help="the gait harmonics it moves (default 4)")
    args = p.parse_args()
    path = LearnedSet.load([args.path]).paths()[0]
    cfg, trajectory, offsets = path.walk_args(with_trot(C.WalkConfig(), path.recorded_controller), path.speed)
    q_ref, _, ref, tau_ref, contact = cycle_means(cfg, trajectory, offsets, torque=True)
    print(f"{path.label} at {path.speed:g} m/s, default PD, ideal robot: {ref.mean_speed:.3f} m/s, "
          f"{ref.energy_per_metre:.1f} J/m (Eq. 7)")
    for gain, factor in (("kp", 2.0), ("kd", 2.0), ("kd", 0.5)):
        new = with_gain(cfg, gain, factor)
        q, _, r, tau, _ = cycle_means(new, trajectory, pd_matched_foot_offsets(cfg, trajectory, offsets, new.pid),
                                      torque=True)
        rms = float(np.sqrt(np.mean((q - q_ref) ** 2))) * 1e3
        at, rest = touchdown_split(tau - tau_ref, contact)
        print(f"  {gain} {factor:g}x re-commanded, ideal robot: motion {rms:.1f} mrad RMS from the default's, "
              f"{r.mean_speed:.3f} m/s, {r.energy_per_metre:.1f} J/m; joint torque {at:.2f} N·m RMS from the "
              f"default's at touchdown, {rest:.2f} over the rest of the cycle", flush=True)
    new = with_gain(cfg, args.gain, args.factor)
    table = pd_matched_foot_offsets(cfg, trajectory, offsets, new.pid)
    print(f"one effect at a time, 12 s after a 3 s run-up: default PD | {args.gain} {args.factor:g}x re-commanded")
    for name, hw in EFFECTS.items():
        a = walk(cfg, 15.0, trajectory, foot_offsets=offsets, run_up=3.0, hardware=hw)
        b = walk(new, 15.0, trajectory, foot_offsets=table, run_up=3.0, hardware=hw)
        print(f"  {name:20s} {a.mean_speed:.3f} m/s {a.energy_per_metre:6.1f} J/m | {b.mean_speed:.3f} m/s "
              f"{b.energy_per_metre:6.1f} J/m ({100 * (b.energy_per_metre / a.energy_per_metre - 1):+.1f} %)",
              flush=True)
    for round_ in range(1, args.ilc + 1):
        q, command, _ = cycle_means(new, trajectory, table)
        table = corrected(table, command, q_ref - q, cfg.robot, args.ilc_gain, args.ilc_harmonics)
        q, _, r = cycle_means(new, trajectory, table)
        rms = float(np.sqrt(np.mean((q - q_ref) ** 2))) * 1e3
        print(f"correction round {round_}, ideal robot: motion {rms:.1f} mrad RMS, {r.mean_speed:.3f} m/s, "
              f"{r.energy_per_metre:.1f} J/m", flush=True)
    if args.ilc:
        b = walk(new, 15.0, trajectory, foot_offsets=table, run_up=3.0, hardware=H)
        print(f"corrected, HARDWARE_LIKE draw 0: {b.mean_speed:.3f} m/s, {b.energy_per_metre:.1f} J/m")


if __name__ == "__main__":
    main()
