"""The learned paths `evaluate.py` walks (a `LearnedSet`): loaded from files, or extracted from trained policies
first. Labels are the provenance's seed ("seed3"), else the file or run folder name.
"""
from __future__ import annotations

import dataclasses
import functools
import json
import time
from pathlib import Path

from cyberdog import config as C
from cyberdog.metrics_csv import run_name
from cyberdog.analysis.extract import CYCLE_CHOICES, ExtractionError, commanded_from_rollout, cycle_rows
from cyberdog.analysis.extract_measured import extract_from_rollout
from cyberdog.analysis.replay_check import ReplayCheck, check_settings, replay_check
from cyberdog.analysis.report import write_rows
from cyberdog.core.learned_set import LearnedPath, LearnedSet, LearnedSetError
from cyberdog.core.trajectories import SampledTrajectory
from cyberdog.evaluation.cli import UsageError
from cyberdog.evaluation.recorded_trot import trot_for
from cyberdog.provenance import portable_path

ROOT = Path(__file__).resolve().parents[2]
DEFAULT_LEARNED = ROOT / "results" / "table5" / "paths"  # the shipped learned paths: one JSON per seed and speed
# the prototype run's default: the battery recipe's paths (configs/battery.yaml, recorded under the trot with foot
# placement and a speed loop bounded at +-10 %); Table 5 keeps the Eq. 7 recipe's (DEFAULT_LEARNED)
DEFAULT_LEARNED_BATTERY = ROOT / "results" / "battery" / "paths"
DEFAULT_METRICS = ROOT / "results" / "table5" / "policy" / "seed0" / "metrics.csv"  # the shipped policy's training log
# the reference row of the matched-lift table: the direct search's shape at the shipped paths' mean lift height
# (tools/optimize_trajectory.py --lift-height 0.095, the same budget at every speed)
DEFAULT_REFERENCE = ROOT / "results" / "searched_shapes" / "optimized_trajectory_H0.095.json"
# the prototype run's reference row: the direct search's shape for the battery on the hardware-like robot, searched
# under the trot the default battery paths were recorded under (..._hardware.json: under the default trot)
DEFAULT_PROTOTYPE_REFERENCE = ROOT / "results" / "searched_shapes" / "optimized_trajectory_H0.085_electrical_hardware_placed_loop.json"
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


def take_recipe_extraction(args) -> dict:
    """For --sweep of a preset's lineages (train.py --config configs/<recipe>.yaml --seeds ...): the preset's
    `extract:` settings, for every option left at its default on the command line (one given wins). Returns
    what was taken."""
    from cyberdog.evaluation.cli import EXTRACT_DEFAULTS

    sweep = getattr(args, "sweep", None)
    lineages = sorted(d for d in sweep.iterdir() if C.is_lineage(d)) if sweep is not None and sweep.is_dir() else []
    if not lineages:
        return {}
    try:
        settings = C.read_phases(lineages[0])[1]
    except ValueError as e:
        raise UsageError(f"--sweep {sweep}: {e}") from None
    taken = {k: v for k, v in settings.items() if getattr(args, k) == EXTRACT_DEFAULTS[k]}
    for key, value in taken.items():
        setattr(args, key, value)
    if taken:
        print(f"extract: the recipe's settings: {', '.join(f'{k}={v}' for k, v in taken.items())}")
    return taken


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


def extraction_speeds(env: C.EnvConfig, speeds: list[float], policy_speed: float | None, log=print) -> list[float]:
    """Speeds at which a policy is rolled out for extraction (see --policy-speed)."""
    if policy_speed is not None:
        lo, hi = env.target_speed_range or (env.target_speed, env.target_speed)
        if not lo - 1e-9 <= policy_speed <= hi + 1e-9:
            log(f"warning: --policy-speed {policy_speed:g} m/s lies outside the speeds the policy was trained at "
                f"({lo:g}-{hi:g} m/s): its path there is an extrapolation")
        return [policy_speed]
    if env.target_speed_range:
        lo, hi = env.target_speed_range
        outside = [v for v in speeds if not lo - 1e-9 <= v <= hi + 1e-9]
        if outside:
            raise UsageError(f"--speeds {outside} lie outside the policy's training range {lo:g}-{hi:g} m/s; "
                             f"--policy-speed V rolls it out at one speed anyway (an extrapolation)")
        return list(speeds)
    return [env.target_speed]


