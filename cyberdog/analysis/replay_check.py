"""Does an extracted path walk? The check extraction runs before it keeps a commanded path.

A policy walks in closed loop; its commanded path, averaged over the rollout's cycles and replayed open loop
through the IK + PID trot, need not (measured: of one battery-preset seed's 1.4 m/s rollouts, the mean path of
two of three lost the gait in replay and slowed to 0.9 m/s, while their cheapest single cycles walked at the
command). `replay_verdict` replays a path as the two tables walk it, and as far as the paper walked:

1. the ideal robot, as the comparison walks it (Table 5: `REPLAY_CHECK_S`, the ±5 % speed band), then over the
   paper's prototype distance (`CHECK_DISTANCE_M`, 100 m, with the prototype's time cap and speed band);
2. hardware-like robots over the same 100 m: `HARDWARE_LIKE` with the seeds `HARDWARE_CHECK_SEEDS`, so mass
   draws and sensor noise that the prototype's robots (seeds 0 .. draws − 1) never have, and with the joint PD
   at 1.0, 0.7 and 1.4 times its stiffness (`HARDWARE_CHECK_PD_SCALES`): the gains are the user's to set;
3. many hardware-like robots at the two ends of the stiffness, each over the prototype's walk (its run-up and
   20 m): `SPREAD_CHECK_SEEDS` at each of `SPREAD_CHECK_PD_SCALES`. A path can walk two gaits on the same
   stiff PD, its own and a slower, dearer one that some robots' sensor noise tips it into: which robots do is
   a matter of chance, so two robots at an end cannot tell a path that holds its gait on most robots from one
   that holds it on half.

Each part was needed (measured on the battery preset's 15 paths): checked for 10 s on the ideal robot alone, a
1.4 m/s path that fell on both prototype robots was kept; with 20 m walks on one, then three hardware-like
robots, one that fell after 14 s on both prototype robots (and on four of six robots drawn with seeds 0–5);
with 20 m walks on six, one that walks 20 m and falls within 100 m on both prototype robots; with parts 1 and 2
alone, a 1.4 m/s path that walks at 98 % of the command on both check robots with the PD 1.4× stiff and at
91–93 % (twice the battery per metre on two) on 3 of 10 test robots, one of them a prototype robot.

The quickest walks first, so that a failing candidate costs little: the ideal robot's 10 s, the spread walks
(stiffest first), then the 100 m walks. It says "ok" or which robot failed and why; extraction then tries the
next candidate (the other cycle choice, another rollout) and records the rejected ones in the path's
provenance. Whether a path passes depends on walking only (fall, speed). A path that passes also reports its
electrical energy per metre on the check's 100 m hardware-like walks (`ReplayCheck.electrical_J_per_m`):
extraction can keep the cheapest of several passing candidates by it (`evaluate.py extract --candidates N`).
All these robots are validation robots: the prototype run, which reports the saving, walks other draws (seeds
0 .. draws − 1).
"""
from __future__ import annotations

import dataclasses
import math
import time
from dataclasses import dataclass

from cyberdog.analysis.prototype import time_cap
from cyberdog.analysis.walk import walk
from cyberdog.config import HARDWARE_LIKE, HardwareConfig, WalkConfig
from cyberdog.config.paper import PAPER_DISTANCE_M, PAPER_WALK_DURATION, PROTOTYPE_DISTANCE_M, PROTOTYPE_RUN_UP_S
from cyberdog.core.learned_set import LearnedPath
from cyberdog.loop.result import LOOP_NOTE_PCT

REPLAY_CHECK_S = PAPER_WALK_DURATION  # s: the comparison's walk (Table 5)
HARDWARE_CHECK_SEEDS = tuple(range(1000, 1006))  # HardwareConfig.seed of the check's robots: far from the prototype's
# × the joint PD's stiffness of each check robot (PIDConfig.stiffness_scaled): a user sets the gains, so a path
# must walk 30 % softer and 40 % stiffer too, and is chosen by its cost over all six
HARDWARE_CHECK_PD_SCALES = (1.0, 0.7, 1.4, 1.0, 0.7, 1.4)
CHECK_DISTANCE_M = PAPER_DISTANCE_M  # m: the paper's prototype walk (evaluate.py --prototype-distance 100)
# part 3: eight robots (seeds of their own) at each end of the stiffness, over the prototype run's walk
SPREAD_CHECK_SEEDS = tuple(range(1100, 1108))
SPREAD_CHECK_PD_SCALES = (1.4, 0.7)
SPREAD_CHECK_DISTANCE_M = PROTOTYPE_DISTANCE_M  # m, after a run-up of PROTOTYPE_RUN_UP_S
HEARTBEAT_S = 10.0  # s of wall time between a long check walk's progress lines (QUIET_LIMIT_S: never 15 s quiet)


