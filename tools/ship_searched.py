#!/usr/bin/env python
"""The walks behind a searched-start recipe's table, made from its paths in one command.

    python tools/ship_searched.py searched_wide --learned results/battery_searched_wide/paths \
        --work runs/searched_wide_walks --workers 2
    python tools/make_readme_tables.py --table searched_wide

NAME is a recipe of `cyberdog.analysis.searched_start_table.RECIPES` (its table reads the files this writes);
--learned are the folders of its paths (seed<N>_<speed>mps.json, every seed in them walked; a speed where a seed
has no path is walked without it). Each step is an `evaluate.py` command, printed before it runs, writing its own
folder under --work:

1. prototype: the prototype run (two hardware-like robots per seed, 20 m at 1.0, 1.2 and 1.4 m/s), the shape
   searched for the battery as its reference                                    -> prototype_NAME.json
2. compare: Table 5's 10 s walk on the ideal robot against the shape searched on Eq. 7 (--eq7-reference)
                                                                                -> comparison_NAME.json
3. mujoco: step 1 in the second engine (--set sim.engine=mujoco)                 -> prototype_NAME_mujoco.json
4. own: step 1 with the recipe's own start as the reference (the shape its preset's trot walks, which a zero
   action walks)                                                                -> prototype_NAME_own.json
5. gains_*: kp or kd alone at 0.5x and 2x the drivers' defaults (`PIDConfig`), on the hardware-like robots: as
   commanded, the searched shape walked under the same gains, and re-commanded for them
   (--pd-matched-from-default, no reference); joined by `tools/merge_walks.py gains`  -> gains_NAME.json
6. gains_own_*: the four as commanded with the own start as the reference        -> gains_NAME_own.json
7. inset: step 1 with the shape searched for the battery with a 30 mm narrower stance as the reference
   (`searched_start_table.INSET_REFERENCE`; --inset-reference)                   -> prototype_NAME_inset.json
8. conditions_*: step 7 with a 3 kg payload, and on floors of friction 0.4 and 1.2 (`CONDITION_SETTINGS`: past
   the ranges the recipes train over); joined by `tools/merge_walks.py conditions`  -> conditions_NAME.json

The prototype-run steps (all but compare) walk each seed once: a step's folder holds batches, one per run,
named by their seeds (`seed40-seed41-...`), and the step's walks are the batches' joined (`all_seeds/`). Every walk
belongs to one seed (its path, and the references at its lift, on the same robots), so a batch walks its seeds as
one run over every seed would. A batch is kept where it holds its result, made by the same command on the same
inputs (each keeps its command, but for --workers, with a digest of its paths' files and of the reference shape it
walks, in `ship_searched_command.txt`); the seeds no kept batch holds are walked in one new batch. So seeds added to
--learned are the only ones walked, a re-make stopped half way continues where it stopped, and a seed whose paths
were re-extracted or re-picked is walked again (with its batch's other seeds). compare walks every seed in one
run (its references are walked once per lift for all seeds) and is kept the same way.

The eight files are made in --work (the gains and the conditions runs joined into --work/joined/) and copied into
--results/figures_input/ once every step and join has succeeded, replacing the ones there. --force walks every step
again. `--quick` walks every step at 1.0 m/s with short walks (2 m and one draw; 2 s), into a --results folder other
than the repository's: a check that the chain runs, not a result.
"""
from __future__ import annotations

import argparse
import hashlib
import json
import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))  # run as a script from anywhere

from cyberdog import config as C  # noqa: E402
from cyberdog.analysis.searched_start_table import INSET_REFERENCE, RECIPES  # noqa: E402
from cyberdog.evaluation.learned import DEFAULT_PROTOTYPE_REFERENCE  # noqa: E402
from cyberdog.provenance import repo_relative  # noqa: E402

EQ7_REFERENCE = REPO / "results/searched_shapes/optimized_trajectory_H0.085_placed_loop.json"  # Eq. 7, H 0.085 m
COMMAND_FILE = "ship_searched_command.txt"
GAIN_SCALES = (0.5, 2.0)
# step 8's settings (`cyberdog.analysis.conditions_table.CONDITIONS`), beyond the recipes' training ranges (mass scale
# 0.9-1.15 on 13.6 kg, floor friction 0.8 x 0.7-1.3): by step name, its --set
CONDITION_SETTINGS = {"payload3": "robot.payload=3.0", "friction0.4": "sim.ground_friction=0.4",
                      "friction1.2": "sim.ground_friction=1.2"}
