"""The learned paths `evaluate.py` walks (a `LearnedSet`) loaded from files, the policies and training logs named
on the command line, and the reference shapes; `extraction` makes learned paths from trained policies. Labels are
the provenance's seed ("seed3"), else the file or run folder name.
"""
from __future__ import annotations

import json
from pathlib import Path

from cyberdog import config as C
from cyberdog.core.learned_set import LearnedSet, LearnedSetError, learned_files
from cyberdog.core.trajectories import SampledTrajectory
from cyberdog.evaluation.options import UsageError
from cyberdog.metrics_csv import run_name

ROOT = Path(__file__).resolve().parents[2]
DEFAULT_LEARNED = ROOT / "results" / "table5" / "paths"  # the shipped learned paths: one JSON per seed and speed
# the prototype run's default: the battery recipe's paths (configs/battery.yaml, recorded under the trot with foot
# placement and a speed loop bounded at +-10 %); Table 5 keeps the Eq. 7 recipe's (DEFAULT_LEARNED)
DEFAULT_LEARNED_BATTERY = ROOT / "results" / "battery" / "paths"
DEFAULT_METRICS = ROOT / "results" / "table5" / "policy" / "seed0" / "metrics.csv"  # the shipped policy's training log
# the reference row of the matched-lift table: the direct search's shape at the shipped paths' mean lift height
# (tools/optimize_trajectory.py --lift-height 0.095, the same budget at every speed)
DEFAULT_REFERENCE = ROOT / "results" / "searched_shapes" / "optimized_trajectory_H0.095.json"
# the prototype run's reference row: the direct search's shape for the battery on the hardware-like robot, the
# cheapest of those searched under a shipped trot, each walked under its own: searched under the default trot
# (4.10 / 3.66 / 3.43 % per 100 m at 1.0 / 1.2 / 1.4 m/s; ..._placed_loop.json, under the battery paths' trot:
# 4.49 / 3.96 / 3.61)
DEFAULT_PROTOTYPE_REFERENCE = ROOT / "results" / "searched_shapes" / "optimized_trajectory_H0.085_electrical_hardware.json"
# preference order: the shipped name, then the actor at the end of stage 2 (fixed in advance), then the one of
# its best-scoring episode (chosen on a noisy score)
STAGE2_ACTORS = ("stage2_actor.pt", "stage2_final_actor.pt", "stage2_best_actor.pt")


def policy_file(path: Path) -> Path:
    """An actor file, or the stage-2 actor of a training run folder."""
    if path.is_file():
        return path
    if path.is_dir():
        for name in STAGE2_ACTORS:
            if (path / name).is_file():
                return path / name
        raise UsageError(f"{path} holds no stage-2 actor (looked for {', '.join(STAGE2_ACTORS)})")
    raise UsageError(f"policy {path} does not exist")


def policy_paths(policies: list[Path] | None, sweep: Path | None) -> list[Path]:
    """The actor files of --policies and of every run folder of --sweep (a seed that is a lineage of phases:
    its last phase's run folder)."""
    paths = [policy_file(p) for p in (policies or [])]
    if sweep is not None:
        if not sweep.is_dir():
            raise UsageError(f"--sweep {sweep} is not a folder")
        try:
            folders = sorted(C.final_run(d) for d in sweep.iterdir() if d.is_dir())
        except ValueError as e:
            raise UsageError(f"--sweep {sweep}: {e}") from None
        runs = [d for d in folders if any((d / n).is_file() for n in STAGE2_ACTORS)]
        if not runs:
            raise UsageError(f"--sweep {sweep} has no run folder with a stage-2 actor ({', '.join(STAGE2_ACTORS)})")
        paths += [policy_file(d) for d in runs]
    return paths


def unique_labels(labels: list[str]) -> list[str]:
    out, seen = [], {}
    for lab in labels:
        seen[lab] = seen.get(lab, 0) + 1
        out.append(lab if labels.count(lab) == 1 else f"{lab}-{seen[lab]}")
    return out


