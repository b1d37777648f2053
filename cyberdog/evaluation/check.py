"""`evaluate.py check`: do learned paths pass the extraction's replay check walk by walk, and do trained policies
walk alone at the paper's speeds?

- Path files (`evaluate.py check PATH ...`, commanded paths as `extract` writes them): every walk of the replay
  check (`cyberdog.analysis.replay_check.check_walks`: the ideal robot, the spread walks at the PD
  stiffness's ends, the 100 m hardware-like walks; or the `--parts` asked for) at the speed each path serves,
  under the trot it was recorded with, as extraction checks it; `--set hardware.*` changes the hardware-like
  robots' model (HARDWARE_LIKE; each check robot keeps its own seed, offset by hardware.seed). `extract` stops
  a candidate's check at its first failing walk; this walks them all and prints per walk the mean speed as a
  share of the command, a fall and the electrical energy per metre (J/m), then each path's verdict ("ok", or the
  walks that failed). Writes replay_check.json; the exit status is 1 where a path fails a walk.
- `--runs RUN ...` (train.py run folders, a recipe's seed folders, shipped policy folders): each run's stage-1
  and stage-2 actors walk `--duration` s from the stand at each speed, deterministically, alone
  (`cyberdog.analysis.policy_check`), on each of `--robots` (default the ideal robot; `hardware:N` the
  hardware-like robot of draw N), in the engine of `--set sim.engine=...` (the one setting `--set` may change
  for them; default the actor's env's), and stage 2's reduction against stage 1 is tabulated (Eq. 7, and the
  electrical energy per metre). A seed folder of a recipe (train.py --seeds) gives its last stage-1 and last
  stage-2 phase's actors. Writes policy_check.{md,json}.

The command line (`cyberdog.evaluation.parsers`) imports this module for its help text and options (`LINE`,
`PARAGRAPH`, `add_options`): it imports neither the simulator nor numpy until a check runs.
"""
from __future__ import annotations

import dataclasses
import json
from pathlib import Path

from cyberdog.config.paper import PAPER_SPEEDS, PAPER_WALK_DURATION
from cyberdog.evaluation.options import UsageError, positive

PARTS = ("ideal", "spread", "hardware")  # the replay check's parts (`CheckWalk.part`)
ACTORS = ("final", "best")  # stage<N>_final_actor.pt or stage<N>_best_actor.pt of a run folder
LINE = "do learned paths pass the replay check, walk by walk (PATH...); do trained policies walk alone (--runs)"
PARAGRAPH = ("path files (commanded paths, as `extract` writes them; folders of them): every walk of the replay "
             "check at the speed each serves, under the trot it was recorded with (its hardware-like robots "
             "HARDWARE_LIKE, or as --set hardware.* makes them), and a verdict per path "
             "(replay_check.json; exit status 1 where one fails). --runs RUN...: each run's stage-1 and stage-2 "
             "actors walk alone at each speed on the ideal robot (or --robots; in MuJoCo with --set sim.engine=mujoco), "
             "and stage 2's reduction against stage 1 on Eq. 7 and the electrical energy per metre "
             "(policy_check.{md,json}).")


def add_options(p) -> None:
    """The options of `check` (besides the shared output folder and --workers)."""
    p.add_argument("paths", nargs="*", type=Path, metavar="PATH",
                   help="commanded path files (JSON) or folders of them")
    p.add_argument("--parts", nargs="+", choices=PARTS, default=None,
                   help="paths: the check's parts to walk (default all): the ideal robot's walks, the spread walks "
                        "at the stiffness's ends, the 100 m hardware-like walks")
    g = p.add_argument_group("trained policies")
    g.add_argument("--runs", type=Path, nargs="+", default=None, metavar="RUN",
                   help="train.py run folders, a recipe's seed folders (RUN_DIR/seed<N>: its last stage-1 and "
                        "stage-2 phases' actors), or shipped ones (results/<recipe>/policy/seed<N>), whose actors "
                        "walk alone (label: the folder's name)")
    g.add_argument("--robots", nargs="+", default=None, metavar="ROBOT",
                   help="the robots each actor walks on: ideal (default), hardware:N (the hardware-like robot of "
                        "draw N: its latency, friction, sensor noise, Kalman speed and mass), e.g. --robots ideal "
                        "hardware:0 hardware:1")
    g.add_argument("--speeds", type=positive, nargs="+", default=None,
                   help="m/s (default " + " ".join(f"{v:g}" for v in PAPER_SPEEDS) + ")")
    g.add_argument("--duration", type=positive, default=None,
                   help=f"s per walk (default {PAPER_WALK_DURATION:g}, the paper's)")
    g.add_argument("--actor", choices=ACTORS, default=None,
                   help="stage<N>_final_actor.pt (default) or stage<N>_best_actor.pt")
    g.add_argument("--trot", action="store_true",
                   help="also walk the trot controller itself at each speed (label trot, stage 0): the reference, "
                        "with the first run's env.walk (its trajectory and lift height)")


