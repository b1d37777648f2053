"""One writing process per run folder: a lock file that names its holder.

`RunLock(run_dir).acquire()` creates `<run_dir>/.train.lock`, holds an exclusive `flock` on it for as long
as the process runs, and writes the holder into it (JSON: pid, host, start time, command, boot id and the
process's start tick, so that a recycled pid is not mistaken for the holder). A second process is refused
with `RunLockedError` naming the holder. The lock file is removed by `release()`; a process that dies
without releasing (SIGKILL, power loss) leaves the file behind, but the kernel drops its `flock`:

* same host, holder gone (its `flock` is free, or no process with its pid and start tick exists): the lock is
  taken over, with a warning naming the dead holder;
* same host, holder alive: refused (whatever the file system);
* another host (a folder on a file system several machines share): refused, naming the holder's host and
  pid, since this machine cannot see that host's processes; delete the lock file once that process is known
  to be gone, or resume on that host, which sees that it is.

What a shared file system does and does not detect. A live holder on another machine is always refused:
by the kernel lock where the file system makes `flock` coherent across hosts (Linux NFS clients turn it into
an NFS byte-range lock unless mounted with `local_lock=flock` or `nolock`; CephFS; Lustre mounted with
`-o flock`), and otherwise by the lock file's contents, which name another host. A dead holder on another
machine cannot be told from a live one: the lock is refused, naming that host and pid, until someone who
knows that process is gone deletes the lock file (or resumes on that host, which can see it is gone, or a
sweep retries its own attempt, which it knows has ended: `break_lock`). Not detected: two processes that
start at the same moment on two hosts of a file system without coherent `flock` can both get the lock.
"""
from __future__ import annotations

import errno
import json
import os
import socket
import sys
import time
import warnings
from pathlib import Path

LOCK_FILE = ".train.lock"


class RunFolderError(RuntimeError):
    """A run folder cannot be used as asked (in use, or it already holds another run)."""


class RunLockedError(RunFolderError):
    """The run folder is in use by another live process (or one this host cannot check)."""


def _boot_id() -> str:
    try:
        return Path("/proc/sys/kernel/random/boot_id").read_text().strip()
    except OSError:
        return ""


def _start_tick(pid: int) -> int | None:
    """The process's start time in clock ticks since boot (Linux), None if there is no such process."""
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return None
    try:
        return int(stat.rsplit(")", 1)[1].split()[19])
    except (IndexError, ValueError):
        return None


def _pid_alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # someone else's process
        return True
    except OSError:
        return False
    return True


def holder_alive(info: dict) -> bool | None:
    """Is the process named in a lock file still running? None when this host cannot tell (another host)."""
    if info.get("host") != socket.gethostname():
        return None
    if info.get("boot_id") and _boot_id() and info["boot_id"] != _boot_id():
        return False  # the machine was restarted since
    pid = info.get("pid")
    if not isinstance(pid, int) or pid <= 0:
        return False
    if not _pid_alive(pid):
        return False
    tick = info.get("start_tick")
    now = _start_tick(pid)
    return tick is None or now is None or tick == now  # another start tick: the pid was recycled


