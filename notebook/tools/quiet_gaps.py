#!/usr/bin/env python3
"""How long does a command stay silent? Runs it, passes its output through, and prints the longest gaps.

    python notebook/tools/quiet_gaps.py -- \\
        .venv/bin/python evaluate.py extract --policies results/table5/policy/seed0 --out runs/x

Every line of the command's standard output and error is shown as it comes (a progress bar's in-place
updates count as lines), then the three longest stretches without one (s), with the line that ended each. Long work in this project prints at least every ~15 s
(`cyberdog.analysis.parallel.QUIET_LIMIT_S`, the trainer's progress line); this measures it on a real run.
"""
from __future__ import annotations

import os
import subprocess
import sys
import time


def main(argv: list[str]) -> int:
    if "--" in argv:
        argv = argv[argv.index("--") + 1:]
    if not argv:
        print(__doc__)
        return 2
    env = {**os.environ, "PYTHONUNBUFFERED": "1"}
    t0 = last = time.perf_counter()
    gaps = []
    with subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, env=env) as proc:
        line = ""
        for char in iter(lambda: proc.stdout.read(1), ""):  # a progress bar's "\r" updates count as lines too
            print(char, end="", flush=char in "\r\n")
            if char in "\r\n":
                now = time.perf_counter()
                gaps.append((now - last, line.strip()[:100]))
                last, line = now, ""
            else:
                line += char
    gaps.append((time.perf_counter() - last, "(the end)"))
    print(f"\n{argv[0]} ... exit {proc.returncode} after {time.perf_counter() - t0:.0f} s; longest silences:")
    for gap, line in sorted(gaps, reverse=True)[:3]:
        print(f"  {gap:6.1f} s before: {line}")
    return proc.returncode


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
