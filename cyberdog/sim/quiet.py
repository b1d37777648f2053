"""Drop the lines PyBullet's C code prints at import and connection, and nothing else.

`import pybullet` writes its build banner ("pybullet build time: ...") to the C-level stderr, and every
DIRECT connection writes "argv[0]=" to the C-level stdout. Neither goes through Python's `sys.stdout` /
`sys.stderr`, so they can only be caught at the file descriptors. `quiet_pybullet()` points descriptors 1
and 2 at temporary files for the duration of the block, then writes back to the real streams every line
that is not one of those known lines: a warning or error PyBullet prints while loading or connecting still
reaches the user, in order, on the stream it was written to.

Every process that simulates (the main one and each spawned walk or collector worker) imports and connects
through `cyberdog.sim.robot`, which uses this block around both, so one place covers them all.
"""
from __future__ import annotations

import contextlib
import ctypes
import os
import sys
import tempfile
import threading

# the exact prefixes PyBullet prints on success; anything else passes through
PYBULLET_NOISE = ("pybullet build time:", "argv[0]=")

try:
    _LIBC = ctypes.CDLL(None)  # the C library this process already uses: to flush its stdio buffers
except OSError:  # no C library handle (unusual platforms): fall back to Python-level flushing only
    _LIBC = None
# descriptors 1 and 2 belong to the whole process: two threads connecting at once would each restore the
# other's temporary file, so the blocks take turns
_LOCK = threading.Lock()


def _flush_all() -> None:
    """Push out everything buffered for descriptors 1 and 2, in Python and in C stdio, before they move."""
    for stream in (sys.stdout, sys.stderr, sys.__stdout__, sys.__stderr__):
        try:
            stream.flush()
        except (AttributeError, OSError, ValueError):  # closed or absent stream (daemons, pythonw)
            pass
    if _LIBC is not None:
        _LIBC.fflush(None)  # C printf output is fully buffered when stdout is a file or a pipe


def _keep(text: str, noise: tuple[str, ...]) -> str:
    return "".join(line for line in text.splitlines(keepends=True) if not line.startswith(noise))


@contextlib.contextmanager
def quiet_pybullet(noise: tuple[str, ...] = PYBULLET_NOISE):
    """Within the block, C-level lines starting with one of `noise` are dropped; all others are kept."""
    with _LOCK:
        yield from _quiet(noise)


def _quiet(noise: tuple[str, ...]):
    _flush_all()
    saved, captured = {}, {}
    try:
        for fd in (1, 2):
            try:
                saved[fd] = os.dup(fd)
            except OSError:  # descriptor not open (a detached process): nothing to silence there
                continue
            captured[fd] = tempfile.TemporaryFile()
            os.dup2(captured[fd].fileno(), fd)
        yield
    finally:
        _flush_all()
        for fd, copy in saved.items():
            os.dup2(copy, fd)
            os.close(copy)
        for fd, tmp in captured.items():
            tmp.seek(0)
            rest = _keep(tmp.read().decode(errors="replace"), noise)
            tmp.close()
            if rest:  # what was not noise goes to the stream it was written to
                stream = sys.stdout if fd == 1 else sys.stderr
                stream.write(rest)
                stream.flush()


__all__ = ["PYBULLET_NOISE", "quiet_pybullet"]
