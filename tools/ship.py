#!/usr/bin/env python
"""Ship trained results into results/: one run or seed folder (`policy`), or the torque recipe's whole re-make
from its trained seeds in one command (`torque`).

    python tools/ship.py policy runs/table5/seed0 --out results/table5/policy/seed0
    python train.py --config configs/torque.yaml --seeds 0-4 --run-dir runs/torque
    python train.py --config configs/torque.yaml --seeds 6-8 --run-dir runs/torque_fresh   # never tuned on
    python tools/ship.py torque runs/torque --fresh runs/torque_fresh --work runs/torque_ship --workers 2

policy: copy a finished training run into a small shipped folder (results/<recipe>/policy/seed<N>/). The run is
a train.py run folder, or a seed folder of a preset's phases. Writes (never over an existing folder unless
--force): stage1_actor.pt and stage2_actor.pt (the final actors of the two stages; no stage1_actor.pt for a
stage-2 run started from another's agent), config.yaml (the resolved experiment), metrics.csv (the training log,
for Figure 6) and metadata.json (seed, env steps, episodes and wall time per stage, final window scores, the source
run, `shipped_at`: the commit of the checkout that shipped it, and `trained_at`: per shipped actor, the commit of
every process that trained it, as the actor file records it; --trained-at COMMIT states it for actor files written
before that record, and is refused for those that have it). Checkpoints with replay buffers are not copied (tens of MB). A seed folder
ships its last phase's run, or with --all-phases the recipe's two actors: stage<N>_actor.pt from the last phase
that ends with stage N, config.yaml and metrics.csv of the last phase, recipe_phases.yaml (every phase's resolved
settings), metrics_<phase>.csv of each phase and, in metadata.json, each phase's summary. A phase whose final
agent was copied into the seed folder from another (a lineage continued from a kept `main`) has no log there:
metadata.json lists it under placed_phases, and its wall time is not in the seed's.

torque: the inputs are recipe run folders (holding seed<N>/) or seed folders themselves, e.g. `runs/torque
results/torque/policy/seed4` to re-make seeds 0-3 and keep the shipped seed 4. In order, each step an existing
command (printed before it runs):
1. each seed folder's actors, logs and phase settings into results/torque/policy/seed<N>/
   (`tools/ship.py policy --all-phases`; a seed folder it already wrote, a kept result, is copied as it is);
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
removes them). Each evaluate.py step writes its own folder under --work (refused if it holds results, unless
--force); results/ is written only from a step that succeeded. 3.3 min on 2 workers for five seeds, 1.9 more
for three fresh ones (2-core AMD EPYC). `--quick` runs every step at 1.0 m/s alone with short walks, into a
--results folder of its own: a check that the chain runs, not a result.
"""
from __future__ import annotations

import argparse
import json
import os
import re
import shutil
import subprocess
import sys
import time
from pathlib import Path

import yaml

from cyberdog.config.preset import final_run, is_lineage, read_phases
from cyberdog.metrics_csv import read_rows, stage_summary
from cyberdog.provenance import code_state, portable_path, repo_relative
from cyberdog.rl.checkpoint import CheckpointError, recorded_code

REPO = Path(__file__).resolve().parents[1]
FILES = {"stage1_final_actor.pt": "stage1_actor.pt", "stage2_final_actor.pt": "stage2_actor.pt",
         "config.yaml": "config.yaml", "metrics.csv": "metrics.csv"}
OPTIONAL = {"stage1_final_actor.pt"}  # a stage-2 run started with --init-from has no stage-1 actor of its own
MAX_BYTES = 2_000_000  # the shipped folder stays under 2 MB
SEED_FOLDER = re.compile(r"seed(\d+)$")
FRESH_FILES = ("torque_check_fresh.json", "comparison_torque_fresh.json", "prototype_torque_fresh.json")
# torque --quick: each evaluate.py step at one speed with short walks, a check that the chain runs (not a result)
QUICK = {"check": ["--speeds", "1.0", "--duration", "2"], "extract": ["--speeds", "1.0"],
         "compare": ["--speeds", "1.0", "--duration", "2"],
         "prototype": ["--speeds", "1.0", "--prototype-distance", "2", "--prototype-draws", "1"]}


