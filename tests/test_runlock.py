"""cyberdog.runlock beyond the trainer's use of it (tests/test_reliability.py): the refusal names the holder's
command, an abandoned lock object frees the folder at once, a race with the holder's release is retried, and a file
system without flock is refused by name."""
from __future__ import annotations

import errno
import gc
import os
import subprocess
import sys
import time

import pytest

from cyberdog import runlock
from cyberdog.runlock import LOCK_FILE, RunFolderError, RunLock, RunLockedError, read_lock


def test_a_second_process_is_refused_with_the_holders_pid_and_command(tmp_path):
    holder = subprocess.Popen([sys.executable, "-c", "import sys, time\nfrom cyberdog.runlock import RunLock\n"
                               f"lock = RunLock({str(tmp_path)!r}).acquire()\nprint('held', flush=True)\n"
                               "time.sleep(60)", "--marker"], stdout=subprocess.PIPE, text=True)
    try:
        assert holder.stdout.readline().strip() == "held"
        with pytest.raises(RunLockedError) as refused:
            RunLock(tmp_path).acquire()
        message = str(refused.value)
        assert f"pid {holder.pid} on host" in message and "running -c --marker" in message
        assert "\n" not in message
    finally:
        holder.kill()
        holder.wait()
    with pytest.warns(RuntimeWarning, match=f"taking over the lock left by pid {holder.pid}"):
        RunLock(tmp_path).acquire().release()
    assert not (tmp_path / LOCK_FILE).exists()


def test_an_abandoned_lock_object_frees_the_folder_at_once(tmp_path):
    RunLock(tmp_path).acquire()  # never released, no reference kept
    gc.disable()  # freed by its reference count, not by a later collection
    try:
        lock = RunLock(tmp_path).acquire()
    finally:
        gc.enable()
    assert lock.held and read_lock(tmp_path)["pid"] == os.getpid()
    lock.release()


def test_a_lock_file_gone_when_the_lock_is_refused_is_tried_again(tmp_path, monkeypatch):
    """The holder released (removed the file) between this process's open and its flock: not "in use"."""
    attempts = []

    class ReleasedMeanwhile(runlock.UnixFileLock):
        def acquire(self, *args, **kwargs):
            attempts.append(time.monotonic())
            if len(attempts) == 1:
                raise runlock.Timeout(str(self.lock_file))  # and there is no lock file: the holder has gone
            return super().acquire(*args, **kwargs)

    monkeypatch.setattr(runlock, "UnixFileLock", ReleasedMeanwhile)
    lock = RunLock(tmp_path).acquire()
    assert lock.held and len(attempts) == 2
    lock.release()


def test_a_file_system_without_flock_is_refused_by_name(tmp_path, monkeypatch):
    class NoFlock(runlock.UnixFileLock):
        def acquire(self, *args, **kwargs):
            raise OSError(errno.ENOLCK, os.strerror(errno.ENOLCK))

    monkeypatch.setattr(runlock, "UnixFileLock", NoFlock)
    with pytest.raises(RunFolderError, match="no flock"):
        RunLock(tmp_path).acquire()