def extract_policies(paths: list[Path], args, speeds: list[float], out: Path, log=print,
                     cfg: C.WalkConfig | None = None) -> LearnedSet:
    """Roll out each policy at each of its speeds, extract its learned path (commanded or measured, see
    --path) and save it under out/learned/ with every cycle in <label>_cycles.csv, each as soon as it is
    extracted. A commanded path must replay (`_extract_commanded`); `cfg`: the walk config of that replay
    (default WalkConfig()). One job per policy and speed (a measured path: one per policy, rescaled to every
    speed). In turn (`args.extract_workers` 1, the default) a failure stops there and keeps what was done; over
    several worker processes every job runs, each saves its path as it ends, and the failures are reported
    together at the end."""
    from cyberdog.rl.rollout import load_actor  # torch: only here, only when asked

    actors, kinds = [load_actor(path) for path in paths], []
    for path, actor in zip(paths, actors):  # every policy checked before the first rollout
        env = actor.config.env
        kind = args.path_kind if args.path_kind != "auto" else ("commanded" if env.action_mode == "foot"
                                                                  else "measured")
        if kind == "commanded" and env.action_mode != "foot":
            raise UsageError(f"{path}: a policy of action_mode {env.action_mode!r} commands no foot path; use "
                             "--path measured")
        kinds.append(kind)
    labels = [f"seed{actor.config.train.seed}" for actor in actors]
    if len(set(labels)) < len(labels):  # runs trained with the same seed: name them by their folders
        labels = [p.parent.name or lab for p, lab in zip(paths, labels)]
    jobs, job_actors = [], []  # (policy file, path kind, label, speed), and its loaded actor
    for path, actor, kind, label in zip(paths, actors, kinds, unique_labels(labels)):
        job_speeds = extraction_speeds(actor.config.env, speeds, args.policy_speed, log)
        for v in job_speeds if kind == "commanded" else job_speeds[:1]:
            jobs.append((path, kind, label, v))
            job_actors.append(actor)
    workers = min(getattr(args, "extract_workers", 1) or 1, len(jobs))
    if workers == 1:
        learned = LearnedSet()
        for (path, kind, label, speed), actor in zip(jobs, job_actors):
            learned.add(_extract_and_save(actor, path, kind, label, speed, args, out, cfg, log)[0])
        return learned
    from cyberdog.analysis.parallel import map_in_processes

    log(f"extraction: {len(jobs)} jobs (policy and speed) over {workers} worker processes")
    done = map_in_processes(functools.partial(_extraction_job, args=args, out=out, cfg=cfg), jobs, workers,
                            on_result=lambda i, r, n: log(f"extraction job {n} of {len(jobs)} ended: "
                                                          f"{jobs[i][2]} at {jobs[i][3]:g} m/s"
                                                          f"{'' if isinstance(r, Path) else ' (failed)'}"))
    failed = [f"{label} at {speed:g} m/s: {r}" for (_, _, label, speed), r in zip(jobs, done)
              if not isinstance(r, Path)]
    if failed:
        raise UsageError(f"{len(failed)} of {len(jobs)} extraction jobs failed (the others' paths are saved in "
                         f"{out / 'learned'}): " + "; ".join(failed))
    return load_learned(done)


def _extraction_job(job: tuple, args, out: Path, cfg: C.WalkConfig | None):
    """One (policy, kind, label, speed) job in a worker process: the saved path's file, or the error's text
    (a job that fails must not stop the others). Its log lines carry the job's label and speed."""
    from cyberdog.rl.rollout import load_actor

    path, kind, label, speed = job
    tag = f"[{label} {speed:g} m/s] "
    try:
        return _extract_and_save(load_actor(path), path, kind, label, speed, args, out, cfg,
                                 lambda m: print(tag + m, flush=True))[1]
    except UsageError as err:
        return str(err)


def _extract_and_save(actor, path: Path, kind: str, label: str, speed: float, args, out: Path, cfg, log):
    """Extract `actor`'s path at `speed` and save it and its cycles under out/learned/: (the `LearnedPath`,
    its file)."""
    prov = {"policy": portable_path(path), "seed": actor.config.train.seed, "policy_meta": actor.meta}
    extract = _extract_commanded if kind == "commanded" else _extract_measured
    ex = extract(actor, path, speed, args, prov, cfg, log)
    p = LearnedPath(label, ex.path if kind == "commanded" else ex.trajectory)
    file = p.save(out / "learned")
    write_rows(cycle_rows(ex), out / "learned", f"{file.stem}_cycles")
    if kind == "commanded":
        log(f"{file.stem}: commanded path from {len(ex.used)} of {len(ex.cycles)} cycles "
            f"({ex.path.provenance.get('cycle', args.cycle)}), "
            f"{ex.energy:.1f} J per cycle, own H = {p.lift_height:.4f} m -> {file}")
    else:
        c = ex.chosen
        log(f"{file.stem}: measured path of cycle {c.index} of {len(ex.cycles)} (t = {c.t_start:.2f} s), "
            f"{c.energy:.1f} J, {c.speed:.3f} m/s, H = {p.lift_height:.3f} m -> {file}")
    return p, file