def trained_at(actors: dict[str, Path], stated: str | None) -> dict:
    """metadata.json's `trained_at`: for each actor to ship (shipped name: source file), the commits its file
    records (`cyberdog.rl.run_state`), or the one --trained-at states for files from before that record."""
    try:
        recorded = {name: recorded_code(path) for name, path in actors.items()}
    except CheckpointError as e:
        sys.exit(str(e))
    if stated is not None:
        if any(recorded.values()):
            sys.exit(f"--trained-at: {', '.join(n for n, r in recorded.items() if r)} record the commit that "
                     f"trained them; leave --trained-at out")
        try:
            sha = subprocess.run(["git", "rev-parse", "--verify", f"{stated}^{{commit}}"], cwd=REPO,
                                 capture_output=True, text=True, check=True).stdout.strip()
        except (OSError, subprocess.CalledProcessError):
            sys.exit(f"--trained-at {stated}: not a commit of this repository")
        return {name: [{"git_commit": sha, "git_dirty": None, "stated": "--trained-at"}] for name in recorded}
    missing = [name for name, r in recorded.items() if not r]
    if missing:
        print(f"note: {', '.join(missing)} do not record the commit that trained them (written before the record); "
              f"--trained-at COMMIT states it", file=sys.stderr)
    return {name: r or "not recorded" for name, r in recorded.items()}


# ---- policy: one run or seed folder ----------------------------------------------------------------------------
def ship_policy(args) -> int:
    """`policy`: one run folder, or a seed folder's last phase (or with --all-phases, every phase)."""
    if args.all_phases:
        return ship_lineage(args)
    if final_run(args.run_dir) != args.run_dir:
        args.run_dir = final_run(args.run_dir)
        print(f"a preset's seed folder: shipping its last phase, {args.run_dir}")
    missing = [f for f in FILES if not (args.run_dir / f).is_file() and f not in OPTIONAL]
    if missing:
        sys.exit(f"{args.run_dir} is not a finished run: missing {missing}")
    if args.out.exists() and not args.force:
        sys.exit(f"{args.out} exists; pass --force to replace it")
    if args.init_from is not None and not args.init_from.is_file():
        sys.exit(f"--init-from {args.init_from}: no such file (the run's start, where it is shipped)")
    code = trained_at({dst: args.run_dir / src for src, dst in FILES.items()
                       if src.endswith("_actor.pt") and (args.run_dir / src).is_file()}, args.trained_at)
    args.out.mkdir(parents=True, exist_ok=True)
    for src, dst in FILES.items():
        if (args.run_dir / src).is_file():
            shutil.copy2(args.run_dir / src, args.out / dst)
    rows = read_rows(args.run_dir / "metrics.csv")
    cfg = yaml.safe_load((args.run_dir / "config.yaml").read_text())
    meta = {"seed": cfg["train"]["seed"], "source_run": portable_path(args.run_dir), "shipped_at": code_state(),
            "trained_at": code, "stage1": stage_summary(rows, 1), "stage2": stage_summary(rows, 2), "note": args.note,
            **({"init_from": portable_path(args.init_from)} if args.init_from is not None else {}),
            "actors": "stage<N>_actor.pt = stage<N>_final_actor.pt of the run (the agent at the end of the stage)"}
    return write_metadata(args.out, meta)


def write_metadata(out: Path, meta: dict) -> int:
    """`out`/metadata.json, then the folder's files and size (a warning over MAX_BYTES); the exit status."""
    (out / "metadata.json").write_text(json.dumps(meta, indent=1) + "\n")
    size = sum(f.stat().st_size for f in out.iterdir())
    print(f"wrote {out} ({size / 1e6:.2f} MB): " + ", ".join(sorted(f.name for f in out.iterdir())))
    if size > MAX_BYTES:
        print(f"warning: {size / 1e6:.2f} MB is over the 2 MB the shipped folder should stay under", file=sys.stderr)
    return 0


