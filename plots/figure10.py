"""Figure 10: total joint power Σ|τ·θ̇| over the last two whole gait cycles of each comparison walk, one
column per speed. Above: the first learned seed and the composite cycloid at its own lift height (matched,
Table 5's headline pair), on their own power scale. Below: the same learned trace with the straight line at
that lift (solid) and both baselines at the paper set's H (dotted), whose spikes (up to ~1.5 kW) would squash
the pair above into the bottom fifth of a shared axis. The dashed vertical line is the gait period boundary.

Drawn from `walks.json` (which walk is which) and `power_traces.npz` (W at the physics rate). The learned
trace is drawn last and above the others: the baselines' larger swings would otherwise hide it. Every line has
a legend entry (under its column).
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
    """Per speed, the walks Figure 10 shows, by key: "learned" = the first seed's that walked at that speed (a seed
    without a path there, skipped by --skip-missing-paths, gives way to the next); "cycloid", "straight" = the
    baselines at that walk's own lift height (matched, as Table 5's headline), where walked; "cycloid paper",
    "straight paper" = the baselines at `lift_height` (default: the highest baseline lift, the paper set's)."""
    base_lifts = [w["lift_height_m"] for w in walks if w["trajectory"] in ("cycloid", "straight")]
    lift = lift_height if lift_height is not None else (max(base_lifts) if base_lifts else None)
    seeds = list(dict.fromkeys(w["seed"] for w in walks if w["trajectory"] == "learned"))
    out: dict[float, dict[str, dict]] = {}
    for v in sorted(dict.fromkeys(w["speed_command_mps"] for w in walks)):
        here = [w for w in walks if w["speed_command_mps"] == v]
        walked = [seed for seed in seeds if any(w["trajectory"] == "learned" and w["seed"] == seed for w in here)]
        learned = [w for w in here if w["trajectory"] == "learned" and (not walked or w["seed"] == walked[0])]
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


TOP_KEYS = ("cycloid", "learned")  # the upper row: the learned path and the cycloid at its lift (the headline)


def trace_label(key: str, w: dict, e_win: float | None) -> str:
    """A walk's legend entry: its trajectory, which lift set, its H and the energy of the drawn window."""
    base, paper = key.split(" ")[0], key.endswith(" paper")
    name = w["label"] if base != "learned" else f"{NAMES['learned']} [{w['seed']}]"
    which = " (paper)" if paper else (" (matched)" if base != "learned" else "")
    if e_win is None:
        return f"{name}{which}: fell, no steady cycles"
    return (f"{name}{which}, H = {w['lift_height_m']:.3f} m: {e_win:.0f} J"
            + ("" if w["speed_ok"] else " (speed miss)"))


def draw_traces(ax, by_key: dict[str, dict], power: dict[int, np.ndarray], keys, cycles: int) -> float | None:
    """The walks of `keys` (in `by_key`'s order, the learned one last and on top) on `ax`; returns the period."""
    period = None
    for z, (key, w) in enumerate(by_key.items()):
        if key not in keys:
            continue
        base, paper = key.split(" ")[0], key.endswith(" paper")
        p = np.asarray(power[w["walk_id"]], dtype=float)
        dt, period = w["controller_dt_s"], w["period_s"]
        seg = p[last_cycles_window(len(p), dt, period, cycles)]
        if w["fell"] or len(seg) == 0:
            ax.plot([], [], color=COLORS[base], label=trace_label(key, w, None))
            continue
        ax.plot(np.arange(len(seg)) * dt, seg, color=COLORS[base], ls=":" if paper else "-",
                lw=1.6 if base == "learned" else (0.9 if paper else 1.1), zorder=2 + z,
                label=trace_label(key, w, float(seg.sum() * dt)))  # J over the window
    for k in range(1, cycles):
        if period:
            ax.axvline(k * period, color="gray", ls="--", lw=0.8,
                       label=f"gait period boundary (T = {period:g} s)" if k == 1 else "_boundary")
    return period


@styled
def draw(walks: list[dict], power: dict[int, np.ndarray], lift_height: float | None = None,
         cycles: int = 2) -> Figure:
    """`power`: W per walk_id at each walk's controller_dt_s; `lift_height` m of the paper's baselines. Per speed
    two panels: above, the learned path and the cycloid at its own lift height (the headline pair, on their
    own scale); below, the same learned trace with the straight line at that lift (solid) and both baselines at
    the paper's H (dotted), whose spikes need a scale of their own."""
    chosen = chosen_walks(walks, lift_height)
    if not chosen:
        raise ValueError("Figure 10 needs at least one walk")
    fig = Figure(figsize=(4.0 * len(chosen), 6.6))
    axes = fig.subplots(2, len(chosen), sharex=True, sharey="row", squeeze=False)
    tags = iter("abcdefghijklmnop")
    for row, keys in enumerate((TOP_KEYS, tuple(k for by in chosen.values() for k in by if k != "cycloid"))):
        for ax, (v, by_key) in zip(axes[row], chosen.items()):
            draw_traces(ax, by_key, power, keys, cycles)
            what = "learned, cycloid at its H" if row == 0 else "+ straight line, paper's H"
            ax.set_title(f"({next(tags)}) {v:g} m/s: {what}", fontsize=9.5)
            ax.grid(alpha=0.3)
            if row == 1:
                ax.set_xlabel(f"time in the last {cycles} gait cycles (s)")
        axes[row][0].set_ylabel("total joint power Σ|τ·θ̇| (W)")
    for col, (ax_top, ax_bottom) in enumerate(zip(*axes)):
        handles, labels = ax_bottom.get_legend_handles_labels()
        top_h, top_l = ax_top.get_legend_handles_labels()
        extra = [(h, lab) for h, lab in zip(top_h, top_l) if lab not in labels]
        order = [*extra, *zip(handles, labels)]
        ax_bottom.legend([h for h, _ in order], [lab for _, lab in order], loc="upper center",
                         bbox_to_anchor=(0.5, -0.2), fontsize=7)
    fig.suptitle(f"Figure 10: joint power over {cycles} gait cycles (energy of the window in the legend; solid: "
                 f"baselines at the learned path's lift height, dotted: at the paper's)", fontsize=10)
    return fig


def figure10(walks: list[dict], power: dict[int, np.ndarray], out_dir: str | Path,
             lift_height: float | None = None, cycles: int = 2, **save) -> list[Path]:
    """Draw Figure 10 and write it into `out_dir`."""
    return save_figure(draw(walks, power, lift_height, cycles), out_dir, STEM, **save)


__all__ = ["STEM", "TOP_KEYS", "chosen_walks", "draw", "draw_traces", "figure10", "last_cycles_window",
           "trace_label"]