@dataclass(frozen=True)
class ReplayCheck:
    """The outcome of `replay_check`."""

    status: str  # "ok", or the first walk that failed and why ("ideal robot, 100 m: fell at 3.20 s")
    electrical_J_per_m: float | None = None  # J/m, mean over the hardware-like check walks (None unless "ok")
    dropped_shifts: int = 0  # leg-periods of the check's walks whose shifted foot target was out of reach


def replay_walk(path: LearnedPath, speed: float, cfg: WalkConfig | None = None, duration: float = REPLAY_CHECK_S,
                hardware: HardwareConfig | None = None, distance: float | None = None, progress=None,
                run_up: float = 0.0):
    """`path` replayed at `speed` (m/s) for `duration` s (or over `distance` m, `duration` then the time cap) on
    the ideal robot (or `hardware`): the walk's `WalkResult`. `progress`: `walk`'s per-second callback;
    `run_up`: s walked before the measured walk (`walk`'s)."""
    walk_cfg, trajectory, offsets = path.walk_args(cfg or WalkConfig(), speed)
    return walk(walk_cfg, duration, trajectory, foot_offsets=offsets, hardware=hardware, distance=distance,
                progress=progress, run_up=run_up)


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
    """"ok" for a walk that neither fell nor left the ±5 % speed band; else "fell at T s" or "speed miss (V m/s)",
    the miss adding how long the trot's speed loop sat at its bound where that is `LOOP_NOTE_PCT` % of the walk or
    more: the path asks more of the loop than its bound gives (a stride too long or too short for the command)."""
    if r.fell:
        return f"fell at {r.duration:.2f} s"
    if r.speed_ok:
        return "ok"
    at_bound = 100.0 * getattr(r, "speed_loop_at_limit", math.nan)
    loop = f"; speed loop at its bound {at_bound:.0f} % of the walk" if at_bound >= LOOP_NOTE_PCT else ""
    return f"speed miss ({r.mean_speed:.3f} m/s{loop})"


def replay_status(path: LearnedPath, speed: float, cfg: WalkConfig | None = None,
                  duration: float = REPLAY_CHECK_S, hardware: HardwareConfig | None = None,
                  distance: float | None = None) -> str:
    """`walk_status` of `replay_walk`."""
    return walk_status(replay_walk(path, speed, cfg, duration, hardware, distance))


@dataclass(frozen=True)
class CheckWalk:
    """One walk of the check: where, how far and at what stiffness (`check_walks`)."""

    name: str  # "hardware-like robot (seed 1100, PD 1.4x), 20 m"
    part: str  # "ideal", "spread" or "hardware": the module docstring's parts 1, 3 and 2
    duration: float  # s: the walk's length, or its time cap when it walks a distance
    hardware: HardwareConfig | None  # None: the ideal robot
    distance: float | None  # m, None: a timed walk
    pd_scale: float = 1.0  # × the joint PD's stiffness (PIDConfig.stiffness_scaled)
    run_up: float = 0.0  # s walked before the measured walk
    counted: bool = False  # in the energy per metre that ranks candidates (the 100 m hardware-like walks)

    def run(self, path: LearnedPath, speed: float, cfg: WalkConfig, progress=None):
        """This walk of `path` at `speed` (m/s) under `cfg`'s trot: its `WalkResult`."""
        walk_cfg = cfg if self.pd_scale == 1 else dataclasses.replace(cfg, pid=cfg.pid.stiffness_scaled(self.pd_scale))
        return replay_walk(path, speed, walk_cfg, self.duration, self.hardware, self.distance, progress=progress,
                           run_up=self.run_up)


def _robot(seed: int, pd: float) -> str:
    return f"hardware-like robot (seed {seed}{f', PD {pd:g}x' if pd != 1 else ''})"


