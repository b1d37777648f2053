"""The paper's figures from saved results (matplotlib, Agg backend; every figure as PNG and PDF).

Plotting never runs physics: each function takes trajectories, training logs or the rows and power traces
written by the comparison and prototype experiments, and returns the paths it wrote.

- Figure 4: the composite cycloid and straight-line foot trajectories (x–z), at the paper's S, H.
- Figure 6: reward (episode score) curves of training stages 1 and 2 from `metrics.csv`.
- Figure 7: the extracted learned trajectory beside the two baselines (x–z path, x and z against phase).
- Figure 10: total joint power Σ|τ·θ̇| over two gait cycles for the three trajectories, one panel per speed.
- Figure 13: energy (Eq. 7) and battery use (prototype experiment, Eq. 13) against speed, per trajectory.
"""
from __future__ import annotations

import csv
import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from cyberdog.analysis.stats import mean_ci, mean_ci_band  # noqa: E402
from cyberdog.core.trajectories import CompositeCycloid, FootTrajectory, StraightLine  # noqa: E402

COLORS = {"learned": "tab:green", "cycloid": "tab:blue", "straight": "tab:red"}
SEED_COLORS = ("tab:purple", "tab:orange", "tab:brown", "tab:olive", "tab:cyan", "tab:pink", "tab:gray")
NAMES = {"learned": "learned (RL)", "cycloid": "composite cycloid", "straight": "straight line"}
plt.rcParams.update({"font.size": 10, "axes.titlesize": 11, "axes.labelsize": 10, "legend.fontsize": 8.5})


def save_figure(fig, out_dir: str | Path, stem: str) -> list[Path]:
    """Write `<stem>.png` (150 dpi) and `<stem>.pdf` into `out_dir`; close the figure."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    paths = [out / f"{stem}.png", out / f"{stem}.pdf"]
    fig.savefig(paths[0], dpi=150, bbox_inches="tight")
    fig.savefig(paths[1], bbox_inches="tight")
    plt.close(fig)
    return paths


def cycle_path(traj: FootTrajectory, step_length: float, lift_height: float, swing_time: float = 0.2,
               stance_time: float = 0.2, n: int = 400) -> tuple[np.ndarray, np.ndarray]:
    """Phases (n,) and foot positions (n, 2) = (x, z), m, over one gait cycle."""
    phase = np.arange(n) / n
    pos, _ = traj.position_velocity(phase, step_length, lift_height, swing_time, stance_time)
    return phase, pos


# ---------------------------------------------------------------------------------------------------------
# Figure 4
# ---------------------------------------------------------------------------------------------------------

def figure4(out_dir, step_length: float = 0.2, lift_height: float = 0.15, straight_shape: str = "rectangle",
            swing_time: float = 0.2, stance_time: float = 0.2) -> list[Path]:
    """The two common foot trajectories over one cycle (swing solid, stance dashed), x–z, in cm."""
    fig, axes = plt.subplots(1, 2, figsize=(9, 3.4), sharey=True)
    beta = swing_time / (swing_time + stance_time)
    for ax, (key, traj, tag) in zip(axes, (("cycloid", CompositeCycloid(), "(a)"),
                                           ("straight", StraightLine(straight_shape), "(b)"))):
        phase, p = cycle_path(traj, step_length, lift_height, swing_time, stance_time)
        sw = phase < beta
        ax.plot(100 * p[sw, 0], 100 * p[sw, 1], color=COLORS[key], lw=2, label="swing")
        ax.plot(100 * p[~sw, 0], 100 * p[~sw, 1], color=COLORS[key], lw=2, ls="--", label="stance")
        ax.plot(100 * p[0, 0], 100 * p[0, 1], "ko", ms=4, label="lift-off")
        ax.annotate("", xy=(100 * p[len(p) // 8 + 1, 0], 100 * p[len(p) // 8 + 1, 1]),
                    xytext=(100 * p[len(p) // 8, 0], 100 * p[len(p) // 8, 1]),
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
    return save_figure(fig, out_dir, "figure4_baseline_trajectories")


# ---------------------------------------------------------------------------------------------------------
# Figure 6
# ---------------------------------------------------------------------------------------------------------

def read_metrics(path: str | Path) -> dict[int, dict[str, np.ndarray]]:
    """Per training stage: stage_episode and score arrays from a trainer's `metrics.csv`."""
    stages: dict[int, dict[str, list]] = {}
    with open(path, newline="") as f:
        for row in csv.DictReader(f):
            try:
                stage, ep, score = int(row["stage"]), int(row["stage_episode"]), float(row["score"])
            except (KeyError, ValueError):
                continue
            d = stages.setdefault(stage, {"episode": [], "score": []})
            d["episode"].append(ep)
            d["score"].append(score)
    return {s: {k: np.asarray(v, dtype=float) for k, v in d.items()} for s, d in sorted(stages.items())}


