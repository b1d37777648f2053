"""The tables of the battery recipes that start from the searched shape (`RECIPES`: `configs/battery_searched.yaml`,
its wide-command variant and its two-lineage pick): the learned paths against the best gait the direct search
finds, on the seeds the recipe was never tuned on (in the sets they were trained as, and pooled) and on its tuning
seeds, each group's rows apart.

From `results/figures_input/`, per recipe named NAME (`Recipe.name`; each optional: the table is made where its
prototype walks are shipped):
- `prototype_NAME.json`: `evaluate.py prototype --learned <the recipe's paths>` (the prototype run: two
  hardware-like robots per seed, 20 m; its reference row is the shape searched for the battery): battery per 100
  m, the saving against the cheaper common trajectory and against the searched shape;
- `comparison_NAME.json`: `evaluate.py compare --learned <the same paths> --reference <a shape searched
  on Eq. 7 at the paths' lift>` (Table 5's 10 s walk on the ideal robot): the paths against that shape on Eq. 7;
- `gains_NAME.json`: `tools/merge_walks.py gains` over four prototype runs with kp or kd alone at 0.5×
  or 2× as commanded (never tuning seeds: the fresh seeds' walks): the saving at each, beside the default's, and
  where a run walked the searched shape under its gains too, that shape's saving and the paths' lead over it;
- `prototype_NAME_own.json`: the same prototype run with the recipe's own start as the reference
  (`--prototype-reference` the shape its trot walks, which a zero action walks): what the policy adds to it;
- `gains_NAME_own.json`: the gains runs as commanded with that start as the reference: its saving under
  each gain, and what the policy adds to it there;
- `prototype_NAME_inset.json`: the prototype run with the shape searched for the battery with a narrower stance as
  its reference (`INSET_REFERENCE`, `tools/optimize_trajectory.py --foot-inset 0.03`: the cheapest shape a search
  that also places the feet finds): the paths' lead over it;
- `conditions_NAME.json`: `tools/merge_walks.py conditions` over that run made with a payload or another floor
  (`cyberdog.analysis.conditions_table`, never tuning seeds): the saving under each, the narrower-stance shape's,
  and the paths' lead over it.
"""
from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path

from cyberdog.analysis import prototype_summary as ps
from cyberdog.analysis import table5
from cyberdog.analysis.conditions_table import conditions_of, conditions_rows
from cyberdog.analysis.gains_table import SEARCHED, SEARCHED_SAVING, gains_rows
from cyberdog.analysis.markdown_cells import fewer_seeds, header, line, mean_ci, missed_walks, seeds_named

OWN_START = "its own start"  # the recipe's start shape under its trot, as the gains rows name it
# the battery shape searched with every foot 30 mm nearer the body's midline (the cheapest of 10-40 mm): the
# reference of prototype_NAME_inset.json
INSET_REFERENCE = "results/searched_shapes/optimized_trajectory_H0.085_electrical_hardware_inset30.json"


def _seeds(first: int, last: int) -> frozenset[str]:
    return frozenset(f"seed{n}" for n in range(first, last + 1))


@dataclass(frozen=True)
class Recipe:
    """A recipe from the searched shape as its table shows it: `name` names its table and its inputs
    (`prototype_<name>.json`, ...), `config` its preset, `label` the recipe in the engines' rows; `fresh_sets`: the
    seeds never tuned on, in the sets they were trained as, each with the README's command at the recipe's frozen
    commit (where several are shipped, their rows are also pooled; a seed in no set makes a group of its own);
    `tuned_seeds`: the seeds it was tuned on (their rows apart, never in a fresh or gains row); `in_readme`: whether
    the README shows its headline (the recipes it leads with) or docs/results.md alone its table."""

    name: str
    config: str
    label: str  # the recipe in a row of another table (the engines')
    fresh_sets: tuple[frozenset[str], ...]
    tuned_seeds: frozenset[str]
    in_readme: bool

    def __post_init__(self):  # a seed in two groups would be counted in both, under two names
        groups = [*self.fresh_sets, self.tuned_seeds]
        shared = {s for i, a in enumerate(groups) for b in groups[i + 1:] for s in a & b}
        if shared:
            raise ValueError(f"recipe {self.name}: {', '.join(sorted(shared))} in two of its seed sets "
                             "(fresh sets and tuning seeds are disjoint)")

    @property
    def prototype_source(self) -> str:  # the prototype run, its reference the shape searched for the battery
        return f"prototype_{self.name}.json"

    @property
    def compare_source(self) -> str:  # Table 5's walk against the shape searched on Eq. 7
        return f"comparison_{self.name}.json"

    @property
    def gains_source(self) -> str:  # the gains runs (tools/merge_walks.py gains)
        return f"gains_{self.name}.json"

    @property
    def own_start_source(self) -> str:  # the prototype run against the recipe's own start
        return f"prototype_{self.name}_own.json"

    @property
    def own_gains_source(self) -> str:  # the gains runs against that start
        return f"gains_{self.name}_own.json"

    @property
    def inset_source(self) -> str:  # the prototype run against the shape searched with a narrower stance
        return f"prototype_{self.name}_inset.json"

    @property
    def conditions_source(self) -> str:  # the inset run with a payload or on other floors (merge_walks conditions)
        return f"conditions_{self.name}.json"

    @property
    def headline(self) -> str:  # the README's table of it
        return f"{self.name}_headline"