def check_walks(speed: float, cfg: WalkConfig | None = None,
                hardware: HardwareConfig = HARDWARE_LIKE) -> list[CheckWalk]:
    """The check's walks at `speed` (m/s), in the order it walks them (the module docstring). `hardware`: the
    hardware-like robots' model, each robot with its seed + `hardware.seed` (HARDWARE_LIKE: the seeds above)."""
    cfg = cfg or WalkConfig()
    cap = time_cap(CHECK_DISTANCE_M, speed, cfg)
    spread_cap = time_cap(SPREAD_CHECK_DISTANCE_M, speed, cfg, PROTOTYPE_RUN_UP_S)

    def robot(seed: int) -> HardwareConfig:
        return dataclasses.replace(hardware, seed=hardware.seed + seed)

    walks = [CheckWalk("ideal robot, 10 s", "ideal", REPLAY_CHECK_S, None, None)]
    walks += [CheckWalk(f"{_robot(robot(seed).seed, pd)}, {SPREAD_CHECK_DISTANCE_M:g} m", "spread", spread_cap,
                        robot(seed), SPREAD_CHECK_DISTANCE_M, pd, PROTOTYPE_RUN_UP_S)
              for pd in SPREAD_CHECK_PD_SCALES for seed in SPREAD_CHECK_SEEDS]
    walks += [CheckWalk(f"ideal robot, {CHECK_DISTANCE_M:g} m", "ideal", cap, None, CHECK_DISTANCE_M)]
    walks += [CheckWalk(f"{_robot(robot(seed).seed, pd)}, {CHECK_DISTANCE_M:g} m", "hardware", cap,
                        robot(seed), CHECK_DISTANCE_M, pd, counted=True)
              for seed, pd in zip(HARDWARE_CHECK_SEEDS, HARDWARE_CHECK_PD_SCALES)]
    return walks


def check_settings() -> dict:
    """What the check walks, for a kept path's provenance: distances, robots' seeds and PD scales of each part."""
    return {"ideal_duration_s": REPLAY_CHECK_S, "distance_m": CHECK_DISTANCE_M,
            "hardware_like_seeds": list(HARDWARE_CHECK_SEEDS),
            "hardware_like_pd_scales": list(HARDWARE_CHECK_PD_SCALES),
            "spread_seeds": list(SPREAD_CHECK_SEEDS), "spread_pd_scales": list(SPREAD_CHECK_PD_SCALES),
            "spread_distance_m": SPREAD_CHECK_DISTANCE_M, "spread_run_up_s": PROTOTYPE_RUN_UP_S}


def walk_settings(cfg: WalkConfig) -> dict:
    """{dotted.setting: value} of the check's walk config where it differs from the defaults (`--set pid.kd=...`,
    a --config), for a kept path's provenance: the costs of two paths compare only where their checks walked the
    same robots. The trot (`controller`) is recorded apart, and the gait is each path's own."""
    from cyberdog.config.preset import changed_settings

    return {k: v for k, (v, _) in changed_settings(cfg, WalkConfig()).items()
            if not k.startswith(("controller.", "gait."))}


def replay_check(path: LearnedPath, speed: float, cfg: WalkConfig | None = None, log=None) -> ReplayCheck:
    """Every walk of `check_walks`, stopping at the first that fails: status "ok" and the mean electrical energy
    per metre of the 100 m hardware-like walks, or the first failure, prefixed with its walk ("ideal robot,
    100 m: fell at 3.20 s"). `log` (a callable) gets a line per walk: the walks are minutes on a loaded
    machine."""
    cfg = cfg or WalkConfig()
    per_metre, dropped = [], 0
    for w in check_walks(speed, cfg):
        r = w.run(path, speed, cfg, progress=None if log is None else heartbeat(log, w.name, w.distance))
        dropped += r.dropped_shifts
        status = walk_status(r)
        if log is not None:
            log(f"replay check, {w.name}: {status}")
        if status != "ok":
            return ReplayCheck(f"{w.name}: {status}", dropped_shifts=dropped)
        if w.counted:
            per_metre.append(r.electrical_energy / r.distance)
    return ReplayCheck("ok", sum(per_metre) / len(per_metre), dropped)


def replay_verdict(path: LearnedPath, speed: float, cfg: WalkConfig | None = None) -> str:
    """The status of `replay_check`: "ok" if `path` walks at `speed` (m/s) in every walk, else the first failure."""
    return replay_check(path, speed, cfg).status


__all__ = ["CHECK_DISTANCE_M", "HARDWARE_CHECK_PD_SCALES", "HARDWARE_CHECK_SEEDS", "HEARTBEAT_S", "REPLAY_CHECK_S",
           "SPREAD_CHECK_DISTANCE_M", "SPREAD_CHECK_PD_SCALES", "SPREAD_CHECK_SEEDS", "CheckWalk", "ReplayCheck",
           "check_settings", "check_walks", "heartbeat", "replay_check", "replay_status", "replay_verdict",
           "replay_walk", "walk_status"]