def _rollout(actor, path: Path, speed: float, args, rollout_seed: int, log):
    from cyberdog.rl.rollout import rollout

    t0 = time.perf_counter()
    r = rollout(actor, speed=speed, duration=args.rollout_duration, seed=rollout_seed, env_config=actor.config.env)
    dropped = f", {r.dropped_shifts} foot shifts out of reach (dropped)" if r.dropped_shifts else ""
    log(f"rollout {path} at {speed:g} m/s (env seed {rollout_seed}): {r.duration:.1f} s, mean {r.mean_speed:.3f} "
        f"m/s, E={r.energy:.0f} J, fell={r.fell}{dropped} ({time.perf_counter() - t0:.0f} s)")
    return r


def _extract_measured(actor, path: Path, speed: float, args, prov: dict, cfg, log):
    r = _rollout(actor, path, speed, args, args.rollout_seed, log)
    try:
        return extract_from_rollout(r, actor.config.env, args.leg, args.speed_tolerance,
                                    provenance={**prov, "rollout_seed": args.rollout_seed})
    except ExtractionError as err:
        raise UsageError(f"extraction from {path} at {speed:g} m/s failed: {err} (try --speed-tolerance or "
                         "--policy-speed)") from None


def _extract_commanded(actor, path: Path, speed: float, args, prov: dict, cfg, log):
    """The commanded path kept for `speed`: rollouts with env seeds --rollout-seed, +1, ... (--replay-attempts
    of them) each give a candidate, the --cycle path, or the other cycle choice if that one does not pass the
    replay check (`replay_check`: the ideal robot, and hardware-like validation robots at three stiffnesses).
    The first --candidates paths that pass are kept as candidates, and the one with the least electrical energy
    per metre on the check's 100 m hardware-like walks (validation robots, never the prototype's) is the path.
    The candidates and the rejected paths are in its provenance; none passing is an error."""
    rejected, passed = [], []
    # the replay check walks the policy's trot, unless the command line chose one (then a note says so)
    cfg = trot_for(args, cfg or C.WalkConfig(), actor.config.env.walk.controller if args.replay_check else None,
                   f"the policy {path}", lambda m: log(f"  {m}"), walked="its replay check walks under it")
    check_controller = cfg.controller
    for k in range(args.replay_attempts if args.replay_check else 1):
        r = _rollout(actor, path, speed, args, args.rollout_seed + k, log)
        for cycle in dict.fromkeys((args.cycle, *CYCLE_CHOICES)):
            candidate = {"rollout_seed": args.rollout_seed + k, "cycle": cycle}
            try:
                ex = commanded_from_rollout(r, actor.config.env, cycle, args.speed_tolerance,
                                            provenance={**prov, "rollout_seed": args.rollout_seed + k,
                                                        "rollout_dropped_shifts": r.dropped_shifts})
            except ExtractionError as err:
                rejected.append({**candidate, "status": f"no path: {err}"})
                continue
            check = (replay_check(LearnedPath("", ex.path), speed, cfg, log=lambda m: log(f"    {m}"))
                     if args.replay_check else ReplayCheck("not checked"))
            if check.status in ("ok", "not checked"):
                if check.electrical_J_per_m is not None:
                    log(f"  candidate: the {cycle} path of env seed {args.rollout_seed + k} replays, "
                        f"{check.electrical_J_per_m:.2f} J/m on the check's hardware-like robots")
                passed.append((ex, check, {**candidate, "electrical_J_per_m": check.electrical_J_per_m}))
                break  # one candidate per rollout
            log(f"  rejected: the {cycle} path of env seed {args.rollout_seed + k} does not replay ({check.status})")
            rejected.append({**candidate, "status": check.status})
        if len(passed) == (args.candidates if args.replay_check else 1):
            break
    if not passed:
        tried = "; ".join(f"{c['cycle']} of env seed {c['rollout_seed']}: {c['status']}" for c in rejected)
        raise UsageError(f"extraction from {path} at {speed:g} m/s: no candidate path passes the replay check "
                         f"({tried}); more with --replay-attempts, or --no-replay-check to keep the first")
    # the cheapest on the validation robots; with one candidate (or unchecked) the first
    ex, check, _ = min(passed, key=lambda c: c[1].electrical_J_per_m if c[1].electrical_J_per_m is not None else 0.0)
    ex.path.provenance["replay_check"] = {
        "status": check.status, "rejected": rejected, "candidates": [c for _, _, c in passed],
        "selected_by": "least electrical energy per metre on the hardware-like check robots",
        "dropped_shifts": check.dropped_shifts,  # leg-periods of the check's walks with a shift out of reach
        **check_settings(),
        "controller": dataclasses.asdict(check_controller)}
    in_rollout = ex.path.provenance.get("rollout_dropped_shifts", 0)
    if check.dropped_shifts or in_rollout:
        log(f"  foot shifts out of reach, dropped (the unshifted target sent): {in_rollout} leg-periods in the "
            f"rollout, {check.dropped_shifts} in the replay check")
    if len(passed) > 1:
        log(f"  kept the {ex.path.provenance.get('cycle', args.cycle)} path of env seed "
            f"{ex.path.provenance['rollout_seed']}, the cheapest of {len(passed)} candidates")
    return ex


