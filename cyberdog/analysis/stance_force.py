"""A learned foot path written as what it does: the motion its feet make and the force its stance legs exert.

A foot-mode policy saves energy by where it commands the feet, but the feet do not get there: the battery recipes'
paths hold their stance feet 22–27 mm from their targets (their own start: 8–10 mm), and the joint PD turns that
error into a force. That force is the saving: commanding the path the feet actually take (the mean realised path)
leaves none of it, and since kp and kd scale what a position error makes, the gains a user sets change the gait
(docs/results.md, "Why the gains cost it"). `stance_force_path` writes the same gait as motion plus force:

- offsets: the feet's mean realised path per leg and phase, the commanded path plus the mean of the foot's error
  (forward kinematics of the joint angles less the target, leg frame) over the walk's cycles;
- feedforward: the mean torque the joint PD exerted per leg, joint and phase in stance (the applied motor torque
  less the command's own feedforward), zero in swing; the trot adds it to its feedforward
  (`cyberdog.core.foot_offsets.FootOffsetPath.feedforward`);

each table kept to its first `harmonics` Fourier harmonics over the phase (the cycle means of a short walk are
noisy, and a sharp corner in the motion is what stiffer damping makes costly). The PD then corrects departures
from that motion only, and the force is the same under any gains. The form is one gait with the path only where
it walks at the path's speed: the mean stance torque carries no correction of the cycle-to-cycle speed, and where
the trot's speed loop sits at its bound (1.4 m/s) the form walks up to 2–3 % slower. So its fore-aft motion is
stretched about its cycle mean until it walks, on the same robot, at the speed the path walked
(`match_speed`: a body on stance feet that do not slip moves as far as they sweep, so the speed goes with the
stretch). The path and its form are walked under the trot the path was recorded with, on the extraction's first
hardware-like check robot (`HARDWARE_CHECK_SEEDS`: never the prototype's test robots).
"""
from __future__ import annotations

import dataclasses

import numpy as np

from cyberdog.analysis.replay_check import HARDWARE_CHECK_SEEDS
from cyberdog.analysis.walk import walk
from cyberdog.config import HARDWARE_LIKE, HardwareConfig, WalkConfig
from cyberdog.core import kinematics as kin
from cyberdog.core.commanded_path import CommandedPath
from cyberdog.core.foot_offsets import FootOffsetPath
from cyberdog.core.gait import GaitScheduler

PHASES = 64  # samples per cycle of the written path
HARMONICS = 6  # Fourier harmonics of the phase kept in each table
RECORD_S = 10.0  # s, the walk whose cycles are averaged (after its run-up)
RUN_UP_S = 3.0  # s, walked first and left out: the start from a stand and the blend into the path
SPEED_TOLERANCE = 0.005  # the form's speed within this share of the path's own: matched
SPEED_WALKS = 3  # walks of the form at most while matching its speed
STRETCH_BOUND = 0.10  # the sweep stretched by at most this share either way (the trot's speed loop's own bound)


def check_robot(model: HardwareConfig = HARDWARE_LIKE) -> HardwareConfig:
    """The robot the path is walked on: `model` as the extraction's first check robot (its seed offset by the
    model's own, as `evaluate.py check` offsets its robots)."""
    return dataclasses.replace(model, seed=model.seed + HARDWARE_CHECK_SEEDS[0])


def phase_table(values: np.ndarray, phases: np.ndarray, n: int = PHASES) -> np.ndarray:
    """(4, n, 3): the mean of `values` (steps, 4, 3) per leg over the steps whose leg phase (`phases`, (steps, 4))
    is nearest k / n; ValueError where a phase has no step (a walk too short for the table)."""
    values, phases = np.asarray(values, dtype=float), np.mod(np.asarray(phases, dtype=float), 1.0)
    if values.ndim != 3 or values.shape[1:] != (4, 3) or phases.shape != values.shape[:2]:
        raise ValueError(f"values must be (steps, 4, 3) and phases (steps, 4), got {values.shape}, {phases.shape}")
    bins = np.rint(phases * n).astype(int) % n
    table = np.empty((4, n, 3))
    for leg in range(4):
        counts = np.bincount(bins[:, leg], minlength=n)
        if counts.min() == 0:
            raise ValueError(f"no step at leg {leg}'s phase {int(np.argmin(counts))}/{n}: walk longer")
        for axis in range(3):
            table[leg, :, axis] = np.bincount(bins[:, leg], values[:, leg, axis], minlength=n) / counts
    return table


