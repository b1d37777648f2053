"""What the project writes down about where a result came from: the code's commit (`code_state`), and paths and
commands (`portable_path`, `portable_command`) as names that mean the same on another machine.

A result file travels (it is shipped in `results/`, copied, cited), so it never names a path of the machine
that made it: a path inside the current folder (the repository, when the CLIs run from its root) is written
relative to it; any other is written as its run folder's name and the file (`long_s0/stage2_final_actor.pt`),
which together with the recorded commit says what produced it.
"""
from __future__ import annotations

import os
import subprocess
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]  # the checkout the package runs from (an editable install)


def code_state(root: str | os.PathLike = REPO) -> dict:
    """The code's commit: {"git_commit": the sha of HEAD, "git_dirty": whether files outside results/ (where
    shipped outputs are written, not code) differ from it, tracked or not}; {"git_commit": "unknown",
    "git_dirty": None} where `root` is not the top of a git checkout (an installed copy of the package, git
    missing): never the commit of some other repository around it."""
    def git(*args: str) -> str:
        return subprocess.run(["git", *args], cwd=root, capture_output=True, text=True, check=True).stdout
    try:
        if Path(git("rev-parse", "--show-toplevel").strip()).resolve() != Path(root).resolve():
            raise ValueError("inside another repository")
        changed = git("status", "--porcelain", "--", ".", ":(exclude)results").strip()
        return {"git_commit": git("rev-parse", "HEAD").strip(), "git_dirty": bool(changed)}
    except (OSError, ValueError, subprocess.CalledProcessError):
        return {"git_commit": "unknown", "git_dirty": None}


def repo_relative(path: str | os.PathLike) -> Path:
    """`path` relative to the repository if it lies inside it (as a tool gives it to the commands it runs, whose
    outputs record it), else absolute."""
    p = Path(path).resolve()
    return p.relative_to(REPO) if p.is_relative_to(REPO) else p


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


__all__ = ["REPO", "code_state", "portable_command", "portable_path", "repo_relative"]
