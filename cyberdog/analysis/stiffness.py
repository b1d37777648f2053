"""Does a battery saving survive the joint PD a user sets? The prototype run at several PD stiffnesses.

A learned commanded path is a shift of the trot's foot targets; what the robot walks is what its joint PD makes
of that target. A path learned under one PD can save energy *because* that PD does not quite follow it (a
soft PD lets a foot sag or lag; a stiffer one executes the command and stubs the toe), and a robot's gains are
set by whoever runs it. This study walks the prototype run's protocol (`run_prototype`: the same hardware-like
robots, run-up and distance) with every walk's PD scaled by each factor of `scales` (kp × s, kd × √s, the
damping ratio kept: `PIDConfig.stiffness_scaled`): the learned paths, the common trajectories at their lift,
the searched shape and, given actors, the policies themselves in closed loop. Each row of `stiffness_table`
is one trajectory at one stiffness and speed: battery % per 100 m and the saving against the cheaper common
trajectory on the same robot at that same stiffness, mean ± 95 % CI across seeds, with the walks that fell
counted; `seed_table` gives each seed's saving on its own. `evaluate.py stiffness` runs it and writes
`stiffness.{csv,json,md}`, `stiffness_seeds.{csv,json,md}` and `stiffness_walks.json`.
"""
from __future__ import annotations

import json
import math
from pathlib import Path

from cyberdog.analysis.prototype import run_prototype
from cyberdog.analysis.prototype_summary import COMMON, REFERENCE, battery_savings_by_seed, summary_rows, walk_counts
from cyberdog.analysis.report import json_safe, markdown_table, write_rows
from cyberdog.loop.result import LOOP_NOTE_PCT

DEFAULT_SCALES = (0.7, 1.0, 1.4)  # × the joint PD's stiffness: 30 % softer, as configured, 40 % stiffer


def check_scales(scales) -> tuple[float, ...]:
    """The stiffness factors as floats, each finite and > 0, at least one, none twice."""
    out = tuple(float(s) for s in scales)
    if not out or not all(math.isfinite(s) and s > 0 for s in out) or len(set(out)) != len(out):
        raise ValueError(f"PD stiffness scales must be distinct finite numbers > 0, got {list(scales)!r}")
    return out


def run_stiffness(scales=DEFAULT_SCALES, log=print, **prototype) -> list[dict]:
    """Every walk of `run_prototype(**prototype)` at each stiffness of `scales` (rows carry `pd_scale`; with
    `pd_matched=True` the paths' commands are re-solved for each PD, `cyberdog.analysis.pd_match_recording`)."""
    rows = []
    matched = ", every path's command re-solved for it" if prototype.get("pd_matched") else ""
    for s in check_scales(scales):
        log(f"joint PD at {s:g}x its stiffness (kp x {s:g}, kd x {math.sqrt(s):.3f}){matched if s != 1 else ''}:")
        rows += run_prototype(log=log, pd_scale=s, **prototype)
    return rows


def stiffness_table(rows: list[dict], robot: str = "hardware") -> list[dict]:
    """Per stiffness, speed and trajectory on `robot`: walks, how many counted and fell, battery % per 100 m and
    the battery saving against the cheaper common trajectory (and against the searched shape, and where some walks
    stood without counting, over every walk that did not fall), mean and 95 % CI across seeds
    (`cyberdog.analysis.prototype_summary.summary_rows` at each stiffness)."""
    keys = ("battery_pct_per_100m", "battery_saving_pct", "battery_vs_searched_pct", "battery_saving_stood_pct")
    out = []
    for r in summary_rows(rows):
        if r["robot"] != robot:
            continue
        row = {k: r[k] for k in ("pd_scale", "speed_mps", "trajectory", "walks", "counted", "fell", "seeds")}
        for k in keys:
            row[f"{k}_mean"] = r.get(f"{k}_mean", math.nan)
            row[f"{k}_ci95"] = r.get(f"{k}_ci95", math.nan)
        row["speed_loop_pct"] = r.get("speed_loop_pct", math.nan)  # % of the command, mean over the walks
        row["speed_loop_at_limit_pct"] = r.get("speed_loop_at_limit_pct", math.nan)
        out.append(row)
    return out


def _cell(row: dict, key: str) -> str:
    m, h = row[f"{key}_mean"], row[f"{key}_ci95"]
    if not math.isfinite(m):
        return "–"
    return f"{m:.1f} %" + (f" ± {h:.1f}" if math.isfinite(h) else "")


