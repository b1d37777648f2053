"""Atomic checkpoints of tensors and plain containers, loaded with `torch.load(weights_only=True)`.

A checkpoint that cannot be read, is not ours, or does not fit the networks of the current config raises
`CheckpointError` with the reason: never a silent fresh start.
"""
from __future__ import annotations

import os
import random
import tempfile
from pathlib import Path

import numpy as np
import torch

FORMAT = "cyberdog-rl-checkpoint"
VERSION = 1


class CheckpointError(RuntimeError):
    """A checkpoint is missing, corrupt, of another format, or does not match the configuration."""


def save_atomic(obj: dict, path: str | Path) -> Path:
    """Write to a temporary file in the same folder, fsync, then `os.replace` (never a half-written file)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        with os.fdopen(fd, "wb") as f:
            torch.save(obj, f)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise
    return path


def save_checkpoint(state: dict, path: str | Path) -> Path:
    return save_atomic({"format": FORMAT, "version": VERSION, **state}, path)


def load_checkpoint(path: str | Path) -> dict:
    path = Path(path)
    if not path.is_file():
        raise CheckpointError(f"checkpoint {path} does not exist")
    try:
        state = torch.load(path, map_location="cpu", weights_only=True)
    except Exception as e:  # truncated or otherwise unreadable file
        raise CheckpointError(f"checkpoint {path} is corrupt or unreadable ({type(e).__name__}: {e}); "
                              f"delete it or resume from another run folder") from e
    if not isinstance(state, dict) or state.get("format") != FORMAT:
        raise CheckpointError(f"{path} is not a {FORMAT} file")
    if state.get("version") != VERSION:
        raise CheckpointError(f"{path} has checkpoint version {state.get('version')}, this code reads {VERSION}")
    return state


def check_shapes(saved: dict, module_state: dict, what: str, path: str | Path = "checkpoint") -> None:
    """Raise `CheckpointError` listing tensors whose names or shapes differ (e.g. another hidden size)."""
    problems = []
    for k in sorted(set(saved) | set(module_state)):
        a, b = saved.get(k), module_state.get(k)
        if a is None or b is None:
            problems.append(f"{k}: {'missing in checkpoint' if a is None else 'not in current model'}")
        elif hasattr(a, "shape") and hasattr(b, "shape") and tuple(a.shape) != tuple(b.shape):
            problems.append(f"{k}: checkpoint {tuple(a.shape)} vs config {tuple(b.shape)}")
    if problems:
        raise CheckpointError(f"{path}: {what} does not match the configured networks "
                              f"(check agent.hidden_sizes and agent.algorithm): " + "; ".join(problems[:5]))


def rng_state() -> dict:
    """torch, numpy and python global RNG states as tensors and plain containers."""
    kind, keys, pos, has_gauss, cached = np.random.get_state()
    py_version, py_state, py_gauss = random.getstate()
    return {"torch": torch.get_rng_state(), "numpy": [kind, torch.from_numpy(keys.astype(np.int64)), int(pos),
                                                      int(has_gauss), float(cached)],
            "python": [py_version, list(py_state), py_gauss]}


def set_rng_state(state: dict) -> None:
    torch.set_rng_state(state["torch"])
    kind, keys, pos, has_gauss, cached = state["numpy"]
    np.random.set_state((kind, keys.numpy().astype(np.uint32), pos, has_gauss, cached))
    py_version, py_state, py_gauss = state["python"]
    random.setstate((py_version, tuple(py_state), py_gauss))