# configs/battery_searched.yaml: tuned on seed 0; seeds 20-24, then 25-29, trained at its frozen commit
SEARCHED_START = Recipe("searched_start", "configs/battery_searched.yaml", "from the searched shape",
                        (_seeds(20, 24), _seeds(25, 29)), frozenset({"seed0"}), in_readme=True)
# configs/battery_searched_wide.yaml: its command range chosen on seeds 1-4 (beside the searched recipe's seed 0);
# seeds 30-34 trained at its frozen commit; its table is docs/results.md's, the README leading with the searched
# recipe (ahead of it at 1.4 m/s on seeds never tuned on)
SEARCHED_WIDE = Recipe("searched_wide", "configs/battery_searched_wide.yaml",
                       "from the searched shape, commands over 0.9–1.5 m/s", (_seeds(30, 34),), _seeds(0, 4),
                       in_readme=False)
# configs/battery_searched.yaml as frozen, two lineages a seed: seed N trained as seeds N and N + 100, and per speed
# the lineage's path cheaper on the extraction's check robots kept (`evaluate.py pick --lineage-offset 100`); seeds
# 20-24 (their first lineages the one-lineage recipe's) and 40-44, none tuned on. The README leads with it (each
# set's lead over the searched shape +10 % or more with the CI above zero at every speed, the bar set for that lead),
# the one-lineage seeds' headline beside it
SEARCHED_PICK = Recipe("searched_pick", "configs/battery_searched.yaml",
                       "from the searched shape, the better of two lineages", (_seeds(20, 24), _seeds(40, 44)),
                       frozenset(), in_readme=True)
RECIPES = (SEARCHED_START, SEARCHED_WIDE, SEARCHED_PICK)

SAVING_ROW = "**battery saving against the cheaper common trajectory, {seeds}**"
VS_SEARCHED_ROW = "**learned against the shape searched for the battery, {seeds}**"
EQ7_ROW = "learned against the shape searched on Eq. 7, on E (ideal robot), {seeds}"  # its lift: the caption's
OWN_START_ROW = "learned against its own start (a zero action's gait), {seeds}"
VS_INSET_ROW = "**learned against the shape searched for the battery with a narrower stance, {seeds}**"
GAINS_ROW = "the saving at {gains}, {seeds}"  # a gains row: "kp 0.5×, as commanded" (bold where re-commanded)
GAINS_SEARCHED_ROW = "{gains}: {row}, {seeds}"  # its rows of the searched shape walked under those gains
FRESH, POOLED = " (never tuned on)", " (never tuned on, pooled)"  # the notes that name a group's seeds


def _is_tuned(walk: dict, recipe: Recipe) -> bool:
    return str(walk.get("seed", "")) in recipe.tuned_seeds


def _fresh_set(walk: dict, recipe: Recipe) -> int:
    """The index of the recipe's fresh set that holds the walk's seed (len(fresh_sets): none does)."""
    sets = recipe.fresh_sets
    return next((i for i, seeds in enumerate(sets) if str(walk["seed"]) in seeds), len(sets))