def cmd_check(args, cfg) -> int:
    if bool(args.paths) == bool(args.runs):
        raise UsageError("check needs path files (PATH ...) or --runs RUN ..., one of the two")
    return _check_paths(args, cfg) if args.paths else _check_policies(args, cfg)


# ---- path files ---------------------------------------------------------------------------------------------

def check_walks_of(path, cfg, parts, hardware) -> list:
    """The replay check's walks of `parts` for `path` at the speed it serves, under `cfg`, its hardware-like robots
    `hardware`'s (`check_walks`)."""
    from cyberdog.analysis.replay_check import check_walks

    return [w for w in check_walks(path.speed, cfg, hardware) if w.part in parts]


def walk_job(job: tuple) -> dict:
    """One check walk of one path file: (file, walk index, parts, walk config, hardware model) → a row (in a
    worker process)."""
    from cyberdog.analysis.replay_check import walk_status
    from cyberdog.core.learned_set import LearnedSet

    file, index, parts, cfg, hardware = job
    path = LearnedSet.load([file]).paths()[0]
    w = check_walks_of(path, cfg, parts, hardware)[index]
    r = w.run(path, path.speed, cfg)
    return {"file": str(file), "speed_mps": path.speed, "walk": w.name, "part": w.part, "pd_scale": w.pd_scale,
            "status": walk_status(r), "fell": r.fell, "speed_share": r.mean_speed / path.speed,
            "electrical_J_per_m": r.electrical_energy / r.distance if r.distance > 0 else float("nan")}


def verdicts(rows: list[dict]) -> dict[str, str]:
    """Per file: "ok" if every walk passed, else its failing walks and why."""
    out: dict[str, list[str]] = {}
    for row in rows:
        failed = out.setdefault(row["file"], [])
        if row["status"] != "ok":
            failed.append(f"{row['walk']}: {row['status']}")
    return {f: "ok" if not failed else "; ".join(failed) for f, failed in out.items()}


def _check_paths(args, cfg) -> int:
    from cyberdog.analysis.parallel import map_in_processes, progress_log
    from cyberdog.analysis.report import json_safe
    from cyberdog.core.learned_set import LearnedSet, learned_files
    from cyberdog.evaluation.output import open_run
    from cyberdog.evaluation.recorded_trot import trot_for

    given = [o for o, v in (("--speeds", args.speeds), ("--duration", args.duration), ("--actor", args.actor),
                            ("--trot", args.trot), ("--robots", args.robots)) if v]
    if given:
        raise UsageError(f"{', '.join(given)}: options of check --runs; a path walks at the one speed it serves")
    files = learned_files(args.paths)
    paths = [LearnedSet.load([f]).paths()[0] for f in files]
    sampled = [str(f) for f, path in zip(files, paths) if not path.commanded]
    if sampled:
        raise UsageError(f"not commanded paths (the check walks a path at the one speed it was recorded at): "
                         f"{sampled}")
    parts = tuple(args.parts or PARTS)
    jobs = []
    for f, path in zip(files, paths):
        walk_cfg = trot_for(args, cfg, path.recorded_controller, f"{f.name}", walked="its check walks under it")
        jobs += [(str(f), i, parts, walk_cfg, args.hardware)
                 for i in range(len(check_walks_of(path, walk_cfg, parts, args.hardware)))]
    run = open_run(args, cfg)
    print(f"{len(jobs)} walks of {len(files)} paths ({', '.join(parts)})", flush=True)

    def line(row: dict) -> str:
        return (f"{Path(row['file']).name} {row['walk']}: {row['status']}, {row['speed_share']:.3f} of the command, "
                f"{row['electrical_J_per_m']:.1f} J/m")

    rows = map_in_processes(walk_job, jobs, args.workers, on_result=progress_log(len(jobs), line))
    results = verdicts(rows)
    for f, verdict in results.items():
        print(f"{f}: {verdict}")
    (run.out / "replay_check.json").write_text(json.dumps(json_safe({"rows": rows, "verdicts": results}), indent=1))
    run.finish()
    return 0 if all(v == "ok" for v in results.values()) else 1


# ---- trained policies ---------------------------------------------------------------------------------------