def ship_lineage(args) -> int:
    """--all-phases: the recipe's two actors and every phase's log, from a preset's seed folder."""
    if not is_lineage(args.run_dir):
        sys.exit(f"{args.run_dir} is not a preset's seed folder (no phases.yaml): --all-phases needs one")
    phases = read_phases(args.run_dir)[0]
    runs = {p.name: args.run_dir / p.name for p in phases}
    shipped = {stage: next((p for p in reversed(phases) if p.last_stage == stage), None) for stage in (1, 2)}
    missing = [p.final_agent for p in phases if not (args.run_dir / p.final_agent).is_file()]
    missing += [f"{p.name}/stage{stage}_final_actor.pt" for stage, p in shipped.items()
                if p is not None and not (runs[p.name] / f"stage{stage}_final_actor.pt").is_file()]
    if missing:
        sys.exit(f"{args.run_dir} is not a finished lineage: missing {missing}")
    # a phase whose final agent was copied in from another folder (the lineage skips it) has no log of its own
    placed = [p.name for p in phases if not (runs[p.name] / "metrics.csv").is_file()]
    if phases[-1].name in placed:
        sys.exit(f"{args.run_dir}: its last phase {phases[-1].name} has no metrics.csv (it was not trained here)")
    if args.out.exists() and not args.force:
        sys.exit(f"{args.out} exists; pass --force to replace it")
    code = trained_at({f"stage{stage}_actor.pt": runs[p.name] / f"stage{stage}_final_actor.pt"
                       for stage, p in shipped.items() if p is not None}, args.trained_at)
    args.out.mkdir(parents=True, exist_ok=True)
    actors = {}
    for stage, last in shipped.items():
        if last is not None:
            shutil.copy2(runs[last.name] / f"stage{stage}_final_actor.pt", args.out / f"stage{stage}_actor.pt")
            actors[f"stage{stage}_actor.pt"] = f"{last.name}/stage{stage}_final_actor.pt"
    final = runs[phases[-1].name]
    shutil.copy2(final / "config.yaml", args.out / "config.yaml")
    shutil.copy2(final / "metrics.csv", args.out / "metrics.csv")
    # under another name: the shipped folder is not a lineage that train.py or extract --sweep would walk into
    shutil.copy2(args.run_dir / "phases.yaml", args.out / "recipe_phases.yaml")
    summaries = {}
    for p in phases:
        if p.name in placed:
            summaries[p.name] = {"stage": p.stage, "from": p.start, "placed": True}
            continue
        shutil.copy2(runs[p.name] / "metrics.csv", args.out / f"metrics_{p.name}.csv")
        rows = read_rows(runs[p.name] / "metrics.csv")
        summary = {s: stage_summary(rows, s) for s in (1, 2)}
        summaries[p.name] = {"stage": p.stage, "from": p.start, **{f"stage{s}": v for s, v in summary.items() if v},
                             "falls": sum(r.get("fell") in ("1", "True", "true") for r in rows)}
    wall = sum(ph[k]["wall_time_s"] for ph in summaries.values() for k in ("stage1", "stage2") if k in ph)
    meta = {"seed": yaml.safe_load((final / "config.yaml").read_text())["train"]["seed"],
            "source_run": portable_path(args.run_dir), "shipped_at": code_state(), "trained_at": code, "actors": actors,
            "phases": summaries, "wall_time_s": round(wall, 1), "placed_phases": placed, "note": args.note}
    return write_metadata(args.out, meta)


# ---- torque: the recipe's whole re-make -----------------------------------------------------------------------
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


def is_shipped(folder: Path) -> bool:
    """A folder `tools/ship.py policy --all-phases` wrote (actors, logs, metadata.json), not a lineage to ship."""
    return (folder / "metadata.json").is_file() and (folder / "recipe_phases.yaml").is_file() \
        and not (folder / "phases.yaml").is_file()


def ship_actors(inputs: list[Path], policy_root: Path, py: str) -> list[Path]:
    """Step 1: each input's seed folders into `policy_root`/seed<N>/ (`policy --all-phases`, or a copy of a
    folder it already wrote); a seed shipped there before and not among the inputs is removed (the
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
            run([py, "tools/ship.py", "policy", folder, "--all-phases", "--out", out, "--force"])
        shipped.append(out)
    return shipped


def evaluate_seeds(shipped: list[Path], folder: Path, figures: Path, work: Path, suffix: str, py: str,
                   n_workers: int, force: list[str], quick: bool = False) -> tuple[Path, int, int]:
    """Steps 2-4 for the seeds shipped in `folder`/policy: their check, their paths into `folder`/paths, Table
    5's rows and the prototype's protocol, each step's output copied to figures/<name><suffix>.json (with
    `quick`, each step on the budgets of QUICK). Returns (folder, paths found, seeds)."""
    policy_root, paths_root = folder / "policy", folder / "paths"
    workers = ["--workers", str(n_workers)]
    small = QUICK if quick else {}
    # 2. do they walk, alone, in the band (and what the trot costs at the same speeds)
    run([py, "evaluate.py", "check", "--runs", *shipped, "--robots", "ideal", "hardware:0", "hardware:1", "--trot",
         "--out", work / "check", *workers, *force, *small.get("check", [])])
    shutil.copyfile(work / "check" / "policy_check.json", figures / f"torque_check{suffix}.json")

    # 3. the paper's extraction; --workers > 1 keeps going past a seed without a path that replays
    failed = not run([py, "evaluate.py", "extract", "--sweep", policy_root, "--out", work / "paths",
                      "--workers", str(max(2, n_workers)), *force, *small.get("extract", [])], stop_on_failure=False)
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
    run([py, "evaluate.py", "compare", "--learned", paths_root, "--out", work / "compare", *workers, *force,
         *small.get("compare", [])])
    shutil.copyfile(work / "compare" / "comparison.json", figures / f"comparison_torque{suffix}.json")
    actors = [f / "stage2_actor.pt" for f in shipped]
    run([py, "evaluate.py", "prototype", "--learned", paths_root, "--closed-loop", *actors,
         "--no-prototype-reference", "--out", work / "prototype", *workers, *force, *small.get("prototype", [])])
    shutil.copyfile(work / "prototype" / "prototype.json", figures / f"prototype_torque{suffix}.json")
    return folder, len(paths), len(shipped)


def ship_torque(args) -> int:
    """`torque`: steps 1-5 of the module's docstring."""
    # inside the repository, paths are given to each step relative to it: the shipped files record them
    runs = [repo_relative(a) for a in args.runs]
    args.fresh = [repo_relative(a) for a in args.fresh]
    work, results = (repo_relative(a) for a in (args.work, args.results))
    os.chdir(REPO)  # as each step runs
    for given, folder in zip(args.runs + args.fresh, runs + args.fresh):
        if not folder.is_dir():
            sys.exit(f"{given}: no such folder")
        if work == folder or folder in work.parents:
            sys.exit("--work must be outside the run folders (their seed<N> folders are the inputs)")
    if args.quick and results == Path("results"):
        sys.exit("--quick makes no result to ship: give it a --results folder of its own")
    py, force = sys.executable, ["--force"] if args.force else []
    policy_root, figures = results / "torque" / "policy", results / "figures_input"
    figures.mkdir(parents=True, exist_ok=True)

    both = {f.name for f in seed_folders(runs)} & ({f.name for f in seed_folders(args.fresh)} if args.fresh else set())
    if both:  # before anything is written
        sys.exit(f"given both as tuned and as --fresh: {', '.join(sorted(both))}")
    tuned = ship_actors(runs, policy_root, py)
    fresh = ship_actors(args.fresh, results / "torque" / "fresh" / "policy", py) if args.fresh else []
    counts = [evaluate_seeds(tuned, results / "torque", figures, work, "", py, args.workers, force, args.quick)]
    if fresh:
        counts.append(evaluate_seeds(fresh, results / "torque" / "fresh", figures, work / "fresh", "_fresh",
                                     py, args.workers, force, args.quick))
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