def check_learned_inputs(args) -> None:
    """Fail now, before any walk, on a missing or unreadable trajectory file or policy, or on a requested
    speed that no learned path can walk."""
    paths = policy_paths(args.policies, args.sweep)
    closed_loop = closed_loop_labels(args)
    if not paths:
        for_prototype = {"all": (False, True), "prototype": (True,), "stiffness": (True,)}.get(args.command, (False,))
        for files in dict.fromkeys(tuple(default_learned(args, p)) for p in for_prototype):
            learned = load_learned(list(files))
            check_speeds_covered(learned, getattr(args, "speeds", []))
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


def check_speeds_covered(learned: LearnedSet, speeds: list[float]) -> None:
    """UsageError unless every label of `learned` has a path at every speed of `speeds` (`LearnedSet.at`,
    the comparison's own rule): a table without its learned row is no Table 5."""
    missing = [v for v in speeds if not learned.covers(v)]
    if missing:
        have = ", ".join(f"{v:g}" for v in learned.speeds())
        raise UsageError(
            f"no learned path at {', '.join(f'{v:g}' for v in missing)} m/s for every label: the learned paths are "
            f"at {have} m/s. Ask for those --speeds, or extract paths at the speed from a policy (evaluate.py "
            f"extract --policies results/table5/policy/seed0 --speeds V; a policy trained at other speeds needs "
            f"--policy-speed V) and pass them with --learned")


def default_learned(args, for_prototype: bool = False) -> list[Path]:
    """The learned path files or folders to load: --learned, else the shipped default (the battery preset's
    paths for the prototype run where they are shipped, the paper preset's otherwise)."""
    given = getattr(args, "learned", None)
    if given:
        return list(given)
    return [DEFAULT_LEARNED_BATTERY if for_prototype and DEFAULT_LEARNED_BATTERY.is_dir() else DEFAULT_LEARNED]


def learned_trajectories(args, out: Path, speeds: list[float], log=print, cfg: C.WalkConfig | None = None,
                         for_prototype: bool = False) -> LearnedSet:
    """Extract from --policies/--sweep when given, else load `default_learned`; the paths used are copied
    beside the results, into out/learned/ (out/<DEFAULT_LEARNED_BATTERY's name>/ for the battery default)."""
    paths = policy_paths(args.policies, args.sweep)
    folder = out / "learned"
    if paths:
        learned = extract_policies(paths, args, speeds, out, log, cfg)
    else:
        files = default_learned(args, for_prototype)
        learned = load_learned(files)
        if files == [DEFAULT_LEARNED_BATTERY]:
            folder = out / DEFAULT_LEARNED_BATTERY.name
    learned.save(folder, overwrite=False)
    return learned


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


__all__ = ["DEFAULT_LEARNED", "DEFAULT_LEARNED_BATTERY", "DEFAULT_METRICS", "DEFAULT_PROTOTYPE_REFERENCE",
           "DEFAULT_REFERENCE", "STAGE2_ACTORS", "check_learned_inputs", "default_learned", "extract_policies",
           "learned_trajectories", "load_learned", "metrics_files", "policy_paths", "reference_shape"]
