"""Extraction from trained policies for `evaluate.py`: each policy rolled out at each of its speeds, its learned
path (commanded, or measured as the paper does) extracted, replay-checked and saved as it is made; the
extraction settings a recipe names (a preset's `extract:`); and `learned_trajectories`, the learned paths a
sub-command walks: extracted where policies are given, else loaded.
"""
from __future__ import annotations

import dataclasses
import functools
import json
import time
from pathlib import Path

from cyberdog import config as C
from cyberdog.analysis.extract import CYCLE_CHOICES, ExtractionError, commanded_from_rollout, cycle_rows
from cyberdog.analysis.extract_measured import extract_from_rollout
from cyberdog.analysis.replay_check import (REPLAY_CHECK_S, ReplayCheck, check_settings, replay_check, replay_walk,
                                            walk_settings, walk_status)
from cyberdog.analysis.report import write_rows
from cyberdog.core.learned_set import LearnedPath, LearnedSet
from cyberdog.evaluation.learned import (DEFAULT_LEARNED_BATTERY, default_learned, load_learned, policy_paths,
                                         unique_labels)
from cyberdog.evaluation.options import EXTRACT_DEFAULTS, UsageError
from cyberdog.evaluation.recorded_trot import trot_for
from cyberdog.provenance import portable_path

# in-band cycles of one rollout whose measured path is replayed before the next rollout runs
MEASURED_CYCLES_TRIED = 6


def take_recipe_extraction(args) -> dict:
    """For --sweep of a preset's lineages (train.py --config configs/<recipe>.yaml --seeds ...): the preset's
    `extract:` settings, for every option left at its default on the command line (one given wins). Returns
    what was taken."""

    sweep = getattr(args, "sweep", None)
    lineages = sorted(d for d in sweep.iterdir() if C.is_lineage(d)) if sweep is not None and sweep.is_dir() else []
    try:
        settings = C.read_phases(lineages[0])[1] if lineages else _sweep_preset_extraction(sweep)
    except ValueError as e:
        raise UsageError(f"--sweep {sweep}: {e}") from None
    taken = {k: v for k, v in settings.items() if getattr(args, k) == EXTRACT_DEFAULTS[k]}
    for key, value in taken.items():
        setattr(args, key, value)
    if taken:
        print(f"extract: the recipe's settings: {', '.join(f'{k}={v}' for k, v in taken.items())}")
    return taken


def _sweep_preset_extraction(sweep: Path | None) -> dict:
    """The `extract:` settings of the preset a sweep of plain run folders was trained from (its sweep.json's
    `source_config`, a preset of one phase), as the file reads now; {} for a sweep without one."""
    record = sweep / "sweep.json" if sweep is not None else None
    if record is None or not record.is_file():
        return {}
    source = json.loads(record.read_text()).get("source_config")
    if not source or not Path(source).is_file():
        return {}
    return dict(C.load_preset(source).extract)


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
        kind = args.path_kind if args.path_kind != "auto" else ("commanded" if env.action_mode in C.FOOT_MODES
                                                                  else "measured")
        if kind == "commanded" and env.action_mode not in C.FOOT_MODES:
            raise UsageError(f"{path}: a policy of action_mode {env.action_mode!r} commands no foot path; use "
                             "--path measured")
        kinds.append(kind)
    labels = [f"seed{actor.config.train.seed}" for actor in actors]
    if len(set(labels)) < len(labels):  # runs trained with the same seed: name them by their folders
        labels = [p.parent.name or lab for p, lab in zip(paths, labels)]
    # (policy file, path kind, label, speed, the speeds its path must walk at), and its loaded actor
    jobs, job_actors = [], []
    for path, actor, kind, label in zip(paths, actors, kinds, unique_labels(labels)):
        job_speeds = extraction_speeds(actor.config.env, speeds, args.policy_speed, log)
        for v in job_speeds if kind == "commanded" else job_speeds[:1]:
            jobs.append((path, kind, label, v, (v,) if kind == "commanded" else tuple(job_speeds)))
            job_actors.append(actor)
    workers = min(getattr(args, "extract_workers", 1) or 1, len(jobs))
    if workers == 1:
        learned = LearnedSet()
        for (path, kind, label, speed, walks_at), actor in zip(jobs, job_actors):
            learned.add(_extract_and_save(actor, path, kind, label, speed, walks_at, args, out, cfg, log)[0])
        return learned
    from cyberdog.analysis.parallel import map_in_processes

    log(f"extraction: {len(jobs)} jobs (policy and speed) over {workers} worker processes")
    done = map_in_processes(functools.partial(_extraction_job, args=args, out=out, cfg=cfg), jobs, workers,
                            on_result=lambda i, r, n: log(f"extraction job {n} of {len(jobs)} ended: "
                                                          f"{jobs[i][2]} at {jobs[i][3]:g} m/s"
                                                          f"{'' if isinstance(r, Path) else ' (failed)'}"))
    failed = [f"{label} at {speed:g} m/s: {r}" for (_, _, label, speed, _), r in zip(jobs, done)
              if not isinstance(r, Path)]
    if failed:
        raise UsageError(f"{len(failed)} of {len(jobs)} extraction jobs failed (the others' paths are saved in "
                         f"{out / 'learned'}): " + "; ".join(failed))
    return load_learned(done)


