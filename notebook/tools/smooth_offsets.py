#!/usr/bin/env python3
"""Does the doubled damping's loss come from the learned path's kinks? Writes low-passed copies of commanded paths.

A foot-mode policy shifts the trot's foot targets every 25 ms and the controller ramps each shift linearly over
the step (`TrotController.ramp_foot_offsets`), so an extracted path's offsets (`FootOffsetPath`) are piecewise
linear in the phase, and their rates, which the trot's velocity feedforward turns into the drivers' joint speed
targets q̇_des, jump at every agent step (40 Hz and its multiples, harmonic 16 of a 0.4 s gait). The drivers'
damping acts on q̇_des − q̇, so a doubled kd doubles what those jumps cost, while the common trajectories are
smooth. This keeps each leg's offsets' harmonics up to `--harmonics` (periodic FFT over the gait cycle) and
writes the paths under OUT with the same names; walk them with `evaluate.py prototype --learned OUT ...`.

    python notebook/tools/smooth_offsets.py results/battery/paths runs/smooth8/learned --harmonics 8
    python evaluate.py prototype --learned runs/smooth8/learned --prototype-modes hardware \
        --no-prototype-reference --set "pid.kd=[4,4,4]" --out runs/smooth8_kd2

Finding: notebook/2026-12-01_gains_phase.md ("Smoothing the paths"): not the cause.
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from cyberdog.core.commanded_path import CommandedPath
from cyberdog.core.foot_offsets import FootOffsetPath


def low_passed(offsets: FootOffsetPath, harmonics: int) -> FootOffsetPath:
    """The same offsets with each leg's and axis's harmonics of the gait frequency above `harmonics` removed
    (the mean, harmonic 0, kept); `harmonics` ≥ n/2 returns the table unchanged."""
    if harmonics < 1:
        raise ValueError(f"harmonics must be >= 1, got {harmonics}")
    spectrum = np.fft.rfft(offsets.offsets, axis=1)
    spectrum[:, harmonics + 1:, :] = 0
    return FootOffsetPath(np.fft.irfft(spectrum, n=offsets.n, axis=1), offsets.period)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("src", type=Path, help="a folder of commanded path files (JSON)")
    ap.add_argument("out", type=Path, help="the folder the low-passed copies are written to (must not be src)")
    ap.add_argument("--harmonics", type=int, default=8, help="harmonics of the gait frequency kept (default 8: "
                                                              "20 Hz at a 0.4 s gait)")
    args = ap.parse_args(argv)
    files = sorted(args.src.glob("*.json"))
    if not files:
        sys.exit(f"no path files in {args.src}")
    if args.out.resolve() == args.src.resolve():
        sys.exit("OUT must differ from SRC: the paths are copied, never overwritten")
    for f in files:
        path = CommandedPath.load(f)
        smooth = low_passed(path.offsets, args.harmonics)
        change_mm = 1e3 * float(np.sqrt(np.mean((smooth.offsets - path.offsets.offsets) ** 2)))
        path.offsets = smooth
        path.provenance = {**path.provenance, "low_passed": {"harmonics": args.harmonics, "from": str(f)}}
        path.save(args.out / f.name)
        print(f"{f.name}: offsets moved {change_mm:.2f} mm rms (of {1e3 * float(np.sqrt(np.mean(path.offsets.offsets ** 2))):.1f})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
