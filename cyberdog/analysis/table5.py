"""Table 5 as the paper lays it out, and the headline summary across seeds (markdown and CSV-ready rows).

Input: the rows of `cyberdog.analysis.compare.comparison_rows` (every walk in its set, with D_t) and the
across-seed means of `compare.seed_means`. Two sets: "same_lift" (the headline: the baselines at the learned
path's own lift height, same step length and period) and "paper" (the baselines at the paper's H = 0.15 m).
"""
from __future__ import annotations

import math

from cyberdog.analysis.comparison_sets import BASELINES, LIFT_DECIMALS, REFERENCE, SETS, same_lift
from cyberdog.analysis.stats import mean_ci
from cyberdog.config.paper import PAPER_SPEEDS

# the paper's Table 5, kJ over the 10 s walk, for reference beside ours
PAPER_TABLE5_KJ = {
    "learned": (1.6236, 1.8152, 2.8261),
    "cycloid": (1.8451, 2.0489, 3.1021),
    "straight": (2.3571, 2.7571, 3.2871),
    "decrement_pct": (12.0, 11.0, 9.0),
}

def table5_rows(rows: list[dict]) -> list[dict]:
    """Table 5, machine-readable: one row per (set, trajectory, seed, speed) with E (kJ) and status, plus a
    "decrement" row per (set, seed, speed) with D_t (%) by Eq. (12) on those E."""
    out = []
    for r in rows:
        out.append({"set": r["set"], "row": r["trajectory"], "label": r["label"], "seed": r["seed"],
                    "lift_height_m": r["lift_height_m"], "speed_mps": r["speed_command_mps"],
                    "energy_kJ": r["energy_kJ"], "valid": r["valid"], "status": r["status"],
                    "D_t_pct": r["D_t_pct"], "D_t_per_100m_pct": r["D_t_per_100m_pct"],
                    "E_min_trajectory": r["E_min_trajectory"]})
    return out


def _cell(r: dict) -> str:
    if r["fell"]:
        return f"fell ({r['duration_s']:.1f} s)"
    txt = f"{r['energy_kJ']:.4f}"
    return txt if r["speed_ok"] else f"{txt} (miss: {r['mean_speed_mps']:.2f} m/s)"


def _mean_cell(m: dict) -> str:
    if not math.isfinite(m["energy_kJ_mean"]):
        return f"no valid walk (n = {m['n_seeds']})"
    ci = f" ± {m['energy_kJ_ci95']:.4f}" if math.isfinite(m["energy_kJ_ci95"]) else ""
    return f"{m['energy_kJ_mean']:.4f}{ci} (n = {m['n_valid']} of {m['n_seeds']})"


def _pct(x: float, ci: float | None = None) -> str:
    if not math.isfinite(x):
        return "–"
    return f"{x:.1f} %" + (f" ± {ci:.1f}" if ci is not None and math.isfinite(ci) else "")


def table5_markdown(rows: list[dict], means: list[dict] | None = None) -> str:
    """Table 5 in the paper's layout (energy in kJ over the walk; columns = speeds), both sets, then the
    paper's own numbers for reference. Cells of walks that fell or missed the speed say so."""
    speeds = list(dict.fromkeys(r["speed_command_mps"] for r in rows))
    lines = ["| Energy (kJ) over the walk | " + " | ".join(f"{v:g} m/s" for v in speeds) + " |",
             "|---|" + "---|" * len(speeds)]
    means = means or []
    all_seeds = list(dict.fromkeys(r["seed"] for r in rows if r["trajectory"] == "learned"))
    for set_name in SETS:
        set_rows = [r for r in rows if r["set"] == set_name]
        if not set_rows:
            continue
        # groups of rows sharing the baselines' lift height (one group in the paper set)
        lifts = list(dict.fromkeys(round(r["lift_height_m"], LIFT_DECIMALS) for r in set_rows
                                   if r["trajectory"] in BASELINES))
        for lift in lifts:
            lines += _lift_group_lines(set_name, set_rows, lift, all_seeds, speeds, means)
        if len(all_seeds) > 1 and set_name == "same_lift":
            ms = _means_at(means, set_name, speeds)
            lines.append(_line("Decrement D_t at the same lift, mean ± 95 % CI",
                               [_pct(m["D_t_pct_mean"], m["D_t_pct_ci95"]) if m else "" for m in ms]))
    return "\n".join(lines + _paper_lines(speeds))


def _line(label: str, cells: list[str]) -> str:
    return f"| {label} | " + " | ".join(cells) + " |"


def _pick(group: list[dict], traj: str, seed: str, v: float) -> dict | None:
    return next((r for r in group if r["trajectory"] == traj and r["speed_command_mps"] == v
                 and (traj != "learned" or r["seed"] == seed)), None)


def _means_at(means: list[dict], set_name: str, speeds: list[float]) -> list[dict | None]:
    return [next((m for m in means if m["set"] == set_name and m["speed_command_mps"] == v), None) for v in speeds]


