"""The result tables of the README and of docs/results.md, made from the shipped results (so the pages and
`results/` cannot disagree).

`python tools/make_readme_tables.py` prints them from `results/figures_input/` (what `python evaluate.py` wrote
and `tools/ship.py` shipped); `--write` puts them into each page of `DOCUMENTS` between its
`<!-- table:NAME -->` and `<!-- /table:NAME -->` markers: docs/results.md holds every table, the README the ones
it marks; `tests/test_readme.py` checks that both hold them as made.

- `table5`: Table 5 over the seeds (`comparison.json`, the walks of `evaluate.py compare`): the learned paths'
  Eq. 7 energy, the common trajectories at each path's own lift, D_t (Eq. 12) on E and on the electrical
  energy, the learned paths against the searched shape, the paper's protocol (baselines at 0.15 m) and the
  paper's own numbers; mean ± 95 % CI over the seeds whose walk is valid (`cyberdog.analysis.table5`).
- `prototype`: the prototype run on the hardware-like robots (`prototype.json`): battery per 100 m, the
  saving against the cheaper common trajectory, range, electrical energy, the searched shape's battery and the
  learned paths against it, the paper's range; mean ± 95 % CI across seeds (`cyberdog.analysis.prototype_summary`);
  where `prototype_fresh.json` is shipped, the same run on the recipe's seeds it was never tuned on.
- `stiffness` (where `stiffness_walks.json` is shipped): the same run with the joint PD at several stiffnesses
  (`evaluate.py stiffness`): the battery saving of the replayed paths, the policies and the searched shape at
  each, falls counted; where `stiffness_matched_walks.json` is shipped too (`evaluate.py stiffness
  --pd-matched`), the replayed paths with every command re-solved for the PD, beside them.
- `gains` (where `gains_walks.json` is shipped, `tools/merge_walks.py gains`): the same run with the drivers' kp or kd
  alone scaled, as commanded and re-commanded (`evaluate.py prototype --pd-matched-from-default`), beside the
  default gains' saving; where the runs walked the policies too (`--closed-loop`), the policies' own saving under
  those gains, beside theirs at the default gains (the stiffness run's PD 1× walks).
- `torque` (where `torque_check.json` is shipped): the paper's agent, the policy alone
  (`cyberdog.analysis.torque_table`), with the rows of the seeds it was never tuned on where
  `torque_check_fresh.json` is shipped.
- `searched_start`, `searched_wide`, `searched_pick` (where `prototype_<name>.json` is shipped): the recipes that
  start from the searched shape against it, on seeds never tuned on (`cyberdog.analysis.searched_start_table.RECIPES`).
- `engines` (where the `*_mujoco.json` twins are shipped): PyBullet and MuJoCo side by side on the same seeds
  (`cyberdog.analysis.engine_table`).
"""
from __future__ import annotations

import json
import re
from pathlib import Path

from cyberdog.analysis import prototype_summary as ps
from cyberdog.analysis import searched_start_table, table5
from cyberdog.analysis.comparison_sets import REFERENCE
from cyberdog.analysis.engine_table import HEADLINE_ROWS as ENGINE_HEADLINE_ROWS
from cyberdog.analysis.engine_table import engine_markdown
from cyberdog.analysis.markdown_cells import header as _header
from cyberdog.analysis.markdown_cells import line as _line
from cyberdog.analysis.markdown_cells import fewer_seeds, mean_ci, missed_walks, seeds_named
from cyberdog.analysis.gains_table import gains_markdown
from cyberdog.config.paper import PAPER_RANGE_1MPS_M
from cyberdog.analysis.torque_table import (TORQUE_FRESH_SAVING_ROW, TORQUE_SAVING_ROW, TORQUE_WALKS_ROW,
                                           torque_markdown)
from cyberdog.config.paper import PAPER_LIFT_HEIGHT, PAPER_SPEEDS

