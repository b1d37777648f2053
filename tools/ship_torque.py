#!/usr/bin/env python
"""Re-make everything results/ ships for the torque recipe from its trained seeds, in one command.

    python train.py --config configs/torque.yaml --seeds 0-4 --run-dir runs/torque
    python train.py --config configs/torque.yaml --seeds 6-8 --run-dir runs/torque_fresh   # never tuned on
    python tools/ship_torque.py runs/torque --fresh runs/torque_fresh --work runs/torque_ship --workers 2

The inputs are recipe run folders (holding seed<N>/) or seed folders themselves, e.g. `runs/torque
results/torque/policy/seed4` to re-make seeds 0-3 and keep the shipped seed 4. In order, each step an existing
command (printed before it runs):
1. each seed folder's actors, logs and phase settings into results/torque/policy/seed<N>/
   (tools/ship_result.py --all-phases; a seed folder it already wrote, a kept result, is copied as it is);
   a shipped seed not among the inputs is removed: results/torque/ holds what was given, nothing older;
2. the walk check of every shipped actor, the policy alone for 10 s on the ideal robot and hardware-like draws 0
   and 1, with the trot controller's cost beside it (evaluate.py check → figures_input/torque_check.json);
3. the paper's extraction of each seed's measured foot path (evaluate.py extract → results/torque/paths/); a seed
   whose stage-2 policy leaves no path that replays in the band at every speed has none, and is named;
4. Table 5's torque rows for those paths (evaluate.py compare → figures_input/comparison_torque.json) and the
   prototype's protocol for the paths and, closed loop, every seed's policy (evaluate.py prototype →
   figures_input/prototype_torque.json);
5. the README's and docs/results.md's tables (tools/make_readme_tables.py --write).
Seeds given with --fresh (the recipe was never tuned on them) go through steps 1-4 apart: results/torque/fresh/
and figures_input/*_fresh.json, so that their rows stand beside the tuning seeds' (a re-make without --fresh
removes them).

Each evaluate.py step writes its own folder under --work (refused if it holds results, unless --force); results/
is written only from a step that succeeded. 3.3 min on 2 workers for five seeds, 1.9 more for
three fresh ones (2-core AMD EPYC).
"""
from __future__ import annotations

import argparse
import os
import re
import shutil
import subprocess
import sys
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
SEED_FOLDER = re.compile(r"seed(\d+)$")
FRESH_FILES = ("torque_check_fresh.json", "comparison_torque_fresh.json", "prototype_torque_fresh.json")


def run(cmd: list, stop_on_failure: bool = True) -> bool:
    """Run one step from the repository root; a failure stops the whole re-make unless told otherwise."""
    shown = " ".join(str(c) for c in cmd)
    print(f"\n$ {shown}", flush=True)
    t0 = time.monotonic()
    done = subprocess.run([str(c) for c in cmd], cwd=REPO)
    if done.returncode != 0 and stop_on_failure:
        sys.exit(f"failed (exit {done.returncode}): {shown}")
    print(f"  ({(time.monotonic() - t0) / 60:.1f} min)", flush=True)
    return done.returncode == 0


def seed_folders(inputs: list[Path]) -> list[Path]:
    """The seed folders of `inputs` (recipe run folders holding seed<N>/, or seed<N> folders), by seed; a seed
    given twice is refused."""
    folders = []
    for runs in inputs:
        if SEED_FOLDER.match(runs.name):
            folders.append(runs)
            continue
        found = [p for p in runs.iterdir() if p.is_dir() and SEED_FOLDER.match(p.name)]
        if not found:
            sys.exit(f"{runs}: no seed<N> folders (train.py --config configs/torque.yaml --seeds ... "
                     f"--run-dir {runs})")
        folders += found
    names = [p.name for p in folders]
    twice = sorted({n for n in names if names.count(n) > 1})
    if twice:
        sys.exit(f"given twice: {', '.join(twice)} ({', '.join(str(p) for p in folders if p.name in twice)})")
    return sorted(folders, key=lambda p: int(SEED_FOLDER.match(p.name).group(1)))


