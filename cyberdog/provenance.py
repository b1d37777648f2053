"""Paths in what the project writes down (provenance, commands): names that mean the same on another machine.

A result file travels (it is shipped in `results/`, copied, cited), so it never names a path of the machine
that made it: a path inside the current folder (the repository, when the CLIs run from its root) is written
relative to it; any other is written as its run folder's name and the file (`long_s0/stage2_final_actor.pt`),
which together with the recorded commit says what produced it.
"""
from __future__ import annotations

import os
from pathlib import Path


def portable_path(path: str | os.PathLike, root: str | os.PathLike | None = None) -> str:
    """`path` relative to `root` (default: the current folder) if it lies inside it, else its last two parts
    (the run folder and the file; one part for a top-level path). Never an absolute path."""
    p = Path(os.path.abspath(os.fspath(path)))
    base = Path(os.path.abspath(os.fspath(root if root is not None else os.getcwd())))
    try:
        return p.relative_to(base).as_posix() or "."
    except ValueError:
        return Path(*p.parts[-2:]).as_posix() if len(p.parts) > 2 else p.name


def portable_command(words: list[str], root: str | os.PathLike | None = None) -> str:
    """A command line with every absolute path among its words (`--out /x/y`, `--out=/x/y`) made portable."""
    out = []
    for w in words:
        key, eq, value = w.partition("=") if w.startswith("--") else ("", "", w)
        out.append(f"{key}={portable_path(value, root)}" if eq and os.path.isabs(value)
                   else portable_path(w, root) if not eq and os.path.isabs(w) else w)
    return " ".join(out)


__all__ = ["portable_command", "portable_path"]