def load_learned(paths: list[Path]) -> LearnedSet:
    """`LearnedSet.load` with evaluate.py's errors (a hint where the shipped default folder is missing)."""
    if list(paths) == [DEFAULT_LEARNED] and not DEFAULT_LEARNED.is_dir():
        raise UsageError(f"learned trajectory {DEFAULT_LEARNED} does not exist (train policies with train.py, then "
                         "`evaluate.py extract --sweep RUNS` and pass its <out>/learned/ folder with --learned)")
    try:
        return LearnedSet.load(paths)
    except LearnedSetError as err:
        raise UsageError(str(err)) from None


def check_learned_inputs(args) -> None:
    """Fail now, before any walk, on a missing or unreadable trajectory file or policy, or on a requested
    speed that no learned path can walk."""
    paths = policy_paths(args.policies, args.sweep)
    closed_loop = closed_loop_labels(args)
    if not paths:
        for_prototype = {"all": (False, True), "prototype": (True,), "stiffness": (True,)}.get(args.command, (False,))
        for files in dict.fromkeys(tuple(default_learned(args, p)) for p in for_prototype):
            learned = load_learned(list(files))
            check_speeds_covered(learned, getattr(args, "speeds", []), getattr(args, "skip_missing_paths", None))
        if closed_loop:  # the prototype's paths (the last loaded): each policy walks beside its own seed's
            closed_loop_policies(args, learned)
    from cyberdog.rl.checkpoint import CheckpointError
    from cyberdog.rl.rollout import load_actor

    for path in paths:  # each policy loads (small files): a wrong file fails here, not after other extractions
        try:
            load_actor(path)
        except (CheckpointError, ValueError) as err:
            raise UsageError(f"--policies {path}: {err}") from None


def closed_loop_labels(args) -> dict[str, Path]:
    """{seed<N>: actor file} of --closed-loop (N: the actor's training seed); UsageError for a file that is
    not an actor or two actors of one seed."""
    files = getattr(args, "closed_loop", None) or []
    if not files:
        return {}
    from cyberdog.rl.checkpoint import CheckpointError
    from cyberdog.rl.rollout import load_actor

    out = {}
    for path in files:
        try:
            label = f"seed{load_actor(path).config.train.seed}"
        except (CheckpointError, ValueError, OSError) as err:
            raise UsageError(f"--closed-loop {path}: {err}") from None
        if label in out:
            raise UsageError(f"--closed-loop: {out[label]} and {path} were both trained with {label}")
        out[label] = Path(path)
    return out


def closed_loop_policies(args, learned: LearnedSet) -> dict[str, str]:
    """--closed-loop's actors by the label of the learned path they walk beside; UsageError for an actor whose
    seed has no learned path."""
    policies = closed_loop_labels(args)
    missing = [f"{path} ({label})" for label, path in policies.items() if label not in learned.labels]
    if missing:
        raise UsageError(f"--closed-loop: no learned path of the same seed for {', '.join(missing)} (learned: "
                         f"{', '.join(learned.labels)})")
    return {label: str(path) for label, path in policies.items()}


def check_speeds_covered(learned: LearnedSet, speeds: list[float], skip_missing: bool | None = None) -> None:
    """UsageError unless every label of `learned` has a path at every speed of `speeds` (`LearnedSet.at`,
    the comparison's own rule): a table without its learned row is no Table 5. `skip_missing` (--skip-missing-paths
    of compare and prototype; None where the command has no such option): one label with a path at each speed is
    enough."""
    if skip_missing:
        missing = [v for v in speeds if not any(learned.has(label, v) for label in learned.labels)]
    else:
        missing = [v for v in speeds if not learned.covers(v)]
    if missing:
        have = ", ".join(f"{v:g}" for v in learned.speeds())
        lacking = "; ".join(f"{label} at {v:g}" for v in missing for label in learned.labels
                            if not learned.has(label, v))
        hint = (" (or --skip-missing-paths to walk each speed with the seeds that have one)"
                if skip_missing is False else "")
        raise UsageError(
            f"no learned path at {', '.join(f'{v:g}' for v in missing)} m/s for every label ({lacking}): the learned "
            f"paths are at {have} m/s. Ask for those --speeds{hint}, or extract paths at the speed from a policy "
            f"(evaluate.py extract --policies results/table5/policy/seed0 --speeds V; a policy trained at other "
            f"speeds needs --policy-speed V) and pass them with --learned")


