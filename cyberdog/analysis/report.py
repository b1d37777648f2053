"""Plain-text, Markdown, CSV and JSON output of result rows (lists of flat dicts)."""
from __future__ import annotations

import csv
import json
import math
from pathlib import Path


def json_safe(x):
    """`x` with every non-finite float (NaN, ±inf, which strict JSON has no words for) replaced by None, through
    dicts and lists."""
    if isinstance(x, float) and not math.isfinite(x):
        return None
    if isinstance(x, dict):
        return {k: json_safe(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [json_safe(v) for v in x]
    return x


def _fmt(v) -> str:
    if isinstance(v, bool):
        return "yes" if v else "no"
    if isinstance(v, float):
        return f"{v:.4g}"
    return str(v)


def all_columns(rows: list[dict]) -> list[str]:
    """Every key of `rows`, in order of first appearance (rows of one table may carry different extras)."""
    return list(dict.fromkeys(k for r in rows for k in r))


def markdown_table(rows: list[dict], columns: list[str] | None = None) -> str:
    """A Markdown table of `rows` (one dict per row), columns in the given order or every row's keys (empty
    cells where a row lacks one)."""
    if not rows:
        return "(no rows)"
    columns = columns or all_columns(rows)
    lines = ["| " + " | ".join(columns) + " |", "|" + "|".join("---" for _ in columns) + "|"]
    lines += ["| " + " | ".join(_fmt(r.get(c, "")) for c in columns) + " |" for r in rows]
    return "\n".join(lines)


def write_rows(rows: list[dict], folder: Path, stem: str, columns: list[str] | None = None) -> None:
    """Write rows as `<stem>.csv`, `<stem>.json` and `<stem>.md` in `folder` (columns: `columns` in that order,
    else every row's keys; empty cells where a row lacks one). No rows, no files: an absent table is an empty
    one (`prototype_gaps` where one robot walked)."""
    folder.mkdir(parents=True, exist_ok=True)
    if not rows:
        return
    with open(folder / f"{stem}.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=columns or all_columns(rows), restval="", extrasaction="ignore")
        w.writeheader()
        w.writerows(rows)
    (folder / f"{stem}.json").write_text(json.dumps(rows, indent=2))
    (folder / f"{stem}.md").write_text(markdown_table(rows, columns) + "\n")
