"""`evaluate.py pick`: one seed's learned path per speed, chosen among several extractions' paths by the
extraction's own check robots.

A commanded path's extraction keeps, among its candidates, the one with the least electrical energy per metre on
the replay check's hardware-like robots (`cyberdog.analysis.replay_check`: six validation robots at PD 0.7 / 1.0 /
1.4x, 100 m each, never the prototype run's test robots), and records that cost in the path's provenance
(`replay_check.candidates[].electrical_J_per_m`). `pick` applies the same rule one level up: given the learned
paths of several extractions (the lineages a seed was trained as, say seed 40 and seed 140 of one recipe), it
keeps at each speed the path cheapest on those robots, and saves it under one label (`--label`; with
`--lineage-offset K`, seeds N, N + K, ... are seed N's lineages, each seed picked apart). A speed where only one
lineage has a path takes that one. Costs are compared only where every candidate was checked by the same walks.

The picked file keeps its path's provenance and adds `label` (which `LearnedSet.load` labels it by) and `picked`:
every candidate's file, label, training seed and cost, and the rule. Writes learned/<label>_<v>mps.json and
pick.{csv,json,md}. It walks nothing, so --set, --config and --no-recorded-trot are refused.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from cyberdog.evaluation.options import UsageError, at_least_one

LINE = "per speed, the learned path cheapest on the extraction's check robots among several extractions'"
PARAGRAPH = ("per speed, keep the learned path (commanded, extracted with the replay check) that is cheapest on "
             "the extraction's hardware-like check robots (the electrical energy per metre its provenance records; "
             "never the prototype's test robots) among those of every --learned folder or file, and save it under "
             "one label (--label, default the first input's): several lineages of one seed become that seed's "
             "paths; with --lineage-offset K, each seed N's lineages (seeds N, N + K, ...) become seed N's. A speed "
             "only one lineage has takes that lineage's path. Writes learned/<label>_<v>mps.json "
             "(provenance: every candidate and its cost) and pick.{csv,json,md}.")
SELECTED_BY = "least electrical energy per metre on the extraction's hardware-like check robots"
# what the check walked: costs are comparable only where these agree (cyberdog.analysis.replay_check.check_settings)
CHECK_KEYS = ("distance_m", "hardware_like_seeds", "hardware_like_pd_scales", "controller")
# the check's other settings (replay_check.walk_settings), compared where every candidate records them: paths
# extracted before they were recorded compare on CHECK_KEYS alone
RECORDED_KEYS = ("walk_settings",)


def add_options(p) -> None:
    """The options of `pick` (besides the output folder)."""
    p.add_argument("--learned", type=Path, nargs="+", required=True, metavar="PATH",
                   help="the candidates: learned path folders (an extraction's <out>/learned/) or files, the paths "
                        "of two or more lineages a label")
    who = p.add_mutually_exclusive_group()
    who.add_argument("--label", default=None,
                     help="the one label the picked paths are saved under (default: the first input's first label, "
                          "e.g. seed40)")
    who.add_argument("--lineage-offset", type=at_least_one, default=None, metavar="K",
                     help="the inputs are several seeds' lineages, seeds N, N + K, ... of seed N (K = 100: seed 140 "
                          "is seed 40's second): a pick for each, saved as seed<N>")


@dataclass(frozen=True)
class Candidate:
    """One commanded learned path offered to the pick, with its cost on the check robots."""

    file: Path
    label: str
    speed: float  # m/s it was recorded at
    seed: int | None  # the training seed of the policy it came from
    electrical_J_per_m: float
    check: dict  # what the check walked (CHECK_KEYS, RECORDED_KEYS)
    source: Path  # the --learned input it came from (a folder or the file itself)
    policy: str | None = None  # the actor it was extracted from, as its provenance names it


def check_cost(provenance: dict, where: str) -> tuple[float, dict]:
    """(electrical J/m of the kept candidate on the check's hardware-like robots, what the check walked) of a
    commanded path's provenance; UsageError where the path was not replay-checked."""
    check = provenance.get("replay_check") or {}
    if check.get("status") != "ok" or not check.get("candidates"):
        raise UsageError(f"{where}: its extraction did not run the replay check (no cost on the check robots to "
                         "pick by); extract it without --no-replay-check")
    kept = [c for c in check["candidates"] if c.get("rollout_seed") == provenance.get("rollout_seed")
            and c.get("cycle") == provenance.get("cycle")]
    if not kept or kept[0].get("electrical_J_per_m") is None:
        raise UsageError(f"{where}: its replay check recorded no electrical energy per metre for the kept path "
                         f"(rollout seed {provenance.get('rollout_seed')}, cycle {provenance.get('cycle')!r})")
    return float(kept[0]["electrical_J_per_m"]), {k: check.get(k) for k in CHECK_KEYS + RECORDED_KEYS}


def load_candidates(inputs: list[Path]) -> list[Candidate]:
    """Every path of every input, in the order given; UsageError for a sampled path, one without a check, or a
    file given twice (a folder and a file in it, say: it would be a candidate against itself)."""
    from cyberdog.core.learned_set import LearnedSet, learned_files

    out, seen = [], {}
    for source in map(Path, inputs):
        for f in learned_files([source]):  # LearnedSetError: a missing or empty input, named
            if f.resolve() in seen:
                raise UsageError(f"--learned: {f} is given twice (in {seen[f.resolve()]} and {source}); name each "
                                 "extraction once")
            seen[f.resolve()] = source
            for p in LearnedSet.load([f]).paths():
                if not p.commanded:
                    raise UsageError(f"--learned {f}: a sampled (measured) path serves every speed and has no cost "
                                     "on the check robots; pick takes commanded paths")
                cost, check = check_cost(p.provenance, f"--learned {f}")
                out.append(Candidate(f, p.label, float(p.speed), p.provenance.get("seed"), cost, check, source,
                                     p.provenance.get("policy")))
    return out


def _same_speed(a: Candidate, b: Candidate) -> bool:
    return abs(a.speed - b.speed) < 1e-6


def pick(candidates: list[Candidate]) -> dict[float, tuple[Candidate, list[Candidate]]]:
    """{speed: (the kept candidate, every candidate at that speed)}: the cheapest on the check robots, the first
    given where two tie. Candidates recorded at speeds within 1e-6 m/s are one group. UsageError where a group's
    candidates were checked by different walks."""
    groups: dict[float, list[Candidate]] = {}
    for c in candidates:
        key = next((v for v in groups if abs(v - c.speed) < 1e-6), c.speed)
        groups.setdefault(key, []).append(c)
    picks = {}
    for speed in sorted(groups):
        group = groups[speed]
        recorded = [k for k in RECORDED_KEYS if all(c.check.get(k) is not None for c in group)]
        differ = [c.file for c in group if any(c.check.get(k) != group[0].check.get(k) for k in CHECK_KEYS)
                  or any(c.check[k] != group[0].check[k] for k in recorded)]
        if differ:
            raise UsageError(f"at {speed:g} m/s, {group[0].file} and {differ[0]} were checked by different walks "
                             f"({', '.join(CHECK_KEYS + RECORDED_KEYS)}): their costs do not compare")
        picks[speed] = (min(group, key=lambda c: c.electrical_J_per_m), group)
    return picks


def refuse_walk_settings(args) -> None:
    """UsageError where a walk's settings are given: pick walks nothing (called before any config is read)."""
    if getattr(args, "overrides", None) or getattr(args, "config", None) or getattr(args, "no_recorded_trot", False):
        raise UsageError("evaluate.py pick reads saved paths and walks nothing, so --set, --config and "
                         "--no-recorded-trot change nothing; leave them out")


def labelled(args, candidates: list[Candidate]) -> dict[str, list[Candidate]]:
    """The candidates of each label to save: all under --label (default the first input's label), or with
    --lineage-offset K the lineages of each seed, seeds N, N + K, N + 2K, ..., under `seed<N mod K>`. UsageError for
    settings that change nothing, a bad label, a label with nothing to choose between, one input holding several
    seeds' paths at a speed without --lineage-offset (a sweep's folder: its seeds would be picked as one), or one
    lineage's path at a speed given twice with it."""
    refuse_walk_settings(args)
    offset = getattr(args, "lineage_offset", None)
    if offset is None:
        label = args.label or candidates[0].label
        if not label or "/" in label or label.startswith("."):
            raise UsageError(f"--label {label!r}: a label is a file-name part, e.g. seed40")
        for a in candidates:
            b = next((b for b in candidates if b.source == a.source and b is not a and _same_speed(a, b)), None)
            if b is not None:
                raise UsageError(f"--learned {a.source} holds two paths at {a.speed:g} m/s ({a.file.name}, "
                                 f"{b.file.name}): several seeds' paths would be picked as one label; give one "
                                 "extraction's paths per input, or --lineage-offset for a sweep's seeds")
        groups = {label: candidates}
    else:
        unseeded = [c.file for c in candidates if not isinstance(c.seed, int)]
        if unseeded:
            raise UsageError(f"--lineage-offset groups paths by their training seed; {unseeded[0]} records none")
        groups = {}
        for c in candidates:
            twin = next((b for b in groups.get(f"seed{c.seed % offset}", []) if b.seed == c.seed
                         and _same_speed(b, c)), None)
            if twin is not None:
                raise UsageError(f"lineage seed{c.seed} has two paths at {c.speed:g} m/s ({twin.file}, {c.file}): "
                                 "give each lineage's extraction once")
            groups.setdefault(f"seed{c.seed % offset}", []).append(c)
    for label, group in groups.items():  # a label whose every speed has one path would be a relabelling
        speeds = [c.speed for c in group]
        if not any(sum(abs(v - w) < 1e-6 for w in speeds) > 1 for v in speeds):
            raise UsageError(f"{label}: one learned path at each speed ({', '.join(str(c.file) for c in group)}), "
                             "nothing to choose between: pick needs two or more lineages' paths a label")
    return groups


def cmd_pick(args, cfg) -> int:
    """The `pick` sub-command: candidates read and checked, the picks made, then the files written."""
    import dataclasses

    from cyberdog.analysis.report import markdown_table, write_rows
    from cyberdog.core.learned_set import LearnedPath, read_path
    from cyberdog.evaluation.output import Run, new_out
    from cyberdog.provenance import portable_path

    candidates = load_candidates(args.learned)
    picks = {label: pick(group) for label, group in labelled(args, candidates).items()}  # UsageError before writing
    out = args.out or new_out()
    # an output folder holding an input could lose it (a re-made folder is cleared first): refused
    inside = [c.file for c in candidates if c.file.resolve().is_relative_to(Path(out).resolve())]
    if inside:
        raise UsageError(f"--out {out}: it holds {inside[0]}, an input of this pick; choose another --out")
    chosen = {(label, speed): LearnedPath(label, read_path(kept.file))
              for label, by_speed in picks.items() for speed, (kept, _) in by_speed.items()}
    run = Run(args, out)
    rows = []
    for label, by_speed in picks.items():
        for speed, (kept, group) in by_speed.items():
            record = [{"file": portable_path(c.file), "label": c.label, "seed": c.seed, "policy": c.policy,
                       "electrical_J_per_m": c.electrical_J_per_m} for c in group]
            path = chosen[label, speed].path
            provenance = {**path.provenance, "label": label,
                          "picked": {"selected_by": SELECTED_BY, "kept": group.index(kept), "candidates": record}}
            saved = LearnedPath(label, dataclasses.replace(path, provenance=provenance)).save(out / "learned")
            rows += [{"label": label, "speed_mps": speed, "candidate": c.label, "seed": c.seed,
                      "electrical_J_per_m": round(c.electrical_J_per_m, 3), "kept": c is kept,
                      "file": portable_path(c.file)} for c in group]
            others = "".join(f"; {c.label} {c.electrical_J_per_m:.2f}" for c in group if c is not kept)
            print(f"{label} at {speed:g} m/s: kept {kept.label}'s path ({kept.electrical_J_per_m:.2f} J/m on the "
                  f"check robots) of {len(group)}{others} -> {saved}")
    write_rows(rows, out, "pick")
    print(markdown_table(rows, list(rows[0])))
    return run.finish()


__all__ = ["CHECK_KEYS", "RECORDED_KEYS", "Candidate", "LINE", "PARAGRAPH", "SELECTED_BY", "add_options",
           "check_cost", "cmd_pick", "labelled", "load_candidates", "pick", "refuse_walk_settings"]
