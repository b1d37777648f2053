"""The common-trajectory walks (paper Section 2.3 and 4.1): each baseline trajectory at each speed."""
from __future__ import annotations

import dataclasses
import time

from cyberdog.config import WalkConfig
from cyberdog.config.paper import PAPER_SPEEDS, PAPER_WALK_DURATION
from cyberdog.analysis.walk import walk

BASELINES = ("cycloid", "straight")  # the paper's composite cycloid ("pendulum") and straight line


def baseline_rows(cfg: WalkConfig, speeds=PAPER_SPEEDS, trajectories=BASELINES, duration: float = PAPER_WALK_DURATION,
                  log=print) -> list[dict]:
    """Walk `duration` s with each trajectory at each speed; one summary row per walk."""
    rows = []
    for name in trajectories:
        for v in speeds:
            gait = dataclasses.replace(cfg.gait, trajectory=name, speed=float(v))
            t0 = time.perf_counter()
            result = walk(dataclasses.replace(cfg, gait=gait), duration)
            label = name if name != "straight" else f"straight ({gait.straight_shape})"
            row = {"trajectory": label, **result.summary(), "wall_s": time.perf_counter() - t0}
            rows.append(row)
            log(f"{label:22s} v={v:.1f} m/s  mean {result.mean_speed:.3f} m/s  E={result.energy:8.1f} J  "
                f"fell={result.fell}  ({row['wall_s']:.1f} s)")
    return rows