def repo_relative(path: Path) -> Path:
    return path.relative_to(REPO) if path.is_relative_to(REPO) else path


def is_shipped(folder: Path) -> bool:
    """A folder tools/ship_result.py --all-phases wrote (actors, logs, metadata.json), not a lineage to ship."""
    return (folder / "metadata.json").is_file() and (folder / "recipe_phases.yaml").is_file() \
        and not (folder / "phases.yaml").is_file()


def ship_actors(inputs: list[Path], policy_root: Path, py: str) -> list[Path]:
    """Step 1: each input's seed folders into `policy_root`/seed<N>/ (tools/ship_result.py --all-phases, or a
    copy of a folder it already wrote); a seed shipped there before and not among the inputs is removed (the
    extraction reads every seed shipped). The shipped folders, by seed."""
    folders = seed_folders(inputs)
    given = {f.name for f in folders}
    for old in sorted(policy_root.glob("seed*")) if policy_root.is_dir() else []:
        if SEED_FOLDER.match(old.name) and old.name not in given:
            print(f"\n{old}: not among the inputs, removed (the extraction reads every seed shipped)", flush=True)
            shutil.rmtree(old)
    shipped = []
    for folder in folders:
        out = policy_root / folder.name
        if is_shipped(folder):  # shipped elsewhere before (a kept result): copied as it is
            print(f"\n{folder} is a shipped folder: copied to {out}", flush=True)
            if out.resolve() != folder.resolve():
                shutil.rmtree(out, ignore_errors=True)
                shutil.copytree(folder, out)
        else:
            run([py, "tools/ship_result.py", folder, "--all-phases", "--out", out, "--force"])
        shipped.append(out)
    return shipped


