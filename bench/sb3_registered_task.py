#!/usr/bin/env python3
"""Is the registered task worth training? A third-party learner, with its own defaults, on `gym.make(TASK)`.

Stable-Baselines3's TD3 (`TD3("MlpPolicy", env)`, every setting its default but `learning_starts`, which is
shortened to fit the budget) trains for `--steps` env steps on `CyberDog-v0` (the shipped agents' task); before
and after, its deterministic policy walks `--episodes` episodes (seeded resets), and the script prints each
episode's length (400 = the whole 10 s), whether it fell, its mean forward speed against the command, and its
score. A task worth training is one where the learner's episodes do not get shorter: on the former default
(residual torques, Eq. 11) SB3's TD3 fell at step 17 after 500 steps.

    pip install -e ".[bench]"      # stable-baselines3
    python bench/sb3_registered_task.py --steps 5000
"""
from __future__ import annotations

import argparse
import sys
import time
import warnings

import numpy as np


def evaluate(model, env, episodes: int, seed: int) -> list[dict]:
    rows = []
    for k in range(episodes):
        obs, info = env.reset(seed=seed + k)
        command, score, speeds, fell, length = env.unwrapped.target_speed, 0.0, [], False, 0
        for length in range(1, 401):
            action = model.predict(obs, deterministic=True)[0] if model is not None else np.zeros(12, np.float32)
            obs, r, terminated, truncated, info = env.step(action)
            score += float(r)
            speeds.append(info["forward_speed"])
            if terminated or truncated:
                fell = bool(terminated)
                break
        rows.append({"length": length, "fell": fell, "command_mps": command,
                     "mean_speed_mps": float(np.mean(speeds[len(speeds) // 2:])), "score": score})
    return rows


def progress_callback(total: int, every_s: float = 15.0):
    """An SB3 callback that prints the env steps done every `every_s` seconds (training is otherwise silent)."""
    from stable_baselines3.common.callbacks import BaseCallback

    class Progress(BaseCallback):
        def _on_training_start(self) -> None:
            self.t0 = self.last = time.perf_counter()

        def _on_step(self) -> bool:
            now = time.perf_counter()
            if now - self.last >= every_s:
                self.last = now
                print(f"  training: {self.num_timesteps} of {total} env steps ({now - self.t0:.0f} s)", flush=True)
            return True

    return Progress()


def report(title: str, rows: list[dict]) -> None:
    print(f"{title}: mean length {np.mean([r['length'] for r in rows]):.0f} steps, falls {sum(r['fell'] for r in rows)}"
          f"/{len(rows)}, mean score {np.mean([r['score'] for r in rows]):.1f}", flush=True)
    for r in rows:
        print(f"  {r['length']:3d} steps, fell={r['fell']!s:5}, {r['mean_speed_mps']:.3f} m/s at a command of "
              f"{r['command_mps']:.2f} m/s, score {r['score']:.1f}", flush=True)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--task", default="CyberDog-v0", help="registered task (default CyberDog-v0)")
    p.add_argument("--steps", type=int, default=5000, help="env steps of training (default 5000)")
    p.add_argument("--learning-starts", type=int, default=1000, help="SB3's learning_starts (its default is 100)")
    p.add_argument("--episodes", type=int, default=3, help="evaluation episodes before and after (default 3)")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--threads", type=int, default=1, help="torch threads (default 1: on a loaded 2-core machine "
                   "torch's default thread count made the same 5000 steps take over an hour instead of 2.5 min)")
    args = p.parse_args(argv)
    import torch
    torch.set_num_threads(args.threads)
    try:
        from stable_baselines3 import TD3
    except ImportError:
        sys.exit("stable-baselines3 is not installed: pip install -e \".[bench]\"")
    import gymnasium as gym

    import cyberdog  # noqa: F401  (registers the tasks)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        env, eval_env = gym.make(args.task), gym.make(args.task)
    model = TD3("MlpPolicy", env, learning_starts=args.learning_starts, seed=args.seed, verbose=0)
    report(f"{args.task}, the zero action (the trot)", evaluate(None, eval_env, args.episodes, 10_000))
    report(f"{args.task}, SB3 TD3 untrained", evaluate(model, eval_env, args.episodes, 10_000))
    t0 = time.perf_counter()
    model.learn(total_timesteps=args.steps, progress_bar=False, log_interval=None,
                callback=progress_callback(args.steps))
    print(f"trained {args.steps} env steps in {time.perf_counter() - t0:.0f} s", flush=True)
    report(f"{args.task}, SB3 TD3 after {args.steps} steps", evaluate(model, eval_env, args.episodes, 10_000))
    return 0


if __name__ == "__main__":
    sys.exit(main())
