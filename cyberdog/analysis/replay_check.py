"""Does an extracted path walk? The check extraction runs before it keeps a commanded path.

A policy walks in closed loop; its commanded path, averaged over the rollout's cycles and replayed open loop
through the IK + PID trot, need not (measured: of one battery-preset seed's 1.4 m/s rollouts, the mean path of
two of three lost the gait in replay and slowed to 0.9 m/s, while their cheapest single cycles walked at the
command). `replay_verdict` replays a path as the two tables walk it, and as far as the paper walked:

1. the ideal robot, as the comparison walks it (Table 5: `REPLAY_CHECK_S`, the ±5 % speed band), then over the
   paper's prototype distance (`CHECK_DISTANCE_M`, 100 m, with the prototype's time cap and speed band);
2. hardware-like robots over the same 100 m: `HARDWARE_LIKE` with the seeds `HARDWARE_CHECK_SEEDS`, so mass
   draws and sensor noise that the prototype's robots (seeds 0 .. draws − 1) never have, and with the joint PD
   at 1.0, 0.7 and 1.4 times its stiffness (`HARDWARE_CHECK_PD_SCALES`): the gains are the user's to set.

Each part was needed (measured on the battery preset's 15 paths): checked for 10 s on the ideal robot alone, a
1.4 m/s path that fell on both prototype robots was kept; with 20 m walks on one, then three hardware-like
robots, one that fell after 14 s on both prototype robots (and on four of six robots drawn with seeds 0–5);
with 20 m walks on six, one that walks 20 m and falls within 100 m on both prototype robots.

It says "ok" or which robot failed and why; extraction then tries the next candidate (the other cycle choice,
another rollout) and records the rejected ones in the path's provenance. Whether a path passes depends on
walking only (fall, speed). A path that passes also reports its electrical energy per metre on the check's
hardware-like robots (`ReplayCheck.electrical_J_per_m`): extraction can keep the cheapest of several passing
candidates by it (`evaluate.py extract --candidates N`). Those robots are validation robots: the prototype
run, which reports the saving, walks other draws (seeds 0 .. draws − 1).
"""
from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass

from cyberdog.analysis.prototype import time_cap
from cyberdog.analysis.walk import walk
from cyberdog.config import HARDWARE_LIKE, HardwareConfig, WalkConfig
from cyberdog.config.paper import PAPER_DISTANCE_M, PAPER_WALK_DURATION
from cyberdog.core.learned_set import LearnedPath

REPLAY_CHECK_S = PAPER_WALK_DURATION  # s: the comparison's walk (Table 5)
HARDWARE_CHECK_SEEDS = tuple(range(1000, 1006))  # HardwareConfig.seed of the check's robots: far from the prototype's
# × the joint PD's stiffness of each check robot (PIDConfig.stiffness_scaled): a user sets the gains, so a path
# must walk 30 % softer and 40 % stiffer too, and is chosen by its cost over all six
HARDWARE_CHECK_PD_SCALES = (1.0, 0.7, 1.4, 1.0, 0.7, 1.4)
CHECK_DISTANCE_M = PAPER_DISTANCE_M  # m: the paper's prototype walk (evaluate.py --prototype-distance 100)
HEARTBEAT_S = 10.0  # s of wall time between a long check walk's progress lines (QUIET_LIMIT_S: never 15 s quiet)


@dataclass(frozen=True)
class ReplayCheck:
    """The outcome of `replay_check`."""

    status: str  # "ok", or the first walk that failed and why ("ideal robot, 100 m: fell at 3.20 s")
    electrical_J_per_m: float | None = None  # J/m, mean over the hardware-like check walks (None unless "ok")
    dropped_shifts: int = 0  # leg-periods of the check's walks whose shifted foot target was out of reach


def replay_walk(path: LearnedPath, speed: float, cfg: WalkConfig | None = None, duration: float = REPLAY_CHECK_S,
                hardware: HardwareConfig | None = None, distance: float | None = None, progress=None):
    """`path` replayed at `speed` (m/s) for `duration` s (or over `distance` m, `duration` then the time cap) on
    the ideal robot (or `hardware`): the walk's `WalkResult`. `progress`: `walk`'s per-second callback."""
    walk_cfg, trajectory, offsets = path.walk_args(cfg or WalkConfig(), speed)
    return walk(walk_cfg, duration, trajectory, foot_offsets=offsets, hardware=hardware, distance=distance,
                progress=progress)