def stiffness_markdown(table: list[dict]) -> str:
    """One line per trajectory and stiffness, one column per speed: the battery saving against the cheaper common
    trajectory (mean ± 95 % CI across seeds) and, where any walk did not count, how many of how many fell; where
    the walks ran the trot's speed loop at its bound for `LOOP_NOTE_PCT` % of the time or more, how long (the
    walk needed a longer stride than the loop may add: it falls behind the command)."""
    speeds = sorted(dict.fromkeys(r["speed_mps"] for r in table))
    index = {(r["trajectory"], r["pd_scale"], r["speed_mps"]): r for r in table}
    lines = []
    for name in dict.fromkeys(r["trajectory"] for r in table):
        for scale in dict.fromkeys(r["pd_scale"] for r in table):
            cells = {}
            for v in speeds:
                r = index.get((name, scale, v))
                if r is None:
                    cells[f"{v:g} m/s"] = ""
                    continue
                if math.isfinite(r["battery_saving_pct_mean"]):
                    saving = _cell(r, "battery_saving_pct")
                elif math.isfinite(r["battery_pct_per_100m_mean"]) and r["trajectory"] in COMMON:
                    saving = f"{r['battery_pct_per_100m_mean']:.2f} % per 100 m"
                else:
                    saving = "–"
                missed = r["walks"] - r["counted"]
                notes = [f"{missed} of {r['walks']} did not count, {r['fell']} fell"] if missed else []
                if math.isfinite(r["battery_saving_stood_pct_mean"]):  # the walks that stood without counting too
                    notes.append("counting every walk that did not fall: " + _cell(r, "battery_saving_stood_pct"))
                if r.get("speed_loop_at_limit_pct", math.nan) >= LOOP_NOTE_PCT:
                    notes.append(f"speed loop at its bound {r['speed_loop_at_limit_pct']:.0f} % of the time")
                cells[f"{v:g} m/s"] = saving + (f" ({'; '.join(notes)})" if notes else "")
            lines.append({"trajectory": name, "PD stiffness": f"{scale:g}x", **cells})
    return markdown_table(lines)


def seed_table(rows: list[dict], robot: str = "hardware") -> list[dict]:
    """Per stiffness, trajectory (the learned paths, the policies) and seed, one column per speed: that seed's
    battery saving against the cheaper common trajectory (the mean over its robots where both counted), and what
    became of each of its walks that did not count; where the run walked the searched shape, a row more per seed
    with the saving against it. A target such as "every seed saves 20 %" is read here, not on a mean."""
    here = [r for r in rows if r["robot"] == robot]
    speeds = sorted(dict.fromkeys(r["speed_mps"] for r in here))
    out = []
    for scale in dict.fromkeys(r.get("pd_scale", 1.0) for r in here):
        at = [r for r in here if r.get("pd_scale", 1.0) == scale]
        names = [n for n in dict.fromkeys(r["trajectory"] for r in at) if n not in COMMON and n != REFERENCE]
        searched = any(r["trajectory"] == REFERENCE for r in at)
        for name in names:
            saving = {v: battery_savings_by_seed(at, robot, v, of=name) for v in speeds}  # seed -> %, per speed
            versus_searched = {v: battery_savings_by_seed(at, robot, v, against=(REFERENCE,), of=name)
                               for v in speeds} if searched else {}
            for seed in dict.fromkeys(r.get("seed", "") for r in at if r["trajectory"] == name):
                row = {"PD stiffness": f"{scale:g}x", "trajectory": name, "seed": seed}
                versus = {"PD stiffness": f"{scale:g}x", "trajectory": f"{name} against the searched shape",
                          "seed": seed}
                for v in speeds:
                    walks = [r for r in at if r["trajectory"] == name and r.get("seed", "") == seed
                             and r["speed_mps"] == v]
                    missed = [_what_became(w) for w in walks if not walk_counts(w)]
                    note = f" ({'; '.join(missed)})" if missed else ""
                    row[f"{v:g} m/s"] = _percent(saving[v].get(seed, math.nan)) + note if walks else ""
                    if searched:
                        versus[f"{v:g} m/s"] = _percent(versus_searched[v].get(seed, math.nan), sign=True) \
                            if walks else ""
                out += [row, versus] if searched else [row]
    return out


def _percent(value: float, sign: bool = False) -> str:
    return format(value, "+.1f" if sign else ".1f") + " %" if math.isfinite(value) else "–"


def _what_became(walk: dict) -> str:
    """Why a walk did not count (`walk_counts`), in a few words."""
    if walk["fell"]:
        return "fell"
    if not walk["reached"]:
        return "did not reach the distance"
    return f"off the band at {walk['mean_speed_mps']:.2f} m/s"


def write_stiffness(rows: list[dict], folder: str | Path) -> str:
    """`stiffness.{csv,json,md}` (the table) and `stiffness_walks.json` (every walk) in `folder`; returns the
    Markdown."""
    folder = Path(folder)
    table = stiffness_table(rows)
    write_rows(table, folder, "stiffness")
    seeds = seed_table(rows)
    write_rows(seeds, folder, "stiffness_seeds")
    matched = (", every path's and trajectory's command re-solved for that PD (the motion it executes under the "
               "configured PD kept: --pd-matched)" if any(r.get("pd_matched") for r in rows) else "")
    md = ("Battery saving against the cheaper common trajectory on the hardware-like robots, at each joint-PD "
          f"stiffness (kp × s, kd × √s){matched}; the common trajectories' rows give their battery % per 100 m\n\n"
          + stiffness_markdown(table) + "\n\nPer seed (the mean of its robots where both walks counted; a walk "
          "that did not count, and why, in brackets)\n\n" + markdown_table(seeds) + "\n")
    (folder / "stiffness.md").write_text(md)
    (folder / "stiffness_walks.json").write_text(json.dumps(json_safe(rows), indent=1))
    return md


__all__ = ["DEFAULT_SCALES", "LOOP_NOTE_PCT", "check_scales", "run_stiffness", "seed_table", "stiffness_markdown",
           "stiffness_table", "write_stiffness"]