def _lift_group_lines(set_name: str, set_rows: list[dict], lift: float, all_seeds: list[str], speeds: list[float],
                      means: list[dict]) -> list[str]:
    """The rows of one set sharing the baselines' lift height `lift`: learned, baselines, D_t (and in the paper
    set the across-seed means)."""
    lines = []
    seeds = [s for s in all_seeds if any(r["trajectory"] == "learned" and r["seed"] == s for r in set_rows)]
    if set_name == "same_lift":
        seeds = [s for s in seeds if any(r["trajectory"] == "learned" and r["seed"] == s
                                         and same_lift(r["lift_height_m"], lift) for r in set_rows)]
        lines.append(_line(f"*control: baselines at the learned lift height H = {lift:.3f} m*", [""] * len(speeds)))
    base = [r for r in set_rows if r["trajectory"] in BASELINES and same_lift(r["lift_height_m"], lift)]
    group = base + [r for r in set_rows if r["trajectory"] == "learned" and r["seed"] in seeds
                    and (set_name != "same_lift" or same_lift(r["lift_height_m"], lift))]  # matched: its own walks
    for s in seeds:
        lr = [_pick(group, "learned", s, v) for v in speeds]
        # each walk's own lift, in the columns' order: one number when the seed's paths share it
        lifts = list(dict.fromkeys(f"{r['lift_height_m']:.3f}" for r in lr if r))
        h = lifts[0] if len(lifts) == 1 else " / ".join(f"{r['lift_height_m']:.3f}" if r else "–" for r in lr)
        tag = f" [{s}]" if s else ""
        lines.append(_line(f"Learned trajectory (H = {h} m){tag}", [_cell(r) if r else "" for r in lr]))
    for name in BASELINES:
        br = [_pick(group, name, "", v) for v in speeds]
        first = next((r for r in br if r), None)
        if first is None:
            continue
        shape = first["label"].partition("(")[2].rstrip(")")
        nice = "Composite cycloid" if name == "cycloid" else "Straight line" + (f", {shape}" if shape else "")
        lines.append(_line(f"{nice} (H = {first['lift_height_m']:.3f} m)", [_cell(r) if r else "" for r in br]))
    for s in seeds:
        lr = [_pick(group, "learned", s, v) for v in speeds]
        tag = f" [{s}]" if len(seeds) > 1 else ""
        lines.append(_line(f"Decrement D_t, Eq. (12){tag}", [_pct(r["D_t_pct"]) if r else "" for r in lr]))
    if len(seeds) > 1 and set_name == "paper":
        ms = _means_at(means, set_name, speeds)
        lines.append(_line(f"Learned, mean ± 95 % CI over {len(seeds)} seeds", [_mean_cell(m) if m else "" for m in ms]))
        lines.append(_line("Decrement D_t, mean ± 95 % CI",
                           [_pct(m["D_t_pct_mean"], m["D_t_pct_ci95"]) if m else "" for m in ms]))
    return lines


def _paper_lines(speeds: list[float]) -> list[str]:
    """The paper's own Table 5 at the speeds it has (none if it has none of them)."""
    p = PAPER_TABLE5_KJ
    idx = [PAPER_SPEEDS.index(v) if v in PAPER_SPEEDS else None for v in speeds]
    if all(i is None for i in idx):
        return []
    lines = [_line(f"*paper, Table 5: {label}*", [f"{p[key][i]:.4f}" if i is not None else "" for i in idx])
             for key, label in (("learned", "simulation trajectory"), ("cycloid", "composite cycloid"),
                                ("straight", "straight line"))]
    return lines + [_line("*paper, Table 5: decrement*", [f"{p['decrement_pct'][i]:.0f} %" if i is not None else ""
                                                          for i in idx])]


# ---------------------------------------------------------------------------------------------------------
# the headline: per set and speed, across seeds
# ---------------------------------------------------------------------------------------------------------

SUMMARY_QUANTITIES = (  # (row key, label, unit scale, format)
    ("energy_kJ", "E, Eq. (7) (kJ)", 1.0, "{:.3f}"),
    ("electrical_energy_J", "electrical energy (kJ)", 1e-3, "{:.3f}"),
    ("positive_work_J", "positive mechanical work (kJ)", 1e-3, "{:.3f}"),
    ("foot_slip_mm_per_cycle", "foot slip (mm per foot and cycle)", 1.0, "{:.1f}"),
)


