"""The cells and lines of the result pages' Markdown tables: numbers with a typographic minus, mean ± 95 % CI."""
from __future__ import annotations

import math
from collections.abc import Iterable

MINUS = "\u2212"  # the pages' minus sign


def number(x: float, fmt: str, sign: bool = False) -> str:
    """`x` formatted, with a typographic minus (and a plus if `sign`)."""
    text = format(x, ("+" if sign else "") + fmt)
    return text.replace("-", MINUS)


def mean_ci(row: dict, key: str, fmt: str, unit: str = "", sign: bool = False) -> str:
    """"m unit ± h" for a row's `key`_mean and `key`_ci95 (no "± h" where the CI is undefined: one value)."""
    m, h = row.get(f"{key}_mean", math.nan), row.get(f"{key}_ci95", math.nan)
    if not math.isfinite(m):
        return "–"
    return number(m, fmt, sign) + unit + (f" ± {number(h, fmt)}" if math.isfinite(h) else "")


def line(label: str, cells: list[str]) -> str:
    """One table row: `label`, then the cells (an empty cell stays empty)."""
    return "|" + "".join(f" {c} |" if c else " |" for c in [label, *cells])


def header(first: str, speeds: list[float]) -> list[str]:
    """A table's header over the commanded speeds (m/s) and its rule."""
    return [line(first, [f"{v:.1f} m/s" for v in speeds]), "|---|" + "---|" * len(speeds)]


def seeds_named(labels: Iterable[str]) -> str:
    """"seeds 5–9": the seeds that labels "seedN" (or "N") name, each run of consecutive seeds as its first and
    last ("seeds 20–24, 40–44"; "seed 0" where one does, "fresh seeds" where none does)."""
    numbers = sorted({int(n) for n in (str(x).removeprefix("seed") for x in labels) if n.isdigit()})
    if not numbers:
        return "fresh seeds"
    if len(numbers) == 1:
        return f"seed {numbers[0]}"
    starts = [n for i, n in enumerate(numbers) if i == 0 or numbers[i - 1] != n - 1]
    ends = [n for i, n in enumerate(numbers) if i == len(numbers) - 1 or numbers[i + 1] != n + 1]
    return "seeds " + ", ".join(f"{a}–{b}" if b > a else f"{a}" for a, b in zip(starts, ends))


def missed_walks(row: dict) -> str:
    """" (k fell, m off the ±5 % band, of n)" for a summary row whose walks did not all count, "" if they did;
    with walks off the band, also the saving counting them ("; with them: s % ± h"): a slow walk left out of the
    mean must not hide what it cost."""
    off = row["walks"] - row["counted"] - row["fell"]
    parts = [f"{row['fell']} fell"] * bool(row["fell"]) + [f"{off} off the ±5 % band"] * bool(off)
    stood = mean_ci(row, "battery_saving_stood_pct", ".1f", " %")  # "–" where no walk stood without counting
    with_them = f"; with {'it' if off == 1 else 'them'}: {stood}" if off and stood != "–" else ""
    return f" ({', '.join(parts)}, of {row['walks']}{with_them})" if parts else ""


def fewer_seeds(walks: list[dict], robot: str, speed: float) -> str:
    """" (4 of 5 seeds)" where fewer seeds have a learned path at `speed` (m/s) on `robot` than the learned walks
    name at any speed (an extraction that found no path there), "" where all have. A seed with no path at any
    speed has no walk to name it: the walks cannot show it."""
    learned = [w for w in walks if w["trajectory"] == "learned" and w["robot"] == robot]
    seeds = {str(w["seed"]) for w in learned}
    here = {str(w["seed"]) for w in learned if w["speed_mps"] == speed}
    return f" ({len(here)} of {len(seeds)} seed{'s' * (len(seeds) != 1)})" if here and len(here) < len(seeds) else ""