def moving_average(x: np.ndarray, window: int) -> np.ndarray:
    """Trailing mean over up to `window` points (the first points average what exists)."""
    x = np.asarray(x, dtype=float)
    c = np.cumsum(np.insert(x, 0, 0.0))
    idx = np.arange(1, len(x) + 1)
    lo = np.maximum(0, idx - window)
    return (c[idx] - c[lo]) / (idx - lo)


def figure6(metrics: dict[str, str | Path], out_dir, window: int | None = None) -> list[Path]:
    """Episode score against episode for stage 1 and stage 2, per run (faint) with a moving average; with
    several runs also their mean and 95 % CI band."""
    logs = {label: read_metrics(p) for label, p in metrics.items()}
    fig, axes = plt.subplots(1, 2, figsize=(10, 3.6))
    for ax, stage, tag in zip(axes, (1, 2), ("(a)", "(b)")):
        curves = []
        for i, (label, log) in enumerate(logs.items()):
            if stage not in log:
                continue
            ep, score = log[stage]["episode"], log[stage]["score"]
            w = window or max(1, min(250, len(score) // 10))
            ma = moving_average(score, w)
            curves.append(ma)
            color = f"C{i % 10}"
            ax.plot(ep, score, color=color, alpha=0.25, lw=0.7)
            ax.plot(ep, ma, color=color, lw=1.6, label=label + (f" (moving mean of {w})" if w > 1 else ""))
        if len(curves) > 1:
            n = min(len(c) for c in curves)
            m, ci = mean_ci_band(np.stack([c[:n] for c in curves]))
            x = np.arange(1, n + 1)
            ax.plot(x, m, color="k", lw=2, label=f"mean of {len(curves)} runs")
            ax.fill_between(x, m - np.nan_to_num(ci), m + np.nan_to_num(ci), color="k", alpha=0.15,
                            label="95 % CI")
        if not curves:
            ax.text(0.5, 0.5, f"no stage-{stage} episodes in the log", ha="center", va="center",
                    transform=ax.transAxes)
        what = "speed and direction, E = 0" if stage == 1 else "with the energy term, Eq. (11)"
        ax.set_title(f"{tag} stage {stage}: {what}")
        ax.set_xlabel("episode (within the stage)")
        ax.set_ylabel("episode score Σ r_t")
        ax.grid(alpha=0.3)
        if curves:
            ax.legend(loc="lower right")
    fig.suptitle("Figure 6: reward curves of the two training stages", fontsize=10)
    return save_figure(fig, out_dir, "figure6_reward_curves")


# ---------------------------------------------------------------------------------------------------------
# Figure 7
# ---------------------------------------------------------------------------------------------------------

def figure7(learned: dict, out_dir, straight_shape: str = "rectangle", paper_lift: float = 0.15,
            swing_time: float = 0.2, stance_time: float = 0.2) -> list[Path]:
    """The learned trajectory (each seed) beside the baselines at the learned S and H (solid) and at the
    paper's H (dotted): (a) x–z path, (b) x against phase, (c) z against phase."""
    fig, axes = plt.subplots(1, 3, figsize=(13, 3.8), gridspec_kw={"width_ratios": [1.4, 1, 1]})
    first = next(iter(learned.values()))
    S, H = first.step_length, first.lift_height
    series = []
    for i, (label, traj) in enumerate(learned.items()):
        name = NAMES["learned"] + (f" [{label}]" if len(learned) > 1 or label else "")
        color = COLORS["learned"] if i == 0 else SEED_COLORS[(i - 1) % len(SEED_COLORS)]
        series.append((name + f", H = {traj.lift_height:.3f} m", traj, traj.step_length, traj.lift_height,
                       color, "-", 2.2))
    for key, traj in (("cycloid", CompositeCycloid()), ("straight", StraightLine(straight_shape))):
        shape = "" if key == "cycloid" else f" ({straight_shape})"
        series.append((f"{NAMES[key]}{shape}, H = {H:.3f} m", traj, S, H, COLORS[key], "-", 1.4))
        series.append((f"{NAMES[key]}{shape}, H = {paper_lift:.2f} m (paper)", traj, S, paper_lift,
                       COLORS[key], ":", 1.2))
    for name, traj, s, h, color, ls, lw in series:
        phase, p = cycle_path(traj, s, h, swing_time, stance_time)
        axes[0].plot(100 * p[:, 0], 100 * p[:, 1], color=color, ls=ls, lw=lw, label=name)
        axes[1].plot(phase, 100 * p[:, 0], color=color, ls=ls, lw=lw)
        axes[2].plot(phase, 100 * p[:, 1], color=color, ls=ls, lw=lw)
    for label, traj in learned.items():
        axes[0].plot(100 * traj.x, 100 * traj.z, ".", color="k", ms=2)
    axes[0].plot([], [], ".", color="k", ms=3, label="extracted samples")
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
    for ax in axes:
        ax.grid(alpha=0.3)
    prov = first.provenance
    if prov.get("path") == "commanded":  # the commanded path of one leg, averaged over the settled cycles
        used = prov.get("cycles_used", [])
        which = (f"LF's commanded path, mean of {len(used)} cycles" if prov.get("cycle") == "mean"
                 else f"LF's commanded path, cycle {used[0] if used else '?'}")
    else:
        which = f"cycle {prov.get('cycle_index', '?')}"
    info = (f"{which} of the rollout at {prov.get('speed_command_mps', '?')} m/s "
            f"(seed {prov.get('seed', '?')}), E = {prov.get('cycle_energy_J', float('nan')):.1f} J per cycle"
            if prov else "")
    fig.suptitle(f"Figure 7: extracted learned foot trajectory (S = {S:.2f} m; {info})", fontsize=10)
    return save_figure(fig, out_dir, "figure7_learned_trajectory")


# ---------------------------------------------------------------------------------------------------------
# Figure 10
# ---------------------------------------------------------------------------------------------------------

def figure10(walks: list[dict], power: dict[int, np.ndarray], out_dir, lift_height: float | None = None,
             cycles: int = 2) -> list[Path]:
    """Total joint power over the last `cycles` whole gait cycles of each 10 s walk, one panel per speed:
    the first learned seed and the baselines at `lift_height` (default: the paper set's, the highest)."""
    from cyberdog.analysis.compare import two_cycle_window

    speeds = sorted(dict.fromkeys(w["speed_command_mps"] for w in walks))
    base_lifts = [w["lift_height_m"] for w in walks if w["trajectory"] != "learned"]
    lift = lift_height if lift_height is not None else (max(base_lifts) if base_lifts else None)
    seeds = list(dict.fromkeys(w["seed"] for w in walks if w["trajectory"] == "learned"))
    fig, axes = plt.subplots(1, len(speeds), figsize=(4.2 * len(speeds), 3.6), sharey=True, squeeze=False)
    for ax, v, tag in zip(axes[0], speeds, "abcdefgh"):
        for key in ("learned", "cycloid", "straight"):
            cand = [w for w in walks if w["trajectory"] == key and w["speed_command_mps"] == v
                    and (key != "learned" or not seeds or w["seed"] == seeds[0])
                    and (key == "learned" or lift is None or abs(w["lift_height_m"] - lift) < 5e-5)]
            if not cand:
                continue
            w = cand[0]
            p = np.asarray(power[w["walk_id"]], dtype=float)
            dt, period = w["physics_dt_s"], w["period_s"]
            win = two_cycle_window(len(p), dt, period, cycles)
            name = w["label"] if key != "learned" else NAMES["learned"]
            seg = p[win]
            if w["fell"] or len(seg) == 0:
                ax.plot([], [], color=COLORS[key], label=f"{name}: fell, no steady cycles")
                continue
            t = np.arange(len(seg)) * dt
            e_win = float(seg.sum() * dt)
            note = "" if w["speed_ok"] else " (speed miss)"
            ax.plot(t, seg, color=COLORS[key], lw=1.1,
                    label=f"{name}, H = {w['lift_height_m']:.3f} m: {e_win:.0f} J{note}")
        for k in range(1, cycles):
            ax.axvline(k * period, color="gray", ls="--", lw=0.8)
        ax.set_title(f"({tag}) {v:g} m/s")
        ax.set_xlabel(f"time in the last {cycles} gait cycles (s)")
        ax.grid(alpha=0.3)
        ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.18), fontsize=7.5)
    axes[0][0].set_ylabel("total joint power Σ|τ·θ̇| (W)")
    fig.suptitle("Figure 10: joint power over two gait cycles (energy of the window in the legend)",
                 fontsize=10)
    return save_figure(fig, out_dir, "figure10_power")


