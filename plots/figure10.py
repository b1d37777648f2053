"""Figure 10: total joint power Σ|τ·θ̇| over the last two whole gait cycles of each comparison walk, one
panel per speed: the first learned seed and the two baselines at the paper set's lift height.

Drawn from `walks.json` (which walk is which) and `power_traces.npz` (W at the physics rate). The learned
trace is drawn last and above the others: the baselines' larger swings would otherwise hide it.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from plots.style import COLORS, NAMES, save_figure, styled

STEM = "figure10_power"
DRAW_ORDER = ("cycloid", "straight", "learned")  # later is on top


def last_cycles_window(n: int, dt: float, period: float, cycles: int = 2) -> slice:
    """Samples of the last `cycles` whole gait-clock cycles of a walk of n samples (t = k·dt, s)."""
    per = int(round(period / dt))
    last = (n // per) * per  # end of the last whole cycle
    return slice(max(0, last - cycles * per), last)


def chosen_walks(walks: list[dict], lift_height: float | None = None) -> dict[float, dict[str, dict]]:
    """Per speed, per trajectory the walk Figure 10 shows: learned = the first seed's, the baselines at
    `lift_height` (default: the highest baseline lift, the paper set's)."""
    base_lifts = [w["lift_height_m"] for w in walks if w["trajectory"] in ("cycloid", "straight")]
    lift = lift_height if lift_height is not None else (max(base_lifts) if base_lifts else None)
    seeds = list(dict.fromkeys(w["seed"] for w in walks if w["trajectory"] == "learned"))
    out: dict[float, dict[str, dict]] = {}
    for v in sorted(dict.fromkeys(w["speed_command_mps"] for w in walks)):
        for key in DRAW_ORDER:
            cand = [w for w in walks if w["trajectory"] == key and w["speed_command_mps"] == v
                    and (key != "learned" or not seeds or w["seed"] == seeds[0])
                    and (key == "learned" or lift is None or abs(w["lift_height_m"] - lift) < 5e-5)]
            if cand:
                out.setdefault(v, {})[key] = cand[0]
    return out


@styled
def draw(walks: list[dict], power: dict[int, np.ndarray], lift_height: float | None = None,
         cycles: int = 2) -> Figure:
    """`power`: W per walk_id at each walk's controller_dt_s; `lift_height` m of the baselines shown."""
    chosen = chosen_walks(walks, lift_height)
    if not chosen:
        raise ValueError("Figure 10 needs at least one walk")
    fig = Figure(figsize=(4.2 * len(chosen), 3.9))
    axes = fig.subplots(1, len(chosen), sharey=True, squeeze=False)[0]
    for ax, (v, by_key), tag in zip(axes, chosen.items(), "abcdefgh"):
        period = None
        for z, (key, w) in enumerate(by_key.items()):
            p = np.asarray(power[w["walk_id"]], dtype=float)
            dt, period = w["controller_dt_s"], w["period_s"]
            seg = p[last_cycles_window(len(p), dt, period, cycles)]
            name = w["label"] if key != "learned" else NAMES["learned"]
            if w["fell"] or len(seg) == 0:
                ax.plot([], [], color=COLORS[key], label=f"{name}: fell, no steady cycles")
                continue
            e_win = float(seg.sum() * dt)  # J over the window
            note = "" if w["speed_ok"] else " (speed miss)"
            ax.plot(np.arange(len(seg)) * dt, seg, color=COLORS[key], lw=1.3 if key == "learned" else 1.0,
                    zorder=2 + z, label=f"{name}, H = {w['lift_height_m']:.3f} m: {e_win:.0f} J{note}")
        for k in range(1, cycles):
            if period:
                ax.axvline(k * period, color="gray", ls="--", lw=0.8)
        ax.set_title(f"({tag}) {v:g} m/s")
        ax.set_xlabel(f"time in the last {cycles} gait cycles (s)")
        ax.grid(alpha=0.3)
        ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.18), fontsize=7.5)
    axes[0].set_ylabel("total joint power Σ|τ·θ̇| (W)")
    fig.suptitle(f"Figure 10: joint power over {cycles} gait cycles (energy of the window in the legend)",
                 fontsize=10)
    return fig


def figure10(walks: list[dict], power: dict[int, np.ndarray], out_dir: str | Path,
             lift_height: float | None = None, cycles: int = 2, **save) -> list[Path]:
    """Draw Figure 10 and write it into `out_dir`."""
    return save_figure(draw(walks, power, lift_height, cycles), out_dir, STEM, **save)


__all__ = ["DRAW_ORDER", "STEM", "chosen_walks", "draw", "figure10", "last_cycles_window"]