def _extraction_job(job: tuple, args, out: Path, cfg: C.WalkConfig | None):
    """One (policy, kind, label, speed, speeds) job in a worker process: the saved path's file, or the error's
    text (a job that fails must not stop the others). Its log lines carry the job's label and speed."""
    from cyberdog.rl.rollout import load_actor

    path, kind, label, speed, walks_at = job
    tag = f"[{label} {speed:g} m/s] "
    try:
        return _extract_and_save(load_actor(path), path, kind, label, speed, walks_at, args, out, cfg,
                                 lambda m: print(tag + m, flush=True))[1]
    except UsageError as err:
        return str(err)


def _extract_and_save(actor, path: Path, kind: str, label: str, speed: float, walks_at: tuple[float, ...], args,
                      out: Path, cfg, log):
    """Extract `actor`'s path at `speed` and save it and its cycles under out/learned/: (the `LearnedPath`,
    its file). `walks_at`: the speeds (m/s) a measured path, rescaled, must replay at (`_extract_measured`)."""
    prov = {"policy": portable_path(path), "seed": actor.config.train.seed, "policy_meta": actor.meta}
    if kind == "commanded":
        ex = _extract_commanded(actor, path, speed, args, prov, cfg, log)
    else:
        ex = _extract_measured(actor, path, speed, walks_at, args, prov, cfg, log)
    p = LearnedPath(label, ex.path if kind == "commanded" else ex.trajectory)
    file = p.save(out / "learned")
    write_rows(cycle_rows(ex), out / "learned", f"{file.stem}_cycles")
    if kind == "commanded":
        log(f"{file.stem}: commanded path from {len(ex.used)} of {len(ex.cycles)} cycles "
            f"({ex.path.provenance.get('cycle', args.cycle)}), "
            f"{ex.energy:.1f} J per cycle, own H = {p.lift_height:.4f} m -> {file}")
    else:
        c = ex.chosen
        log(f"{file.stem}: measured path of {ex.trajectory.provenance['leg']}'s cycle {c.index} of {len(ex.cycles)} "
            f"(t = {c.t_start:.2f} s), {c.energy:.1f} J, {c.speed:.3f} m/s, H = {p.lift_height:.3f} m -> {file}")
    return p, file


def _rollout(actor, path: Path, speed: float, args, rollout_seed: int, log):
    from cyberdog.rl.rollout import rollout

    t0 = time.perf_counter()
    r = rollout(actor, speed=speed, duration=args.rollout_duration, seed=rollout_seed, env_config=actor.config.env)
    dropped = f", {r.dropped_shifts} foot shifts out of reach (dropped)" if r.dropped_shifts else ""
    log(f"rollout {path} at {speed:g} m/s (env seed {rollout_seed}): {r.duration:.1f} s, mean {r.mean_speed:.3f} "
        f"m/s, E={r.energy:.0f} J, fell={r.fell}{dropped} ({time.perf_counter() - t0:.0f} s)")
    return r


