"""What every figure shares: colours and names of the trajectories, font sizes, and how a figure is saved.

Figures are `matplotlib.figure.Figure` objects, never pyplot's global state: no GUI backend is touched, and
several figures can be drawn in one process (or in tests) without leaking memory.
"""
from __future__ import annotations

import functools
from pathlib import Path

import matplotlib
from matplotlib.figure import Figure

COLORS = {"learned": "tab:green", "cycloid": "tab:blue", "straight": "tab:red", "searched": "tab:gray"}
SEED_COLORS = ("tab:purple", "tab:orange", "tab:brown", "tab:olive", "tab:cyan", "tab:pink", "tab:gray")
NAMES = {"learned": "learned (RL)", "cycloid": "composite cycloid", "straight": "straight line",
         "searched": "direct search (reference)"}
FONTS = {"font.size": 10, "axes.titlesize": 11, "axes.labelsize": 10, "legend.fontsize": 8.5}
DPI = 150  # of the PNGs in a results folder; the README's copies are drawn smaller (plots/png/)
FADED_ALPHA = 0.35  # a bar of a walk that does not count (fell or off the speed band)


def styled(draw):
    """Run a drawing function under the project's font sizes (rcParams are read when a text is created, so
    the whole drawing runs inside the context; the global settings are left as they were)."""
    @functools.wraps(draw)
    def wrapper(*args, **kwargs):
        with matplotlib.rc_context(FONTS):
            return draw(*args, **kwargs)
    return wrapper


def save_figure(fig: Figure, out_dir: str | Path, stem: str, dpi: int = DPI, pdf: bool = True) -> list[Path]:
    """Write `<stem>.png` (at `dpi`) and, with `pdf`, `<stem>.pdf` into `out_dir`; returns the paths."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    paths = [out / f"{stem}.png"] + ([out / f"{stem}.pdf"] if pdf else [])
    # a fixed creation date and no software tag: the same inputs give the same bytes, so a redraw of the
    # shipped PNGs changes nothing in git unless the figure changed
    fig.savefig(paths[0], dpi=dpi, bbox_inches="tight", metadata={"Software": None})
    if pdf:
        fig.savefig(paths[1], bbox_inches="tight", metadata={"CreationDate": None, "Producer": None})
    return paths


__all__ = ["COLORS", "DPI", "FADED_ALPHA", "FONTS", "NAMES", "SEED_COLORS", "save_figure", "styled"]