FRESH_SEEDS = "seeds 5–9"  # the seeds the recipes were never tuned on, as their rows name them
FRESH_ROW = f"**D_t on E, {FRESH_SEEDS} (never tuned on)**"  # a headline row only where its walks are shipped
FRESH_PROTOTYPE_ROW = f"**battery saving, {FRESH_SEEDS} (never tuned on)**"  # the same, the prototype run's
FRESH_VS_SEARCHED_ROW = f"learned against the shape searched for the battery, {FRESH_SEEDS} (never tuned on)"
# the README's headline tables: a few rows of a full table (docs/results.md), chosen by their first cell
HEADLINES = {
    "table5_headline": ("table5", ("**D_t on E, Eq. 12**", FRESH_ROW, "*paper: D_t*")),
    "prototype_headline": ("prototype", ("**battery saving against the cheaper common trajectory**",
                                         FRESH_PROTOTYPE_ROW,
                                         "learned against the shape searched for the battery (the best alternative)",
                                         FRESH_VS_SEARCHED_ROW,
                                         "*paper, 1 m/s: range learned / cycloid*")),
    "torque_headline": ("torque", (TORQUE_WALKS_ROW.format(robots="ideal robot, hardware-like draws 0 and 1"),
                                   "electrical J/m, stage 1 (ideal robot)",
                                   "**electrical J/m, stage 2 (ideal robot)**",
                                   TORQUE_SAVING_ROW.format(robot="ideal robot"),
                                   TORQUE_FRESH_SAVING_ROW.format(seeds=FRESH_SEEDS),
                                   "electrical J/m, the trot controller (H = 0.10 m, ideal robot)")),
    "engines_headline": ("engines", ENGINE_HEADLINE_ROWS),
    # the searched-start recipes the README leads with: their rows name their shipped seeds (`make_tables` sets them)
    **{recipe.headline: (recipe.name, ()) for recipe in searched_start_table.RECIPES if recipe.in_readme},
}
# the fresh seeds' rows: in a headline only where their walks are shipped
OPTIONAL_ROWS = {FRESH_ROW, FRESH_PROTOTYPE_ROW, FRESH_VS_SEARCHED_ROW,
                 TORQUE_FRESH_SAVING_ROW.format(seeds=FRESH_SEEDS),
                 *ENGINE_HEADLINE_ROWS[1:]}  # and the engines' rows of the parts whose twins are not all there
NAMES = ("table5", "prototype", "stiffness", "gains", "torque", "engines",
         *(recipe.name for recipe in searched_start_table.RECIPES), *HEADLINES)
SOURCES = {"table5": "comparison.json", "prototype": "prototype.json"}
TORQUE_SOURCE = "comparison_torque.json"  # optional: the paper's torque agent's paths, compared as the others
TORQUE_FRESH_SOURCE = "comparison_torque_fresh.json"  # optional: the same of the seeds it was never tuned on
FRESH_SOURCE = "comparison_fresh.json"  # optional: the Table 5 recipe's paths of seeds it was never tuned on
# optional: the prototype run of the battery recipe's paths of seeds it was never tuned on
PROTOTYPE_FRESH_SOURCE = "prototype_fresh.json"
STIFFNESS_SOURCE = "stiffness_walks.json"  # optional: `evaluate.py stiffness`'s walks (the PD at several stiffnesses)
STIFFNESS_MATCHED_SOURCE = "stiffness_matched_walks.json"  # optional: the same with --pd-matched
GAINS_SOURCE = "gains_walks.json"  # optional: prototype runs with kp or kd alone changed (tools/merge_walks.py gains)
# optional: `evaluate.py check --runs <the torque recipe's actors> --robots ideal hardware:0 hardware:1 --trot`
TORQUE_CHECK_SOURCE = "torque_check.json"
TORQUE_CHECK_FRESH_SOURCE = "torque_check_fresh.json"  # optional: the same check of the seeds never tuned on
# the pages the tables are written into (relative to the repository root), and whether a page must hold every
# table made (the full tables live in docs/results.md; the README marks the ones it shows)
DOCUMENTS = {"README.md": False, "docs/results.md": True}


