#!/usr/bin/env python3
"""Training throughput: env steps/s of this pipeline at one update per env step, against Stable-Baselines3 TD3.

Both learn on the same CyberDog-v0 (the environment of `--config`, by default configs/table5.yaml's, the
shipped Table 5 policies': foot mode, 62 observations; the stage-1 reward) in this process, on the same machine,
with the same number of torch threads:

  ours   the real training path, `cyberdog.rl.Trainer` (the TD3 update of `cyberdog.rl.td3`, TorchRL's replay
         buffer and collector, logging), with updates_per_frame=1, batch 256, actor and critics of 3x128, no
         initial random actions, frames_per_batch 200; once per collection mode asked for (--collection sync
         async) and per number of env processes (train.num_envs: 1 and each of --num-envs, default 2; "ours
         sync x2" is sync with two)
  SB3    `stable_baselines3.TD3("MlpPolicy")` with net_arch [128, 128, 128], batch_size 256, train_freq 1,
         gradient_steps 1, Gaussian exploration noise 0.1

Each learns for a warm-up of `--learning-starts` env steps (no updates; ours rounds it up to whole collection
batches of `frames_per_batch`), and then `--steps` env steps with one gradient update per env step, which is
what is timed: env steps/s and updates/s over that window, and the ratio ours / SB3 (the project aims at >= 2).

The bare update rate (updates/s with no env: batches sampled from a filled replay buffer, one update each) of
both is printed too: ours through `Trainer._updates`, SB3 through `TD3.train`.

On a machine shared with other work the wall-clock rates say as much about the neighbours as about the code,
so CPU time is counted too: CPU ms per env step of each process (ours async: the trainer and the collector
process), and from it the rate the pipeline would reach on two otherwise idle cores ("2-core est."): one
process, 1 / its CPU time per step; ours async, 1 / the larger of the two processes' CPU times per step.
With several env processes there is no such estimate (the process that waits for them, TorchRL's
`ParallelEnv`, polls busily, so its CPU time is not its work): measure those on an idle machine with at least
num_envs + 1 cores (+ 2 for async). The last table gives env steps/s against num_envs per collection mode.

    pip install -e .[bench]            # stable-baselines3
    python bench/train_throughput.py [--steps 2000] [--repeats 3] [--threads 1] [--collection sync async]
                                     [--num-envs 2 4 8]

Numbers are noisy on a shared machine: each repetition runs every variant once, in turn, and the best and the
median over the repetitions are printed.
"""
from __future__ import annotations

import argparse
import math
import os
import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import torch
from tensordict import TensorDict

import cyberdog.rl.trainer as trainer_module
from cyberdog import config as C
from cyberdog.config.preset import load_preset
from cyberdog.rl.torchrl_env import make_gym_env
from cyberdog.envs.cyberdog_env import observation_size
from cyberdog.rl.trainer import Trainer

ROOT = Path(__file__).resolve().parents[1]


