"""Draw the paper's figures from a results folder: `python -m plots --from DIR --out DIR`.

    python -m plots --from runs/evaluate-<time> --out runs/figures          # every figure it has inputs for
    python -m plots --from results/figures_input --out plots/png --readme    # the README's PNGs
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

from plots import FIGURES, draw_all
from plots.shipped import README_DPI, README_FIGURES, export_inputs
from plots.style import DPI


def parse_args(argv=None) -> argparse.Namespace:
    p = argparse.ArgumentParser(prog="python -m plots", description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--from", dest="from_dir", type=Path, required=True, metavar="DIR",
                   help="a results folder written by `evaluate.py` (all, compare, prototype), or "
                        "results/figures_input")
    p.add_argument("--out", type=Path, required=True, metavar="DIR", help="where the figures go")
    p.add_argument("--metrics", type=Path, nargs="+", default=None, metavar="CSV",
                   help="training logs (metrics.csv) for Figure 6; its title names each run by its folder")
    p.add_argument("--only", nargs="+", default=None, choices=FIGURES, help="draw only these figures")
    p.add_argument("--dpi", type=int, default=DPI, help=f"PNG resolution (default {DPI})")
    p.add_argument("--no-pdf", action="store_true", help="PNG only")
    p.add_argument("--readme", action="store_true",
                   help=f"the README's figures: --only {' '.join(README_FIGURES)} --dpi {README_DPI} --no-pdf")
    p.add_argument("--save-inputs", type=Path, default=None, metavar="DIR",
                   help="also write the small inputs of the README's figures there (e.g. results/figures_input)")
    args = p.parse_args(argv)
    if args.readme:
        args.only, args.dpi, args.no_pdf = list(README_FIGURES), README_DPI, True
    if args.dpi < 10:
        p.error(f"--dpi must be >= 10, got {args.dpi}")
    if not args.from_dir.is_dir():
        p.error(f"--from {args.from_dir} is not a folder")
    return args


def main(argv=None) -> int:
    args = parse_args(argv)
    for m in args.metrics or []:
        if not m.is_file():
            print(f"python -m plots: error: --metrics {m} does not exist", file=sys.stderr)
            return 2
    try:
        paths = draw_all(args.from_dir, args.out, args.metrics, args.only, args.dpi, not args.no_pdf)
        if args.save_inputs is not None:
            paths += export_inputs(args.from_dir, args.save_inputs)
    except (ValueError, OSError, KeyError) as err:
        print(f"python -m plots: error: {err}", file=sys.stderr)
        return 2
    print(f"wrote {len(paths)} files:")
    for path in paths:
        print(f"  {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