def table5_markdown(walks: list[dict], straight_shape: str = "rectangle",
                    torque_walks: list[dict] | None = None, fresh_walks: list[dict] | None = None,
                    torque_fresh_walks: list[dict] | None = None,
                    torque_seeds: tuple[int | None, int | None] = (None, None)) -> str:
    """The README's Table 5 from the walks of `evaluate.py compare` (its comparison.json); with `torque_walks`
    (the same for the paper's torque agent's paths) its D_t at matched lift as rows of its own, with the
    number of seeds whose path replays (no fall, ±5 % speed) at each speed, of `torque_seeds[0]` (the seeds
    trained; default: those with a path); with `fresh_walks` (the recipe's paths of seeds it was never tuned
    on) their E and D_t beside the shipped seeds'; with `torque_fresh_walks` the torque agent's likewise (of
    `torque_seeds[1]`)."""
    summary = table5.summary_rows(walks)
    same = [r for r in summary if r["set"] == "same_lift"]
    paper = {r["speed_command_mps"]: r for r in summary if r["set"] == "paper"}
    if not same:
        raise ValueError("the walks hold no learned path compared at its own lift height (set 'same_lift')")
    speeds = [r["speed_command_mps"] for r in same]
    lines = _header("", speeds)
    lines.append(_line("E, learned (kJ)", [mean_ci(r, "learned_energy_kJ", ".3f") for r in same]))
    lines.append(_line("E, composite cycloid (kJ)", [mean_ci(r, "cycloid_energy_kJ", ".3f") for r in same]))
    lines.append(_line(f"E, straight line, {straight_shape} (kJ)",
                       [mean_ci(r, "straight_energy_kJ", ".3f") for r in same]))
    lines.append(_line("**D_t on E, Eq. 12**", [f"**{mean_ci(r, 'D_t_pct', '.1f', ' %')}**" for r in same]))
    lines.append(_line("D_t on the electrical energy", [mean_ci(r, "D_t_electrical_pct", ".1f", " %") for r in same]))
    if fresh_walks:
        lines += _fresh_lines(fresh_walks, speeds)
    if torque_walks:
        lines += _torque_lines(torque_walks, speeds, " (joint torques)", "", torque_seeds[0])
    if torque_fresh_walks:
        named = seeds_named(w.get("seed", "") for w in torque_fresh_walks)
        lines += _torque_lines(torque_fresh_walks, speeds, f", {named} (never tuned on)", f", {named}",
                               torque_seeds[1])
    searched = [r.get(f"{REFERENCE}_lift_height_m") for r in same]
    if all(h is not None for h in searched):
        lines.append(_line(f"learned against the direct search's shape at {searched[0]:.3f} m, on E",
                           [mean_ci(r, "D_ref_pct", ".1f", " %") for r in same]))
    if all(v in paper for v in speeds):
        p = [paper[v] for v in speeds]
        lines.append(_line(f"*paper's protocol:* E, cycloid / straight at {PAPER_LIFT_HEIGHT:.2f} m (kJ)",
                           [f"{r['cycloid_energy_kJ_mean']:.3f} / {r['straight_energy_kJ_mean']:.3f}" for r in p]))
        lines.append(_line("***paper's protocol:* D_t on E**",
                           [f"**{mean_ci(r, 'D_t_pct', '.1f', ' %')}**" for r in p]))
    t = table5.PAPER_TABLE5_KJ
    idx = [PAPER_SPEEDS.index(v) if v in PAPER_SPEEDS else None for v in speeds]
    lines.append(_line("*paper, Table 5: learned / cycloid / straight (kJ)*",
                       [f"{t['learned'][i]:.2f} / {t['cycloid'][i]:.2f} / {t['straight'][i]:.2f}" if i is not None
                        else "" for i in idx]))
    lines.append(_line("*paper: D_t*", [f"{t['decrement_pct'][i]:.0f} %" if i is not None else "" for i in idx]))
    return "\n".join(lines)


def _torque_lines(walks: list[dict], speeds: list[float], who: str, whose: str, n_seeds: int | None) -> list[str]:
    """Table 5's rows of the torque agent's paths: D_t on E and on the electrical energy, with the seeds whose
    path replays of the `n_seeds` trained (a seed whose path does not replay in the band has none)."""
    rows = {r["speed_command_mps"]: r for r in table5.summary_rows(walks) if r["set"] == "same_lift"}
    t = [rows.get(v, {"n_valid": 0, "n_seeds": 0}) for v in speeds]
    return [_line(f"**D_t on E, the paper's agent{who}**",
                  [f"**{mean_ci(r, 'D_t_pct', '.1f', ' %')}** ({r['n_valid']} of {n_seeds or r['n_seeds']})"
                   for r in t]),
            _line(f"D_t on the electrical energy, the paper's agent{whose}",
                  [mean_ci(r, "D_t_electrical_pct", ".1f", " %") for r in t])]


def _fresh_lines(walks: list[dict], speeds: list[float]) -> list[str]:
    """Table 5's rows of the fresh seeds' paths (the seeds named in their rows), with the seeds that replay."""
    fresh = {r["speed_command_mps"]: r for r in table5.summary_rows(walks) if r["set"] == "same_lift"}
    rows = [fresh.get(v, {"n_valid": 0, "n_seeds": 0}) for v in speeds]
    named = seeds_named(w.get("seed", "") for w in walks)
    return [_line(f"E, learned, {named} (kJ)", [mean_ci(r, "learned_energy_kJ", ".3f") for r in rows]),
            _line(f"**D_t on E, {named} (never tuned on)**",
                  [f"**{mean_ci(r, 'D_t_pct', '.1f', ' %')}** ({r['n_valid']} of {r['n_seeds']})" for r in rows])]