def _groups(walks: list[dict], recipe: Recipe) -> dict[str, tuple[str, list[dict]]]:
    """{"fresh<i>" | "pooled" | "tuned": (name, walks)} where that group has walks: each fresh set's, in
    `recipe.fresh_sets`' order (then the fresh seeds in no set), all fresh seeds pooled where they span several groups,
    and the tuning seeds'; a walk of no seed (a comparison's common trajectories, shared by the paths of a lift)
    belongs to each."""
    shared = [w for w in walks if not w.get("seed")]
    fresh = [w for w in walks if w.get("seed") and not _is_tuned(w, recipe)]
    by_set: dict[int, list[dict]] = {}
    for w in fresh:
        by_set.setdefault(_fresh_set(w, recipe), []).append(w)
    groups = {f"fresh{i}": (f"{seeds_named(w['seed'] for w in group)}{FRESH}", group + shared)
              for i, group in sorted(by_set.items())}
    if len(by_set) > 1:
        groups["pooled"] = (f"{seeds_named(w['seed'] for w in fresh)}{POOLED}", fresh + shared)
    if tuned := [w for w in walks if _is_tuned(w, recipe)]:
        groups["tuned"] = (f"{seeds_named(w['seed'] for w in tuned)} (tuned on)", tuned + shared)
    return groups


def _prototype_lines(walks: list[dict], name: str, speeds: list[float], robot: str) -> list[str]:
    by = {(r["trajectory"], r["speed_mps"]): r for r in ps.summary_rows(walks) if r["robot"] == robot}
    learned = [by.get(("learned", v)) for v in speeds]
    searched = [by.get((ps.REFERENCE, v)) for v in speeds]

    def cell(r: dict | None, key: str, fmt: str, sign: bool = False) -> str:
        return "–" if r is None else mean_ci(r, key, fmt, " %" if key.endswith("pct") else "", sign)

    def note(r: dict | None, v: float) -> str:
        return fewer_seeds(walks, robot, v) if r else ""

    return [line(f"battery % per 100 m: learned / searched shape, {name}",
                 [f"{cell(r, 'battery_pct_per_100m', '.2f')} / {cell(s, 'battery_pct_per_100m', '.2f')}"
                  for r, s in zip(learned, searched)]),
            line(SAVING_ROW.format(seeds=name),
                 [f"**{cell(r, 'battery_saving_pct', '.1f')}**" + (missed_walks(r) if r else "") + note(r, v)
                  for r, v in zip(learned, speeds)]),
            line(VS_SEARCHED_ROW.format(seeds=name),
                 [f"**{cell(r, 'battery_vs_searched_pct', '.1f', sign=True)}**" + note(r, v)
                  for r, v in zip(learned, speeds)])]


def _eq7_lines(walks: list[dict], name: str, speeds: list[float]) -> list[str]:
    same = {r["speed_command_mps"]: r for r in table5.summary_rows(walks) if r["set"] == "same_lift"}
    lifts = {r.get(f"{table5.REFERENCE}_lift_height_m") for r in same.values()}
    if not same or None in lifts or len(lifts) != 1:
        return []
    return [line(EQ7_ROW.format(seeds=name),
                 ["–" if v not in same else mean_ci(same[v], "D_ref_pct", ".1f", " %", sign=True) for v in speeds])]


def _vs_reference_lines(walks: list[dict], row: str, name: str, speeds: list[float], robot: str) -> list[str]:
    """The learned paths against the run's reference row (the recipe's start, or the shape searched with a
    narrower stance), `row` naming it; bold where the row is."""
    by = {r["speed_mps"]: r for r in ps.summary_rows(walks) if r["robot"] == robot and r["trajectory"] == "learned"}
    if not any(math.isfinite(r.get("battery_vs_searched_pct_mean", math.nan)) for r in by.values()):
        return []
    bold = "**" if row.startswith("**") else ""
    return [line(row.format(seeds=name), ["–" if v not in by else
                                          bold + mean_ci(by[v], "battery_vs_searched_pct", ".1f", " %", sign=True)
                                          + bold + fewer_seeds(walks, robot, v) for v in speeds])]


