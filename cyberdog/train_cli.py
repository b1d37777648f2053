"""Train the CyberDog walking agent with TD3 or DDPG in two stages (paper Section 3): the command line of
`train.py`. `python -m cyberdog.train_cli` is the same command without the sweep's learning-curve figure (drawn
by the checkout's `plots/`); it is what a sweep launches for each seed, and what an installed package has.

A preset (configs/<recipe>.yaml) is a whole recipe: its phases (stage 1, stage 2, continuations) run in order
for each seed, each in RUN_DIR/<phase>/ (per seed: RUN_DIR/seed<N>/<phase>/), each starting from the previous
one's final agent; an interrupted lineage continues with --resume at the phase it reached. The presets:
{presets}
Examples:
  python train.py --config configs/battery.yaml --seeds 5-9 --run-dir runs/battery   # every phase, 5 seeds
  python train.py --show configs/battery.yaml     # its resolved settings per phase, as changes from the defaults
  python train.py --config configs/tiny.yaml --run-dir runs/tiny              # stage 1 then stage 2
  python train.py --config configs/paper.yaml --stage 1 --seed 3 --run-dir runs/paper_s3
  python train.py --config configs/table5.yaml --set agent.algorithm=ddpg --set train.batch_size=128
  python train.py --resume runs/table5                                         # continue a killed run
  python train.py --resume runs/table5 --set train.stage2.max_env_steps=320000   # its last stage longer
  python train.py --config configs/table5.yaml --stage 2 --init-from runs/table5/stage1_final.pt --run-dir runs/t2

Seeds at scale (one run per seed in RUN_DIR/seed<N>/, retried from its checkpoint if it fails, then aggregated):
  python train.py --config configs/table5.yaml --seeds 0-9 --run-dir runs/sweep_table5       # local processes
  python train.py --config configs/table5.yaml --seeds 0,3,7 --backend ray --workers 3      # local Ray instance
  python train.py --config configs/paper.yaml --seeds 0-9 --backend ray --ray-address auto # existing cluster
  python train.py --resume runs/sweep_table5                  # finish a killed or failed sweep
  python train.py --aggregate runs/sweep_table5               # (re)write curves, evaluation and tables

Outputs in the run folder: config.yaml (resolved), metrics.csv (one row per episode), tb/ (TensorBoard),
checkpoint.pt (resume point: agent, optimizers, RNG states and the replay buffer, about 0.5 kB per stored
transition), stage<N>_final.pt (the agent for --init-from, no replay buffer: about 1 MB), stage<N>_final_actor.pt
and stage<N>_best_actor.pt (the actor for evaluate.py), saved/ (agents above save_score).
Outputs in a sweep folder: sweep.json, sweep_config.yaml, sweep_status.json (live, per seed), seed<N>/ (run
folders, each with train.log), learning_curves.png/.csv, evaluation.json, aggregate.csv/.md.

One process per run folder: every run folder this script writes is locked by RUN_DIR/.train.lock (pid, host,
start time, command) while it trains; a second process is refused with a message naming the holder, and a lock
left by a dead process on this machine is taken over with a warning. On a file system shared by several machines,
a holder on another machine is refused too (by the kernel lock where flock is coherent across hosts, else by the
file's contents); delete the lock once that process is known to be gone. docs/training.md has the details.

A setting that would make a stage end without any gradient update (a budget shorter than learning_starts,
init_random_frames or batch_size) is refused before anything starts.
"""
from __future__ import annotations

import argparse
import sys
import warnings
from pathlib import Path

from cyberdog import config as C


PRESETS = Path(__file__).resolve().parents[1] / "configs"  # a checkout's presets (an installed wheel has none)


def _preset_lines() -> str:
    from cyberdog.config.preset import preset_summaries

    rows = preset_summaries(PRESETS) if PRESETS.is_dir() else []
    return "\n".join(f"  configs/{name:<14} {summary}" for name, summary in rows) or "  (none: configs/ not found)"


