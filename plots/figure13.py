"""Figure 13: energy against speed, by foot trajectory. (a) E by Eq. (7) over the comparison walk: the learned
paths (mean ± 95 % CI over seeds), the baselines at each learned path's own lift height (matched, Table 5's
headline; plain bars) and at the paper's H (hatched: the paper's protocol), and the direct search's shape (the
strongest alternative the project builds; grey) where the comparison walked it; (b) battery used per 100 m,
Eq. (13), in the prototype experiment, one panel per robot (ideal, hardware-like) that the run walked.

Drawn from `comparison.json` and `prototype.json`. Each mark means one thing, said once in the figure's legend:
colour = the foot trajectory; hatching = a baseline at the paper's H (panel (a) only); error bar = 95 % CI
across seeds; "×  k/n" over a bar = k of its n walks fell or missed the command by more than the speed band
(`cyberdog.config.paper.SPEED_BAND`, ±5 %), and the bar is the mean of the walks that counted; a faded bar =
none of its walks counted (drawn as walked). The prototype walks are shorter than the paper's 100 m (20 m by
default): (b) scales their battery use to 100 m, and its title says from which distance.
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Patch

from cyberdog.analysis.prototype_summary import METRICS, summary_rows, walk_counts
from cyberdog.analysis.stats import mean_ci
from cyberdog.config.paper import PAPER_DISTANCE_M, SPEED_BAND
from plots.style import COLORS, FADED_ALPHA, NAMES, save_figure, styled

STEM = "figure13_energy_vs_speed"
PAPER_HATCH = "//"  # the one hatch of the figure: a baseline walked at the paper's H (its protocol)
MISS_MARKER = "x"  # over a bar: some of its walks fell or left the speed band
Bar = tuple[float, float, int, int]  # (value, 95 % CI half-width or nan, walks that did not count, walks)


def bars(ax, speeds, groups: dict[str, list[Bar]], ylabel: str, title: str,
         styles: dict[str, tuple[str, str | None]]) -> None:
    """Grouped bars: per speed one bar per group; `styles` gives each group's colour and hatch (None or
    PAPER_HATCH). A bar some of whose walks did not count carries "× k/n" above it; one none of whose walks
    counted is also faded. The figure's legend (`legend_handles`) says what each mark means."""
    keys = list(groups)
    width = 0.8 / max(1, len(keys))
    x = np.arange(len(speeds))
    top = max((v + (c if math.isfinite(c) else 0.0) for g in groups.values() for v, c, _, _ in g
               if math.isfinite(v)), default=1.0)
    for i, key in enumerate(keys):
        color, hatch = styles[key]
        for j, (val, ci, bad, n) in enumerate(groups[key]):
            if not math.isfinite(val):
                continue
            xc = x[j] + (i - (len(keys) - 1) / 2) * width
            ax.bar(xc, val, width, color=color, alpha=FADED_ALPHA if n and bad == n else 1.0, hatch=hatch,
                   edgecolor="k", lw=0.5, yerr=ci if math.isfinite(ci) else None, capsize=3, label=key)
            if bad:
                y = val + (ci if math.isfinite(ci) else 0.0) + 0.03 * top
                ax.plot([xc], [y], MISS_MARKER, color="k", ms=6, mew=1.5, label="_miss")
                ax.text(xc, y + 0.03 * top, f"{bad}/{n}", ha="center", va="bottom", fontsize=6.5)
    ax.set_xticks(x, [f"{v:g} m/s" for v in speeds])
    ax.set_xlabel("commanded speed")
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    ax.set_ylim(0, 1.15 * top)
    ax.grid(alpha=0.3, axis="y")


def per_speed(speeds, rows: list[dict]) -> list[Bar]:
    """Per speed: mean ± 95 % CI of the rows that count (`valid`: did not fall, kept the speed band), with how
    many did not; where none counted, the mean as walked."""
    vals: list[Bar] = []
    for v in speeds:
        sel = [r for r in rows if r["speed_command_mps"] == v]
        ok = [r["energy_kJ"] for r in sel if r["valid"]]
        if ok:
            vals.append((*mean_ci(ok), len(sel) - len(ok), len(sel)))
        elif sel:
            vals.append((float(np.mean([r["energy_kJ"] for r in sel])), math.nan, len(sel), len(sel)))
        else:
            vals.append((math.nan, math.nan, 0, 0))
    return vals


