"""The two physics engines side by side: the shipped comparisons walked again in MuJoCo (`SimConfig.engine`), each
cell "PyBullet / MuJoCo" over the same paths, policies, robots and seeds.

Each PyBullet input of `results/figures_input/` has a MuJoCo twin of the same format, `<name>_mujoco.json`
(the same command with `--set sim.engine=mujoco`, results/README.md); a twin that walked other learned paths than
its PyBullet file is refused. The rows, per commanded speed, means over the seeds:

- Table 5 at matched conditions (`comparison.json`, `comparison_fresh.json`: ideal robot, 10 s): Eq. 7 per metre
  of the cheaper common trajectory at each learned path's own lift and of the learned path, over the seeds whose
  learned walk is valid (no fall, ±5 % band); D_t on E (Eq. 12).
- The prototype run (`prototype.json`, `prototype_fresh.json`: two hardware-like robots a seed, 20 m): the
  battery's energy per metre (the electrical energy Eq. 13 drains) of the cheaper common trajectory and of the
  learned path, over the walks that count; the battery saving (`prototype_summary.battery_savings_by_seed`).
- The battery policies closed loop on the same robots: PyBullet's are the stiffness run's walks at PD 1×
  (`stiffness_walks.json`, whose paths' walks are the prototype run's), MuJoCo's the policy walks of
  `prototype_mujoco.json` (`prototype --closed-loop`).
- The battery recipes from the searched shape (`prototype_<name>.json` of each of
  `searched_start_table.RECIPES`, the same run on its paths): the battery saving against the cheaper common
  trajectory and against the searched shape.
- The torque agent's stage-2 actors alone on the ideal robot (`torque_check.json`, `torque_check_fresh.json`):
  the walks in the band.

A saving's cell gives in brackets MuJoCo's saving less PyBullet's on the seed where they differ most (points), and
notes the walks in the band of those walked where one on either engine fell or left the band.
"""
from __future__ import annotations

import json
import math
from pathlib import Path

from cyberdog.analysis import prototype_summary as ps
from cyberdog.analysis.comparison_sets import same_lift
from cyberdog.analysis.markdown_cells import header, line, number
from cyberdog.analysis.searched_start_table import RECIPES, Recipe
from cyberdog.analysis.stats import mean_ci

ENGINES = ("PyBullet", "MuJoCo")
TWIN_SUFFIX = "_mujoco.json"  # a PyBullet input's MuJoCo twin: <name>_mujoco.json
TABLE5 = ("comparison.json", "comparison_fresh.json")
PROTOTYPE = ("prototype.json", "prototype_fresh.json")
POLICY_PYBULLET = "stiffness_walks.json"  # the PD 1× walks: the policies beside the prototype's robots and paths
TORQUE = ("torque_check.json", "torque_check_fresh.json")
HARDWARE = "hardware"  # the prototype's robot
TABLE5_SAVING_ROW = "Table 5: D_t on E (%)"
PROTOTYPE_SAVING_ROW = "prototype: battery saving (%)"
POLICY_SAVING_ROW = "policies, closed loop: battery saving (%)"
TORQUE_WALKS_ROW = "torque agent, stage 2: walks in the band"
SEARCHED_START_SAVING_ROW = "{recipe}: battery saving (%)"  # a recipe from the searched shape, by its label
SEARCHED_START_VS_ROW = "{recipe}: against the searched shape (%)"
# the README's rows of the full table, by first cell
HEADLINE_ROWS = (f"**{TABLE5_SAVING_ROW}**", f"**{PROTOTYPE_SAVING_ROW}**", POLICY_SAVING_ROW,
                 TORQUE_WALKS_ROW)  # the saving rows in bold, as the table has them


def twin(name: str) -> str:
    """The MuJoCo twin's file name of a PyBullet input."""
    return name.removesuffix(".json") + TWIN_SUFFIX


def _load(results: Path, names) -> list | dict | None:
    """The walks of `names` joined (a check's walks lists joined under "walks"); None where one is missing."""
    files = [results / n for n in names]
    if not all(f.is_file() for f in files):
        return None
    loaded = [json.loads(f.read_text()) for f in files]
    if isinstance(loaded[0], dict):
        return {"walks": [w for d in loaded for w in d["walks"]]}
    return [w for d in loaded for w in d]


def _paths_walked(walks: list[dict]) -> set:
    """The learned paths a comparison or prototype run walked: (seed, speed, lift height to 0.1 mm)."""
    return {(w["seed"], w.get("speed_command_mps", w.get("speed_mps")), round(w["lift_height_m"], 4))
            for w in walks if w["trajectory"] == "learned"}


def _twins(results: Path, names) -> tuple | None:
    """(PyBullet's walks, MuJoCo's) of `names` and their twins; None where one is missing; ValueError where the
    twins walked other paths than the PyBullet files (one was made again without the other)."""
    pair = _load(results, names), _load(results, [twin(n) for n in names])
    if None in pair:
        return None
    if isinstance(pair[0], list) and _paths_walked(pair[0]) != _paths_walked(pair[1]):
        raise ValueError(f"{', '.join(twin(n) for n in names)} walked other learned paths than {', '.join(names)}: "
                         "make them again with the same command and --set sim.engine=mujoco (results/README.md)")
    return pair


