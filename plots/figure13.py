"""Figure 13: energy against speed, by foot trajectory. (a) E by Eq. (7) over the comparison walk: the learned
paths (mean ± 95 % CI over seeds), the baselines at each learned path's own lift height (matched, Table 5's
headline) and at the paper's H (hatched, the paper's protocol); (b) battery used per 100 m, Eq. (13), in the
prototype experiment on the ideal (plain) and hardware-like (dotted) robot.

Drawn from `comparison.json` and `prototype.json`. A bar counts only if its walk neither fell nor missed the
command by more than the speed band (`cyberdog.config.paper.SPEED_BAND`, ±5 %); every other bar is faded
and cross-hatched, in both panels. The prototype walks are shorter than the paper's 100 m (20 m by
default): (b) scales their battery use to 100 m, and its title says from which distance.
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from cyberdog.analysis.prototype_summary import METRICS, summary_rows, walk_counts
from cyberdog.analysis.stats import mean_ci
from cyberdog.config.paper import PAPER_DISTANCE_M, SPEED_BAND
from plots.style import COLORS, FADED_ALPHA, NAMES, save_figure, styled

STEM = "figure13_energy_vs_speed"
Bar = tuple[float, float, bool]  # (value, 95 % CI half-width or nan, counts)


def bars(ax, speeds, groups: dict[str, list[Bar]], ylabel: str, title: str,
         styles: dict[str, tuple[str, str | None]], legend_columns: int = 2) -> None:
    """Grouped bars: per speed one bar per group; `styles` gives each group's colour and hatch; a bar that
    does not count is faded and cross-hatched. The legend goes under the panel, in `legend_columns` columns
    (panel (a)'s long labels take one, so that its legend stays under its own panel)."""
    keys = list(groups)
    width = 0.8 / max(1, len(keys))
    x = np.arange(len(speeds))
    for i, key in enumerate(keys):
        color, hatch = styles[key]
        for j, (val, ci, ok) in enumerate(groups[key]):
            if not math.isfinite(val):
                continue
            ax.bar(x[j] + (i - (len(keys) - 1) / 2) * width, val, width, color=color,
                   alpha=1.0 if ok else FADED_ALPHA, hatch=hatch if ok else "xx", edgecolor="k", lw=0.5,
                   yerr=ci if math.isfinite(ci) else None, capsize=3, label=key if j == 0 else None)
    ax.set_xticks(x, [f"{v:g} m/s" for v in speeds])
    ax.set_xlabel("commanded speed")
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    ax.grid(alpha=0.3, axis="y")
    ax.legend(fontsize=7.5, loc="upper center", bbox_to_anchor=(0.5, -0.2), ncol=legend_columns)


def simulation_groups(rows: list[dict]) -> tuple[list[float], dict[str, list[Bar]], dict[str, tuple]]:
    """Panel (a): per speed the learned paths (mean ± 95 % CI over seeds), the baselines at matched lift (each
    seed's own H, as Table 5's headline: mean ± CI of the seeds' baseline walks; solid) and at the paper's H
    (hatched), in kJ. Rows of the paper set alone (no matched walks) give the paper's bars only."""
    speeds = sorted(dict.fromkeys(r["speed_command_mps"] for r in rows if r["set"] == "paper"))
    groups: dict[str, list[Bar]] = {}
    styles: dict[str, tuple] = {}
    matched_set = any(r["set"] == "same_lift" for r in rows)
    learned = [r for r in rows if r["set"] == "paper" and r["trajectory"] == "learned"]
    n_seeds = len(dict.fromkeys(r["seed"] for r in learned))

    def per_speed(sel_rows: list[dict]) -> list[Bar]:
        vals: list[Bar] = []
        for v in speeds:
            sel = [r for r in sel_rows if r["speed_command_mps"] == v]
            ok = [r["energy_kJ"] for r in sel if r["valid"]]  # valid = did not fall, kept the speed band
            if ok:
                vals.append((*mean_ci(ok), True))
            elif sel:
                vals.append((float(np.mean([r["energy_kJ"] for r in sel])), math.nan, False))
            else:
                vals.append((math.nan, math.nan, False))
        return vals

    if learned:
        label = (f"{NAMES['learned']}, mean ± 95 % CI of {n_seeds} seeds (own H)" if n_seeds > 1
                 else f"{NAMES['learned']} (H = {learned[0]['lift_height_m']:.3f} m)")
        groups[label], styles[label] = per_speed(learned), (COLORS["learned"], None)
    for key in ("cycloid", "straight"):
        if matched_set:  # the baseline walk each learned walk was compared with (same set, same lift)
            mine = [r for r in rows if r["set"] == "same_lift" and r["trajectory"] == key]
            if mine:
                label = f"{mine[0]['label']} at matched lift (each seed's H: the headline)"
                groups[label], styles[label] = per_speed(mine), (COLORS[key], None)
        paper = [r for r in rows if r["set"] == "paper" and r["trajectory"] == key]
        if paper:
            label = f"{paper[0]['label']} at H = {paper[0]['lift_height_m']:.2f} m (the paper's protocol)"
            groups[label], styles[label] = per_speed(paper), (COLORS[key], "//")
    return speeds, groups, styles


def prototype_counts(row: dict) -> bool:
    """A prototype walk counts if it reached the distance, did not fall and kept the speed band."""
    return walk_counts(row)


def prototype_groups(rows: list[dict]) -> tuple[list[float], dict[str, list[Bar]], dict[str, tuple]]:
    """Panel (b): per trajectory and robot, battery % per 100 m at each speed: the mean and 95 % CI across seeds
    of the summary (`cyberdog.analysis.prototype_summary`; a seed's value is its draws' mean). A bar is faded
    where a walk of its group did not count, and drawn from the walks that did."""
    speeds = sorted(dict.fromkeys(r["speed_mps"] for r in rows))
    summary = {(r["trajectory"], r["robot"], r["speed_mps"]): r for r in summary_rows(rows)}
    groups: dict[str, list[Bar]] = {}
    styles: dict[str, tuple] = {}
    for name in dict.fromkeys(r["trajectory"] for r in rows):
        for robot in ("ideal", "hardware"):
            vals: list[Bar] = []
            for v in speeds:
                r = summary.get((name, robot, v))
                if r is None:
                    vals.append((math.nan, math.nan, False))
                elif r["counted"] == 0:  # none counted: the walks as they went, faded
                    walked = [METRICS["battery_pct_per_100m"](w) for w in rows if w["trajectory"] == name
                              and w["robot"] == robot and w["speed_mps"] == v and w["distance_m"] > 0]
                    vals.append((float(np.mean(walked)) if walked else math.nan, math.nan, False))
                else:
                    vals.append((r["battery_pct_per_100m_mean"], r["battery_pct_per_100m_ci95"],
                                 r["counted"] == r["walks"]))
            if any(math.isfinite(v[0]) for v in vals):
                key = f"{name} ({robot} robot)"
                groups[key] = vals
                styles[key] = (COLORS.get(name.split(" ")[0], "gray"), ".." if robot == "hardware" else None)
    return speeds, groups, styles


def walk_length(rows: list[dict]) -> str:
    """The prototype walks' distance in words (the median walked, rounded: every walk is asked for the same)."""
    d = [r["distance_m"] for r in rows if r["distance_m"] > 0]
    run_up = float(np.median([r.get("run_up_s", 0.0) for r in rows])) if rows else 0.0  # older rows: from a stand
    return (f"{float(np.median(d)):.0f} m" if d else "? m") + (f" walks after a {run_up:g} s run-up" if run_up > 0
                                                                else " walks")


@styled
def draw(rows: list[dict], prototype_rows: list[dict] | None = None) -> Figure:
    """`rows`: comparison rows (energy_kJ per walk); `prototype_rows`: prototype walks, or None for (a) only."""
    n_panels = 2 if prototype_rows else 1
    fig = Figure(figsize=(6 * n_panels, 4.6))
    axes = fig.subplots(1, n_panels, squeeze=False)[0]
    speeds, groups, styles = simulation_groups(rows)
    duration = max((r["duration_s"] for r in rows if r["set"] == "paper"), default=math.nan)
    bars(axes[0], speeds, groups, "energy over the walk, Eq. (7) (kJ)",
         f"(a) simulation, {duration:g} s walks (Table 5)", styles, legend_columns=1)
    if prototype_rows:
        p_speeds, pgroups, pstyles = prototype_groups(prototype_rows)
        bars(axes[1], p_speeds, pgroups, f"battery used per {PAPER_DISTANCE_M:g} m, Eq. (13) (% of the pack)",
             f"(b) prototype in simulation: {walk_length(prototype_rows)}, per {PAPER_DISTANCE_M:g} m",
             pstyles)
    fig.suptitle(f"Figure 13: energy against speed, by foot trajectory (faded, cross-hatched: the walk fell or "
                 f"missed the speed by > {100 * SPEED_BAND:g} %)", fontsize=10, y=1.0)
    return fig


def figure13(rows: list[dict], out_dir: str | Path, prototype_rows: list[dict] | None = None, **save) -> list[Path]:
    """Draw Figure 13 and write it into `out_dir`."""
    return save_figure(draw(rows, prototype_rows), out_dir, STEM, **save)


__all__ = ["STEM", "bars", "draw", "figure13", "prototype_counts", "prototype_groups", "simulation_groups",
           "walk_length"]