QUICK = {"prototype": ["--speeds", "1.0", "--prototype-distance", "2", "--prototype-draws", "1"],
         "compare": ["--speeds", "1.0", "--duration", "2"]}


def gain_setting(gain: str, scale: float) -> str:
    """`--set pid.kp=[30.0,30.0,30.0]`'s value: the drivers' default `gain` times `scale` on every joint."""
    return f"pid.{gain}=[{','.join(repr(v * scale) for v in getattr(C.PIDConfig(), gain))}]"


def steps(own_start: Path, eq7: Path, inset: Path) -> list[tuple[str, list, str]]:
    """(folder, evaluate.py arguments but the paths, its result file) of every step, in the order they run; the
    paths go in as `--learned ... --skip-missing-paths` after the subcommand."""
    own = ["--prototype-reference", own_start]
    out = [("prototype", ["prototype"], "prototype.json"),
           ("compare", ["compare", "--reference", eq7], "comparison.json"),
           ("mujoco", ["prototype", "--set", "sim.engine=mujoco"], "prototype.json"),
           ("own", ["prototype", *own], "prototype.json")]
    for gain in ("kp", "kd"):
        for scale in GAIN_SCALES:
            tag, gains = f"{gain}{scale:g}", ["--prototype-modes", "hardware", "--set", gain_setting(gain, scale)]
            out += [(f"gains_{tag}", ["prototype", *gains], "prototype.json"),
                    (f"gains_{tag}_recommanded", ["prototype", *gains, "--no-prototype-reference",
                                                  "--pd-matched-from-default"], "prototype.json"),
                    (f"gains_own_{tag}", ["prototype", *gains, *own], "prototype.json")]
    out.append(("inset", ["prototype", "--prototype-reference", inset], "prototype.json"))
    return out + [(f"conditions_{tag}", ["prototype", "--prototype-reference", inset, "--set", setting],
                   "prototype.json") for tag, setting in CONDITION_SETTINGS.items()]


def with_paths(argv: list, paths: list) -> list:
    """The step's evaluate.py arguments walking `paths` (folders or files)."""
    return [argv[0], "--learned", *paths, "--skip-missing-paths", *argv[1:]]


def seed_files(learned: list[Path]) -> dict[str, list[Path]]:
    """{seed label: its path files} over the folders (seed<N>_<speed>mps.json), in the seeds' order; exits on a file
    name found in two folders (one seed's path twice)."""
    by_seed: dict[str, list[Path]] = {}
    where: dict[str, Path] = {}
    for folder in learned:
        for f in sorted(folder.glob("seed*_*mps.json")):
            if f.name in where:
                sys.exit(f"--learned: {f.name} is in {where[f.name]} and in {folder}: give each seed's paths once")
            where[f.name] = folder
            by_seed.setdefault(f.name.split("_", 1)[0], []).append(f)
    number = lambda label: (0, int(label[4:]), "") if label[4:].isdigit() else (1, 0, label)
    return dict(sorted(by_seed.items(), key=lambda item: number(item[0])))


def step_references(argv: list) -> list[Path]:
    """The reference shape a step walks beside the paths: the file its arguments name, else the prototype run's
    default (none with --no-prototype-reference)."""
    for flag in ("--reference", "--prototype-reference"):
        if flag in argv:
            return [Path(argv[argv.index(flag) + 1])]
    none = argv[0] != "prototype" or "--no-prototype-reference" in argv
    return [] if none else [repo_relative(DEFAULT_PROTOTYPE_REFERENCE)]


def inputs_digest(files: list[Path]) -> str:
    """sha256 over the names and bytes of `files`: what the walks read besides their command."""
    h = hashlib.sha256()
    for f in sorted(files):
        h.update(str(f).encode() + b"\0" + f.read_bytes() + b"\0")
    return h.hexdigest()


def step_command(folder: Path, argv: list, digest: str) -> tuple[list, str]:
    """The evaluate.py words of a step into `folder`, and the record that says what it walks: its command (but
    --workers, which changes no walk) and the digest of what it reads."""
    words = ["evaluate.py", *argv, "--out", folder]
    return words, " ".join(str(w) for w in words) + (f"\ninputs sha256 {digest}" if digest else "")