def run_actors(runs: list[Path], actor: str) -> dict[str, dict[int, Path]]:
    """{run folder name: {stage: actor file}} of the stages each run has (a shipped folder's stage<N>_actor.pt are
    its run's final actors); a run with neither stage is refused."""
    from cyberdog.config import is_lineage, read_phases
    actors = {}
    for run in runs:
        names = [f"stage{{}}_{actor}_actor.pt"] + (["stage{}_actor.pt"] if actor == "final" else [])
        if is_lineage(run):  # a recipe's seed folder: the last phase that trains each stage
            try:
                phases = read_phases(run)[0]
            except ValueError as err:
                raise UsageError(f"--runs {run}: {err}") from None
            folders = {s: next((run / p.name for p in reversed(phases) if p.stage in (str(s), "both")), run)
                       for s in (1, 2)}
        else:
            folders = {1: run, 2: run}
        stages = {s: next((folders[s] / n.format(s) for n in names if (folders[s] / n.format(s)).is_file()), None)
                  for s in (1, 2)}
        for s, folder in folders.items():  # a stage a recipe's phase trains, but that phase has not finished
            if folder != run and stages[s] is None:
                raise UsageError(f"--runs {run}: its phase {folder.name} (stage {s}) has no stage{s}_{actor}_actor.pt "
                                 f"(not finished?): `train.py --resume {run}` continues it")
        stages = {s: f for s, f in stages.items() if f is not None}
        if not stages:
            raise UsageError(f"--runs {run}: no stage1_{actor}_actor.pt or stage2_{actor}_actor.pt")
        if run.name in actors:
            raise UsageError(f"--runs: two runs named {run.name} (a walk's label is its run folder's name)")
        actors[run.name] = stages
    return actors


ENGINE_SETTING = "sim.engine"  # the one --set a policy check takes: the physics engine its walks run in


def _policy_engine(args, cfg) -> str | None:
    """The engine --set names for the policies' walks (None: each actor's own); UsageError for any option a
    policy check does not take (a policy walks in the env it was trained in)."""
    sets = [str(s).split("=", 1)[0].strip() for s in args.overrides or []]
    given = [o for o, v in (("--parts", args.parts), ("--config", args.config),
                            ("--set " + ", ".join(k for k in sets if k != ENGINE_SETTING),
                             any(k != ENGINE_SETTING for k in sets)),
                            ("--no-recorded-trot", args.no_recorded_trot)) if v]
    if given:
        raise UsageError(f"{', '.join(given)}: not for --runs (a policy walks in the env it was trained in, its "
                         f"run's config.yaml; --robots chooses the robot it walks, --set {ENGINE_SETTING}=... "
                         "the physics engine)")
    return cfg.sim.engine if ENGINE_SETTING in sets else None


def _check_policies(args, cfg) -> int:
    from cyberdog.analysis.parallel import map_in_processes, progress_log
    from cyberdog.analysis.policy_check import COLUMNS, check_actor, check_jobs, check_trot, stage_reductions
    from cyberdog.analysis.report import json_safe, markdown_table
    from cyberdog.evaluation.output import Run, new_out
    from cyberdog.rl.rollout import load_actor

    engine = _policy_engine(args, cfg)
    speeds, duration = args.speeds or list(PAPER_SPEEDS), args.duration or PAPER_WALK_DURATION
    robots = args.robots or ["ideal"]
    try:
        jobs = check_jobs(run_actors(args.runs, args.actor or "final"), speeds, duration, robots=robots,
                          engine=engine)
    except (ValueError, FileNotFoundError) as err:
        raise UsageError(str(err)) from None
    out = args.out or new_out()
    try:
        run = Run(args, out)  # no config.yaml: each policy walks in its own run's config
    except OSError as err:
        raise UsageError(f"cannot write the output folder --out {out}: {err.strerror or err}") from None
    print(f"{len(jobs)} walks of {duration:g} s on {', '.join(robots)}, the policies alone"
          f"{f', in {engine}' if engine else ''}", flush=True)

    def line(r: dict) -> str:
        return (f"{r['label']} stage {r['stage']} {r['robot']} {r['speed_command_mps']:g} m/s: "
                f"{r['mean_speed_mps']:.3f} m/s, {'fell' if r['fell'] else 'walks' if r['walks'] else 'off the band'}, "
                f"{r['energy_J']:.0f} J, {r['electrical_per_metre_J']:.0f} J/m electrical")

    rows = map_in_processes(check_actor, jobs, args.workers, on_result=progress_log(len(jobs), line))
    if args.trot:  # the reference: the trot controller's own walks, as the first actor's env has it
        walk_cfg = load_actor(jobs[0][2]).config.env.walk
        if engine is not None:
            walk_cfg = dataclasses.replace(walk_cfg, sim=dataclasses.replace(walk_cfg.sim, engine=engine))
        trot_jobs = [(float(v), duration, walk_cfg, robot) for robot in robots for v in speeds]
        rows += map_in_processes(check_trot, trot_jobs, args.workers, on_result=progress_log(len(trot_jobs), line))
    reductions = stage_reductions(rows)
    md = ("## Every walk\n\n" + markdown_table([{k: r[k] for k in COLUMNS} for r in rows])
          + "\n\n## Stage 2 against stage 1 (same robot, speed and duration)\n\n" + markdown_table(reductions) + "\n")
    print(md)
    (run.out / "policy_check.md").write_text(md)
    (run.out / "policy_check.json").write_text(json.dumps(json_safe({"walks": rows, "reductions": reductions}),
                                                          indent=1))
    return run.finish()


__all__ = ["PARTS", "add_options", "check_walks_of", "cmd_check", "verdicts", "walk_job"]
