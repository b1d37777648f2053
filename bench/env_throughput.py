#!/usr/bin/env python3
"""Env steps per second of CyberDog-v0 against the bare loop of the same physics steps with the same PID.

Both run in this process on the same machine: the env (residual mode, zero action, so the trot controller's
PID runs at every physics step) and a bare loop that calls the same trot controller and `Robot.step` for the
same number of physics steps, with nothing else. Several repetitions; the medians and their ratio are
printed (issue target: env ≤ 1.25 × bare loop time).

    python bench/env_throughput.py [--steps 400] [--repeats 5]
"""
from __future__ import annotations

import argparse
import statistics
import time

import numpy as np

from cyberdog.control.trot import BodyFeedback
from cyberdog.envs.cyberdog_env import CyberDogEnv


def time_env(env: CyberDogEnv, steps: int) -> float:
    env.reset(seed=0)
    action = np.zeros(12, dtype=np.float32)
    t0 = time.perf_counter()
    for _ in range(steps):
        env.step(action)
    return time.perf_counter() - t0


def time_bare(env: CyberDogEnv, steps: int) -> float:
    """The same physics steps with the same controller, and only that."""
    robot, ctrl = env.robot, env.controller
    robot.reset()
    ctrl.reset()
    dt = env.dt
    s = robot.read_state()
    start = s.base_position.copy()
    t0 = time.perf_counter()
    for k in range(steps * env.decimation):
        robot.step(ctrl.torque(k * dt, s.q, s.dq, BodyFeedback.from_state(s, start)))
        s = robot.read_state()
    return time.perf_counter() - t0


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--steps", type=int, default=400, help="env steps per repetition (default 400 = one episode)")
    p.add_argument("--repeats", type=int, default=5)
    args = p.parse_args()
    env = CyberDogEnv()
    env_times, bare_times = [], []
    for i in range(args.repeats):
        env_times.append(time_env(env, args.steps))
        bare_times.append(time_bare(env, args.steps))
        print(f"rep {i}: env {args.steps / env_times[-1]:7.1f} steps/s   bare {args.steps / bare_times[-1]:7.1f} "
              f"(agent-step equivalents)/s", flush=True)
    env.close()
    te, tb = statistics.median(env_times), statistics.median(bare_times)
    print(f"median env: {args.steps / te:.1f} env steps/s ({args.steps * env.decimation / te:.0f} physics steps/s)")
    print(f"median bare loop: {args.steps / tb:.1f} agent-step equivalents/s "
          f"({args.steps * env.decimation / tb:.0f} physics steps/s)")
    print(f"env time / bare time = {te / tb:.3f} (target <= 1.25)")


if __name__ == "__main__":
    main()