def default_learned(args, for_prototype: bool = False) -> list[Path]:
    """The learned path files or folders to load: --learned, else the shipped default (the battery preset's
    paths for the prototype run where they are shipped, the paper preset's otherwise)."""
    given = getattr(args, "learned", None)
    if given:
        return list(given)
    return [DEFAULT_LEARNED_BATTERY if for_prototype and DEFAULT_LEARNED_BATTERY.is_dir() else DEFAULT_LEARNED]


def reference_shape(args, log=print, prototype: bool = False) -> SampledTrajectory | None:
    """The reference shape of the matched-lift table: --reference FILE, else the shipped one if it is there;
    None with --no-reference or --no-same-lift. With `prototype`, the prototype run's: --prototype-reference
    FILE, else the shipped battery search's; None with --no-prototype-reference."""
    flag, default, where = (("prototype_reference", DEFAULT_PROTOTYPE_REFERENCE, "the prototype tables") if prototype
                            else ("reference", DEFAULT_REFERENCE, "the matched-lift table"))
    if getattr(args, f"no_{flag}", False) or (not prototype and getattr(args, "no_same_lift", False)):
        return None
    option = "--" + flag.replace("_", "-")
    path = getattr(args, flag, None)
    if path is None:
        if not default.is_file():
            log(f"no reference shape ({default} is missing): no reference row in {where}")
            return None
        path = default
    if not Path(path).is_file():
        raise UsageError(f"{option} {path} does not exist")
    try:
        return SampledTrajectory.load(path)
    except (OSError, ValueError, KeyError, json.JSONDecodeError) as err:
        raise UsageError(f"{option} {path}: not a saved foot trajectory ({err})") from None


def metrics_files(metrics: list[Path] | None, policies: list[Path] = ()) -> dict[str, Path]:
    """Training logs for Figure 6 by label: --metrics, else the policies' metrics.csv, else the shipped one."""
    if metrics:
        missing = [m for m in metrics if not m.is_file()]
        if missing:
            raise UsageError(f"--metrics file(s) do not exist: {', '.join(map(str, missing))}")
        return dict(zip(unique_labels([run_name(m) for m in metrics]), metrics))
    found = [p.parent / "metrics.csv" for p in policies if (p.parent / "metrics.csv").is_file()]
    if not found and DEFAULT_METRICS.is_file():
        found = [DEFAULT_METRICS]
    return dict(zip(unique_labels([run_name(m) for m in found]), found))




def open_path_rewrite(args, cfg: C.WalkConfig, why_commanded: str, refusal=None):
    """The output run and the commanded paths of a sub-command that writes each path anew as
    `<out>/learned/<same file name>` (`pd-match`, `stance-force`): the paths of `args.paths` (files or folders);
    a sampled path (`why_commanded` says why it cannot be rewritten), an --out that would write over an input and
    what `refusal(paths)` says (a message, or None) are UsageErrors, raised before the output folder is made."""
    from cyberdog.evaluation.output import new_out, open_run

    files = learned_files(args.paths)
    paths = LearnedSet.load(files).paths()
    flat = [p.label for p in paths if not p.commanded]
    if flat:
        raise UsageError(f"{', '.join(flat)}: {why_commanded}; give commanded path files")
    why = refusal(paths) if refusal is not None else None
    if why:
        raise UsageError(why)
    args.out = args.out or new_out()
    written = {(args.out / "learned" / p.file_name()).resolve() for p in paths}
    if written & {f.resolve() for f in files}:
        raise UsageError(f"--out {args.out} would write over the paths it reads: choose another folder")
    run = open_run(args, cfg)
    (run.out / "learned").mkdir(exist_ok=True)
    return run, paths


__all__ = ["DEFAULT_LEARNED", "DEFAULT_LEARNED_BATTERY", "DEFAULT_METRICS", "DEFAULT_PROTOTYPE_REFERENCE",
           "DEFAULT_REFERENCE", "STAGE2_ACTORS", "check_learned_inputs", "default_learned",
           "load_learned", "metrics_files", "open_path_rewrite", "policy_paths", "reference_shape"]