def summary_rows(rows: list[dict]) -> list[dict]:
    """Per set and speed: each quantity of `SUMMARY_QUANTITIES` for the learned walks and for each baseline
    walk it was compared with (its own lift height in "same_lift", the paper's in "paper"), mean and 95 %
    CI half-width over the seeds whose learned walk is valid; D_t (Eq. 12) on E and on the electrical energy.
    """
    out = []
    learned = [r for r in rows if r["trajectory"] == "learned"]
    for set_name in SETS:
        for v in dict.fromkeys(r["speed_command_mps"] for r in learned):
            mine = [r for r in learned if r["set"] == set_name and r["speed_command_mps"] == v]
            if not mine:
                continue
            ok = [r for r in mine if r["valid"]]
            row = {"set": set_name, "speed_command_mps": v, "n_seeds": len(mine), "n_valid": len(ok)}
            groups = {"learned": ok}
            for name in BASELINES:
                same = [b for b in rows if b["set"] == set_name and b["trajectory"] == name
                        and b["speed_command_mps"] == v]
                if set_name == "same_lift":  # one baseline walk per learned walk, at that walk's lift height
                    group = [next((b for b in same if same_lift(b["lift_height_m"], r["lift_height_m"])), None)
                             for r in ok]
                    groups[name] = [b for b in group if b is not None]
                else:  # the one walk at the paper's lift height
                    groups[name] = same[:1]
            reference = [b for b in rows if b["set"] == set_name and b["trajectory"] == REFERENCE
                         and b["speed_command_mps"] == v]
            if reference:  # the direct search's shape: one walk per speed, at its own lift height
                groups[REFERENCE] = reference[:1]
                row[f"{REFERENCE}_lift_height_m"] = reference[0]["lift_height_m"]
                row[f"{REFERENCE}_valid"] = reference[0]["valid"]
            for key, _, scale, _ in SUMMARY_QUANTITIES:
                for name, group in groups.items():
                    m, ci = mean_ci([scale * b[key] for b in group])
                    row[f"{name}_{key}_mean"], row[f"{name}_{key}_ci95"] = m, ci
            row["lift_height_m_mean"], row["lift_height_m_ci95"] = mean_ci([r["lift_height_m"] for r in ok])
            for key in ("D_t_pct", "D_t_electrical_pct") + (("D_ref_pct", "D_ref_electrical_pct") if reference else ()):
                row[f"{key}_mean"], row[f"{key}_ci95"] = mean_ci([r[key] for r in ok])
            row["mean_speed_min_mps"] = min((r["mean_speed_mps"] for r in mine), default=float("nan"))
            row["mean_speed_max_mps"] = max((r["mean_speed_mps"] for r in mine), default=float("nan"))
            out.append(row)
    return out


def _mci(m: float, ci: float, fmt: str) -> str:
    if not math.isfinite(m):
        return "–"
    return fmt.format(m) + (f" ± {fmt.format(ci)}" if math.isfinite(ci) else "")


def summary_markdown(summary: list[dict], set_name: str, brief: bool = False) -> str:
    """One set of `summary_rows` as a table: rows = quantities, columns = speeds; mean ± 95 % CI over seeds.
    `brief`: the valid walks, the lift height, E of each trajectory and both D_t only (the main job's summary)."""
    rows = [r for r in summary if r["set"] == set_name]
    if not rows:
        return ""
    lines = ["| mean ± 95 % CI over seeds | " + " | ".join(f"{r['speed_command_mps']:g} m/s" for r in rows) + " |",
             "|---|" + "---|" * len(rows)]

    def line(label: str, cells: list[str]) -> None:
        lines.append(f"| {label} | " + " | ".join(cells) + " |")

    line("learned walks valid (no fall, speed ±5 %)", [f"{r['n_valid']} of {r['n_seeds']}" for r in rows])
    line("lift height H of the learned path (m)",
         [_mci(r["lift_height_m_mean"], r["lift_height_m_ci95"], "{:.4f}") for r in rows])
    has_reference = all(f"{REFERENCE}_lift_height_m" in r for r in rows) and not brief
    names = {"learned": "learned", "cycloid": "composite cycloid", "straight": "straight line"}
    if has_reference:
        names[REFERENCE] = f"searched shape (H = {rows[0][f'{REFERENCE}_lift_height_m']:.3f} m, reference)"
    for key, label, _, fmt in SUMMARY_QUANTITIES[:1] if brief else SUMMARY_QUANTITIES:  # brief: E only
        for name in ("learned",) + BASELINES + ((REFERENCE,) if has_reference else ()):
            line(f"{label}, {names[name]}", [_mci(r[f"{name}_{key}_mean"], r[f"{name}_{key}_ci95"], fmt)
                                             for r in rows])
    line("**D_t, Eq. (12), on E (%)**", [f"**{_mci(r['D_t_pct_mean'], r['D_t_pct_ci95'], '{:.1f}')}**"
                                          for r in rows])
    line("D_t on the electrical energy (%)",
         [_mci(r["D_t_electrical_pct_mean"], r["D_t_electrical_pct_ci95"], "{:.1f}") for r in rows])
    if has_reference:
        line("learned against the searched shape, Eq. (12)'s formula, on E (%)",
             [_mci(r["D_ref_pct_mean"], r["D_ref_pct_ci95"], "{:.1f}") for r in rows])
        line("learned against the searched shape, on the electrical energy (%)",
             [_mci(r["D_ref_electrical_pct_mean"], r["D_ref_electrical_pct_ci95"], "{:.1f}") for r in rows])
    return "\n".join(lines)