def _prototype_fresh_lines(walks: list[dict], robot: str, speeds: list[float]) -> list[str]:
    """The prototype table's rows of the fresh seeds' paths: their battery per 100 m and their saving against
    the cheaper common trajectory (walks that fell or left the band counted, as in the robustness table)."""
    by = {(r["trajectory"], r["speed_mps"]): r for r in ps.summary_rows(walks) if r["robot"] == robot}
    rows = [by.get(("learned", v)) for v in speeds]
    named = seeds_named(w.get("seed", "") for w in walks)
    lines = [_line(f"battery % per 100 m: learned, {named}",
                   ["–" if r is None else mean_ci(r, "battery_pct_per_100m", ".2f") for r in rows]),
             _line(f"**battery saving, {named} (never tuned on)**",
                   ["–" if r is None else f"**{mean_ci(r, 'battery_saving_pct', '.1f', ' %')}**{missed_walks(r)}"
                    f"{fewer_seeds(walks, robot, r['speed_mps'])}" for r in rows])]
    if all((ps.REFERENCE, v) in by for v in speeds):  # the run walked the searched shape beside them
        lines.append(_line(FRESH_VS_SEARCHED_ROW.replace(FRESH_SEEDS, named),
                           ["–" if r is None else mean_ci(r, "battery_vs_searched_pct", ".1f", " %", sign=True)
                            + fewer_seeds(walks, robot, r["speed_mps"]) for r in rows]))
    return lines


def prototype_markdown(walks: list[dict], robot: str = "hardware", fresh_walks: list[dict] | None = None) -> str:
    """The README's prototype table from the walks of `evaluate.py prototype` (its prototype.json); with
    `fresh_walks` (the same run on the recipe's paths of seeds it was never tuned on), their rows too."""
    summary = [r for r in ps.summary_rows(walks) if r["robot"] == robot]
    by = {(r["trajectory"], r["speed_mps"]): r for r in summary}
    speeds = sorted({r["speed_mps"] for r in summary if r["trajectory"] == "learned"})
    if not speeds:
        raise ValueError(f"the walks hold no learned path on the {robot!r} robot")
    learned, cycloid, straight = ([by[(name, v)] for v in speeds] for name in ("learned", "cycloid", "straight"))
    lines = _header("hardware-like robot" if robot == "hardware" else f"{robot} robot", speeds)
    lines.append(_line("battery % per 100 m: learned", [mean_ci(r, "battery_pct_per_100m", ".2f") for r in learned]))
    lines.append(_line("battery % per 100 m: composite cycloid / straight line",
                       [f"{mean_ci(c, 'battery_pct_per_100m', '.2f')} / {mean_ci(s, 'battery_pct_per_100m', '.2f')}"
                        for c, s in zip(cycloid, straight)]))
    lines.append(_line("**battery saving against the cheaper common trajectory**",
                       [f"**{mean_ci(r, 'battery_saving_pct', '.1f', ' %')}**" for r in learned]))
    searched = all((ps.REFERENCE, v) in by for v in speeds)  # the run walked the searched shape too
    if searched:
        lines.append(_line("learned against the shape searched for the battery (the best alternative)",
                           [mean_ci(r, "battery_vs_searched_pct", ".1f", " %", sign=True) for r in learned]))
    if fresh_walks:
        lines += _prototype_fresh_lines(fresh_walks, robot, speeds)
    lines.append(_line("range on a full charge (m): learned / cycloid",
                       [f"{mean_ci(r, 'range_full_charge_m', '.0f')} / {mean_ci(c, 'range_full_charge_m', '.0f')}"
                        for r, c in zip(learned, cycloid)]))
    lines.append(_line("electrical energy per 100 m (kJ): learned / cycloid",
                       [f"{mean_ci(r, 'electrical_kJ_per_100m', '.1f')} / {mean_ci(c, 'electrical_kJ_per_100m', '.1f')}"
                        for r, c in zip(learned, cycloid)]))
    if searched:
        lines.append(_line("*reference: a shape searched for the battery on this robot, battery % per 100 m*",
                           [f"*{by[(ps.REFERENCE, v)]['battery_pct_per_100m_mean']:.2f}*" for v in speeds]))
    gain = PAPER_RANGE_1MPS_M["learned"] / PAPER_RANGE_1MPS_M["cycloid"] - 1.0
    lines.append(_line("*paper, 1 m/s: range learned / cycloid*",
                       [f"*{PAPER_RANGE_1MPS_M['learned']:,.0f} / {PAPER_RANGE_1MPS_M['cycloid']:,.0f} m "
                        f"({gain * 100:+.0f} %)*"] + [""] * (len(speeds) - 1)))
    return "\n".join(lines)