def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = p.add_subparsers(dest="command", required=True, metavar="{policy,torque}")
    q = sub.add_parser("policy", help="one finished run (or a preset's seed folder) into a shipped policy folder")
    q.add_argument("run_dir", type=Path, help="a finished run folder (train.py output): both stages, or stage 2 "
                   "alone started from another's agent; or a preset's seed folder (its last phase's run)")
    q.add_argument("--out", type=Path, required=True, help="the shipped folder, e.g. results/table5/policy/seed0")
    q.add_argument("--force", action="store_true", help="replace an existing output folder")
    q.add_argument("--note", default="", help="free text stored in metadata.json")
    q.add_argument("--init-from", type=Path, default=None, metavar="ACTOR",
                   help="the file the run started from (train.py --init-from), where it is shipped: recorded in "
                        "metadata.json as init_from, relative to the repository")
    q.add_argument("--trained-at", default=None, metavar="COMMIT",
                   help="the commit whose code trained the run, for actor files written before they recorded it "
                        "(refused for those that record it)")
    q.add_argument("--all-phases", action="store_true",
                   help="a preset's seed folder: ship the last stage-1 and the last stage-2 phase's actors and "
                        "every phase's log (default: its last phase's run)")
    t = sub.add_parser("torque", help="re-make everything results/ ships for the torque recipe from its seeds")
    t.add_argument("runs", type=Path, nargs="+", help="the recipe's run folders (train.py --run-dir), holding "
                   "seed<N>/, or seed folders; a seed folder that `tools/ship.py policy --all-phases` already wrote "
                   "is copied as it is")
    t.add_argument("--fresh", type=Path, nargs="+", default=[], metavar="RUNS",
                   help="run or seed folders of seeds the recipe was never tuned on: shipped apart, into "
                   "results/torque/fresh/, with the figures_input files named *_fresh.json")
    t.add_argument("--work", type=Path, required=True,
                   help="folder for the evaluate.py outputs (check/, paths/, compare/, prototype/)")
    t.add_argument("--results", type=Path, default=REPO / "results",
                   help="the results folder to write torque/ and figures_input/ into (default: the repository's)")
    t.add_argument("--workers", type=int, default=2, help="walk processes at once (default 2)")
    t.add_argument("--force", action="store_true", help="replace earlier outputs under --work")
    t.add_argument("--quick", action="store_true", help="each step at 1.0 m/s alone with short walks (2 s; 2 m, "
                   "one hardware-like draw): a check that the chain runs, into a --results folder other than the "
                   "repository's")
    args = p.parse_args(argv)
    return ship_policy(args) if args.command == "policy" else ship_torque(args)


if __name__ == "__main__":
    sys.exit(main())