def frames_per_batch(args, num_envs: int = 1) -> int:
    """--frames-per-batch, rounded up to a multiple of num_envs (each env takes the same number of steps)."""
    return -(-args.frames_per_batch // num_envs) * num_envs


def experiment(args, collection: str, steps: int, num_envs: int = 1) -> C.ExperimentConfig:
    """`--config`'s environment (the preset resolved, `base:` and all); default agent with 3x128 nets; one update
    per env step, batch 256 and a stage-1 budget of `steps`, collected by `num_envs` envs. (Only the env of the
    preset is kept: the timing does not depend on the other agent settings.)"""
    path = Path(args.config)
    env = load_preset(path if path.is_absolute() else ROOT / path).config.env
    sets = ["train.batch_size=256", "train.updates_per_frame=1", "train.init_random_frames=0",
            f"train.learning_starts={args.learning_starts}", f"train.stage1.max_env_steps={steps}",
            "train.stage1.stop_score=.inf", "train.stage1.save_score=.inf", "train.checkpoint_every=1000000000",
            f"train.num_threads={args.threads}", "agent.hidden_sizes=[128, 128, 128]",
            f"train.frames_per_batch={frames_per_batch(args, num_envs)}", "train.buffer_size=100000"]
    sets += [f"train.collection={collection}", f"train.num_envs={num_envs}"]
    return C.override(C.ExperimentConfig(env=env), sets)


def warmup_steps(args, num_envs: int = 1) -> int:
    """Env steps before the first update in our pipeline: learning_starts, rounded up to whole batches."""
    fpb = frames_per_batch(args, num_envs)
    return max(1, math.ceil(args.learning_starts / fpb)) * fpb


# ---- ours ----------------------------------------------------------------------------------------------
WORKER_CPU: list[float] = []  # CPU seconds of the collector process per batch, in arrival order


class RecordingCollector(trainer_module.ProcessCollector):
    def __next__(self):
        batch = super().__next__()
        WORKER_CPU.append(self.last_collect_cpu)
        return batch


def run_ours(args, collection: str, num_envs: int = 1) -> dict:
    """Stage 1 of the real trainer; timed from the end of the first round of updates to the end of the last."""
    w = warmup_steps(args, num_envs)
    total = w + args.steps  # the window opens when the first round of updates (after w env steps) ends
    trainer_module.ProcessCollector = RecordingCollector  # (the trainer looks it up at each stage)
    WORKER_CPU.clear()
    with tempfile.TemporaryDirectory() as tmp:
        trainer = Trainer(experiment(args, collection, total, num_envs), tmp, stages=(1,), progress=False)
        marks: list[tuple[float, float, int, int, int]] = []  # (time, CPU, env steps, updates, batches) per round
        updates = trainer._updates

        def timed_updates(frames: int) -> int:
            n = updates(frames)
            if n:
                marks.append((time.perf_counter(), time.process_time(), trainer.progress.env_steps,
                              trainer.agent.updates, len(WORKER_CPU)))
            return n

        trainer._updates = timed_updates
        trainer.run()
    if len(marks) < 2:
        sys.exit(f"ours ({collection}, {num_envs} env(s)) made {len(marks)} round(s) of updates, too few to time: "
                 f"give --steps more than one batch (--frames-per-batch), and --learning-starts at least the batch "
                 f"size (256), which the replay buffer must hold before the first update")
    (t0, c0, s0, u0, b0), (t1, c1, s1, u1, b1) = marks[0], marks[-1]
    steps = s1 - s0
    out = {"steps_per_s": steps / (t1 - t0), "updates_per_s": (u1 - u0) / (t1 - t0), "steps": steps,
           "cpu_ms": 1e3 * (c1 - c0) / steps}
    if num_envs > 1:  # the waiting process polls busily: CPU time is not work (see the docstring)
        out["est"] = math.nan
    elif collection == "async":  # the batches that arrived in the window, collected in the worker
        out["worker_cpu_ms"] = 1e3 * sum(WORKER_CPU[b0:b1]) / steps
        out["est"] = 1e3 / max(out["cpu_ms"], out["worker_cpu_ms"])
    else:
        out["est"] = 1e3 / out["cpu_ms"]
    return out


def random_transitions(n: int, obs_size: int, action_size: int, seed: int = 0) -> TensorDict:
    g = torch.Generator().manual_seed(seed)
    return TensorDict({"observation": torch.randn(n, obs_size, generator=g),
                       "action": torch.rand(n, action_size, generator=g) * 2 - 1,
                       "next": {"observation": torch.randn(n, obs_size, generator=g),
                                "reward": torch.randn(n, 1, generator=g),
                                "done": torch.zeros(n, 1, dtype=torch.bool),
                                "terminated": torch.zeros(n, 1, dtype=torch.bool)}}, [n])


def bare_ours(args, trainer: Trainer) -> tuple[float, float]:
    """Updates/s of `Trainer._updates` (replay sampling, TD3 update, metrics) on a filled buffer: per second of
    wall-clock time and per second of CPU time."""
    t0, c0 = time.perf_counter(), time.process_time()
    n = trainer._updates(args.bare_updates)
    return n / (time.perf_counter() - t0), n / (time.process_time() - c0)


# ---- Stable-Baselines3 ---------------------------------------------------------------------------------
def import_sb3():
    try:
        import stable_baselines3
        from stable_baselines3.common.callbacks import BaseCallback
        from stable_baselines3.common.noise import NormalActionNoise
    except ImportError as e:
        sys.exit(f"Stable-Baselines3 is needed for the comparison ({e}): pip install -e '.[bench]' "
                 f"(or pip install stable-baselines3), or run with --no-sb3")
    return stable_baselines3, BaseCallback, NormalActionNoise


def make_sb3(args, env, learning_starts: int):
    sb3, _, NormalActionNoise = import_sb3()
    n = env.action_space.shape[0]
    return sb3.TD3("MlpPolicy", env, policy_kwargs={"net_arch": [128, 128, 128]}, batch_size=256, train_freq=1,
                   gradient_steps=1, learning_starts=learning_starts, buffer_size=100_000, device="cpu",
                   action_noise=NormalActionNoise(np.zeros(n), 0.1 * np.ones(n)), seed=0, verbose=0)


def run_sb3(args, cfg: C.ExperimentConfig) -> dict:
    _, BaseCallback, _ = import_sb3()
    w = warmup_steps(args)

    class Mark(BaseCallback):
        def _on_step(self) -> bool:
            if self.num_timesteps == w:
                self.start = (time.perf_counter(), time.process_time(), self.model._n_updates)
            return True

    env = make_gym_env(cfg.env, C.stage_reward(cfg.train.stage1))
    model = make_sb3(args, env, w)
    mark = Mark()
    model.learn(total_timesteps=w + args.steps, callback=mark)
    t1, c1, u1 = time.perf_counter(), time.process_time(), model._n_updates
    env.close()
    t0, c0, u0 = mark.start
    cpu_ms = 1e3 * (c1 - c0) / args.steps
    return {"steps_per_s": args.steps / (t1 - t0), "updates_per_s": (u1 - u0) / (t1 - t0), "steps": args.steps,
            "cpu_ms": cpu_ms, "est": 1e3 / cpu_ms}


def bare_sb3(args, cfg: C.ExperimentConfig) -> float:
    """Updates/s of `TD3.train` (replay sampling and the TD3 update) on a filled buffer."""
    from stable_baselines3.common.logger import configure
    env = make_gym_env(cfg.env, C.stage_reward(cfg.train.stage1))
    model = make_sb3(args, env, 0)
    model.set_logger(configure(None, []))
    rng = np.random.default_rng(0)
    for _ in range(5000):
        obs_size = observation_size(cfg.env)
        model.replay_buffer.add(rng.standard_normal((1, obs_size), dtype=np.float32),
                                rng.standard_normal((1, obs_size), dtype=np.float32),
                                rng.uniform(-1, 1, (1, cfg.env.action_size)).astype(np.float32),
                                rng.standard_normal(1).astype(np.float32), np.zeros(1), [{}])
    model.train(gradient_steps=10, batch_size=256)  # warm-up
    t0, c0 = time.perf_counter(), time.process_time()
    model.train(gradient_steps=args.bare_updates, batch_size=256)
    rates = args.bare_updates / (time.perf_counter() - t0), args.bare_updates / (time.process_time() - c0)
    env.close()
    return rates


def env_only(cfg: C.ExperimentConfig, steps: int) -> tuple[float, float]:
    """Env steps/s of the bare gymnasium env with small random actions, per wall-clock and per CPU second."""
    env = make_gym_env(cfg.env, C.stage_reward(cfg.train.stage1))
    env.reset(seed=0)
    rng = np.random.default_rng(0)
    t0, c0 = time.perf_counter(), time.process_time()
    for _ in range(steps):
        _, _, term, trunc, _ = env.step(rng.uniform(-0.1, 0.1, cfg.env.action_size).astype(np.float32))
        if term or trunc:
            env.reset()
    rates = steps / (time.perf_counter() - t0), steps / (time.process_time() - c0)
    env.close()
    return rates


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--steps", type=int, default=2000, help="timed env steps (one update each) per run (default 2000)")
    p.add_argument("--learning-starts", type=int, default=256,
                   help="env steps without updates before the timed window (default 256 = the batch size)")
    p.add_argument("--frames-per-batch", type=int, default=200,
                   help="our env steps per collection batch (default 200)")
    p.add_argument("--repeats", type=int, default=3)
    p.add_argument("--config", default="configs/table5.yaml",
                   help="the preset whose env both learn on (default configs/table5.yaml, the shipped Table 5 "
                        "policies')")
    p.add_argument("--threads", type=int, default=1, help="torch threads of the updates, ours and SB3 (default 1)")
    p.add_argument("--collection", nargs="+", default=["sync", "async"], choices=C.COLLECTION_MODES,
                   help="our collection modes to run")
    p.add_argument("--num-envs", nargs="+", type=int, default=[2], metavar="N",
                   help="numbers of env processes (train.num_envs) to run ours with, besides 1, in each collection "
                        "mode (default 2; e.g. --num-envs 2 4 8 for a scaling table); --frames-per-batch is rounded "
                        "up to a multiple of each")
    p.add_argument("--bare-updates", type=int, default=300, help="updates per bare-update measurement")
    p.add_argument("--env-steps", type=int, default=400, help="steps of the env-only measurement (0: skip)")
    p.add_argument("--no-sb3", action="store_true", help="skip Stable-Baselines3")
    p.add_argument("--bare-only", action="store_true", help="only the bare update rates")
    args = p.parse_args()
    if any(n < 1 for n in args.num_envs):
        p.error(f"--num-envs must be integers >= 1, got {args.num_envs}")
    env_counts = sorted({1, *args.num_envs})
    if not args.no_sb3:
        import_sb3()
    torch.set_num_threads(args.threads)
    cfg = experiment(args, "sync", 1000)
    print(f"CyberDog-v0 {cfg.env.action_mode} mode, {cfg.env.max_episode_steps}-step episodes; batch 256, 3x128 "
          f"nets, 1 update per env step; {args.steps} timed steps after {warmup_steps(args)}; "
          f"torch {torch.__version__}, {args.threads} thread(s); {os.cpu_count()} CPUs, load average "
          f"{os.getloadavg()[0]:.1f} at the start", flush=True)

    res: dict[str, list[float]] = {}

    def add(key: str, value: float) -> float:
        res.setdefault(key, []).append(value)
        return value

    with tempfile.TemporaryDirectory() as tmp:
        bare_trainer = Trainer(cfg, tmp, stages=(1,), progress=False)
        bare_trainer._begin_stage(cfg.train.stage1)  # the stage's update settings, resolved as a stage starts
        bare_trainer.progress.stage_env_steps = bare_trainer.progress.env_steps = 10 ** 9  # past learning_starts
        bare_trainer.rb.extend(random_transitions(5000, observation_size(cfg.env), cfg.env.action_size))
        bare_trainer._updates(10)  # warm-up
        for r in range(args.repeats):
            print(f"rep {r}:", flush=True)
            wall, cpu = bare_ours(args, bare_trainer)
            line = (f"  bare updates/s: ours {add('bare ours', wall):.1f} "
                    f"({add('bare ours per CPU s', cpu):.1f} per CPU s)")
            if not args.no_sb3:
                wall, cpu = bare_sb3(args, cfg)
                line += f", SB3 {add('bare SB3', wall):.1f} ({add('bare SB3 per CPU s', cpu):.1f} per CPU s)"
            print(line, flush=True)
            if args.bare_only:
                continue
            if args.env_steps:
                wall, cpu = env_only(cfg, args.env_steps)
                print(f"  env alone: {add('env alone', wall):.1f} steps/s ({1e3 / add('env alone per CPU s', cpu):.2f} "
                      f"CPU ms/step)", flush=True)
            runs = [(ours_name(mode, n), lambda mode=mode, n=n: run_ours(args, mode, n))
                    for n in env_counts for mode in args.collection]
            if not args.no_sb3:
                runs.append(("SB3", lambda: run_sb3(args, cfg)))
            for name, run in runs:
                out = run()
                cpu = f"{out['cpu_ms']:.2f}"
                if "worker_cpu_ms" in out:
                    cpu += f" + collector {out['worker_cpu_ms']:.2f}"
                est = (f"2-core est. {add(name + ' 2-core est.', out['est']):.1f} steps/s"
                       if math.isfinite(out["est"]) else "no CPU estimate (several env processes)")
                print(f"  {name:<14s} {add(name + ' steps/s', out['steps_per_s']):7.1f} env steps/s, "
                      f"{add(name + ' updates/s', out['updates_per_s']):7.1f} updates/s over {out['steps']} steps; "
                      f"CPU ms/step {cpu}; {est}", flush=True)
            if not args.no_sb3:
                for mode in args.collection:
                    add(f"ratio {mode}", res[f"ours {mode} steps/s"][-1] / res["SB3 steps/s"][-1])
                    add(f"ratio {mode} 2-core est.", res[f"ours {mode} 2-core est."][-1] / res["SB3 2-core est."][-1])
                    for n in env_counts[1:]:
                        add(f"ratio {mode} x{n}", res[f"{ours_name(mode, n)} steps/s"][-1] / res["SB3 steps/s"][-1])
        bare_trainer.logger.close()

    print(f"\nover {args.repeats} repetitions (best, median):")
    for key, values in res.items():
        if not key.startswith("ratio"):
            print(f"  {key:<34s} {max(values):8.1f} {statistics.median(values):8.1f}")
    for mode in args.collection:
        if f"ratio {mode}" in res:
            print(f"ours ({mode}) / SB3 env steps/s: {statistics.median(res[f'ratio {mode}']):.2f} measured, "
                  f"{statistics.median(res[f'ratio {mode} 2-core est.']):.2f} on 2 idle cores (est. from CPU time); "
                  f"medians of per-repetition ratios (the project aims at >= 2)")
        for n in env_counts[1:]:
            if f"ratio {mode} x{n}" in res:
                print(f"ours ({mode}, {n} env processes) / SB3 env steps/s: "
                      f"{statistics.median(res[f'ratio {mode} x{n}']):.2f} measured")
    if not args.bare_only:
        scaling_table(res, args.collection, env_counts, args.no_sb3)


def ours_name(mode: str, num_envs: int) -> str:
    return f"ours {mode}" if num_envs == 1 else f"ours {mode} x{num_envs}"


def scaling_table(res: dict, modes: list[str], env_counts: list[int], no_sb3: bool) -> None:
    """Median env steps/s (and updates/s) of ours against train.num_envs, one column per collection mode."""
    sb3 = "" if no_sb3 else f" (SB3: {statistics.median(res['SB3 steps/s']):.1f})"
    print(f"\nenv steps/s against train.num_envs, medians at one update per env step{sb3}:")
    print("  num_envs " + "".join(f"{mode + ' steps/s':>16s}{mode + ' updates/s':>18s}" for mode in modes))
    for n in env_counts:
        cells = "".join(f"{statistics.median(res[ours_name(m, n) + ' steps/s']):16.1f}"
                        f"{statistics.median(res[ours_name(m, n) + ' updates/s']):18.1f}" for m in modes)
        print(f"  {n:8d} {cells}")


if __name__ == "__main__":
    main()