def searched_start_markdown(prototype_walks: list[dict], compare_walks: list[dict] | None = None,
                            gains_walks: list[dict] | None = None, robot: str = "hardware",
                            own_start_walks: list[dict] | None = None,
                            own_start_gains_walks: list[dict] | None = None,
                            recipe: Recipe = SEARCHED_START, inset_walks: list[dict] | None = None,
                            conditions_walks: list[dict] | None = None) -> str:
    """The table: per group of seeds (never tuned on, then tuned on) the prototype rows, the row against the shape
    searched with a narrower stance (`inset_walks`: the prototype run with it as its reference), the row against
    the recipe's own start (`own_start_walks`: the same with that start as its reference) and the Eq. 7 row,
    then the gains rows of the fresh seeds (`gains_table.gains_rows`, of the fresh seeds' walks alone), the own
    start's under the gains (`own_start_gains_walks`: the gains runs with it as the reference), and the fresh
    seeds' rows with a payload or on other floors (`conditions_walks`: `conditions_table.conditions_rows`)."""
    speeds = sorted({w["speed_mps"] for w in prototype_walks if w["trajectory"] == "learned" and w["robot"] == robot})
    if not speeds:
        raise ValueError(f"the walks hold no learned path on the {robot!r} robot")
    lines = header(f"`{recipe.config}`, hardware-like robot", speeds)
    compared, own = _groups(compare_walks or [], recipe), _groups(own_start_walks or [], recipe)
    inset, groups = _groups(inset_walks or [], recipe), _groups(prototype_walks, recipe)
    for kind, (name, walks) in groups.items():
        lines += _prototype_lines(walks, name, speeds, robot)
        for reference, row in ((inset, VS_INSET_ROW), (own, OWN_START_ROW)):  # named by the seeds they walked
            if kind in reference:
                lines += _vs_reference_lines(reference[kind][1], row, reference[kind][0], speeds, robot)
        if kind in compared:
            lines += _eq7_lines(compared[kind][1], name, speeds)
    lines += _gains_lines(_fresh_walks(gains_walks, groups, recipe), groups, robot, recipe)
    lines += _gains_lines(_fresh_walks(own_start_gains_walks, groups, recipe), groups, robot, recipe,
                          reference=OWN_START)
    lines += _conditions_lines(_fresh_walks(conditions_walks, groups, recipe), speeds, robot)
    return "\n".join(lines)


def _conditions_lines(walks: list[dict], speeds: list[float], robot: str) -> list[str]:
    """The conditions rows of the fresh seeds' walks (`_fresh_walks`), each condition's named by the seeds it
    walked."""
    lines = []
    for run in conditions_of(walks):
        at = [w for w in walks if (w["condition"], w["condition_value"]) == run]
        lines += [line(f"{label}, {_seeds_of(at)}", cells) for label, cells in conditions_rows(at, speeds, robot)]
    return lines


def _gains_lines(gains_walks: list[dict], groups: dict, robot: str, recipe: Recipe,
                 reference: str = SEARCHED) -> list[str]:
    """The gains rows (`gains_table.gains_rows`) of the fresh seeds' gains walks (`_fresh_walks`), named by those
    walks' own seeds; the default gains' walks of the fresh groups they fall in give the rows their speeds. With
    another `reference` than the searched shape, only that reference's rows (the paths' own rows are the searched
    shape's runs')."""
    if not (name := _seeds_of(gains_walks)):
        return []
    lines, default = [], [w for kind in _gains_groups(gains_walks, groups, recipe) for w in groups[kind][1]]
    for label, cells in gains_rows(gains_walks, default, robot, reference):
        bold = label.startswith("**")  # re-commanded: the row bold as a whole
        gains, _, searched = label.strip("*").partition(": ")  # "kd 2×, as commanded: the searched shape's saving"
        if reference != SEARCHED and not searched:
            continue
        row = (GAINS_SEARCHED_ROW.format(gains=gains, row=searched, seeds=name) if searched
               else GAINS_ROW.format(gains=gains, seeds=name))
        lines.append(line(f"**{row}**" if bold else row, cells))
    return lines


def _gains_groups(gains_walks: list[dict], groups: dict, recipe: Recipe) -> list[str]:
    """The fresh groups of `groups` that the gains walks' seeds fall in."""
    return sorted({f"fresh{_fresh_set(w, recipe)}" for w in gains_walks if w.get("seed")} & set(groups))


def _fresh_walks(walks: list[dict] | None, groups: dict, recipe: Recipe) -> list[dict]:
    """The walks (of the gains or the conditions runs) of the fresh seeds whose group the table shows (a tuning
    seed's, or a seed of a set with no prototype walks, would be counted under names that are not its own)."""
    return [w for w in walks or [] if w.get("seed") and not _is_tuned(w, recipe)
            and f"fresh{_fresh_set(w, recipe)}" in groups]


def _seeds_of(walks: list[dict]) -> str | None:
    """"seeds 20–24": the seeds the walks were walked on (None where there are none)."""
    seeds = [w["seed"] for w in walks if w.get("seed")]
    return seeds_named(seeds) if seeds else None