def simulation_groups(rows: list[dict]) -> tuple[list[float], dict[str, list[Bar]], dict[str, tuple]]:
    """Panel (a): per speed the learned paths (mean ± 95 % CI over seeds), the baselines at matched lift (each
    seed's own H, as Table 5's headline: mean ± CI of the seeds' baseline walks; plain) and at the paper's H
    (hatched), in kJ. Rows of the paper set alone (no matched walks) give the paper's bars only."""
    speeds = sorted(dict.fromkeys(r["speed_command_mps"] for r in rows if r["set"] == "paper"))
    groups: dict[str, list[Bar]] = {}
    styles: dict[str, tuple] = {}
    matched_set = any(r["set"] == "same_lift" for r in rows)
    learned = [r for r in rows if r["set"] == "paper" and r["trajectory"] == "learned"]
    n_seeds = len(dict.fromkeys(r["seed"] for r in learned))
    if learned:
        label = (f"{NAMES['learned']}, mean ± 95 % CI of {n_seeds} seeds (own H)" if n_seeds > 1
                 else f"{NAMES['learned']} (H = {learned[0]['lift_height_m']:.3f} m)")
        groups[label], styles[label] = per_speed(speeds, learned), (COLORS["learned"], None)
    for key in ("cycloid", "straight"):
        if matched_set:  # the baseline walk each learned walk was compared with (same set, same lift)
            mine = [r for r in rows if r["set"] == "same_lift" and r["trajectory"] == key]
            if mine:
                label = f"{mine[0]['label']} at matched lift (each seed's H: the headline)"
                groups[label], styles[label] = per_speed(speeds, mine), (COLORS[key], None)
        paper = [r for r in rows if r["set"] == "paper" and r["trajectory"] == key]
        if paper:
            label = f"{paper[0]['label']} at H = {paper[0]['lift_height_m']:.2f} m (the paper's protocol)"
            groups[label], styles[label] = per_speed(speeds, paper), (COLORS[key], PAPER_HATCH)
    searched = [r for r in rows if r["trajectory"] == "searched"]  # the direct search's shape, one walk a speed
    if searched:
        label = f"{NAMES['searched']} at H = {searched[0]['lift_height_m']:.3f} m"
        groups[label], styles[label] = per_speed(speeds, searched), (COLORS["searched"], None)
    return speeds, groups, styles


def prototype_counts(row: dict) -> bool:
    """A prototype walk counts if it reached the distance, did not fall and kept the speed band."""
    return walk_counts(row)


def prototype_robots(rows: list[dict]) -> list[str]:
    """The robots the prototype walked, ideal first: one panel each."""
    return [r for r in ("ideal", "hardware") if any(w["robot"] == r for w in rows)]


def prototype_groups(rows: list[dict], robot: str = "hardware"
                     ) -> tuple[list[float], dict[str, list[Bar]], dict[str, tuple]]:
    """Panel (b) of one robot: per trajectory, battery % per 100 m at each speed: the mean and 95 % CI across
    seeds of the summary (`cyberdog.analysis.prototype_summary`; a seed's value is its draws' mean), drawn
    from the walks that counted, with how many did not."""
    speeds = sorted(dict.fromkeys(r["speed_mps"] for r in rows))
    summary = {(r["trajectory"], r["robot"], r["speed_mps"]): r for r in summary_rows(rows)}
    groups: dict[str, list[Bar]] = {}
    styles: dict[str, tuple] = {}
    for name in dict.fromkeys(r["trajectory"] for r in rows):
        vals: list[Bar] = []
        for v in speeds:
            r = summary.get((name, robot, v))
            if r is None:
                vals.append((math.nan, math.nan, 0, 0))
            elif r["counted"] == 0:  # none counted: the walks as they went, faded
                walked = [METRICS["battery_pct_per_100m"](w) for w in rows if w["trajectory"] == name
                          and w["robot"] == robot and w["speed_mps"] == v and w["distance_m"] > 0]
                vals.append((float(np.mean(walked)) if walked else math.nan, math.nan, r["walks"], r["walks"]))
            else:
                vals.append((r["battery_pct_per_100m_mean"], r["battery_pct_per_100m_ci95"],
                             r["walks"] - r["counted"], r["walks"]))
        if any(math.isfinite(v[0]) for v in vals):
            groups[name], styles[name] = vals, (COLORS.get(name.split(" ")[0], "gray"), None)
    return speeds, groups, styles


def walk_length(rows: list[dict]) -> str:
    """The prototype walks' distance in words (the median walked, rounded: every walk is asked for the same)."""
    d = [r["distance_m"] for r in rows if r["distance_m"] > 0]
    run_up = float(np.median([r.get("run_up_s", 0.0) for r in rows])) if rows else 0.0  # older rows: from a stand
    return (f"{float(np.median(d)):.0f} m" if d else "? m") + (f" walks after a {run_up:g} s run-up" if run_up > 0
                                                                else " walks")


def trajectory_names(rows: list[dict]) -> dict[str, str]:
    """The legend's name of each trajectory: the paper's, with the straight line's shape where the rows say it
    (their label "straight (rectangle)")."""
    names = dict(NAMES)
    for r in rows:
        if r["trajectory"] == "straight" and "(" in r.get("label", ""):
            names["straight"] = f"{NAMES['straight']} ({r['label'].split('(', 1)[1]}"
    return names


