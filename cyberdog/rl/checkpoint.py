"""Atomic checkpoints of tensors and plain containers, loaded with `torch.load(weights_only=True)`.

A checkpoint that cannot be read, is not ours, or does not fit the networks of the current config raises
`CheckpointError` with the reason: never a silent fresh start.

Tensors that are views of a larger storage (a slice of the replay buffer's preallocated storage) are copied
before saving: `torch.save` writes a view's whole storage, which made a checkpoint of 1,600 transitions as
large as one of the full 100,000-transition buffer.
"""
from __future__ import annotations

import os
import random
import tempfile
from pathlib import Path

import numpy as np
import torch

from cyberdog import config as C
from cyberdog.config.io import not_found

FORMAT = "cyberdog-rl-checkpoint"
VERSION = 1


class CheckpointError(RuntimeError):
    """A checkpoint is missing, corrupt, of another format, or does not match the configuration."""


def compact(obj):
    """`obj` with every tensor that views a larger storage replaced by a copy of just its elements."""
    if isinstance(obj, torch.Tensor):
        if obj.untyped_storage().nbytes() > obj.numel() * obj.element_size():
            return obj.clone(memory_format=torch.contiguous_format)
        return obj
    if isinstance(obj, dict):
        return {k: compact(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return type(obj)(compact(v) for v in obj)
    return obj


_UMASK = os.umask(0)
os.umask(_UMASK)
TEMPORARY_GLOB = ".*.pt.*.tmp"  # what save_atomic leaves behind when its process is killed mid-write


def save_atomic(obj: dict, path: str | Path) -> Path:
    """Write to a temporary file in the same folder, fsync, then `os.replace` (never a half-written file)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        with os.fdopen(fd, "wb") as f:
            torch.save(compact(obj), f)
            f.flush()
            os.fsync(f.fileno())
        os.chmod(tmp, 0o666 & ~_UMASK)  # mkstemp makes it private; the result is an ordinary file
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise
    return path


def remove_stale_temporaries(run_dir: str | Path) -> list[Path]:
    """Delete the temporary files of `save_atomic` that a killed process left in `run_dir` and `run_dir/saved`
    (call it only while holding the run folder's lock: a live writer's temporary file would go too)."""
    removed = []
    for folder in (Path(run_dir), Path(run_dir) / "saved"):
        for p in folder.glob(TEMPORARY_GLOB) if folder.is_dir() else ():
            try:
                p.unlink()
                removed.append(p)
            except FileNotFoundError:
                pass
    return removed


def save_checkpoint(state: dict, path: str | Path) -> Path:
    return save_atomic({"format": FORMAT, "version": VERSION, **state}, path)


def load_torch_file(path: str | Path, what: str):
    """`torch.load` of a file the trainer wrote (tensors and plain containers only), or one clear
    CheckpointError naming `what` and the file: torch's own message for a file that is not one (advice to load
    it with weights_only=False, which would run code from the file) is not passed on."""
    path = Path(path)
    if not path.is_file():
        raise CheckpointError(not_found(path, what))
    try:
        return torch.load(path, map_location="cpu", weights_only=True)
    except Exception as e:  # not a torch file, truncated, or holding more than tensors and containers
        raise CheckpointError(f"{what} {path} is corrupt, truncated, or not a file written by train.py "
                              f"(torch.load failed: {type(e).__name__})") from e


def recorded_code(path: str | Path) -> list | None:
    """The `trained_at` a training file records (checkpoint, stage-final or actor file): the code's commit of
    every process that trained the run; None for a file written before that record."""
    state = load_torch_file(path, "training file")
    return (state.get("trained_at") if isinstance(state, dict) else None) or None


def saved_config(config: dict | None) -> C.ExperimentConfig:
    """The experiment config that a checkpoint or actor file recorded (its plain dict, read as the config layer
    reads a saved config)."""
    return C.from_dict(C.ExperimentConfig, dict(config or {}))


def load_checkpoint(path: str | Path, actor_file: bool = False) -> dict:
    """A checkpoint the trainer wrote (checkpoint.pt, stage<N>_final.pt); with `actor_file`, an actor file
    (`stage<N>_actor.pt`, what `--init-from` may start an actor from) is returned as it is."""
    state = load_torch_file(path, "checkpoint")
    if actor_file and isinstance(state, dict) and "actor" in state and "format" not in state:
        return state
    if isinstance(state, dict) and "actor" in state and "format" not in state:
        raise CheckpointError(f"{path} is an actor file (for evaluate.py), not a checkpoint: use a run's "
                              f"checkpoint.pt or stage<N>_final.pt")
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


BUDGET_FIELDS = ("max_env_steps", "max_episodes")  # what a resume may change: "train this stage longer/shorter"


def budget_change(saved: dict, current: dict, stage: int, path: str | Path = "checkpoint",
                  done: dict | None = None) -> dict:
    """The budget fields of `stage` that `current` (config dict) changes from `saved` (the checkpoint's), as
    {dotted name: (saved, current)}. Any other difference or a budget of another stage raises `CheckpointError`:
    a resumed run continues the same experiment. Nothing in training depends on the budget but where the stage
    ends, so a raised budget trains it longer, and a lowered one that the stage has not yet reached (`done`: the
    stage's counters so far, {"max_env_steps": env steps, "max_episodes": episodes}, and "finished") ends it
    there: the same run as one planned that short from the start. Lowered to or below what the stage has
    already made, it is refused."""
    def flat(d, prefix=""):
        out = {}
        for k, v in (d or {}).items():
            out.update(flat(v, f"{prefix}{k}.") if isinstance(v, dict) else {f"{prefix}{k}": v})
        return out
    a, b = flat(saved), flat(current)
    budget = {f"train.stage{stage}.{f}" for f in BUDGET_FIELDS}
    differ = [k for k in sorted(set(a) | set(b)) if a.get(k) != b.get(k)]
    other = [f"{k}: checkpoint {a.get(k)!r} vs config {b.get(k)!r}" for k in differ if k not in budget]
    if other:
        raise CheckpointError(f"{path} was written with another configuration than the run's config: "
                              + "; ".join(other[:5]) + f" (a resume may only change the current stage's budget, "
                              f"train.stage{stage}.max_env_steps or train.stage{stage}.max_episodes)")
    changes = {k: (a.get(k), b.get(k)) for k in differ}
    done = done or {}
    for k, (old, new) in changes.items():
        # max_env_steps 0 means "no step budget" (the episode budget decides): going to 0 is not lowering
        lowered = new != 0 and (old == 0 or new < old) if k.endswith("max_env_steps") else new < old
        made = done.get(k.rsplit(".", 1)[1], 0)
        if lowered and (done.get("finished", True) or new <= made):
            raise CheckpointError(f"{k}: a resume may lower a stage's budget only above what the stage has made "
                                  f"({made}), not lower it to {new} (was {old})")
    return changes