def is_kept(folder: Path, record: str, result: str) -> bool:
    """`folder` holds `result` from the step `record` describes."""
    made = folder / COMMAND_FILE
    return (folder / result).is_file() and made.is_file() and made.read_text().strip() == record


def run_step(folder: Path, argv: list, result: str, workers: int, force: bool, digest: str = "") -> None:
    """One evaluate.py step into `folder`, unless it holds `result` from the same command on inputs of the same
    `digest`; exits on a failure."""
    words, record = step_command(folder, argv, digest)
    if not force and is_kept(folder, record, result):
        print(f"\nkept {folder} (its result, from the same command)", flush=True)
        return
    print(f"\n$ python {' '.join(str(w) for w in words)} --workers {workers}", flush=True)
    t0 = time.monotonic()
    done = subprocess.run([sys.executable, *(str(w) for w in words), "--workers", str(workers), "--force"],
                          cwd=REPO)  # --force: the folder is this tool's own
    if done.returncode != 0:
        sys.exit(f"failed (exit {done.returncode}): python {' '.join(str(w) for w in words)}")
    (folder / COMMAND_FILE).write_text(record + "\n")
    print(f"  ({time.monotonic() - t0:.0f} s)", flush=True)


def run_batched_step(folder: Path, argv: list, result: str, by_seed: dict[str, list[Path]], shared: list[Path],
                     workers: int, force: bool) -> Path:
    """A prototype-run step over every seed of `by_seed`, walked in batches under `folder` (the module docstring):
    the batches kept, the other seeds walked in one new batch, and their walks joined into `folder`/all_seeds/
    (`result` and the runs' config.yaml, the same in every batch), which is returned."""
    folder.mkdir(parents=True, exist_ok=True)

    def batch(seeds: list[str]) -> tuple[Path, list, str]:
        files = [f for s in seeds for f in by_seed[s]]
        return folder / "-".join(seeds), with_paths(argv, files), inputs_digest(files + shared)

    batches, covered = [], set()
    for old in sorted(p for p in folder.iterdir() if p.is_dir() and p.name.startswith("seed")):
        seeds = old.name.split("-")
        if force or not set(seeds) <= by_seed.keys() - covered or not is_kept(old, step_command(*batch(seeds))[1],
                                                                                   result):
            shutil.rmtree(old)  # the tool's own folder: seeds gone from --learned, or walked on other inputs
            continue
        print(f"\nkept {old} (its result, from the same command)", flush=True)
        batches.append(old)
        covered |= set(seeds)
    todo = [s for s in by_seed if s not in covered]
    if todo:
        new, step_argv, digest = batch(todo)
        run_step(new, step_argv, result, workers, True, digest)
        batches.append(new)
    order = list(by_seed)
    return join_batches(sorted(batches, key=lambda b: order.index(b.name.split("-")[0])), folder / "all_seeds", result)


def join_batches(batches: list[Path], out: Path, result: str) -> Path:
    """The batches' walks (lists of rows) in one `result` under `out`, with their config.yaml (exits if two batches
    walked other settings)."""
    configs = {(b / "config.yaml").read_text() for b in batches}
    if len(configs) != 1:
        sys.exit(f"the batches {', '.join(b.name for b in batches)} walked with other settings (config.yaml)")
    out.mkdir(parents=True, exist_ok=True)
    rows = [row for b in batches for row in json.loads((b / result).read_text())]
    (out / result).write_text(json.dumps(rows, indent=2))
    (out / "config.yaml").write_text(configs.pop())
    return out


