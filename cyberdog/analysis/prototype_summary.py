"""The prototype experiment at scale: across seeds and hardware draws, per robot, speed and trajectory.

`run_prototype` walks every learned seed's path and the two common trajectories at that path's lift height on
several hardware-like robots (draws). This module reduces its rows to what the paper reports (Section 4.2),
each as a mean and a 95 % Student-t interval across seeds (`cyberdog.analysis.stats.mean_ci`): battery used
per 100 m (Eq. 13), Eq. (7) and electrical energy per 100 m, the electrical cost of transport and the range on
a full charge (the paper's 3,600 → 3,924 m at 1 m/s). A seed's value is the mean over its draws; only walks
that reached the distance without falling and held the ±5 % speed band count (`walk_counts`), and the rows
say how many did and how many fell, so a replay that falls is reported, never dropped silently. Where a walk
stood but did not count (it left the band, or ran out of time before the distance), the row also gives the
saving counting every walk that did not fall (`walk_stood`: battery per metre of the distance it walked), so a
slow and costly walk left out of the mean shows what it would have cost the mean.

The learned rows also carry the saving the paper measured on the battery: per seed and draw, Eq. (12)'s
D = 100·(1 − B_learned / B_min) on the battery used per metre, against the cheaper of the common trajectories
(`COMMON`) that counted on the same robot at the same lift, then averaged over draws and across seeds. Where
the run walked the direct search's shape (`REFERENCE`, "searched"), the same saving against it alone says how
close the learned path comes to a shape searched for the battery (negative: the searched shape is cheaper).
"""
from __future__ import annotations

import math

from cyberdog.analysis.report import markdown_table
from cyberdog.analysis.stats import mean_ci
from cyberdog.config.paper import PAPER_DISTANCE_M, speed_within_band

COMMON = ("cycloid", "straight")  # the paper's common trajectories: what the learned path's saving is against
REFERENCE = "searched"  # the prototype run's reference row: a shape the direct search found for the battery
# metric name → its value per walk (per 100 m where it is an amount; NaN where a row lacks the field, as the
# figures' exported inputs do)
METRICS = {
    "battery_pct_per_100m": lambda r: PAPER_DISTANCE_M * r["battery_used_pct"] / r["distance_m"],
    "energy_kJ_per_100m": lambda r: 0.1 * r.get("energy_J", math.nan) / r["distance_m"],
    "electrical_kJ_per_100m": lambda r: 0.1 * r.get("electrical_energy_J", math.nan) / r["distance_m"],
    "electrical_cost_of_transport": lambda r: r.get("electrical_cost_of_transport", math.nan),
    "range_full_charge_m": lambda r: r.get("range_full_charge_m", math.nan),
}


def walk_counts(row: dict) -> bool:
    """A prototype walk counts if it reached the distance, did not fall and kept the speed band."""
    return (bool(row["reached"]) and not row["fell"]
            and speed_within_band(row["mean_speed_mps"], row["speed_mps"]))


def walk_stood(row: dict) -> bool:
    """A walk that did not fall, whatever its speed and distance: the wider set a row's saving is also given
    over when some of its walks stood without counting."""
    return not row["fell"]


def _seed_means(walks: list[dict], value) -> list[float]:
    """Per seed, the mean of `value` over its counting walks (seeds without one left out)."""
    out = []
    for seed in dict.fromkeys(w.get("seed", "") for w in walks):
        vals = [value(w) for w in walks if w.get("seed", "") == seed and walk_counts(w)]
        if vals:
            out.append(sum(vals) / len(vals))
    return out


def battery_savings(rows: list[dict], robot: str, speed: float, against: tuple[str, ...] = COMMON,
                    of: str = "learned", counts=walk_counts) -> list[float]:
    """Per seed, the battery saving (%) of the walks named `of` (the learned path; also the policy or the
    searched shape) against the cheaper counting trajectory of `against` (default: the common ones) on the same
    robot draw at the same lift, averaged over the draws where both counted (`counts`: which walks count, by
    default `walk_counts`; `walk_stood` counts every walk that did not fall)."""
    return list(battery_savings_by_seed(rows, robot, speed, against, of, counts).values())


def battery_savings_by_seed(rows: list[dict], robot: str, speed: float, against: tuple[str, ...] = COMMON,
                            of: str = "learned", counts=walk_counts) -> dict:
    """`battery_savings` by seed label: {seed: saving %}, seeds without a draw where both counted left out."""
    here = [r for r in rows if r["robot"] == robot and r["speed_mps"] == speed]
    out = {}
    for seed in dict.fromkeys(r.get("seed", "") for r in here if r["trajectory"] == of):
        per_draw = []
        for learned in (r for r in here if r["trajectory"] == of and r.get("seed", "") == seed):
            others = [METRICS["battery_pct_per_100m"](r) for r in here
                      if r["trajectory"] in against and r.get("seed", "") == seed
                      and r.get("draw", 0) == learned.get("draw", 0) and counts(r)]
            if others and counts(learned):
                per_draw.append(100.0 * (1.0 - METRICS["battery_pct_per_100m"](learned) / min(others)))
        if per_draw:
            out[seed] = sum(per_draw) / len(per_draw)
    return out