def parse_args(argv=None) -> argparse.Namespace:
    p = argparse.ArgumentParser(description=__doc__.replace("{presets}", _preset_lines()),
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--config", type=Path, help="a preset (configs/<recipe>.yaml: env, agent, train settings as "
                   "changes from its base, its phases, its extraction); default: built-in defaults")
    p.add_argument("--show", type=Path, metavar="PRESET",
                   help="print the preset's resolved settings, phase by phase, as changes from the defaults; no "
                        "training")
    p.add_argument("--stage", choices=("1", "2", "both"), default=None,
                   help="stage 1 (no energy term), stage 2 (Eq. 11 with energy), or both in sequence (default); "
                        "a preset with phases names its own stages")
    p.add_argument("--seed", type=int, help="random seed; overrides train.seed")
    p.add_argument("--run-dir", type=Path, help="output folder (default runs/<config name>_seed<seed>)")
    C.add_override_option(p, "train.stage1.max_env_steps=5000",
                          "; with --resume only the current stage's budget may change (train.stage<N>.max_env_steps, "
                          "max_episodes): raised, the stage, finished or not, continues (the stage-final files of a "
                          "finished one are kept as stage<N>_final*_<steps>steps.pt); lowered to a point an "
                          "unfinished stage has not reached, it ends there")
    p.add_argument("--resume", type=Path, metavar="RUN_DIR",
                   help="continue the run in RUN_DIR from its checkpoint.pt with its saved config.yaml; if RUN_DIR is "
                        "a sweep folder (sweep.json), continue every seed of the sweep that is not done")
    p.add_argument("--init-from", type=Path, metavar="CHECKPOINT",
                   help="start from this checkpoint's agent (e.g. runs/x/stage1_final.pt), or from an actor file's "
                        "actor with new critics (e.g. results/battery/policy/seed0/stage2_actor.pt; give the "
                        "stage critic_warmup_updates); default for --stage 2: <run-dir>/stage1_final.pt")
    p.add_argument("--device", choices=C.DEVICES, help="overrides train.device: cpu, cuda or auto")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    g = p.add_argument_group("seeds at scale (sweeps)")
    g.add_argument("--seeds", metavar="SEEDS",
                   help="train one run per seed: a range 0-9, a list 0,3,7 or both (0-2,5); each in "
                        "RUN_DIR/seed<N>/ of the sweep folder RUN_DIR (default runs/sweep_<config name>), then "
                        "aggregate. Resume a sweep with --resume RUN_DIR")
    g.add_argument("--backend", choices=("local", "ray"),
                   help="where the seeds run: local processes (default) or Ray (pip install -e '.[ray]')")
    g.add_argument("--workers", type=int, metavar="N",
                   help="seeds trained at the same time (default: the available CPU cores, at most the number of "
                        "seeds; with Ray: the local instance's CPUs, or all CPUs of the cluster); also the number "
                        "of processes evaluating the policies when that is long")
    g.add_argument("--ray-address", metavar="ADDRESS",
                   help="join an existing Ray cluster (e.g. auto, or HEAD_IP:6379) instead of starting a local Ray "
                        "instance; the sweep folder must be on a file system all nodes share")
    g.add_argument("--max-retries", type=int, metavar="N",
                   help="times a failed or killed seed is restarted from its last checkpoint (default 2)")
    g.add_argument("--aggregate", type=Path, metavar="SWEEP_DIR",
                   help="no training: (re)aggregate the sweep folder SWEEP_DIR (learning curves with 95%% bands, "
                        "evaluation of each seed's final actors, summary table)")
    g.add_argument("--eval-duration", type=float, metavar="S",
                   help="seconds of each evaluation rollout after a sweep or with --aggregate (default 10, the "
                        "paper's Tf; 0 = no evaluation)")
    g.add_argument("--eval-speed", type=float, metavar="V",
                   help="commanded speed of the evaluation rollouts in m/s (default 1.0)")
    return p.parse_args(argv)


SWEEP_OPTIONS = ("backend", "workers", "ray_address", "max_retries", "eval_duration", "eval_speed")


def _flag(name: str) -> str:
    return "--" + name.replace("_", "-")


def _sweep_main(args, sweep_dir: Path | None, resume: bool) -> int:
    """--seeds, --resume of a sweep folder, --aggregate."""
    from cyberdog.sweeps import SweepError, run_sweep

    try:
        if args.aggregate is not None:
            used = [o for o in ("config", "seed", "seeds", "resume", "init_from", "device", "run_dir")
                    if getattr(args, o) is not None] + (["set"] if args.overrides else [])
            used += [o for o in ("backend", "ray_address", "max_retries") if getattr(args, o) is not None]
            if used:
                sys.exit(f"--aggregate reads an existing sweep folder; do not combine it with "
                         f"{', '.join(_flag(u) for u in used)}")
            return _aggregate(args, args.aggregate)
        if args.workers is not None and args.workers < 1:
            raise SweepError(f"--workers must be >= 1, got {args.workers}")
        if args.max_retries is not None and args.max_retries < 0:
            raise SweepError(f"--max-retries must be >= 0, got {args.max_retries}")
        if args.ray_address and args.backend != "ray":
            raise SweepError("--ray-address needs --backend ray")
        _check_eval_args(args)
        if not resume:
            for o in ("seed", "init_from", "resume"):
                if getattr(args, o) is not None:
                    sys.exit(f"--seeds cannot be combined with {_flag(o)}" + (
                        ": resume a sweep with --resume SWEEP_DIR alone" if o == "resume" else ""))
            sweep_dir = _new_sweep(args)
        status = run_sweep(sweep_dir, backend=args.backend or "local", workers=args.workers,
                           max_retries=2 if args.max_retries is None else args.max_retries,
                           ray_address=args.ray_address, progress=not args.no_progress)
        failed = [s["seed"] for s in status["seeds"] if s["state"] != "done"]
        if any(s["state"] == "done" for s in status["seeds"]):
            _aggregate(args, sweep_dir)
    except SweepError as e:
        sys.exit(f"error: {e}")
    except KeyboardInterrupt:
        print(f"\nsweep interrupted; its training processes were stopped. Continue with: "
              f"python train.py --resume {sweep_dir}", file=sys.stderr)
        return 130
    if failed:
        print(f"sweep: seeds {failed} failed (errors in {sweep_dir}/sweep_status.json and seed<N>/train.log); "
              f"continue with: python train.py --resume {sweep_dir}", file=sys.stderr)
        return 1
    return 0


def _new_sweep(args) -> Path:
    """Create the sweep folder of --seeds: one run folder per seed, or one lineage per seed for a preset with
    phases (each seed's phases.yaml written now, so a resume continues them as resolved)."""
    from cyberdog.sweeps import create_sweep, parse_seeds

    seeds = parse_seeds(args.seeds)
    preset, cfg, name = _resolve_config(args)
    sweep_dir = args.run_dir or Path("runs") / f"sweep_{name}"
    if preset.phased:
        _check_lineage_args(args)
        _check_phases(preset)
        create_sweep(sweep_dir, cfg, seeds, "phases", source_config=args.config, overrides=args.overrides)
        for seed in seeds:
            C.write_phases(sweep_dir / f"seed{seed}", preset, seed)
    else:
        stage = args.stage or "both"
        if stage == "2":
            sys.exit("--seeds trains --stage both or 1 (stage 2 alone needs a stage-1 agent per seed)")
        try:
            C.check_planned_updates(cfg, (1, 2) if stage == "both" else (int(stage),))
        except ValueError as e:
            sys.exit(f"config error: {e}")
        create_sweep(sweep_dir, cfg, seeds, stage, source_config=args.config, overrides=args.overrides)
    print(f"sweep: seeds {seeds} in {sweep_dir}")
    return sweep_dir


def _check_eval_args(args) -> None:
    from cyberdog.sweeps.aggregate import check_eval_options

    check_eval_options(args.eval_duration, args.eval_speed)


def _aggregate(args, sweep_dir: Path) -> int:
    from cyberdog.sweeps import SweepError, available_cores
    from cyberdog.sweeps.aggregate import aggregate_sweep

    try:
        _check_eval_args(args)
        aggregate_sweep(sweep_dir, eval_duration=10.0 if args.eval_duration is None else args.eval_duration,
                        eval_speed=1.0 if args.eval_speed is None else args.eval_speed,
                        workers=args.workers or available_cores(), progress=not args.no_progress,
                        draw_learning_curves=args.draw_learning_curves)
    except SweepError as e:
        sys.exit(f"error: {e}")
    print((sweep_dir / "aggregate.md").read_text())
    print(f"sweep folder: {sweep_dir}/")  # the last line: where the sweep and its aggregate are
    return 0


def _resolve_config(args):
    """The preset of --config with --set, --device and --seed applied to every phase's settings; its main
    settings; and its name for default folders."""
    from cyberdog.config.preset import Preset, _phases

    sets = list(args.overrides)
    if args.seed is not None:
        sets.append(f"train.seed={args.seed}")
    if args.device:
        sets.append(f"train.device={args.device}")
    try:
        if args.config:
            preset = C.load_preset(args.config, sets)
        else:
            cfg = C.override(C.ExperimentConfig(), sets)
            preset = Preset(path=Path("default.yaml"), summary="", config=cfg,
                            phases=_phases(None, Path("default.yaml"), {}, sets))
    except (ValueError, TypeError, OSError) as e:
        sys.exit(f"config error: {e}")
    return preset, preset.config, (args.config.stem if args.config else "default")


def _check_lineage_args(args) -> None:
    for given, flag in ((args.stage, "--stage"), (args.init_from, "--init-from")):
        if given is not None:
            sys.exit(f"{args.config} names its phases (train.py --show {args.config}); do not combine it with {flag}")


def _check_phases(preset) -> None:
    """Every phase's planned updates, before the first starts (a phase hours in must not fail on its settings)."""
    for phase in preset.phases:
        try:
            C.check_planned_updates(phase.config, (1, 2) if phase.stage == "both" else (int(phase.stage),))
        except ValueError as e:
            sys.exit(f"config error: phase {phase.name}: {e}")


def _warning_line(message, category, filename, lineno, line=None) -> str:
    return f"warning: {message}\n"


def main(argv=None, draw_learning_curves=None) -> int:
    """The command line; `draw_learning_curves(sweep_dir) -> [paths]` draws a sweep's learning_curves.png from
    its learning_curves.csv (the checkout's train.py passes `plots`'s; None: the CSV only)."""
    args = parse_args(argv)
    args.draw_learning_curves = draw_learning_curves
    warnings.formatwarning = _warning_line  # one plain line per warning (a lock taken over, a cut metrics.csv)
    if args.show is not None:
        try:
            print(C.describe(C.load_preset(args.show)))
        except (ValueError, OSError) as e:
            sys.exit(f"config error: {e}")
        return 0
    if args.seeds is not None or args.aggregate is not None:
        return _sweep_main(args, None, resume=False)
    if args.resume is not None and (args.resume / "sweep.json").is_file():  # a sweep folder
        if args.config or args.overrides or args.seed is not None or args.init_from or args.device or args.run_dir:
            sys.exit("--resume of a sweep folder uses its sweep.json and sweep_config.yaml; do not combine it with "
                     "--config, --set, --seed, --init-from, --device or --run-dir")
        return _sweep_main(args, args.resume, resume=True)
    used = [_flag(o) for o in SWEEP_OPTIONS if getattr(args, o) is not None]
    if used:
        sys.exit(f"{', '.join(used)} only apply to sweeps (--seeds, --resume SWEEP_DIR, --aggregate)")
    if args.resume is not None and C.is_lineage(args.resume):
        if args.config or args.overrides or args.seed is not None or args.init_from or args.device or args.stage:
            sys.exit("--resume of a lineage folder (phases.yaml) continues its phases as resolved; do not combine "
                     "it with --config, --set, --seed, --init-from, --device or --stage")
        return _lineage(args, args.resume)
    if args.resume is None and args.config is not None:
        preset, cfg, name = _resolve_config(args)
        if preset.phased:
            _check_lineage_args(args)
            _check_phases(preset)
            run_dir = args.run_dir or Path("runs") / f"{name}_seed{cfg.train.seed}"
            if C.is_lineage(run_dir) or (run_dir / "checkpoint.pt").exists():
                sys.exit(f"{run_dir} already holds a run; use --resume {run_dir} or another --run-dir")
            C.write_phases(run_dir, preset, cfg.train.seed)
            return _lineage(args, run_dir)
    cfg, run_dir, trainer_kwargs = _resumed_run(args) if args.resume is not None else _new_run(args)
    return _train(args, cfg, run_dir, trainer_kwargs)


def _lineage(args, folder: Path) -> int:
    """Every phase of the lineage in `folder` (cyberdog.lineage); a failure names its seed and phase."""
    from cyberdog.lineage import LineageError, run_lineage

    def train(cfg, label, **kwargs):
        return _train(args, cfg, kwargs["run_dir"], kwargs, label=label, resume_hint=folder)

    try:
        return run_lineage(folder, train)
    except (LineageError, ValueError) as e:
        sys.exit(f"error: {e}")


def _resumed_run(args) -> tuple:
    """(config, run folder, Trainer keywords) of --resume RUN_DIR."""
    if args.config or args.seed is not None or args.init_from:
        sys.exit("--resume uses the run folder's config.yaml; do not combine it with --config, --seed or "
                 "--init-from (--set may change the current stage's budget)")
    if args.device:
        sys.exit("--device cannot be combined with --resume: the run continues with its saved train.device")
    cfg = _resumable_config(args.resume)
    if args.overrides:  # the trainer refuses anything but a changed budget of the current stage
        try:
            cfg = C.override(cfg, args.overrides)
        except (ValueError, TypeError) as e:
            sys.exit(f"config error: {e}")
    return cfg, args.resume, dict(run_dir=args.resume, resume=True)


def _new_run(args) -> tuple:
    """(config, run folder, Trainer keywords) of a new run (--config, --stage, --init-from, --run-dir)."""
    _, cfg, name = _resolve_config(args)
    run_dir = args.run_dir or Path("runs") / f"{name}_seed{cfg.train.seed}"
    if (run_dir / "checkpoint.pt").exists():
        sys.exit(f"{run_dir} already holds a run; use --resume {run_dir} or another --run-dir")
    stages = (1, 2) if args.stage in (None, "both") else (int(args.stage),)
    init_from = args.init_from
    if stages == (2,) and init_from is None:
        init_from = run_dir / "stage1_final.pt"
        if not init_from.is_file():
            sys.exit(f"--stage 2 needs a stage-1 agent: pass --init-from, or run stage 1 in {run_dir} first")
    return cfg, run_dir, dict(run_dir=run_dir, stages=stages, init_from=init_from)


def _train(args, cfg, run_dir: Path, trainer_kwargs: dict, label: str = "", resume_hint: Path | None = None) -> int:
    """Run the trainer; one line for a refused setting, a pause (SIGINT/SIGTERM) or the result (a lineage's
    phase: prefixed by its `label`, and the resume hint names the lineage folder)."""
    from cyberdog.rl import CheckpointError, NonFiniteError, Trainer  # slow import after --help
    from cyberdog.rl.stop import TrainingInterrupted
    from cyberdog.runlock import RunFolderError

    where, resume = f"{label}: " if label else "", resume_hint or run_dir
    try:
        summary = Trainer(cfg, progress=not args.no_progress, **trainer_kwargs).run()
    except (CheckpointError, NonFiniteError, RunFolderError) as e:
        sys.exit(f"error: {where}{e}")
    except (ValueError, OSError) as e:  # settings refused before the start (no update would happen, no CUDA)
        sys.exit(f"error: {where}{e}")
    except TrainingInterrupted as stop:
        print(f"\n{where}{stop}; continue with: python train.py --resume {resume}", file=sys.stderr)
        return stop.exit_code
    except KeyboardInterrupt:  # a second Ctrl-C: stopped at once
        print(f"\n{where}stopped at once: the steps since the last checkpoint are lost; continue with: python "
              f"train.py --resume {resume}", file=sys.stderr)
        return 130
    print("done: " + ", ".join(f"{k}={v}" for k, v in summary.items()
                               if k in ("stage", "env_steps", "episodes", "updates", "buffer_size",
                                        "window_mean_score")))
    print(f"run folder: {run_dir}/")  # the last line: where the run was written
    return 0


def _resumable_config(run_dir: Path):
    """The saved config of the training run in `run_dir`, or exit with one line saying why it is not one."""
    cfg_path = run_dir / "config.yaml"
    if not run_dir.is_dir():
        sys.exit(f"--resume {run_dir}: no such folder (a training run folder holds config.yaml and checkpoint.pt)")
    if not cfg_path.is_file():
        sys.exit(f"--resume {run_dir}: not a training run (no config.yaml there)")
    try:
        cfg = C.load(C.ExperimentConfig, cfg_path)
    except (ValueError, OSError) as e:
        try:
            C.load_walked(cfg_path)
            what = "an evaluate.py output folder (its config.yaml is a walk config)"
        except (ValueError, OSError):
            what = f"its config.yaml is not an experiment config ({str(e)[:300]})"
        sys.exit(f"--resume {run_dir}: not a training run of train.py: {what}")
    if not (run_dir / "checkpoint.pt").is_file():
        sys.exit(f"--resume {run_dir}: no checkpoint.pt there, nothing to resume (a run stopped before its first "
                 f"checkpoint, every train.checkpoint_every={cfg.train.checkpoint_every} env steps, or a folder of "
                 f"exported actors); start a new run: --config {cfg_path} --run-dir NEW_FOLDER")
    return cfg


if __name__ == "__main__":
    sys.exit(main())
