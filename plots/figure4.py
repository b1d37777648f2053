"""Figure 4: the two common foot trajectories (composite cycloid, straight line) over one gait cycle, x–z.

The shapes are computed, not read: `cyberdog.core.trajectories` is the same pure-numpy code the controller
draws its foot targets from, so the figure shows exactly what the robot is asked to follow.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from cyberdog.core.trajectories import CompositeCycloid, FootTrajectory, StraightLine
from plots.style import COLORS, NAMES, save_figure, styled

STEM = "figure4_baseline_trajectories"


def cycle_path(traj: FootTrajectory, step_length: float, lift_height: float, swing_time: float = 0.2,
               stance_time: float = 0.2, n: int = 400) -> tuple[np.ndarray, np.ndarray]:
    """Phases (n,) and foot positions (n, 2) = (x, z), m, over one gait cycle (phase 0 = lift-off)."""
    phase = np.arange(n) / n
    pos, _ = traj.position_velocity(phase, step_length, lift_height, swing_time, stance_time)
    return phase, pos


@styled
def draw(step_length: float = 0.2, lift_height: float = 0.15, straight_shape: str = "rectangle",
         swing_time: float = 0.2, stance_time: float = 0.2) -> Figure:
    """Both trajectories, swing solid and stance dashed, in cm; S and H in m."""
    fig = Figure(figsize=(9, 3.4))
    axes = fig.subplots(1, 2, sharey=True)
    beta = swing_time / (swing_time + stance_time)  # swing share of the cycle
    for ax, (key, traj, tag) in zip(axes, (("cycloid", CompositeCycloid(), "(a)"),
                                           ("straight", StraightLine(straight_shape), "(b)"))):
        phase, p = cycle_path(traj, step_length, lift_height, swing_time, stance_time)
        sw = phase < beta
        ax.plot(100 * p[sw, 0], 100 * p[sw, 1], color=COLORS[key], lw=2, label="swing")
        ax.plot(100 * p[~sw, 0], 100 * p[~sw, 1], color=COLORS[key], lw=2, ls="--", label="stance")
        ax.plot(100 * p[0, 0], 100 * p[0, 1], "ko", ms=4, label="lift-off")
        k = len(p) // 8  # an arrow early in the swing shows the direction of travel
        ax.annotate("", xy=(100 * p[k + 1, 0], 100 * p[k + 1, 1]), xytext=(100 * p[k, 0], 100 * p[k, 1]),
                    arrowprops=dict(arrowstyle="->", color="k"))
        shape = "" if key == "cycloid" else f" ({straight_shape})"
        ax.set_title(f"{tag} {NAMES[key]}{shape}")
        ax.set_xlabel("foot x relative to the hip (cm)")
        ax.grid(alpha=0.3)
        ax.set_aspect("equal")
    axes[0].set_ylabel("foot height z (cm)")
    axes[0].legend(loc="upper left")
    fig.suptitle(f"Figure 4: common foot trajectories, S = {step_length:.2f} m, H = {lift_height:.2f} m, "
                 f"swing {swing_time:g} s + stance {stance_time:g} s", fontsize=10)
    return fig


def figure4(out_dir: str | Path, step_length: float = 0.2, lift_height: float = 0.15,
            straight_shape: str = "rectangle", swing_time: float = 0.2, stance_time: float = 0.2,
            **save) -> list[Path]:
    """Draw Figure 4 and write it into `out_dir` (`save`: dpi, pdf of `save_figure`)."""
    return save_figure(draw(step_length, lift_height, straight_shape, swing_time, stance_time), out_dir, STEM,
                       **save)


__all__ = ["STEM", "cycle_path", "draw", "figure4"]