def keep_harmonics(table: np.ndarray, harmonics: int) -> np.ndarray:
    """`table` (4, n, 3), periodic over its phase axis, with only its mean and first `harmonics` harmonics."""
    n = table.shape[1]
    if not (isinstance(harmonics, int) and 1 <= harmonics < n // 2):
        raise ValueError(f"harmonics must be an integer in [1, {n // 2 - 1}], got {harmonics!r}")
    spectrum = np.fft.rfft(table, axis=1)
    spectrum[:, harmonics + 1:] = 0.0
    return np.fft.irfft(spectrum, n=n, axis=1)


def stretch_sweep(offsets: np.ndarray, realised: np.ndarray, stretch: float) -> np.ndarray:
    """`offsets` (4, n, 3) shifted so that the fore-aft motion they make, `realised` (4, n, 3, the feet's position
    in the leg frame), becomes `stretch` times as long about each leg's cycle mean; y and z unchanged."""
    if not (np.isfinite(stretch) and stretch > 0):
        raise ValueError(f"stretch must be > 0 and finite, got {stretch!r}")
    out = np.array(offsets, dtype=float)
    x = np.asarray(realised, dtype=float)[..., 0]
    out[..., 0] += (stretch - 1.0) * (x - x.mean(axis=1, keepdims=True))
    return out


def match_speed(make, speed: float, walk_speed) -> tuple[float, list[dict]]:
    """The stretch of the form's sweep (`make(stretch)` -> FootOffsetPath) whose walk (`walk_speed(offsets)` -> m/s)
    comes nearest `speed`: walked at 1, then stretched in proportion to the speed missed, at most `SPEED_WALKS`
    walks, stopping within `SPEED_TOLERANCE`, the stretch kept within 1 ± `STRETCH_BOUND`. Returns it and every
    walk's (stretch, speed)."""
    stretch, walks = 1.0, []
    for _ in range(SPEED_WALKS):
        v = float(walk_speed(make(stretch)))
        walks.append({"stretch": stretch, "speed_mps": v})
        if abs(v / speed - 1.0) <= SPEED_TOLERANCE or v <= 0:
            break
        stretch = float(np.clip(stretch * speed / v, 1.0 - STRETCH_BOUND, 1.0 + STRETCH_BOUND))
    best = min(walks, key=lambda w: abs(w["speed_mps"] - speed))
    return best["stretch"], walks


def stance_force_path(path: CommandedPath, cfg: WalkConfig, hardware: HardwareConfig | None = check_robot(),
                      harmonics: int = HARMONICS, duration: float = RECORD_S,
                      run_up: float = RUN_UP_S) -> tuple[CommandedPath, dict]:
    """The path as motion + stance force (the module docstring), and a record of how it was made; `cfg` is the walk
    with the path's own trot and PD. Raises RuntimeError if the walk falls."""
    if path.offsets.feedforward is not None:
        raise ValueError("the path already carries a joint torque: write the force of a path of offsets alone")
    cfg = dataclasses.replace(cfg, gait=path.gait)
    result = walk(cfg, duration + run_up, None, foot_offsets=path.offsets, hardware=hardware, record=True,
                  run_up=run_up)
    if result.fell:
        raise RuntimeError(f"the path fell in its recording walk at {path.speed:g} m/s: no force to write")
    traces = result.traces
    settled = traces["t"] >= run_up
    q = traces["q"][settled].reshape(-1, 4, 3)
    foot = kin.foot_position(q, cfg.robot, np.broadcast_to(kin.LEFT_RIGHT, q.shape[:-1]))  # m, leg frame
    error = foot - traces["foot_targets"][settled]  # where the foot is less where it was sent
    pd_torque = (traces["tau"] - traces["feedforward"])[settled].reshape(-1, 4, 3)  # N·m, what the PD exerted
    phases = GaitScheduler.from_config(cfg.gait).leg_phases(traces["t"][settled])
    grid = np.arange(PHASES) / PHASES
    commanded = np.stack([path.offsets.sample(leg, grid) for leg in range(4)])
    motion = commanded + phase_table(error, phases)
    realised = phase_table(foot, phases)
    force = keep_harmonics(phase_table(pd_torque, phases), harmonics)
    force[:, grid < cfg.gait.swing_time / cfg.gait.period] = 0.0  # the swing's own PD stays as it was

    def make(stretch: float) -> FootOffsetPath:
        return FootOffsetPath(keep_harmonics(stretch_sweep(motion, realised, stretch), harmonics),
                              path.offsets.period, force)

    def walk_speed(offsets: FootOffsetPath) -> float:
        form = walk(cfg, duration + run_up, None, foot_offsets=offsets, hardware=hardware, run_up=run_up)
        if form.fell:
            raise RuntimeError(f"the path as motion + force fell at {path.speed:g} m/s while matching its speed")
        return form.mean_speed

    stretch, speed_walks = match_speed(make, result.mean_speed, walk_speed)
    stance = traces["contacts"][settled]
    record = {"robot": "ideal" if hardware is None else f"hardware-like, seed {hardware.seed}",
              "walked_s": duration, "run_up_s": run_up, "harmonics": harmonics, "phases": PHASES,
              "pid": {"kp": list(cfg.pid.kp), "kd": list(cfg.pid.kd)},
              "stance_error_rms_mm": round(1e3 * float(np.sqrt(np.mean(np.sum(error[stance] ** 2, axis=-1)))), 2),
              "mean_feedforward_Nm": np.round(np.abs(force).mean(axis=(0, 1)), 3).tolist(),
              "path_speed_mps": round(float(result.mean_speed), 4), "sweep_stretch": round(stretch, 5),
              "speed_walks": [{k: round(v, 5) for k, v in w.items()} for w in speed_walks]}
    written = CommandedPath(path.speed, path.gait, make(stretch),
                            {**path.provenance, "stance_force": record})
    return written, record


__all__ = ["HARMONICS", "PHASES", "SPEED_TOLERANCE", "SPEED_WALKS", "STRETCH_BOUND", "check_robot", "keep_harmonics",
           "match_speed", "phase_table", "stance_force_path", "stretch_sweep"]
