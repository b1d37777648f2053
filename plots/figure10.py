"""Figure 10: total joint power Σ|τ·θ̇| over the last two whole gait cycles of each comparison walk, one
panel per speed: the first learned seed, the two baselines at its own lift height (matched, solid) and at the
paper set's (dotted).

Drawn from `walks.json` (which walk is which) and `power_traces.npz` (W at the physics rate). The learned
trace is drawn last and above the others: the baselines' larger swings would otherwise hide it.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from plots.style import COLORS, NAMES, save_figure, styled

STEM = "figure10_power"


def last_cycles_window(n: int, dt: float, period: float, cycles: int = 2) -> slice:
    """Samples of the last `cycles` whole gait-clock cycles of a walk of n samples (t = k·dt, s)."""
    per = int(round(period / dt))
    last = (n // per) * per  # end of the last whole cycle
    return slice(max(0, last - cycles * per), last)


def chosen_walks(walks: list[dict], lift_height: float | None = None) -> dict[float, dict[str, dict]]:
    """Per speed, the walks Figure 10 shows, by key: "learned" = the first seed's; "cycloid", "straight" = the
    baselines at that walk's own lift height (matched, as Table 5's headline), where walked; "cycloid paper",
    "straight paper" = the baselines at `lift_height` (default: the highest baseline lift, the paper set's)."""
    base_lifts = [w["lift_height_m"] for w in walks if w["trajectory"] in ("cycloid", "straight")]
    lift = lift_height if lift_height is not None else (max(base_lifts) if base_lifts else None)
    seeds = list(dict.fromkeys(w["seed"] for w in walks if w["trajectory"] == "learned"))
    out: dict[float, dict[str, dict]] = {}
    for v in sorted(dict.fromkeys(w["speed_command_mps"] for w in walks)):
        here = [w for w in walks if w["speed_command_mps"] == v]
        learned = [w for w in here if w["trajectory"] == "learned" and (not seeds or w["seed"] == seeds[0])]
        own = round(learned[0]["lift_height_m"], 4) if learned else None
        for key in ("cycloid", "straight"):
            for suffix, h in (("", own), (" paper", lift)):
                cand = [w for w in here if w["trajectory"] == key and h is not None
                        and abs(w["lift_height_m"] - h) < 5e-5]
                if cand and not (suffix and own is not None and abs(h - own) < 5e-5):
                    out.setdefault(v, {})[key + suffix] = cand[0]
        if learned:
            out.setdefault(v, {})["learned"] = learned[0]  # last: drawn on top
    return out


@styled
def draw(walks: list[dict], power: dict[int, np.ndarray], lift_height: float | None = None,
         cycles: int = 2) -> Figure:
    """`power`: W per walk_id at each walk's controller_dt_s; `lift_height` m of the paper's baselines. The
    baselines at the learned path's own lift height are solid, those at the paper's dotted."""
    chosen = chosen_walks(walks, lift_height)
    if not chosen:
        raise ValueError("Figure 10 needs at least one walk")
    fig = Figure(figsize=(4.0 * len(chosen), 4.1))
    axes = fig.subplots(1, len(chosen), sharey=True, squeeze=False)[0]
    for ax, (v, by_key), tag in zip(axes, chosen.items(), "abcdefgh"):
        period = None
        for z, (key, w) in enumerate(by_key.items()):
            base, paper = key.split(" ")[0], key.endswith(" paper")
            p = np.asarray(power[w["walk_id"]], dtype=float)
            dt, period = w["controller_dt_s"], w["period_s"]
            seg = p[last_cycles_window(len(p), dt, period, cycles)]
            name = w["label"] if base != "learned" else f"{NAMES['learned']} [{w['seed']}]"
            which = " (paper)" if paper else (" (matched)" if base != "learned" else "")
            if w["fell"] or len(seg) == 0:
                ax.plot([], [], color=COLORS[base], label=f"{name}{which}: fell, no steady cycles")
                continue
            e_win = float(seg.sum() * dt)  # J over the window
            note = "" if w["speed_ok"] else " (speed miss)"
            ax.plot(np.arange(len(seg)) * dt, seg, color=COLORS[base], ls=":" if paper else "-",
                    lw=1.6 if base == "learned" else (0.9 if paper else 1.1), zorder=2 + z,
                    label=f"{name}{which}, H = {w['lift_height_m']:.3f} m: {e_win:.0f} J{note}")
        for k in range(1, cycles):
            if period:
                ax.axvline(k * period, color="gray", ls="--", lw=0.8)
        ax.set_title(f"({tag}) {v:g} m/s")
        ax.set_xlabel(f"time in the last {cycles} gait cycles (s)")
        ax.grid(alpha=0.3)
        ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.18), fontsize=7)
    axes[0].set_ylabel("total joint power Σ|τ·θ̇| (W)")
    fig.suptitle(f"Figure 10: joint power over {cycles} gait cycles (energy of the window in the legend; solid: "
                 f"baselines at the learned path's lift height, dotted: at the paper's)", fontsize=10)
    return fig


def figure10(walks: list[dict], power: dict[int, np.ndarray], out_dir: str | Path,
             lift_height: float | None = None, cycles: int = 2, **save) -> list[Path]:
    """Draw Figure 10 and write it into `out_dir`."""
    return save_figure(draw(walks, power, lift_height, cycles), out_dir, STEM, **save)


__all__ = ["STEM", "chosen_walks", "draw", "figure10", "last_cycles_window"]
