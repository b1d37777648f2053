#!/usr/bin/env python3
"""Env steps per second of CyberDog-v0 against the bare loop of the same physics steps with the same PID.

Both run in this process on the same machine: the env (residual mode, zero action, so the trot controller's
PID runs at every physics step) and a bare loop that calls the same trot controller and `Robot.step` for the
same number of physics steps, with nothing else. Several repetitions; the medians and their ratio are
printed (the project aims at env ≤ 1.25 × bare loop time).

Each repetition is timed twice: wall clock (time.perf_counter) and this process's CPU time
(time.process_time). On a shared machine the wall clock counts the time other processes held the CPU, so
the CPU-time rate and the best repetition are the numbers to compare between code versions.

    python bench/env_throughput.py [--steps 400] [--repeats 5]
"""
from __future__ import annotations

import argparse
import statistics
import time

import numpy as np

from cyberdog.control.trot import BodyFeedback
from cyberdog.envs.cyberdog_env import CyberDogEnv


def time_env(env: CyberDogEnv, steps: int) -> tuple[float, float]:
    """(wall s, CPU s) of `steps` env steps from a reset."""
    env.reset(seed=0)
    action = np.zeros(12, dtype=np.float32)
    t0, c0 = time.perf_counter(), time.process_time()
    for _ in range(steps):
        env.step(action)
    return time.perf_counter() - t0, time.process_time() - c0


def time_bare(env: CyberDogEnv, steps: int) -> tuple[float, float]:
    """The same physics steps with the same controller, and only that: (wall s, CPU s)."""
    robot, ctrl = env.robot, env.controller
    robot.reset()
    ctrl.reset()
    dt = env.dt
    s = robot.read_state()
    start = s.base_position.copy()
    t0, c0 = time.perf_counter(), time.process_time()
    for k in range(steps * env.decimation):
        robot.step(ctrl.torque(k * dt, s.q, s.dq, BodyFeedback.from_state(s, start)))
        s = robot.read_state()
    return time.perf_counter() - t0, time.process_time() - c0


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--steps", type=int, default=400, help="env steps per repetition (default 400 = one episode)")
    p.add_argument("--repeats", type=int, default=5)
    args = p.parse_args()
    env = CyberDogEnv()
    env_times, bare_times = [], []  # (wall, cpu) per repetition
    n = args.steps
    for i in range(args.repeats):
        env_times.append(time_env(env, n))
        bare_times.append(time_bare(env, n))
        (ew, ec), (bw, bc) = env_times[-1], bare_times[-1]
        print(f"rep {i}: env {n / ew:7.1f} steps/s (CPU time: {n / ec:7.1f})   bare {n / bw:7.1f} "
              f"(CPU time: {n / bc:7.1f}) (agent-step equivalents)/s", flush=True)
    env.close()
    physics = n * env.decimation
    for label, k in (("wall clock", 0), ("CPU time", 1)):
        te = statistics.median(t[k] for t in env_times)
        tb = statistics.median(t[k] for t in bare_times)
        best_e, best_b = min(t[k] for t in env_times), min(t[k] for t in bare_times)
        print(f"[{label}] median env: {n / te:.1f} env steps/s ({physics / te:.0f} physics steps/s), "
              f"best {n / best_e:.1f}")
        print(f"[{label}] median bare loop: {n / tb:.1f} agent-step equivalents/s ({physics / tb:.0f} physics "
              f"steps/s), best {n / best_b:.1f}")
        print(f"[{label}] env time / bare time = {te / tb:.3f} (target <= 1.25)")


if __name__ == "__main__":
    main()