def main(argv: list[str] | None = None) -> int:
    names = {r.name: r for r in RECIPES}
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("name", choices=sorted(names), help="the recipe whose table the walks are for")
    p.add_argument("--learned", type=Path, nargs="+", required=True,
                   help="the folders of the recipe's paths (seed<N>_<speed>mps.json)")
    p.add_argument("--work", type=Path, required=True, help="folder for the steps' evaluate.py outputs")
    p.add_argument("--results", type=Path, default=REPO / "results",
                   help="the results folder whose figures_input/ gets the files (default: the repository's)")
    p.add_argument("--eq7-reference", type=Path, default=EQ7_REFERENCE,
                   help=f"the shape searched on Eq. 7 at the paths' lift, step 2's reference (default "
                        f"{EQ7_REFERENCE.relative_to(REPO)})")
    p.add_argument("--inset-reference", type=Path, default=REPO / INSET_REFERENCE,
                   help=f"the shape searched for the battery with a narrower stance, step 7's reference (default "
                        f"{INSET_REFERENCE})")
    p.add_argument("--workers", type=int, default=2, help="walk processes at once in each step (default 2)")
    p.add_argument("--force", action="store_true", help="walk every step again, even one whose result is there")
    p.add_argument("--quick", action="store_true", help="every step at 1.0 m/s with short walks, into a --results "
                   "folder other than the repository's: a check that the chain runs")
    args = p.parse_args(argv)
    recipe = names[args.name]
    learned = [repo_relative(f) for f in args.learned]
    work, results, eq7, inset = (repo_relative(f) for f in (args.work, args.results, args.eq7_reference,
                                                             args.inset_reference))
    os.chdir(REPO)  # as each step runs
    for given, folder in zip(args.learned, learned):
        if not folder.is_dir() or not any(folder.glob("seed*_*mps.json")):
            sys.exit(f"--learned {given}: not a folder of paths (seed<N>_<speed>mps.json)")
    for given, reference in ((f"--eq7-reference {args.eq7_reference}", eq7),
                             (f"--inset-reference {args.inset_reference}", inset)):
        if not reference.is_file():
            sys.exit(f"{given}: no such file")
    if args.workers < 1:
        sys.exit(f"--workers {args.workers}: at least 1")
    if args.quick and results == Path("results"):
        sys.exit("--quick makes no result to ship: give it a --results folder of its own")
    sampled = C.load_preset(recipe.config).phases[-1].config.env.walk.gait.sampled_file
    if not sampled:
        sys.exit(f"{recipe.config}: its trot walks no searched shape (gait.sampled_file), so it has no own start to "
                 "walk as a reference: not a searched-start recipe")
    own_start = Path(sampled)
    by_seed = seed_files(learned)
    paths = [f for folder in learned for f in folder.glob("*.json")]

    made = {}
    for folder, step_argv, result in steps(own_start, eq7, inset):
        if step_argv[0] == "compare":  # its references are walked once per lift for every seed: one run
            run_step(work / folder, with_paths(step_argv, learned) + (QUICK["compare"] if args.quick else []),
                     result, args.workers, args.force, inputs_digest(paths + step_references(step_argv)))
            made[folder] = work / folder / result
        else:
            step_argv = step_argv + (QUICK["prototype"] if args.quick else [])
            made[folder] = run_batched_step(work / folder, step_argv, result, by_seed,
                                            step_references(step_argv), args.workers, args.force) / result

    joined = work / "joined"  # the runs joined here first: nothing is shipped until all eight files are made
    joined.mkdir(parents=True, exist_ok=True)
    own_gains = [f for f in made if f.startswith("gains_own_")]
    gains = [f for f in made if f.startswith("gains_") and f not in own_gains]
    conditions = [f for f in made if f.startswith("conditions_")]
    for kind, folders, target in (("gains", gains, recipe.gains_source), ("gains", own_gains, recipe.own_gains_source),
                                  ("conditions", conditions, recipe.conditions_source)):
        merge = [sys.executable, "tools/merge_walks.py", kind, *(made[f].parent for f in folders), "--out",
                 joined / target, "--force"]
        print("\n$ python " + " ".join(str(w) for w in merge[1:]), flush=True)
        if subprocess.run([str(w) for w in merge]).returncode != 0:
            sys.exit(f"failed: joining {', '.join(folders)} into {joined / target}")
        made[target] = joined / target
    figures = results / "figures_input"
    figures.mkdir(parents=True, exist_ok=True)
    for source, target in (("prototype", recipe.prototype_source), ("compare", recipe.compare_source),
                           ("mujoco", f"prototype_{recipe.name}_mujoco.json"), ("own", recipe.own_start_source),
                           ("inset", recipe.inset_source),
                           (recipe.gains_source, recipe.gains_source),
                           (recipe.own_gains_source, recipe.own_gains_source),
                           (recipe.conditions_source, recipe.conditions_source)):
        shutil.copyfile(made[source], figures / target)
    print(f"\nwrote {figures}/: {recipe.prototype_source}, {recipe.compare_source}, prototype_{recipe.name}_mujoco"
          f".json, {recipe.own_start_source}, {recipe.gains_source}, {recipe.own_gains_source}, "
          f"{recipe.inset_source}, {recipe.conditions_source}; the table: python "
          f"tools/make_readme_tables.py --table {recipe.name}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
