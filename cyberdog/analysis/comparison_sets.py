"""The names a trajectory comparison's walks carry (`cyberdog.analysis.compare`), shared with the tables made
from its saved rows: which walks are Eq. (12)'s baselines, which is the direct search's reference, the two sets of
baselines, and when two lifts count as one. Pure Python: a table drawn from saved walks loads no simulator."""
from __future__ import annotations

BASELINES = ("cycloid", "straight")  # the paper's two common trajectories (Figure 4), E_min of Eq. (12)
REFERENCE = "searched"  # the direct search's shape (trajectory name of its walks)
SETS = ("paper", "same_lift")  # the baselines at the paper's H, and at the learned path's own H
LIFT_DECIMALS = 4  # lift heights equal to 0.1 mm share their baseline walks


def same_lift(a: float, b: float) -> bool:
    """Whether two lift heights (m) are one for the comparison (equal to `LIFT_DECIMALS` decimals)."""
    return round(a, LIFT_DECIMALS) == round(b, LIFT_DECIMALS)