# ---------------------------------------------------------------------------------------------------------
# Figure 13
# ---------------------------------------------------------------------------------------------------------

def _bars(ax, speeds, groups: dict[str, list[tuple[float, float, bool]]], ylabel: str, title: str,
          styles: dict[str, tuple[str, str | None]]) -> None:
    """Grouped bars: per speed one bar per group (value, CI half-width, valid); `styles` gives each group's
    colour and hatch; bars of walks that fell or missed the speed are faded with a cross-hatch."""
    keys = list(groups)
    width = 0.8 / max(1, len(keys))
    x = np.arange(len(speeds))
    for i, key in enumerate(keys):
        color, hatch = styles[key]
        for j, (val, ci, ok) in enumerate(groups[key]):
            if not math.isfinite(val):
                continue
            ax.bar(x[j] + (i - (len(keys) - 1) / 2) * width, val, width, color=color, alpha=1.0 if ok else 0.35,
                   hatch=hatch if ok else "xx", edgecolor="k", lw=0.5,
                   yerr=ci if math.isfinite(ci) else None, capsize=3, label=key if j == 0 else None)
    ax.set_xticks(x, [f"{v:g} m/s" for v in speeds])
    ax.set_xlabel("commanded speed")
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    ax.grid(alpha=0.3, axis="y")
    ax.legend(fontsize=7.5, loc="upper center", bbox_to_anchor=(0.5, -0.2), ncol=2)