HEADLINE_MAX_ROWS = 6  # the README's headline: the prototype's rows, then the optional rows in this order (the rows
# against the shape searched with a narrower stance come beside them, not in their place)
# the gains rows after the Eq. 7 row, as room is left: the saving at the gain that costs it most without a fall, the
# searched shape's own saving there, then the next gain's
HEADLINE_GAINS = ("kd 2×", "kp 0.5×")
HEADLINE_SEARCHED_GAINS = "kd 2×"


def headline_rows(prototype_walks: list[dict], gains_walks: list[dict] | None = None,
                  recipe: Recipe = SEARCHED_START,
                  inset_walks: list[dict] | None = None) -> tuple[tuple[str, ...], frozenset[str]]:
    """The README's rows of the table and which of them may be missing: the first fresh group's saving against
    the cheaper common trajectory, against the searched shape and, where `inset_walks` hold that group, against
    the shape searched with a narrower stance, the pooled fresh seeds' alike (where several sets are shipped),
    then, up to `HEADLINE_MAX_ROWS`, the first group's row against the Eq. 7 shape, the saving at the
    first of `HEADLINE_GAINS`, the searched shape's saving at `HEADLINE_SEARCHED_GAINS` and the saving at the
    next gain (the row against the recipe's own start stays in the full table). The prototype's rows are
    required; the others' inputs (the Eq. 7 comparison, the gains runs) are optional. No rows where no fresh seed
    walked."""
    groups = _groups([w for w in prototype_walks if w["trajectory"] == "learned"], recipe)
    fresh = [name for kind, (name, _) in groups.items() if kind.startswith("fresh")]
    if not fresh:
        return (), frozenset()
    inset = {name: kind for kind, (name, _) in _groups([w for w in inset_walks or [] if w["trajectory"] == "learned"],
                                                       recipe).items()}
    named = [(kind, groups[kind][0]) for kind in ([next(k for k in groups if k.startswith("fresh"))]
                                                  + (["pooled"] if "pooled" in groups else []))]
    with_inset = [inset.get(name) == kind for kind, name in named]  # the inset run walked the same seeds
    required = [row.format(seeds=name) for (kind, name), both in zip(named, with_inset)
                for row in (SAVING_ROW, VS_SEARCHED_ROW, *([VS_INSET_ROW] if both else []))]
    room = HEADLINE_MAX_ROWS - len(required) + sum(with_inset)
    optional = [EQ7_ROW.format(seeds=fresh[0])]
    if gains := _seeds_of(_fresh_walks(gains_walks, groups, recipe)):
        first, *others = (GAINS_ROW.format(gains=f"{g}, as commanded", seeds=gains) for g in HEADLINE_GAINS)
        optional += [first, GAINS_SEARCHED_ROW.format(gains=f"{HEADLINE_SEARCHED_GAINS}, as commanded",
                                                      row=SEARCHED_SAVING, seeds=gains), *others]
    optional = optional[:max(0, room)]
    return tuple(required + optional), frozenset(optional)


def _read(results: Path, name: str) -> list[dict] | None:
    """The walks of a shipped input, None where it is not there; ValueError for a file that holds none (a
    half-made input: no table is made from it, rather than a table missing its rows)."""
    if not (results / name).is_file():
        return None
    walks = json.loads((results / name).read_text())
    if not walks:
        raise ValueError(f"{results / name} holds no walks: make it again (tools/ship_searched.py)")
    return walks


def headline_of(results: Path, recipe: Recipe = SEARCHED_START) -> tuple[tuple[str, ...], frozenset[str]]:
    """`headline_rows` of the recipe's shipped inputs in `results` (no rows where its prototype walks are not
    there)."""
    walks = _read(Path(results), recipe.prototype_source)
    return (headline_rows(walks, _read(Path(results), recipe.gains_source), recipe,
                          _read(Path(results), recipe.inset_source)) if walks else ((), frozenset()))


def make_table(results: Path, recipe: Recipe = SEARCHED_START) -> str | None:
    """The recipe's table from a folder of shipped inputs, None where its prototype walks are not there."""
    results = Path(results)
    if not (results / recipe.prototype_source).is_file():
        return None
    return searched_start_markdown(
        _read(results, recipe.prototype_source), _read(results, recipe.compare_source),
        _read(results, recipe.gains_source), own_start_walks=_read(results, recipe.own_start_source),
        own_start_gains_walks=_read(results, recipe.own_gains_source), recipe=recipe,
        inset_walks=_read(results, recipe.inset_source), conditions_walks=_read(results, recipe.conditions_source))
