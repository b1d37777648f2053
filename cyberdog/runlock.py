"""One writing process per run folder: a lock file that names its holder.

`RunLock(run_dir).acquire()` takes `<run_dir>/.train.lock` with `filelock` (an exclusive `flock`, which the kernel
drops when the process ends, however it ends) and writes the holder into it (JSON: pid, host, start time,
command). A second process, or a second `RunLock` in the same process, is refused with `RunLockedError` naming
the holder. `release()` removes the file; a process that dies without releasing (SIGKILL, power loss) leaves it
behind with its record, but not its `flock`:

* same host: the next process gets the `flock`, so the holder is gone: the lock is taken over, with a warning
  naming the dead holder;
* another host named in the file (a folder on a file system several machines share): refused, naming the
  holder's host and pid, since this machine cannot see that host's processes; delete the lock file once that
  process is known to be gone, or resume on that host. A sweep retrying its own attempt, which it knows has
  ended, removes it with `break_lock`.

On a shared file system a live holder on another machine is refused by the kernel lock where the file system
makes `flock` coherent across hosts (Linux NFS clients turn it into an NFS byte-range lock unless mounted with
`local_lock=flock` or `nolock`; CephFS; Lustre mounted with `-o flock`), and otherwise by the record, which
names another host. Not detected: two processes that start at the same moment on two hosts of a file system
without coherent `flock` can both get the lock. filelock's own stand-in where a file system has no `flock` at
all (its marker file, `SoftFileLock`) cannot hold this record, so there the run folder is refused.
"""
from __future__ import annotations

import errno
import json
import os
import shlex
import socket
import sys
import time
import warnings
import weakref
from pathlib import Path

from filelock import Timeout, UnixFileLock

LOCK_FILE = ".train.lock"
NO_FLOCK = (errno.ENOLCK, errno.EOPNOTSUPP, errno.ENOSYS, errno.EINVAL)  # the file system has no flock


class RunFolderError(RuntimeError):
    """A run folder cannot be used as asked (in use, or it already holds another run)."""


class RunLockedError(RunFolderError):
    """The run folder is in use by another live process (or one this host cannot check)."""


def describe(info: dict) -> str:
    started = info.get("started")
    when = time.strftime("%Y-%m-%d %H:%M:%S", time.localtime(started)) if isinstance(started, (int, float)) else "?"
    command = info.get("command")
    ran = f", running {shlex.join(map(str, command[1:]))}" if isinstance(command, list) and len(command) > 1 else ""
    return f"pid {info.get('pid', '?')} on host {info.get('host', '?')}, started {when}{ran}"


def read_lock(run_dir: str | Path) -> dict:
    """The holder recorded in the lock file ({} if there is none or it cannot be read)."""
    try:
        data = json.loads((Path(run_dir) / LOCK_FILE).read_text())
    except (OSError, ValueError):
        return {}
    return data if isinstance(data, dict) else {}


def break_lock(run_dir: str | Path, pid: int | None, host: str | None) -> bool:
    """Remove the lock file if it names exactly this process (`pid` on `host`): for a supervisor that knows
    that process has ended, e.g. a sweep retrying a seed on another node. Returns whether it was removed."""
    info = read_lock(run_dir)
    if not info or info.get("pid") != pid or info.get("host") != host:
        return False
    try:
        (Path(run_dir) / LOCK_FILE).unlink()
    except FileNotFoundError:
        return False
    return True


class RunLock:
    """Exclusive use of `run_dir` by this process; `with RunLock(run_dir): ...` or acquire()/release()."""

    def __init__(self, run_dir: str | Path, purpose: str = "train.py"):
        self.run_dir, self.purpose = Path(run_dir), purpose
        self.path = self.run_dir / LOCK_FILE
        self.taken_over: dict | None = None  # the dead holder whose lock this one replaced
        me = weakref.ref(self)  # not the bound method: an abandoned RunLock must be freed, and released, at once
        self._lock = UnixFileLock(self.path, timeout=0, thread_local=False,
                                  on_acquired=lambda fd: me()._claim(fd))
        self._inode: tuple[int, int] | None = None  # the lock file this process wrote its record into

    @property
    def held(self) -> bool:
        return self._lock.is_locked

    def acquire(self) -> "RunLock":
        if self.held:
            return self
        self.run_dir.mkdir(parents=True, exist_ok=True)
        for _ in range(10):  # the holder may remove the file between our open and our flock: try again
            try:
                self._lock.acquire()
                return self
            except Timeout:
                if not self.path.exists():
                    continue
                info = read_lock(self.run_dir)
                who = describe(info) if info else "another process (it has not written its name yet)"
                raise RunLockedError(
                    f"{self.run_dir} is in use by {who} (lock file {self.path}); one process per run folder: wait "
                    f"for it to finish or stop it, or use another --run-dir") from None
            except OSError as e:
                if e.errno in NO_FLOCK:
                    raise RunFolderError(f"{self.run_dir}: its file system offers no flock ({e.strerror}), which "
                                         f"the run lock needs: use a run folder on another file system") from None
                raise
        raise RunLockedError(f"{self.path}: the lock file keeps changing; is another process starting in "
                             f"{self.run_dir}?")

    def _claim(self, fd: int) -> None:
        """With the `flock` held (filelock's callback): read the record left in the file, then write ours."""
        try:
            raw = os.pread(fd, 65536, 0)
            info = json.loads(raw.decode()) if raw.strip() else {}
        except (OSError, ValueError, UnicodeDecodeError):
            info = None
        if info is None or not isinstance(info, dict):
            self.taken_over = {"unreadable": True}
            warnings.warn(f"{self.run_dir}: taking over an unreadable lock file {self.path} (its writer was "
                          f"killed while writing it)", RuntimeWarning, stacklevel=2)
        elif info:
            if info.get("host") != socket.gethostname():  # it may be alive; we cannot see its processes
                raise RunLockedError(
                    f"{self.run_dir} is locked by {describe(info)} (another machine; lock file {self.path}). This "
                    f"machine cannot tell whether that process still runs: if it does not, delete {self.path} "
                    f"and try again")
            if info.get("pid") != os.getpid():  # our flock: its holder died without releasing (killed, crashed)
                self.taken_over = info
                warnings.warn(f"{self.run_dir}: taking over the lock left by {describe(info)}, whose process has "
                              f"ended", RuntimeWarning, stacklevel=2)
        me = {"pid": os.getpid(), "host": socket.gethostname(), "started": time.time(),
              "started_local": time.strftime("%Y-%m-%d %H:%M:%S"), "purpose": self.purpose,
              "command": [sys.executable] + sys.argv}
        data = (json.dumps(me, indent=1) + "\n").encode()
        os.ftruncate(fd, 0)
        os.pwrite(fd, data, 0)
        os.fsync(fd)
        st = os.fstat(fd)
        self._inode = (st.st_dev, st.st_ino)

    def release(self) -> None:
        """Remove the lock file and drop the lock (idempotent)."""
        if not self.held:
            return
        try:
            st = self.path.stat()
            if (st.st_dev, st.st_ino) == self._inode and read_lock(self.run_dir).get("pid") == os.getpid():
                self.path.unlink()  # while the flock is held: a process waiting on this file tries again
        except OSError:
            pass
        finally:
            self._lock.release(force=True)

    def __enter__(self) -> "RunLock":
        return self.acquire()

    def __exit__(self, *exc) -> None:
        self.release()

    def __del__(self):  # an abandoned lock object (never released) must not keep the folder locked
        try:
            self.release()
        except Exception:
            pass
