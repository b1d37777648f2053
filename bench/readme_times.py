#!/usr/bin/env python3
"""Re-measure the wall times the README states, on this machine, and say what machine it is.

The README's times were measured on two idle 2-core x86-64 machines (an AMD EPYC, and a 2.1 GHz Intel Xeon at
about half its speed); they scale with the cores (`evaluate.py` walks in one process per core, the test suite and a
training run use one or two) and with whatever else runs (a loaded machine took 5-6x as long). This script prints
the machine (CPU model, cores, load average before and after) and times each command as the README writes it, one
after another, in wall and CPU time (user + system of every process it started):

    python bench/readme_times.py                       # evaluate.py (command 1's job) and the tiny training run
    python bench/readme_times.py --tests               # + the quick test tier and the full test run (command 2)
    python bench/readme_times.py --only tiny           # one of them

Outputs go to a temporary folder that is deleted afterwards; each command prints its own progress as it runs.
"""
from __future__ import annotations

import argparse
import os
import platform
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]


def commands(out: Path) -> dict[str, list[str]]:
    py = sys.executable
    return {"evaluate": [py, "evaluate.py", "--out", str(out / "evaluate")],
            "tiny": [py, "train.py", "--config", "configs/tiny.yaml", "--run-dir", str(out / "tiny"), "--no-progress"],
            "quick_tests": [py, "-m", "pytest", "-q", "-m", "not slow", "-p", "no:cacheprovider"],
            "tests": [py, "-m", "pytest", "-q", "-p", "no:cacheprovider"]}


def machine() -> str:
    model = "unknown CPU"
    try:
        model = next(line.split(":", 1)[1].strip() for line in Path("/proc/cpuinfo").read_text().splitlines()
                     if line.startswith("model name"))
    except (OSError, StopIteration):
        model = platform.processor() or model
    return f"{model}, {os.cpu_count()} cores, {platform.system()} {platform.machine()}, Python {platform.python_version()}"


def load() -> str:
    try:
        return "load average (1 min) {:.2f}".format(os.getloadavg()[0])
    except OSError:
        return "load average unknown"


def _children_cpu_s() -> float:
    """s of CPU (user + system) the finished child processes used so far (their workers included)."""
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def _minutes(seconds: float) -> str:
    return f"{seconds // 60:.0f} min {seconds % 60:.0f} s"


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--tests", action="store_true", help="also time the quick test tier and the full test run")
    p.add_argument("--only", choices=["evaluate", "tiny", "quick_tests", "tests"], help="time this command alone")
    args = p.parse_args(argv)
    print(f"machine: {machine()}; {load()}", flush=True)
    with tempfile.TemporaryDirectory(prefix="readme_times_") as tmp:
        todo = commands(Path(tmp))
        names = [args.only] if args.only else ["evaluate", "tiny"] + (["quick_tests", "tests"] if args.tests else [])
        for name in names:
            print(f"{name}: {' '.join(todo[name][1:])} ...", flush=True)
            t0, cpu0 = time.perf_counter(), _children_cpu_s()
            done = subprocess.run(todo[name], cwd=REPO)
            seconds, cpu = time.perf_counter() - t0, _children_cpu_s() - cpu0
            status = "ok" if done.returncode == 0 else f"failed (exit {done.returncode})"
            print(f"{name}: {_minutes(seconds)} wall, {_minutes(cpu)} CPU, {status}; {load()}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
