#!/usr/bin/env python
"""Make the README's two result tables (Table 5, the prototype run) from the shipped results.

    python tools/make_readme_tables.py                 # print them from results/figures_input/
    python tools/make_readme_tables.py --write         # and put them into README.md between its markers
    python tools/make_readme_tables.py --from runs/eval # from another `evaluate.py` output folder

The tables are made by `cyberdog.analysis.readme_tables` from comparison.json and prototype.json, the walks
that `python evaluate.py` writes; results/figures_input/ holds the shipped ones. tests/test_readme.py checks that the
README holds exactly what this prints.
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

from cyberdog.analysis.readme_tables import make_tables, replace_blocks  # noqa: E402

DEFAULT_SOURCE = REPO / "results" / "figures_input"


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--from", dest="source", type=Path, default=DEFAULT_SOURCE,
                   help="folder holding comparison.json and prototype.json (default results/figures_input/)")
    p.add_argument("--write", action="store_true", help="replace the tables in README.md (between its markers)")
    p.add_argument("--readme", type=Path, default=REPO / "README.md", help=argparse.SUPPRESS)
    args = p.parse_args(argv)
    try:
        tables = make_tables(args.source)
        if args.write:
            text = args.readme.read_text()
            new = replace_blocks(text, tables)
            args.readme.write_text(new)
            print(f"{args.readme}: {'tables rewritten' if new != text else 'tables already as made'}")
            return 0
    except (FileNotFoundError, ValueError) as e:
        print(f"readme_tables: {e}", file=sys.stderr)
        return 2
    for name, table in tables.items():
        print(f"<!-- table:{name} -->\n{table}\n<!-- /table:{name} -->\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