def figure13(rows: list[dict], out_dir, prototype_rows: list[dict] | None = None) -> list[Path]:
    """(a) E by Eq. (7) over the 10 s walk against speed (the paper set; learned: mean ± 95 % CI over seeds
    when there are several; faded and cross-hatched = fell or missed the speed); (b) battery used per 100 m
    (Eq. 13) in the prototype experiment, ideal (plain) and hardware-like (dotted) robot."""
    paper = [r for r in rows if r["set"] == "paper"]
    speeds = sorted(dict.fromkeys(r["speed_command_mps"] for r in paper))
    groups: dict[str, list] = {}
    styles: dict[str, tuple] = {}
    for key in ("learned", "cycloid", "straight"):
        mine = [r for r in paper if r["trajectory"] == key]
        if not mine:
            continue
        vals = []
        for v in speeds:
            sel = [r for r in mine if r["speed_command_mps"] == v]
            ok = [r["energy_kJ"] for r in sel if r["valid"]]
            if ok:
                vals.append((*mean_ci(ok), True))
            elif sel:
                vals.append((float(np.mean([r["energy_kJ"] for r in sel])), float("nan"), False))
            else:
                vals.append((float("nan"), float("nan"), False))
        n_seeds = len(dict.fromkeys(r["seed"] for r in mine))
        if n_seeds > 1:
            label = f"{NAMES['learned']}, mean ± 95 % CI of {n_seeds} seeds (own H)"
        else:
            label = (mine[0]["label"] if key != "learned" else NAMES["learned"]) + \
                f" (H = {mine[0]['lift_height_m']:.3f} m)"
        groups[label] = vals
        styles[label] = (COLORS[key], None)
    n_panels = 2 if prototype_rows else 1
    fig, axes = plt.subplots(1, n_panels, figsize=(6 * n_panels, 4.4), squeeze=False)
    duration = max((r["duration_s"] for r in paper), default=float("nan"))
    _bars(axes[0][0], speeds, groups, "energy over the walk, Eq. (7) (kJ)",
          f"(a) simulation, {duration:g} s walks (Table 5)", styles)
    if prototype_rows:
        p_speeds = sorted(dict.fromkeys(r["speed_mps"] for r in prototype_rows))
        pgroups: dict[str, list] = {}
        pstyles: dict[str, tuple] = {}
        for name in dict.fromkeys(r["trajectory"] for r in prototype_rows):
            for robot in ("ideal", "hardware"):
                vals = []
                for v in p_speeds:
                    r = next((r for r in prototype_rows if r["trajectory"] == name and r["speed_mps"] == v
                              and r["robot"] == robot), None)
                    if r is None or not r["distance_m"] > 0:
                        vals.append((float("nan"), float("nan"), False))
                        continue
                    vals.append((100.0 * r["battery_used_pct"] / r["distance_m"], float("nan"),
                                 bool(r["reached"]) and not r["fell"]))
                if any(math.isfinite(v[0]) for v in vals):
                    key = f"{name} ({robot} robot)"
                    pgroups[key] = vals
                    pstyles[key] = (COLORS.get(name.split(" ")[0], "gray"), ".." if robot == "hardware" else None)
        _bars(axes[0][1], p_speeds, pgroups, "battery used per 100 m, Eq. (13) (% of the pack)",
              "(b) prototype experiment in simulation", pstyles)
    fig.suptitle("Figure 13: energy against speed, by foot trajectory (faded, cross-hatched: the walk fell or "
                 "missed the speed by > 5 %)", fontsize=10)
    return save_figure(fig, out_dir, "figure13_energy_vs_speed")


__all__ = ["cycle_path", "figure10", "figure13", "figure4", "figure6", "figure7", "moving_average",
           "read_metrics", "save_figure"]
