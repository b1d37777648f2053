"""Figure 7: the learned foot trajectory beside the two common ones: (a) x–z path, (b) x and (c) z against
the gait phase.

The learned paths are read from the results folder's `learned/*.json` as a `LearnedSet`: per seed the path
`LearnedSet.figure_paths` gives at 1 m/s, the one Table 5 walked there (a commanded path's reference leg, LF).
The baselines are drawn at the learned S and at the H Table 5 matches them at (solid: the first seed's lift
height, the mean of its four legs' peaks, which the legend gives beside the LF leg's own) and at the paper's H
(dotted: the paper's protocol).
"""
from __future__ import annotations

from pathlib import Path

from matplotlib.figure import Figure

from cyberdog.config.paper import PAPER_LIFT_HEIGHT
from cyberdog.core.trajectories import CompositeCycloid, SampledTrajectory, StraightLine
from plots.figure4 import cycle_path
from plots.style import COLORS, NAMES, SEED_COLORS, save_figure, styled

STEM = "figure7_learned_trajectory"


def matched_lift(traj: SampledTrajectory) -> float:
    """m, the lift height Table 5 matches the baselines at: a commanded path's mean over its legs (recorded in
    the provenance by `CommandedPath.as_sampled`), else the path's own peak."""
    return float(traj.provenance.get("own_lift_height_m", traj.lift_height))


def provenance_line(prov: dict) -> str:
    """Where the first learned path comes from, in words (empty without provenance)."""
    if not prov:
        return ""
    if prov.get("path") == "commanded":  # the commanded path of one leg, averaged over the settled cycles
        used = prov.get("cycles_used", [])
        which = (f"LF's commanded path, mean of {len(used)} cycles" if prov.get("cycle") == "mean"
                 else f"LF's commanded path, cycle {used[0] if used else '?'}")
    else:
        which = f"cycle {prov.get('cycle_index', '?')}"
    return (f"{which} of the rollout at {prov.get('speed_command_mps', '?')} m/s (seed {prov.get('seed', '?')}), "
            f"E = {prov.get('cycle_energy_J', float('nan')):.1f} J per cycle")


@styled
def draw(learned: dict[str, SampledTrajectory], straight_shape: str = "rectangle",
         paper_lift: float = PAPER_LIFT_HEIGHT, swing_time: float = 0.2, stance_time: float = 0.2) -> Figure:
    """`learned`: {label: path}; the first one sets the S and H the solid baselines are drawn at."""
    if not learned:
        raise ValueError("Figure 7 needs at least one learned trajectory")
    fig = Figure(figsize=(13, 3.8))
    axes = fig.subplots(1, 3, gridspec_kw={"width_ratios": [1.4, 1, 1]})
    first = next(iter(learned.values()))
    S = first.step_length
    H = matched_lift(first)
    series = []  # (legend name, trajectory, S, H, colour, line style, width)
    colors = {}
    for i, (label, traj) in enumerate(learned.items()):
        name = NAMES["learned"] + (f" [{label}]" if len(learned) > 1 or label else "")
        colors[label] = COLORS["learned"] if i == 0 else SEED_COLORS[(i - 1) % len(SEED_COLORS)]
        own = matched_lift(traj)
        heights = (f"H = {own:.3f} m (LF's peak {traj.lift_height:.3f} m)" if abs(own - traj.lift_height) > 5e-4
                   else f"H = {own:.3f} m")
        series.append((f"{name}, {heights}", traj, traj.step_length, traj.lift_height, colors[label], "-", 2.2))
    for key, traj in (("cycloid", CompositeCycloid()), ("straight", StraightLine(straight_shape))):
        shape = "" if key == "cycloid" else f" ({straight_shape})"
        series.append((f"{NAMES[key]}{shape}, H = {H:.3f} m (matched, as Table 5)", traj, S, H, COLORS[key], "-",
                       1.4))
        series.append((f"{NAMES[key]}{shape}, H = {paper_lift:.2f} m (paper)", traj, S, paper_lift,
                       COLORS[key], ":", 1.2))
    for name, traj, s, h, color, ls, lw in series:
        phase, p = cycle_path(traj, s, h, swing_time, stance_time)
        axes[0].plot(100 * p[:, 0], 100 * p[:, 1], color=color, ls=ls, lw=lw, label=name)
        axes[1].plot(phase, 100 * p[:, 0], color=color, ls=ls, lw=lw)
        axes[2].plot(phase, 100 * p[:, 1], color=color, ls=ls, lw=lw)
    for label, traj in learned.items():  # the points the spline runs through, under the lines, in each colour
        axes[0].plot(100 * traj.x, 100 * traj.z, ".", color=colors[label], ms=1.5, alpha=0.5, zorder=0)
    axes[0].plot([], [], ".", color="gray", ms=3, label="extracted samples (each seed's colour)")
    axes[0].set_title("(a) foot path, x–z")
    axes[0].set_xlabel("foot x relative to the hip (cm)")
    axes[0].set_ylabel("foot height z (cm)")
    axes[0].legend(loc="upper left", bbox_to_anchor=(0.0, -0.18), ncol=2)
    axes[1].set_title("(b) x against gait phase")
    axes[1].set_ylabel("x (cm)")
    axes[2].set_title("(c) z against gait phase")
    axes[2].set_ylabel("z (cm)")
    for ax in axes[1:]:
        ax.set_xlabel("gait phase (0 = lift-off)")
    fig.subplots_adjust(wspace=0.32)  # room for (b)'s and (c)'s y labels beside the panel before
    for ax in axes:
        ax.grid(alpha=0.3)
    info = provenance_line(first.provenance)
    fig.suptitle(f"Figure 7: extracted learned foot trajectory (S = {S:.2f} m" + (f"; {info})" if info else ")"),
                 fontsize=10, y=1.02)
    return fig


def figure7(learned: dict[str, SampledTrajectory], out_dir: str | Path, straight_shape: str = "rectangle",
            paper_lift: float = PAPER_LIFT_HEIGHT, swing_time: float = 0.2, stance_time: float = 0.2,
            **save) -> list[Path]:
    """Draw Figure 7 and write it into `out_dir`."""
    return save_figure(draw(learned, straight_shape, paper_lift, swing_time, stance_time), out_dir, STEM, **save)


__all__ = ["STEM", "draw", "figure7", "matched_lift", "provenance_line"]