def stiffness_markdown(walks: list[dict], robot: str = "hardware", matched: list[dict] | None = None) -> str:
    """The README's robustness table from the walks of `evaluate.py stiffness`: per walk kind (the replayed
    learned path, the policy closed loop, the searched shape) and PD stiffness, the battery saving against the
    cheaper common trajectory at that stiffness (mean ± 95 % CI across seeds of the walks that count), and the
    walks that fell or left the ±5 % speed band. `matched`: the walks of `evaluate.py stiffness --pd-matched`,
    whose replayed paths at each stiffness but 1× (there nothing is re-solved) follow the plain ones' rows."""
    summary = [r for r in ps.summary_rows(walks) if r["robot"] == robot]
    speeds = sorted({r["speed_mps"] for r in summary})
    scales = sorted({r["pd_scale"] for r in summary})
    by = {(r["trajectory"], r["pd_scale"], r["speed_mps"]): r for r in summary}
    if matched:
        by.update({("matched", r["pd_scale"], r["speed_mps"]): r for r in ps.summary_rows(matched)
                   if r["robot"] == robot and r["trajectory"] == "learned" and r["pd_scale"] != 1.0})
    names = {"learned": "replayed learned path", "matched": "replayed learned path re-commanded for the PD",
             "policy": "the policy, closed loop", ps.REFERENCE: "searched shape"}
    lines = _header("battery saving against the cheaper common trajectory", speeds)
    for name, title in names.items():
        for scale in scales:
            rows = [by.get((name, scale, v)) for v in speeds]
            if not any(rows):
                continue
            cells = [("" if r is None else mean_ci(r, "battery_saving_pct", ".1f", " %") + missed_walks(r)) for r in rows]
            bold = name in ("learned", "matched")
            label = f"{title}, PD {scale:g}×"
            lines.append(_line(f"**{label}**" if bold else label, [f"**{c}**" if bold and c else c for c in cells]))
    return "\n".join(lines)


def _optional(path: Path):
    """The JSON at `path`, None where it is not shipped."""
    return json.loads(path.read_text()) if path.is_file() else None


def _checked_seeds(check: dict | None) -> set[str]:
    """The seeds (labels) of a torque check's policy walks; none without the check."""
    return {w["label"] for w in check["walks"] if w["label"] != "trot"} if check else set()