def _per_metre(walk: dict, key: str) -> float:
    return walk[key] / walk["distance_m"] if walk["distance_m"] > 0 else math.nan


def _means(pair: tuple[dict, dict], fmt: str) -> str:
    """"PyBullet / MuJoCo" of two {seed: value} maps: each the mean over its seeds."""
    means = [mean_ci(list(values.values()))[0] for values in pair]
    return " / ".join(number(m, fmt) if math.isfinite(m) else "–" for m in means)


def _largest_gap(pair: tuple[dict, dict], fmt: str = ".1f") -> str:
    """" (d)": MuJoCo's value less PyBullet's on the seed where they differ most (of the seeds both have)."""
    diffs = [pair[1][s] - pair[0][s] for s in pair[0] if s in pair[1]]
    return f" ({number(max(diffs, key=abs), fmt, sign=True)})" if diffs else ""


def _counts(pair: tuple[tuple[int, int, int], ...]) -> str:
    """"k₁ / k₂ of n": the walks that count on each engine of those walked, "; fell f₁ / f₂" where one fell."""
    (k1, n1, f1), (k2, n2, f2) = pair
    text = f"{k1} / {k2} of {n1}" if n1 == n2 else f"{k1} of {n1} / {k2} of {n2}"
    return text + (f"; fell {f1} / {f2}" if f1 or f2 else "")


def _note(pair: tuple[tuple[int, int, int], ...]) -> str:
    """"" where every walk on both engines counts, else " (k₁ / k₂ of n in the band...)"."""
    return "" if all(k == n for k, n, _ in pair) else f" ({_counts(pair)} in the band)"


def _row(label: str, cells: list[str], bold: bool = False) -> str:
    """A row: the label, then one cell a speed."""
    return line(f"**{label}**" if bold else label, cells)


def _saving_cells(pairs: list[tuple[dict, dict]], walks: list[tuple], bold: bool = False) -> list[str]:
    """Per speed "PyBullet / MuJoCo" of the seeds' savings (mean over the seeds), the largest difference on one
    seed in brackets, and the walks that did not count noted."""
    return [(f"**{_means(p, '.1f')}**" if bold else _means(p, ".1f")) + _largest_gap(p) + _note(w)
            for p, w in zip(pairs, walks)]


# ---- Table 5 --------------------------------------------------------------------------------------------------

def _table5_at(walks: list[dict], speed: float) -> dict[str, dict]:
    """Per seed at `speed`: the learned walk at matched lift and the cheaper common trajectory's walk at its lift."""
    here = [w for w in walks if w["set"] == "same_lift" and w["speed_command_mps"] == speed]
    out = {}
    for learned in (w for w in here if w["trajectory"] == "learned"):
        common = next((w for w in here if w["trajectory"] == learned["E_min_trajectory"]
                       and same_lift(w["lift_height_m"], learned["lift_height_m"])), None)
        out[learned["seed"]] = {"learned": learned, "common": common}
    return out


def _table5_lines(engines: tuple[list, list], speeds: list[float]) -> list[str]:
    at = [[_table5_at(walks, v) for walks in engines] for v in speeds]

    def valid(seeds: dict) -> dict:
        return {s: p for s, p in seeds.items() if p["learned"]["valid"] and p["common"] is not None}

    def metric(value):
        return [tuple({s: value(p) for s, p in valid(e).items()} for e in pair) for pair in at]

    saving = metric(lambda p: p["learned"]["D_t_pct"])
    walks = [tuple((sum(p["learned"]["valid"] for p in e.values()), len(e),
                    sum(bool(p["learned"]["fell"]) for p in e.values())) for e in pair) for pair in at]
    return [_row("Table 5: Eq. 7 J/m, cheaper common trajectory",
                 [_means(p, ".1f") for p in metric(lambda p: _per_metre(p["common"], "energy_J"))]),
            _row("Table 5: Eq. 7 J/m, learned",
                 [_means(p, ".1f") for p in metric(lambda p: _per_metre(p["learned"], "energy_J"))]),
            _row(TABLE5_SAVING_ROW, _saving_cells(saving, walks, bold=True), bold=True)]


# ---- the prototype run ----------------------------------------------------------------------------------------

def _cheaper_common(rows: list[dict], speed: float) -> dict[str, float]:
    """Per seed: the battery J/m of the cheaper counting common trajectory on each draw, averaged over the draws."""
    here = [r for r in rows if r["robot"] == HARDWARE and r["speed_mps"] == speed and r["trajectory"] in ps.COMMON
            and ps.walk_counts(r)]
    out = {}
    for seed in dict.fromkeys(r["seed"] for r in here):
        draws = dict.fromkeys(r["draw"] for r in here if r["seed"] == seed)
        per_draw = [min(_per_metre(r, "electrical_energy_J") for r in here if r["seed"] == seed and r["draw"] == d)
                    for d in draws]
        out[seed] = sum(per_draw) / len(per_draw)
    return out