def describe(info: dict) -> str:
    started = info.get("started")
    when = time.strftime("%Y-%m-%d %H:%M:%S", time.localtime(started)) if isinstance(started, (int, float)) else "?"
    return f"pid {info.get('pid', '?')} on host {info.get('host', '?')}, started {when}"


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
        self._fd: int | None = None
        self.taken_over: dict | None = None  # the dead holder whose lock this one replaced

    @property
    def held(self) -> bool:
        return self._fd is not None

    def acquire(self) -> "RunLock":
        if self._fd is not None:
            return self
        self.run_dir.mkdir(parents=True, exist_ok=True)
        for _ in range(10):  # the holder may unlink the file between our open and our flock: open it again
            fd = os.open(self.path, os.O_RDWR | os.O_CREAT, 0o644)
            try:
                kernel_lock = self._flock(fd)
                if kernel_lock and not self._same_file(fd):
                    os.close(fd)
                    continue
                self._claim(fd, kernel_lock)
            except BaseException:
                os.close(fd)
                raise
            self._fd = fd
            return self
        raise RunLockedError(f"{self.path}: the lock file keeps changing; is another process starting in "
                             f"{self.run_dir}?")

    def _flock(self, fd: int) -> bool:
        """True if this process now holds the kernel lock; False where the file system has no flock."""
        try:
            import fcntl
        except ImportError:  # not a POSIX system: the lock file's contents decide alone
            return False
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            return True
        except OSError as e:
            if e.errno in (errno.EWOULDBLOCK, errno.EAGAIN, errno.EACCES):
                info = self._read(fd)
                who = describe(info) if info else "another process (it has not written its name yet)"
                raise RunLockedError(
                    f"{self.run_dir} is in use by {who} (lock file {self.path}); one process per run folder: wait "
                    f"for it to finish or stop it, or use another --run-dir") from None
            if e.errno in (errno.ENOLCK, errno.EOPNOTSUPP, errno.ENOSYS, errno.EINVAL):
                return False  # this file system has no flock: the lock file's contents decide alone
            raise

    def _same_file(self, fd: int) -> bool:
        try:
            return os.fstat(fd).st_ino == os.stat(self.path).st_ino
        except FileNotFoundError:
            return False

    @staticmethod
    def _read(fd: int) -> dict:
        try:
            raw = os.pread(fd, 65536, 0)
            data = json.loads(raw.decode()) if raw.strip() else {}
        except (OSError, ValueError, UnicodeDecodeError):
            return {"unreadable": True}
        return data if isinstance(data, dict) else {"unreadable": True}

    def _claim(self, fd: int, kernel_lock: bool) -> None:
        info = self._read(fd)
        if info and not info.get("unreadable"):
            alive = holder_alive(info)
            mine = info.get("pid") == os.getpid() and info.get("host") == socket.gethostname()
            if alive is None:  # another host: it may be alive; we cannot see its processes
                raise RunLockedError(
                    f"{self.run_dir} is locked by {describe(info)} (another machine; lock file {self.path}). This "
                    f"machine cannot tell whether that process still runs: if it does not, delete {self.path} "
                    f"and try again")
            if alive and not kernel_lock and not mine:
                raise RunLockedError(f"{self.run_dir} is in use by {describe(info)} (lock file {self.path}); "
                                     f"one process per run folder: wait for it to finish or stop it")
            if not mine:  # the holder died without releasing (killed, crashed) on this machine
                self.taken_over = info
                warnings.warn(f"{self.run_dir}: taking over the lock left by {describe(info)}, which is no longer "
                              f"running", RuntimeWarning, stacklevel=4)
        elif info.get("unreadable"):
            self.taken_over = info
            warnings.warn(f"{self.run_dir}: taking over an unreadable lock file {self.path} (its writer was "
                          f"killed while writing it)", RuntimeWarning, stacklevel=4)
        me = {"pid": os.getpid(), "host": socket.gethostname(), "started": time.time(),
              "started_local": time.strftime("%Y-%m-%d %H:%M:%S"), "purpose": self.purpose,
              "command": [sys.executable] + sys.argv, "boot_id": _boot_id(), "start_tick": _start_tick(os.getpid())}
        data = (json.dumps(me, indent=1) + "\n").encode()
        os.ftruncate(fd, 0)
        os.pwrite(fd, data, 0)
        os.fsync(fd)

    def release(self) -> None:
        """Remove the lock file and drop the lock (idempotent)."""
        if self._fd is None:
            return
        fd, self._fd = self._fd, None
        try:
            if self._same_file(fd) and self._read(fd).get("pid") == os.getpid():
                self.path.unlink()
        except OSError:
            pass
        finally:
            os.close(fd)  # drops the flock

    def __enter__(self) -> "RunLock":
        return self.acquire()

    def __exit__(self, *exc) -> None:
        self.release()

    def __del__(self):  # an abandoned lock object (never released) must not keep the folder locked
        try:
            self.release()
        except Exception:
            pass
