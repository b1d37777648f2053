#!/usr/bin/env python
"""Train the CyberDog walking agent with TD3 or DDPG in two stages (paper Section 3).

Examples:
  python train.py --config configs/quick.yaml --run-dir runs/quick            # stage 1 then stage 2
  python train.py --config configs/paper.yaml --stage 1 --seed 3 --run-dir runs/paper_s3
  python train.py --config configs/quick.yaml --set agent.algorithm=ddpg --set train.batch_size=128
  python train.py --resume runs/quick                                         # continue a killed run
  python train.py --config configs/quick.yaml --stage 2 --init-from runs/quick/stage1_final.pt --run-dir runs/q2

Outputs in the run folder: config.yaml (resolved), metrics.csv (one row per episode), tb/ (TensorBoard),
checkpoint.pt (resume point), stage<N>_final.pt, stage<N>_best_actor.pt, saved/ (agents above save_score).
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

from cyberdog import config as C


def parse_args(argv=None) -> argparse.Namespace:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--config", type=Path, help="experiment YAML (ExperimentConfig: env, agent, train); "
                   "default: built-in defaults")
    p.add_argument("--stage", choices=("1", "2", "both"), default="both",
                   help="stage 1 (no energy term), stage 2 (Eq. 11 with energy), or both in sequence (default)")
    p.add_argument("--seed", type=int, help="random seed; overrides train.seed")
    p.add_argument("--run-dir", type=Path, help="output folder (default runs/<config name>_seed<seed>)")
    p.add_argument("--set", dest="overrides", action="append", default=[], metavar="SECTION.FIELD=VALUE",
                   help="override a config field, value parsed as YAML, e.g. --set train.stage1.max_env_steps=5000 "
                        "(repeatable)")
    p.add_argument("--resume", type=Path, metavar="RUN_DIR",
                   help="continue the run in RUN_DIR from its checkpoint.pt with its saved config.yaml")
    p.add_argument("--init-from", type=Path, metavar="CHECKPOINT",
                   help="start from this checkpoint's agent (e.g. runs/x/stage1_final.pt); "
                        "default for --stage 2: <run-dir>/stage1_final.pt")
    p.add_argument("--device", choices=C.DEVICES, help="overrides train.device: cpu, cuda or auto")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    return p.parse_args(argv)


def main(argv=None) -> int:
    args = parse_args(argv)
    from cyberdog.rl import CheckpointError, NonFiniteError, Trainer  # slow import after --help

    if args.resume is not None:
        if args.config or args.overrides or args.seed is not None or args.init_from:
            sys.exit("--resume uses the run folder's config.yaml; do not combine it with --config, --set, "
                     "--seed or --init-from")
        cfg_path = args.resume / "config.yaml"
        if not cfg_path.is_file():
            sys.exit(f"--resume {args.resume}: no config.yaml there")
        cfg = C.load(C.ExperimentConfig, cfg_path)
        if args.device:
            sys.exit("--device cannot be combined with --resume: the run continues with its saved train.device")
        trainer_kwargs = dict(run_dir=args.resume, resume=True)
    else:
        try:
            cfg = C.load(C.ExperimentConfig, args.config) if args.config else C.ExperimentConfig()
            sets = list(args.overrides)
            if args.seed is not None:
                sets.append(f"train.seed={args.seed}")
            if args.device:
                sets.append(f"train.device={args.device}")
            cfg = C.override(cfg, sets)
        except (ValueError, TypeError, OSError) as e:
            sys.exit(f"config error: {e}")
        name = args.config.stem if args.config else "default"
        run_dir = args.run_dir or Path("runs") / f"{name}_seed{cfg.train.seed}"
        if (run_dir / "checkpoint.pt").exists():
            sys.exit(f"{run_dir} already holds a run; use --resume {run_dir} or another --run-dir")
        stages = (1, 2) if args.stage == "both" else (int(args.stage),)
        init_from = args.init_from
        if stages == (2,) and init_from is None:
            init_from = run_dir / "stage1_final.pt"
            if not init_from.is_file():
                sys.exit(f"--stage 2 needs a stage-1 agent: pass --init-from, or run stage 1 in {run_dir} first")
        trainer_kwargs = dict(run_dir=run_dir, stages=stages, init_from=init_from)
    try:
        summary = Trainer(cfg, progress=not args.no_progress, **trainer_kwargs).run()
    except (CheckpointError, NonFiniteError) as e:
        sys.exit(f"error: {e}")
    print("done: " + ", ".join(f"{k}={v}" for k, v in summary.items()
                               if k in ("stage", "env_steps", "episodes", "updates", "buffer_size",
                                        "window_mean_score")))
    return 0


if __name__ == "__main__":
    sys.exit(main())