def summary_rows(rows: list[dict]) -> list[dict]:
    """Per joint-PD stiffness (`pd_scale`, 1 where a row has none), robot, speed and trajectory: walks, counting
    walks, falls, seeds, and every metric's mean and 95 % CI across seeds; every row but the common trajectories'
    adds the battery saving against the cheaper common trajectory (and, where some walks stood without counting,
    `battery_saving_stood_pct` over every walk that did not fall), and the learned path's and the policy's the
    saving against the searched shape where it was walked; the trot's speed loop (`speed_loop_pct`,
    `speed_loop_at_limit_pct`) is the mean over all the walks, where the rows carry it."""
    out = []
    for scale in dict.fromkeys(r.get("pd_scale", 1.0) for r in rows):
        out += [{"pd_scale": scale, **r} for r in _summary_at([r for r in rows if r.get("pd_scale", 1.0) == scale])]
    return out


def _summary_at(rows: list[dict]) -> list[dict]:
    """`summary_rows` of walks at one PD stiffness."""
    out = []
    for robot in dict.fromkeys(r["robot"] for r in rows):
        for v in sorted(dict.fromkeys(r["speed_mps"] for r in rows if r["robot"] == robot)):
            for name in dict.fromkeys(r["trajectory"] for r in rows):
                walks = [r for r in rows if r["robot"] == robot and r["speed_mps"] == v and r["trajectory"] == name]
                if not walks:
                    continue
                row = {"robot": robot, "speed_mps": v, "trajectory": name, "walks": len(walks),
                       "counted": sum(map(walk_counts, walks)), "fell": sum(bool(w["fell"]) for w in walks),
                       "seeds": len(dict.fromkeys(w.get("seed", "") for w in walks)),
                       "draws": len(dict.fromkeys(w.get("draw", 0) for w in walks))}
                for key, value in METRICS.items():
                    row[f"{key}_mean"], row[f"{key}_ci95"] = mean_ci(_seed_means(walks, value))
                row.update(_speed_loop(walks))
                if name not in COMMON:
                    savings = battery_savings(rows, robot, v, of=name)
                    row["battery_saving_pct_mean"], row["battery_saving_pct_ci95"] = mean_ci(savings)
                    row["battery_saving_seeds"] = len(savings)
                    if row["walks"] - row["fell"] > row["counted"]:  # some stood without counting: with them too
                        row["battery_saving_stood_pct_mean"], row["battery_saving_stood_pct_ci95"] = mean_ci(
                            battery_savings(rows, robot, v, of=name, counts=walk_stood))
                    if name != REFERENCE and any(r["trajectory"] == REFERENCE for r in rows):
                        row["battery_vs_searched_pct_mean"], row["battery_vs_searched_pct_ci95"] = mean_ci(
                            battery_savings(rows, robot, v, against=(REFERENCE,), of=name))
                out.append(row)
    return out


def _speed_loop(walks: list[dict]) -> dict:
    """The trot's speed loop over all `walks` (counted or not: a walk that fell behind is where it ran out): the
    mean stride it added, % of the command, and the mean share of a walk it spent at its bound, %."""
    out = {}
    for key in ("speed_loop_pct", "speed_loop_at_limit_pct"):
        vals = [w[key] for w in walks if math.isfinite(w.get(key, math.nan))]
        out[key] = sum(vals) / len(vals) if vals else math.nan
    return out


def _cell(row: dict, key: str, fmt: str) -> str:
    m, h = row.get(f"{key}_mean", math.nan), row.get(f"{key}_ci95", math.nan)
    if not math.isfinite(m):
        return "–"
    return format(m, fmt) + (f" ± {format(h, fmt)}" if math.isfinite(h) else "")


def summary_markdown(summary: list[dict], robot: str) -> str:
    """One robot's table: a row per speed and trajectory (mean ± 95 % CI across seeds)."""
    shown = []
    for r in (r for r in summary if r["robot"] == robot):
        saving = (_cell(r, "battery_saving_pct", ".1f") + f" % ({r['battery_saving_seeds']} seeds)"
                  if "battery_saving_seeds" in r else "")
        shown.append({"speed (m/s)": f"{r['speed_mps']:g}", "trajectory": r["trajectory"],
                      "walks counted / fell": f"{r['counted']} of {r['walks']} / {r['fell']}",
                      "battery % per 100 m": _cell(r, "battery_pct_per_100m", ".2f"),
                      "range on a full charge (m)": _cell(r, "range_full_charge_m", ".0f"),
                      "Eq. 7 (kJ per 100 m)": _cell(r, "energy_kJ_per_100m", ".2f"),
                      "electrical (kJ per 100 m)": _cell(r, "electrical_kJ_per_100m", ".2f"),
                      "electrical CoT": _cell(r, "electrical_cost_of_transport", ".3f"),
                      "battery saving vs the cheaper common": saving,
                      **({"vs the searched shape": (_cell(r, "battery_vs_searched_pct", ".1f") + " %"
                                                    if "battery_vs_searched_pct_mean" in r else "")}
                         if any("battery_vs_searched_pct_mean" in x for x in summary) else {})})
    return markdown_table(shown)


__all__ = ["COMMON", "METRICS", "REFERENCE", "battery_savings", "battery_savings_by_seed", "summary_markdown",
           "summary_rows", "walk_counts", "walk_stood"]