def make_tables(results: Path, straight_shape: str = "rectangle") -> dict[str, str]:
    """Both tables from a folder holding comparison.json and prototype.json (and comparison_torque.json, if
    the paper's torque agent's paths were compared)."""
    results = Path(results)
    for name, file in SOURCES.items():
        if not (results / file).is_file():
            raise FileNotFoundError(f"{results / file} not found: the {name} table is made from it "
                                    "(`python evaluate.py` writes it; results/figures_input/ holds the shipped one)")
    walks = {name: json.loads((results / file).read_text()) for name, file in SOURCES.items()}
    torque, fresh, fresh_prototype, torque_fresh = (_optional(results / name) for name in (
        TORQUE_SOURCE, FRESH_SOURCE, PROTOTYPE_FRESH_SOURCE, TORQUE_FRESH_SOURCE))
    # the torque rows count the seeds whose path replays of the seeds the check walked (every seed trained)
    torque_seeds = tuple(len(_checked_seeds(_optional(results / name)))
                         or None for name in (TORQUE_CHECK_SOURCE, TORQUE_CHECK_FRESH_SOURCE))
    tables = {"table5": table5_markdown(walks["table5"], straight_shape, torque, fresh, torque_fresh, torque_seeds),
              "prototype": prototype_markdown(walks["prototype"], fresh_walks=fresh_prototype)}
    if (results / STIFFNESS_SOURCE).is_file():
        matched = results / STIFFNESS_MATCHED_SOURCE
        tables["stiffness"] = stiffness_markdown(json.loads((results / STIFFNESS_SOURCE).read_text()),
                                                 matched=json.loads(matched.read_text()) if matched.is_file() else None)
    headlines = dict(HEADLINES)
    if (results / TORQUE_CHECK_SOURCE).is_file():
        fresh_check = results / TORQUE_CHECK_FRESH_SOURCE
        fresh_torque = json.loads(fresh_check.read_text()) if fresh_check.is_file() else None
        tables["torque"] = torque_markdown(json.loads((results / TORQUE_CHECK_SOURCE).read_text()), fresh_torque)
        if fresh_torque is not None:  # its rows are named by the seeds checked so far ("seeds 5–6")
            named = seeds_named(w["label"] for w in fresh_torque["walks"] if w["label"] != "trot")
            full, rows = headlines["torque_headline"]
            headlines["torque_headline"] = (full, tuple(r.replace(FRESH_SEEDS, named) for r in rows))
    if (results / GAINS_SOURCE).is_file():
        stiffness = (json.loads((results / STIFFNESS_SOURCE).read_text())
                     if (results / STIFFNESS_SOURCE).is_file() else [])
        tables["gains"] = gains_markdown(json.loads((results / GAINS_SOURCE).read_text()), walks["prototype"],
                                         default_policy_walks=[w for w in stiffness if w["pd_scale"] == 1.0])
    if (engines := engine_markdown(results)) is not None:  # where the MuJoCo twins are shipped
        tables["engines"] = engines
    optional = set(OPTIONAL_ROWS)
    for recipe in searched_start_table.RECIPES:
        if (table := searched_start_table.make_table(results, recipe)) is not None:
            tables[recipe.name] = table
            if recipe.in_readme:  # its rows name its shipped seeds; its prototype rows are required, the others not
                rows, optional_rows = searched_start_table.headline_of(results, recipe)
                headlines[recipe.headline] = (recipe.name, rows)
                optional |= optional_rows
    tables.update({name: headline(tables[full], rows, optional) for name, (full, rows) in headlines.items()
                   if full in tables})
    return tables


def headline(table: str, rows: tuple[str, ...], optional: set[str] | frozenset[str] = frozenset(OPTIONAL_ROWS)
             ) -> str:
    """The header and the `rows` (by first cell, in the full table's order) of a Markdown table; a row that is
    not there and not `optional` is an error (a renamed row must not vanish from the README unnoticed)."""
    lines = table.splitlines()
    kept = [ln for ln in lines[2:] if ln.split("|")[1].strip() in rows]
    missing = set(rows) - {ln.split("|")[1].strip() for ln in kept} - set(optional)
    if missing:
        raise ValueError(f"headline rows {sorted(missing)} are not in the table")
    return "\n".join(lines[:2] + kept)


def _block(name: str) -> re.Pattern:
    return re.compile(rf"(<!-- table:{name} -->\n)(.*?)(\n<!-- /table:{name} -->)", re.S)


def readme_blocks(text: str) -> dict[str, str]:
    """The tables between the README's markers, by name (a name without markers is absent)."""
    return {name: m.group(2) for name in NAMES if (m := _block(name).search(text))}


def replace_blocks(text: str, tables: dict[str, str], page: str = "the README", every: bool = True) -> str:
    """`text` with each marked block replaced by its table; with `every`, a table without its markers in `text`
    is an error naming it and `page`, else such a table is left out."""
    for name, table in tables.items():
        pattern = _block(name)
        if not pattern.search(text):
            if not every:
                continue
            raise ValueError(f"no '<!-- table:{name} -->' ... '<!-- /table:{name} -->' block in {page}")
        text = pattern.sub(lambda m: m.group(1) + table + m.group(3), text)
    return text


def write_documents(root: Path, tables: dict[str, str]) -> dict[str, bool]:
    """Each page of `DOCUMENTS` under `root` with its marked tables rewritten; whether each changed. A page that
    must hold every table and misses one's markers is refused (ValueError) before any page is written."""
    new = {}
    for page, every in DOCUMENTS.items():
        text = (Path(root) / page).read_text()
        shown = tables if not every else {n: t for n, t in tables.items() if n not in HEADLINES}
        new[page] = (text, replace_blocks(text, shown, page, every))
    for page, (old, text) in new.items():
        if text != old:
            (Path(root) / page).write_text(text)
    return {page: old != text for page, (old, text) in new.items()}