def _own(rows: list[dict], speed: float, name: str) -> dict[str, float]:
    """Per seed: the battery J/m of the counting walks named `name`, averaged over the draws."""
    here = [r for r in rows if r["robot"] == HARDWARE and r["speed_mps"] == speed and r["trajectory"] == name
            and ps.walk_counts(r)]
    seeds = dict.fromkeys(r["seed"] for r in here)
    return {s: sum(_per_metre(r, "electrical_energy_J") for r in here if r["seed"] == s)
            / sum(r["seed"] == s for r in here) for s in seeds}


def _walk_count(rows: list[dict], speed: float, name: str) -> tuple[int, int, int]:
    here = [r for r in rows if r["robot"] == HARDWARE and r["speed_mps"] == speed and r["trajectory"] == name]
    return sum(map(ps.walk_counts, here)), len(here), sum(bool(r["fell"]) for r in here)


def _saving(rows: list[dict], speed: float, name: str, against: tuple[str, ...] = ps.COMMON) -> dict[str, float]:
    return ps.battery_savings_by_seed(rows, HARDWARE, speed, against=against, of=name)


def _prototype_lines(engines: tuple[list, list], speeds: list[float]) -> list[str]:
    pairs = [tuple(_saving(e, v, "learned") for e in engines) for v in speeds]
    return [_row("prototype: battery J/m, cheaper common trajectory",
                 [_means(tuple(_cheaper_common(e, v) for e in engines), ".0f") for v in speeds]),
            _row("prototype: battery J/m, learned", [_means(tuple(_own(e, v, "learned") for e in engines), ".0f")
                                                     for v in speeds]),
            _row(PROTOTYPE_SAVING_ROW, _saving_cells(pairs, [tuple(_walk_count(e, v, "learned") for e in engines)
                                                             for v in speeds], bold=True), bold=True)]


def _policy_lines(engines: tuple[list, list], speeds: list[float]) -> list[str]:
    return [_row(POLICY_SAVING_ROW, _saving_cells([tuple(_saving(e, v, "policy") for e in engines) for v in speeds],
                                                  [tuple(_walk_count(e, v, "policy") for e in engines)
                                                   for v in speeds]))]


def _searched_start_lines(engines: tuple[list, list], speeds: list[float], recipe: Recipe) -> list[str]:
    counts = [tuple(_walk_count(e, v, "learned") for e in engines) for v in speeds]
    vs_searched = [tuple(_saving(e, v, "learned", against=(ps.REFERENCE,)) for e in engines) for v in speeds]
    return [_row(SEARCHED_START_SAVING_ROW.format(recipe=recipe.label),
                 _saving_cells([tuple(_saving(e, v, "learned") for e in engines) for v in speeds], counts)),
            _row(SEARCHED_START_VS_ROW.format(recipe=recipe.label), _saving_cells(vs_searched, counts))]


# ---- the torque agent -----------------------------------------------------------------------------------------

def _torque_lines(engines: tuple[dict, dict], speeds: list[float]) -> list[str]:
    def stage2(check: dict, v: float) -> list[dict]:
        return [w for w in check["walks"] if w["label"] != "trot" and w["stage"] == 2 and w["robot"] == "ideal"
                and w["speed_command_mps"] == v]

    at = [tuple(stage2(e, v) for e in engines) for v in speeds]
    return [_row(TORQUE_WALKS_ROW,
                 [_counts(tuple((sum(w["walks"] for w in e), len(e), sum(w["fell"] for w in e)) for e in pair))
                  for pair in at])]


def engine_markdown(results: Path) -> str | None:
    """The engines' table from the inputs in `results` and their MuJoCo twins; None where Table 5's twin is not
    there (the other parts' rows only where theirs are)."""
    results = Path(results)
    table5 = _twins(results, TABLE5)
    if table5 is None:
        return None
    speeds = sorted({w["speed_command_mps"] for w in table5[0] if w["trajectory"] == "learned"})
    lines = header(" / ".join(ENGINES), speeds) + _table5_lines(table5, speeds)
    prototype = _twins(results, PROTOTYPE)
    if prototype is not None:
        lines += _prototype_lines(prototype, speeds)
    policy = _load(results, [POLICY_PYBULLET]), _load(results, [twin(PROTOTYPE[0])])
    if None not in policy:
        policy = ([w for w in policy[0] if w.get("pd_scale", 1.0) == 1.0], policy[1])
        if all(any(w["trajectory"] == "policy" for w in e) for e in policy):
            lines += _policy_lines(policy, speeds)
    for recipe in RECIPES:
        if (searched_start := _twins(results, (recipe.prototype_source,))) is not None:
            lines += _searched_start_lines(searched_start, speeds, recipe)
    torque = _twins(results, TORQUE)
    if torque is not None:
        lines += _torque_lines(torque, speeds)
    return "\n".join(lines)


__all__ = ["ENGINES", "HEADLINE_ROWS", "TWIN_SUFFIX", "engine_markdown", "twin"]