def heartbeat(log, name: str, distance: float | None, every_s: float = HEARTBEAT_S):
    """A `walk` progress callback that logs "<name>: 41 m of 100 (42 s walked)" when `every_s` s of wall time
    have passed since the walk began or since its last line (a 100 m check is 20 s or more under load)."""
    last = [time.monotonic()]

    def progress(t: float, x: float) -> None:
        now = time.monotonic()
        if now - last[0] >= every_s:
            last[0] = now
            so_far = f"{x:.0f} m of {distance:g}" if distance is not None else f"{x:.0f} m"
            log(f"replay check, {name}: {so_far} ({t:.0f} s walked)")
    return progress


def walk_status(r) -> str:
    """"ok" for a walk that neither fell nor left the ±5 % speed band; else "fell at T s" or "speed miss (V m/s)"."""
    if r.fell:
        return f"fell at {r.duration:.2f} s"
    return "ok" if r.speed_ok else f"speed miss ({r.mean_speed:.3f} m/s)"


def replay_status(path: LearnedPath, speed: float, cfg: WalkConfig | None = None,
                  duration: float = REPLAY_CHECK_S, hardware: HardwareConfig | None = None,
                  distance: float | None = None) -> str:
    """`walk_status` of `replay_walk`."""
    return walk_status(replay_walk(path, speed, cfg, duration, hardware, distance))


def replay_check(path: LearnedPath, speed: float, cfg: WalkConfig | None = None, log=None) -> ReplayCheck:
    """Every walk of the module docstring (the quickest first), stopping at the first that fails: status "ok"
    and the mean electrical energy per metre of the hardware-like walks, or the first failure, prefixed with
    its walk ("ideal robot, 100 m: fell at 3.20 s"). `log` (a callable) gets a line per walk: eight walks of
    up to 100 m are minutes on a loaded machine."""
    cfg = cfg or WalkConfig()
    cap = time_cap(CHECK_DISTANCE_M, speed, cfg)
    walks = [("ideal robot, 10 s", REPLAY_CHECK_S, None, None, 1.0),
             (f"ideal robot, {CHECK_DISTANCE_M:g} m", cap, None, CHECK_DISTANCE_M, 1.0)]
    walks += [(f"hardware-like robot (seed {seed}{f', PD {pd:g}x' if pd != 1 else ''}), {CHECK_DISTANCE_M:g} m",
               cap, dataclasses.replace(HARDWARE_LIKE, seed=seed), CHECK_DISTANCE_M, pd)
              for seed, pd in zip(HARDWARE_CHECK_SEEDS, HARDWARE_CHECK_PD_SCALES)]
    per_metre, dropped = [], 0
    for name, duration, hardware, distance, pd in walks:
        walk_cfg = cfg if pd == 1 else dataclasses.replace(cfg, pid=cfg.pid.stiffness_scaled(pd))
        r = replay_walk(path, speed, walk_cfg, duration, hardware, distance,
                        progress=None if log is None else heartbeat(log, name, distance))
        dropped += r.dropped_shifts
        status = walk_status(r)
        if log is not None:
            log(f"replay check, {name}: {status}")
        if status != "ok":
            return ReplayCheck(f"{name}: {status}", dropped_shifts=dropped)
        if hardware is not None:
            per_metre.append(r.electrical_energy / r.distance)
    return ReplayCheck("ok", sum(per_metre) / len(per_metre), dropped)


def replay_verdict(path: LearnedPath, speed: float, cfg: WalkConfig | None = None) -> str:
    """The status of `replay_check`: "ok" if `path` walks at `speed` (m/s) in every walk, else the first failure."""
    return replay_check(path, speed, cfg).status


__all__ = ["CHECK_DISTANCE_M", "HARDWARE_CHECK_PD_SCALES", "HARDWARE_CHECK_SEEDS", "HEARTBEAT_S", "REPLAY_CHECK_S",
           "ReplayCheck", "heartbeat", "replay_check", "replay_status", "replay_verdict", "replay_walk", "walk_status"]