def evaluate_seeds(shipped: list[Path], folder: Path, figures: Path, work: Path, suffix: str, py: str,
                   n_workers: int, force: list[str]) -> tuple[Path, int, int]:
    """Steps 2-4 for the seeds shipped in `folder`/policy: their check, their paths into `folder`/paths, Table
    5's rows and the prototype's protocol, each step's output copied to figures/<name><suffix>.json. Returns
    (folder, paths found, seeds)."""
    policy_root, paths_root = folder / "policy", folder / "paths"
    workers = ["--workers", str(n_workers)]
    # 2. do they walk, alone, in the band (and what the trot costs at the same speeds)
    run([py, "evaluate.py", "check", "--runs", *shipped, "--robots", "ideal", "hardware:0", "hardware:1", "--trot",
         "--out", work / "check", *workers, *force])
    shutil.copyfile(work / "check" / "policy_check.json", figures / f"torque_check{suffix}.json")

    # 3. the paper's extraction; --workers > 1 keeps going past a seed without a path that replays
    failed = not run([py, "evaluate.py", "extract", "--sweep", policy_root, "--out", work / "paths",
                      "--workers", str(max(2, n_workers)), *force], stop_on_failure=False)
    paths = sorted(q for q in (work / "paths" / "learned").glob("seed*.json") if SEED_FOLDER.match(q.stem))
    if not paths:
        sys.exit("the extraction found no path that replays in the band for any seed")
    missing = sorted({f.name for f in shipped} - {q.stem for q in paths})
    if failed or missing:
        print(f"  no path (none replays in the band): {', '.join(missing) or 'see the log above'}", flush=True)
    if paths_root.exists():
        shutil.rmtree(paths_root)  # a seed without a path now must not keep the old one
    paths_root.mkdir(parents=True)
    for q in paths:
        shutil.copyfile(q, paths_root / q.name)

    # 4. Table 5's torque rows for the seeds with a path; the prototype's protocol for those paths and, closed
    # loop, for every seed's policy (a policy whose path does not replay still walks the protocol itself)
    run([py, "evaluate.py", "compare", "--learned", paths_root, "--out", work / "compare", *workers, *force])
    shutil.copyfile(work / "compare" / "comparison.json", figures / f"comparison_torque{suffix}.json")
    actors = [f / "stage2_actor.pt" for f in shipped]
    run([py, "evaluate.py", "prototype", "--learned", paths_root, "--closed-loop", *actors,
         "--no-prototype-reference", "--out", work / "prototype", *workers, *force])
    shutil.copyfile(work / "prototype" / "prototype.json", figures / f"prototype_torque{suffix}.json")
    return folder, len(paths), len(shipped)


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("runs", type=Path, nargs="+", help="the recipe's run folders (train.py --run-dir), holding "
                   "seed<N>/, or seed folders; a seed folder that tools/ship_result.py --all-phases already wrote "
                   "is copied as it is")
    p.add_argument("--fresh", type=Path, nargs="+", default=[], metavar="RUNS",
                   help="run or seed folders of seeds the recipe was never tuned on: shipped apart, into "
                   "results/torque/fresh/, with the figures_input files named *_fresh.json")
    p.add_argument("--work", type=Path, required=True,
                   help="folder for the evaluate.py outputs (check/, paths/, compare/, prototype/)")
    p.add_argument("--results", type=Path, default=REPO / "results",
                   help="the results folder to write torque/ and figures_input/ into (default: the repository's)")
    p.add_argument("--workers", type=int, default=2, help="walk processes at once (default 2)")
    p.add_argument("--force", action="store_true", help="replace earlier outputs under --work")
    args = p.parse_args(argv)
    # inside the repository, paths are given to each step relative to it: the shipped files record them
    runs = [repo_relative(a.resolve()) for a in args.runs]
    args.fresh = [repo_relative(a.resolve()) for a in args.fresh]
    work, results = (repo_relative(a.resolve()) for a in (args.work, args.results))
    os.chdir(REPO)  # as each step runs
    for given, folder in zip(args.runs + args.fresh, runs + args.fresh):
        if not folder.is_dir():
            sys.exit(f"{given}: no such folder")
        if work == folder or folder in work.parents:
            sys.exit("--work must be outside the run folders (their seed<N> folders are the inputs)")
    py, force = sys.executable, ["--force"] if args.force else []
    policy_root, figures = results / "torque" / "policy", results / "figures_input"

    both = {f.name for f in seed_folders(runs)} & ({f.name for f in seed_folders(args.fresh)} if args.fresh else set())
    if both:  # before anything is written
        sys.exit(f"given both as tuned and as --fresh: {', '.join(sorted(both))}")
    tuned = ship_actors(runs, policy_root, py)
    fresh = ship_actors(args.fresh, results / "torque" / "fresh" / "policy", py) if args.fresh else []
    counts = [evaluate_seeds(tuned, results / "torque", figures, work, "", py, args.workers, force)]
    if fresh:
        counts.append(evaluate_seeds(fresh, results / "torque" / "fresh", figures, work / "fresh", "_fresh",
                                     py, args.workers, force))
    elif (results / "torque" / "fresh").exists():  # fresh seeds of an older recipe must not outlive it
        print(f"\n{results / 'torque' / 'fresh'}: no --fresh seeds given, removed", flush=True)
        shutil.rmtree(results / "torque" / "fresh")
        for name in FRESH_FILES:
            (figures / name).unlink(missing_ok=True)

    # 5. the tables
    if results == Path("results"):
        run([py, "tools/make_readme_tables.py", "--write"])
    for (folder, n_paths, n_seeds), suffix in zip(counts, ("", "_fresh")):
        print(f"\nshipped: {folder / 'policy'}, {folder / 'paths'} ({n_paths} paths of {n_seeds} seeds), "
              f"{figures}/torque_check{suffix}.json, comparison_torque{suffix}.json, prototype_torque{suffix}.json")
    return 0


if __name__ == "__main__":
    sys.exit(main())
