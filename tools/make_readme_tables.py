#!/usr/bin/env python
"""Make the result tables (Table 5, the prototype run, the PD's stiffness) of the README and docs/results.md.

    python tools/make_readme_tables.py                 # print them from results/figures_input/
    python tools/make_readme_tables.py --write         # and put them into README.md and docs/results.md
    python tools/make_readme_tables.py --from runs/eval # from another `evaluate.py` output folder
    python tools/make_readme_tables.py --table engines  # one table (its name between the pages' markers)

The tables are made by `cyberdog.analysis.readme_tables` from comparison.json and prototype.json (and the
stiffness walks where shipped), the walks that `python evaluate.py` writes; results/figures_input/ holds the
shipped ones. `--write` replaces each table between its `<!-- table:NAME -->` markers: docs/results.md holds
every table, README.md the ones it marks. tests/test_readme.py checks that both hold exactly what this prints.
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

from cyberdog.analysis.readme_tables import NAMES, make_tables, write_documents  # noqa: E402

DEFAULT_SOURCE = REPO / "results" / "figures_input"


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--from", dest="source", type=Path, default=DEFAULT_SOURCE,
                   help="folder holding comparison.json and prototype.json (default results/figures_input/)")
    p.add_argument("--write", action="store_true",
                   help="replace the tables in README.md and docs/results.md (between their markers)")
    p.add_argument("--table", choices=NAMES, default=None, help="print this table only (default: every table)")
    p.add_argument("--root", type=Path, default=REPO, help=argparse.SUPPRESS)  # where the pages are (tests)
    args = p.parse_args(argv)
    try:
        tables = make_tables(args.source)
        if args.write:
            for page, changed in write_documents(args.root, tables).items():
                print(f"{page}: {'tables rewritten' if changed else 'tables already as made'}")
            return 0
    except (FileNotFoundError, ValueError) as e:
        print(f"readme_tables: {e}", file=sys.stderr)
        return 2
    if args.table is not None and args.table not in tables:
        print(f"readme_tables: no {args.table} table: its inputs are not in {args.source}", file=sys.stderr)
        return 2
    for name, table in tables.items():
        if args.table not in (None, name):
            continue
        print(f"<!-- table:{name} -->\n{table}\n<!-- /table:{name} -->\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