def _extract_measured(actor, path: Path, speed: float, walks_at: tuple[float, ...], args, prov: dict, cfg, log):
    """The measured path: the cheapest in-band cycle of the reference foot (--leg, the paper's LF) in a rollout at
    `speed` (`extract_from_rollout`) whose path, replayed with IK + PID as Table 5 walks it (the ideal robot,
    10 s), walks within the band at every speed of `walks_at` with no fall; else the next cheapest cycle (up to
    `MEASURED_CYCLES_TRIED` a rollout), then the rollout of the next env seed (--replay-attempts), and only when
    no cycle of that foot replays, the other feet in turn (a policy's four feet need not move alike: one foot's
    path can be the one that does not carry the body when all four are driven along it). A path the policy
    walked need not walk open loop: a cycle cut from a transient (a stride still speeding up) can be the
    cheapest and replay 10-30 % slow. The choice looks at walking only, as the commanded path's check does; the
    rejected cycles are in the provenance. Without the replay check (--no-replay-check) the first rollout's
    cheapest cycle of the reference foot, as the paper took it."""
    cfg = trot_for(args, cfg or C.WalkConfig(), actor.config.env.walk.controller if args.replay_check else None,
                   f"the policy {path}", lambda m: log(f"  {m}"), walked="its replay check walks under it")
    rejected, rollouts = [], {}
    legs = (args.leg, *(leg for leg in C.LEG_NAMES if leg != args.leg)) if args.replay_check else (args.leg,)
    for leg in legs:
        if leg != args.leg:
            log(f"  no cycle of {legs[legs.index(leg) - 1]} replays in the band: the {leg} foot's cycles next")
        for k in range(args.replay_attempts if args.replay_check else 1):
            seed = args.rollout_seed + k
            if seed not in rollouts:  # each foot's cycles come from the same rollouts
                rollouts[seed] = _rollout(actor, path, speed, args, seed, log)
            skipped: list[int] = []
            while len(skipped) < MEASURED_CYCLES_TRIED:
                try:
                    ex = extract_from_rollout(rollouts[seed], actor.config.env, leg, args.speed_tolerance,
                                              provenance={**prov, "rollout_seed": seed}, skip_cycles=skipped)
                except ExtractionError as err:
                    if not args.replay_check:
                        raise UsageError(f"extraction from {path} at {speed:g} m/s failed: {err} (try "
                                         "--speed-tolerance or --policy-speed)") from None
                    rejected.append({"leg": leg, "rollout_seed": seed, "status": f"no path: {err}"})
                    break
                if not args.replay_check:
                    return ex
                status = _measured_replay_status(ex, walks_at, cfg, log)
                if status == "ok":
                    ex.trajectory.provenance["replay_check"] = {
                        "status": "ok", "rejected": rejected, "walks": "ideal robot, Table 5's walk",
                        "duration_s": REPLAY_CHECK_S, "speeds_mps": list(walks_at),
                        "controller": dataclasses.asdict(cfg.controller)}
                    return ex
                log(f"  rejected: cycle {ex.chosen.index} of {leg} in env seed {seed} does not replay ({status})")
                rejected.append({"leg": leg, "rollout_seed": seed, "cycle_index": ex.chosen.index, "status": status})
                skipped.append(ex.chosen.index)
    replayed = "; ".join(f"{c['leg']} cycle {c.get('cycle_index', '-')} of env seed {c['rollout_seed']}: {c['status']}"
                      for c in rejected[:8])
    more = f"; {len(rejected) - 8} more" if len(rejected) > 8 else ""
    raise UsageError(f"extraction from {path} at {speed:g} m/s: no measured path of any foot replays in the band "
                     f"({len(rejected)} replayed: {replayed}{more}); more with --replay-attempts, --speed-tolerance, or "
                     "--no-replay-check to keep the cheapest")


def _measured_replay_status(ex, walks_at: tuple[float, ...], cfg: C.WalkConfig, log) -> str:
    """"ok" when the measured path replays within the band with no fall at every speed of `walks_at`, else the
    first walk that failed ("1.2 m/s: speed miss (0.740 m/s)")."""
    path = LearnedPath("", ex.trajectory)
    for v in walks_at:
        status = walk_status(replay_walk(path, v, cfg))
        if status != "ok":
            return f"{v:g} m/s: {status}"
    log(f"  cycle {ex.chosen.index} ({ex.chosen.energy:.1f} J, {ex.chosen.speed:.3f} m/s) replays in the band at "
        f"{', '.join(f'{v:g}' for v in walks_at)} m/s")
    return "ok"


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
        replayed = "; ".join(f"{c['cycle']} of env seed {c['rollout_seed']}: {c['status']}" for c in rejected)
        raise UsageError(f"extraction from {path} at {speed:g} m/s: no candidate path passes the replay check "
                         f"({replayed}); more with --replay-attempts, or --no-replay-check to keep the first")
    # the cheapest on the validation robots; with one candidate (or unchecked) the first
    ex, check, _ = min(passed, key=lambda c: c[1].electrical_J_per_m if c[1].electrical_J_per_m is not None else 0.0)
    ex.path.provenance["replay_check"] = {
        "status": check.status, "rejected": rejected, "candidates": [c for _, _, c in passed],
        "selected_by": "least electrical energy per metre on the hardware-like check robots",
        "dropped_shifts": check.dropped_shifts,  # leg-periods of the check's walks with a shift out of reach
        **check_settings(),
        "controller": dataclasses.asdict(check_controller),
        "walk_settings": walk_settings(cfg)}  # what else the check's robots were set to (pick compares it)
    in_rollout = ex.path.provenance.get("rollout_dropped_shifts", 0)
    if check.dropped_shifts or in_rollout:
        log(f"  foot shifts out of reach, dropped (the unshifted target sent): {in_rollout} leg-periods in the "
            f"rollout, {check.dropped_shifts} in the replay check")
    if len(passed) > 1:
        log(f"  kept the {ex.path.provenance.get('cycle', args.cycle)} path of env seed "
            f"{ex.path.provenance['rollout_seed']}, the cheapest of {len(passed)} candidates")
    return ex
