"""Seeds at scale: one training run per seed, in parallel, with retries from the last checkpoint, then the
across-seed aggregation.

A sweep folder holds

    sweep.json            what the sweep is: seeds, stages, the original config file and overrides
    sweep_config.yaml     the resolved experiment config every seed trains with (train.seed set per seed)
    sweep_status.json     live status per seed: state, attempts, pid/host, stage, env steps, best score, errors
    seed<N>/              an ordinary run folder of `train.py` (+ train.log, sweep_attempt.json)
    aggregate.*, evaluation.json, learning_curves.*   written by `cyberdog.sweeps.aggregate` at the end

Every attempt of a seed is a separate process of the package's entry point, `python -m cyberdog.train_cli --config
sweep_config.yaml --seed N --run-dir seed<N> --no-progress`, and a retry is `python -m cyberdog.train_cli --resume
seed<N>`. Why processes rather than
calling the trainer in a pool worker: a seed that segfaults in PyBullet, leaks memory or is killed cannot take
the sweep down with it; a retry starts from a clean interpreter exactly like a user's `--resume`; the two
backends differ only in *where* the process is started (here, or inside a Ray task on any node of a cluster).
The training process dies with the process that started it (Linux `PR_SET_PDEATHSIG`), so a killed sweep
leaves no orphan writing into its run folders.

Backends: "local" keeps up to `workers` training processes running on this machine; "ray" submits one Ray
task per attempt (1 CPU each) to a local Ray instance or to an existing cluster (`ray_address`). With a
cluster, the sweep folder must be on a file system that every node sees at the same path (the tasks write
the run folders there and the driver reads the status from them), and the code (`train.py` + `cyberdog/`) is
shipped to the nodes as the Ray job's working_dir; each node needs the project's dependencies installed.

Orchestration, not learning: this package starts processes and reads the files they write, and importing it
imports neither torch nor PyBullet (only `aggregate`'s evaluation rollouts do, inside the function). Modules:

    folder      the sweep folder: sweep.json, seeds, seed<N>/, the arguments of a seed's next attempt
    process     how an attempt runs: the "local" and "ray" backends (standard library only, shipped to Ray
                workers by value)
    status      per-seed status, sweep_status.json, rate and ETA
    run         the driver loop: `run_sweep`
    aggregate   across-seed learning curves, evaluation of every seed's actors, summary tables
"""
from cyberdog.analysis.parallel import available_cores
from cyberdog.sweeps.folder import (CONFIG_FILE, STATUS_FILE, SweepSpec, attempt_args, create_sweep, is_sweep_dir,
                                    load_sweep, parse_seeds, seed_dir, stage_budget)
from cyberdog.sweeps.process import SweepError
from cyberdog.sweeps.run import BACKENDS, run_sweep

__all__ = ["BACKENDS", "CONFIG_FILE", "STATUS_FILE", "SweepError", "SweepSpec", "attempt_args", "available_cores",
           "create_sweep", "is_sweep_dir", "load_sweep", "parse_seeds", "run_sweep", "seed_dir", "stage_budget"]
