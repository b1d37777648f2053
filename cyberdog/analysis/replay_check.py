"""Does an extracted path walk? The check extraction runs before it keeps a commanded path.

A policy walks in closed loop; its commanded path, averaged over the rollout's cycles and replayed open loop
through the IK + PID trot, need not (measured: of one battery-preset seed's 1.4 m/s rollouts, the mean path of
two of three lost the gait in replay and slowed to 0.9 m/s, while their cheapest single cycles walked at the
command). `replay_status` replays a path as the comparison does (the ideal robot, `REPLAY_CHECK_S`, the ±5 %
speed band over the last half) and says "ok" or why not; extraction then tries the next candidate (the other
cycle choice, another rollout) and records the rejected ones in the path's provenance. The check looks at
walking only (fall, speed), never at energy, so it cannot select for a saving.
"""
from __future__ import annotations

from cyberdog.analysis.walk import walk
from cyberdog.config import WalkConfig
from cyberdog.config.paper import PAPER_WALK_DURATION
from cyberdog.core.learned_set import LearnedPath

REPLAY_CHECK_S = PAPER_WALK_DURATION  # s: the comparison's walk (Table 5)


def replay_status(path: LearnedPath, speed: float, cfg: WalkConfig | None = None,
                  duration: float = REPLAY_CHECK_S) -> str:
    """"ok" if `path` replayed at `speed` (m/s) on the ideal robot for `duration` s neither falls nor leaves
    the ±5 % speed band; else "fell at T s" or "speed miss (V m/s)"."""
    walk_cfg, trajectory, offsets = path.walk_args(cfg or WalkConfig(), speed)
    r = walk(walk_cfg, duration, trajectory, foot_offsets=offsets)
    if r.fell:
        return f"fell at {r.duration:.2f} s"
    return "ok" if r.speed_ok else f"speed miss ({r.mean_speed:.3f} m/s)"


__all__ = ["REPLAY_CHECK_S", "replay_status"]