def legend_handles(bar_groups: list[dict[str, list[Bar]]], learned_label: str | None, trajectories: list[str],
                   names: dict[str, str], paper_lift: float | None, matched: bool) -> tuple[list, list[str]]:
    """One entry per encoding, each said once: a colour per trajectory, then the hatch (baselines at the paper's
    H), the plain baseline (matched lift), the error bar, the × and the fading (each only where shown)."""
    handles: list = [Patch(facecolor=COLORS.get(n, "gray"), edgecolor="k", lw=0.5) for n in trajectories]
    labels = [learned_label if n == "learned" and learned_label else names.get(n, n) for n in trajectories]
    if paper_lift is not None:
        handles.append(Patch(facecolor="white", edgecolor="k", lw=0.5, hatch=PAPER_HATCH))
        labels.append(f"hatched: baseline at H = {paper_lift:.2f} m, the paper's protocol")
    if matched:
        handles.append(Patch(facecolor="white", edgecolor="k", lw=0.5))
        labels.append("plain baseline in (a): at each learned seed's own H (matched, Table 5's headline)")
    handles.append(Line2D([], [], color="k", marker="|", ms=10, ls="none"))
    labels.append("error bar: 95 % CI across seeds")
    shown = [b for g in bar_groups for vals in g.values() for b in vals if math.isfinite(b[0])]
    if any(bad for _, _, bad, _ in shown):
        handles.append(Line2D([], [], color="k", marker=MISS_MARKER, ms=6, mew=1.5, ls="none"))
        labels.append(f"× k/n: k of the bar's n walks fell or missed the speed by > {100 * SPEED_BAND:g} % "
                      "(the bar: mean of the others)")
    if any(n and bad == n for _, _, bad, n in shown):
        handles.append(Patch(facecolor="gray", alpha=FADED_ALPHA, edgecolor="k", lw=0.5))
        labels.append("faded: none of the bar's walks counted (drawn as walked)")
    return handles, labels


@styled
def draw(rows: list[dict], prototype_rows: list[dict] | None = None) -> Figure:
    """`rows`: comparison rows (energy_kJ per walk); `prototype_rows`: prototype walks, or None for (a) only."""
    robots = prototype_robots(prototype_rows) if prototype_rows else []
    fig = Figure(figsize=(6 * (1 + len(robots)), 5.4))
    axes = fig.subplots(1, 1 + len(robots), squeeze=False)[0]
    speeds, groups, styles = simulation_groups(rows)
    duration = max((r["duration_s"] for r in rows if r["set"] == "paper"), default=math.nan)
    bars(axes[0], speeds, groups, "energy over the walk, Eq. (7) (kJ)",
         f"(a) simulation, {duration:g} s walks (Table 5)", styles)
    shown, drawn = [groups], list(styles.values())
    for ax, robot, tag in zip(axes[1:], robots, "bc"):
        p_speeds, pgroups, pstyles = prototype_groups(prototype_rows, robot)
        bars(ax, p_speeds, pgroups, f"battery used per {PAPER_DISTANCE_M:g} m, Eq. (13) (% of the pack)",
             f"({tag}) prototype in simulation, {robot}{'-like' if robot == 'hardware' else ''} robot:\n"
             f"{walk_length(prototype_rows)}, per {PAPER_DISTANCE_M:g} m", pstyles)
        shown.append(pgroups)
        drawn += pstyles.values()
    paper = [r["lift_height_m"] for r in rows if r["set"] == "paper" and r["trajectory"] in ("cycloid", "straight")]
    handles, labels = legend_handles(shown, next((k for k in groups if k.startswith(NAMES["learned"])), None),
                                     [n for n in COLORS if COLORS[n] in {c for c, _ in drawn}],
                                     trajectory_names(rows), paper[0] if paper else None,
                                     any("matched lift" in k for k in groups))
    fig.legend(handles, labels, loc="upper center", bbox_to_anchor=(0.5, 0.0), ncol=2, fontsize=7.5,
               frameon=False)
    fig.suptitle("Figure 13: energy against speed, by foot trajectory", fontsize=10, y=1.0)
    return fig


def figure13(rows: list[dict], out_dir: str | Path, prototype_rows: list[dict] | None = None, **save) -> list[Path]:
    """Draw Figure 13 and write it into `out_dir`."""
    return save_figure(draw(rows, prototype_rows), out_dir, STEM, **save)


__all__ = ["MISS_MARKER", "PAPER_HATCH", "STEM", "bars", "draw", "figure13", "legend_handles",
           "per_speed", "prototype_counts", "prototype_groups", "prototype_robots", "simulation_groups",
           "trajectory_names", "walk_length"]
