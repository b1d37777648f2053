"""The torque recipe's table (the paper's agent: joint torques every 25 ms) from a policy check.

`evaluate.py check --runs <the recipe's actors> --robots ideal hardware:0 hardware:1 --trot` writes
policy_check.json (shipped as `results/figures_input/torque_check.json`): each actor's stage 1 and stage 2 walk,
the policy alone, 10 s, on each robot at each speed, the trot controller's walk beside them, and stage 2's
per-metre saving against stage 1 (`cyberdog.analysis.policy_check.stage_reductions`). The table counts the walks
in the ±5 % band, gives each stage's electrical energy per metre and stage 2's saving as the mean ± 95 % CI over
the seeds (the lowest seed's beside it), and the trot's cost; a check of the recipe's seeds it was never tuned on
(`torque_check_fresh.json`) adds its band count and its saving on the ideal robot as rows of their own.
"""
from __future__ import annotations

import math

from cyberdog.analysis.markdown_cells import header, line, number, seeds_named
from cyberdog.analysis.stats import mean_ci

TORQUE_WALKS_ROW = "walks in the ±5 % band, no fall (both stages; {robots})"  # the robots the check walked
TORQUE_SAVING_ROW = "**stage 2's saving against stage 1, electrical per metre ({robot})**"
# the fresh seeds' rows, named by their seeds ("seeds 5–9"), on the same robots as the check's
TORQUE_FRESH_WALKS_ROW = "walks in the ±5 % band, no fall, {seeds} (never tuned on)"
TORQUE_FRESH_SAVING_ROW = "**stage 2's saving against stage 1, {seeds} (never tuned on; ideal robot)**"


def _seeds(walks: list[dict]) -> list[str]:
    """The actors' labels ("seedN"), numbered seeds first in their order."""
    def order(label: str):
        n = label.removeprefix("seed")
        return (0, int(n), label) if n.isdigit() else (1, 0, label)
    return sorted({w["label"] for w in walks}, key=order)


def _cell(values: list[float], fmt: str, unit: str = "", lowest: bool = False) -> str:
    """"m unit ± h" over the seeds' values (and the lowest, with `lowest`); "–" for none."""
    if not values:
        return "–"
    m, h = mean_ci(values)
    text = number(m, fmt) + unit + (f" ± {number(h, fmt)}" if math.isfinite(h) else "")
    return text + (f" (lowest {number(min(values), fmt)}{unit})" if lowest and len(values) > 1 else "")


def _policy_walks(check: dict) -> list[dict]:
    return [w for w in check["walks"] if w["label"] != "trot"]


def _band(walks: list[dict], speeds: list[float]) -> list[str]:
    """Per speed, "k of n": the walks in the band (no fall) of all walked there."""
    at = [[w for w in walks if w["speed_command_mps"] == v] for v in speeds]
    return [f"{sum(w['walks'] for w in ws)} of {len(ws)}" for ws in at]


def _savings(check: dict, robot: str, speed: float) -> list[float]:
    """Stage 2's per-metre saving, %, of each seed whose two stages both walk in the band on `robot` at `speed`."""
    return [r["electrical_reduction_per_metre_pct"] for r in check["reductions"]
            if r["robot"] == robot and r["speed_command_mps"] == speed and r["both_walk"]]


def _saving_cells(check: dict, robot: str, speeds: list[float], checked: int) -> list[str]:
    """Per speed, stage 2's saving over the seeds whose two stages walk in the band (mean ± 95 % CI, the lowest
    seed's), saying over how many seeds where fewer than the `checked` ones count."""
    cells = []
    for v in speeds:
        saving = _savings(check, robot, v)
        fewer = f" ({len(saving)} of {checked} seeds)" if len(saving) < checked else ""
        cells.append(f"**{_cell(saving, '.1f', ' %', lowest=True)}**{fewer}")
    return cells


def torque_markdown(check: dict, fresh: dict | None = None) -> str:
    """The torque recipe's table from a policy check (`evaluate.py check ... --trot`'s policy_check.json): how many
    of its walks keep the band, each stage's electrical energy per metre (mean ± 95 % CI over the seeds), stage 2's
    saving against stage 1 per metre (and the lowest seed's), and the trot's cost; with `fresh` (the same check of
    seeds the recipe was never tuned on), their band count and their saving on the ideal robot, named by their
    seeds; a saving counted over fewer seeds than were checked (a stage off the band) says over how many."""
    walks = _policy_walks(check)
    trot = {(w["robot"], w["speed_command_mps"]): w for w in check["walks"] if w["label"] == "trot"}
    speeds = sorted({w["speed_command_mps"] for w in walks})
    robots = sorted({w["robot"] for w in walks}, key=lambda r: (r != "ideal", r))
    lines = header(f"the policy alone, 10 s ({len(_seeds(walks))} seeds)", speeds)
    draws = [r.split(":")[1] for r in robots if r != "ideal"]
    named = ["ideal robot"] if "ideal" in robots else []
    if draws:
        listed = draws[0] if len(draws) == 1 else ", ".join(draws[:-1]) + " and " + draws[-1]
        named.append(f"hardware-like draw{'s' if len(draws) > 1 else ''} {listed}")
    lines.append(line(TORQUE_WALKS_ROW.format(robots=", ".join(named)), _band(walks, speeds)))
    if fresh is not None:
        fresh_walks = _policy_walks(fresh)
        fresh_seeds = _seeds(fresh_walks)
        lines.append(line(TORQUE_FRESH_WALKS_ROW.format(seeds=seeds_named(fresh_seeds)), _band(fresh_walks, speeds)))
    for robot in robots:
        where = "ideal robot" if robot == "ideal" else f"hardware-like draw {robot.split(':')[1]}"
        for stage in (1, 2):
            label = f"electrical J/m, stage {stage} ({where})"
            values = [[w["electrical_per_metre_J"] for w in walks if w["robot"] == robot and w["stage"] == stage
                       and w["speed_command_mps"] == v and not w["fell"]] for v in speeds]
            cells = [_cell(x, ".0f") for x in values]
            lines.append(line(f"**{label}**", [f"**{c}**" for c in cells]) if stage == 2 else line(label, cells))
        lines.append(line(TORQUE_SAVING_ROW.format(robot=where),
                          _saving_cells(check, robot, speeds, len(_seeds(walks)))))
        if robot == "ideal" and fresh is not None:
            lines.append(line(TORQUE_FRESH_SAVING_ROW.format(seeds=seeds_named(fresh_seeds)),
                              _saving_cells(fresh, "ideal", speeds, len(fresh_seeds))))
        if any((robot, v) in trot for v in speeds):
            lines.append(line(f"electrical J/m, the trot controller (H = 0.10 m, {where})",
                              [number(trot[robot, v]["electrical_per_metre_J"], ".0f") if (robot, v) in trot
                               else "–" for v in speeds]))
    return "\n".join(lines)
