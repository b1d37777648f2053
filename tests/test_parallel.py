"""The one process pool (`cyberdog.analysis.parallel`): order, in-process shortcut, errors naming the job,
worker reuse, a failure that does not wait for the other jobs, and workers that end with their parent."""
from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from cyberdog.analysis.parallel import (PARENT_CHECK_S, ProcessMap, available_cores, map_in_processes,
                                        resolve_workers)


def pid_after(delay_s: float) -> tuple[float, int]:
    """Sleeps, then says which process ran it (module level: spawned workers import it by name)."""
    time.sleep(delay_s)
    return delay_s, os.getpid()


def fail_on_three(x: int) -> int:
    if x == 3:
        raise KeyError(f"no value for {x}")
    return x * x


def fail_fast_or_sleep(delay_s: float) -> float:
    if delay_s == 0:
        raise RuntimeError("the quick job failed")
    time.sleep(delay_s)
    return delay_s


def write_pid_and_sleep(job: tuple[str, float]) -> None:
    """Leaves its process id in a file of the folder, then sleeps (a long walk that nobody will collect)."""
    folder, delay_s = job
    (Path(folder) / f"{os.getpid()}.pid").write_text(str(os.getpid()))
    time.sleep(delay_s)


def _running(pid: int) -> bool:
    """The process exists and is not a zombie (a container's init may never reap an orphan)."""
    try:
        return "\nState:\tZ" not in Path(f"/proc/{pid}/status").read_text()
    except (FileNotFoundError, ProcessLookupError):
        return False


@pytest.mark.skipif(not Path("/proc/self/status").exists(), reason="reads process states from /proc")
def test_workers_end_when_their_parent_is_killed(tmp_path):
    """SIGKILL leaves the parent no time to stop its pool: the workers must notice and end by themselves."""
    script = ("import sys; sys.path.insert(0, sys.argv[1]); import test_parallel as t; "
              "from cyberdog.analysis.parallel import map_in_processes; "
              "map_in_processes(t.write_pid_and_sleep, [(sys.argv[2], 300.0)] * 2, workers=2)")
    parent = subprocess.Popen([sys.executable, "-c", script, str(Path(__file__).parent), str(tmp_path)],
                              cwd=Path(__file__).resolve().parents[1])
    workers: list[int] = []
    try:
        deadline = time.monotonic() + 120.0
        while len(list(tmp_path.glob("*.pid"))) < 2:
            assert time.monotonic() < deadline and parent.poll() is None, "the two workers never started their jobs"
            time.sleep(0.2)
        workers = [int(f.read_text()) for f in tmp_path.glob("*.pid")]
        assert all(_running(pid) for pid in workers)
    finally:
        parent.send_signal(signal.SIGKILL)
        parent.wait()
    deadline = time.monotonic() + 10 * PARENT_CHECK_S + 5.0
    while any(_running(pid) for pid in workers) and time.monotonic() < deadline:
        time.sleep(0.2)
    left = [pid for pid in workers if _running(pid)]
    for pid in left:  # leave no orphan behind, whatever the verdict
        os.kill(pid, signal.SIGKILL)
    assert not left, f"workers {left} outlived their killed parent"


def test_results_in_job_order_while_workers_finish_out_of_order():
    delays = [2.0, 0.0, 0.3, 0.0]  # the first job finishes last (by far: spawn start-up times vary)
    seen = []
    out = map_in_processes(pid_after, delays, workers=2, on_result=lambda i, r, done: seen.append((i, done)))
    assert [d for d, _ in out] == delays
    assert os.getpid() not in {pid for _, pid in out}, "two workers and four jobs: spawned processes"
    assert sorted(i for i, _ in seen) == [0, 1, 2, 3] and [done for _, done in seen] == [1, 2, 3, 4]
    assert seen[-1][0] == 0, "on_result follows the finishing order"


@pytest.mark.parametrize("workers, jobs", [(1, [0.0, 0.0, 0.0]), (4, [0.0])])
def test_one_worker_or_one_job_runs_in_this_process(workers, jobs):
    assert {pid for _, pid in map_in_processes(pid_after, jobs, workers=workers)} == {os.getpid()}


@pytest.mark.parametrize("workers", [1, 2])
def test_a_failing_job_keeps_its_error_type_and_is_named(workers):
    with pytest.raises(KeyError, match="no value for 3") as e:
        map_in_processes(fail_on_three, [1, 2, 3, 4], workers=workers, describe=lambda x: f"x={x}")
    assert any("job 2 of 4" in note and "x=3" in note for note in e.value.__notes__), e.value.__notes__


def test_a_failure_stops_the_other_jobs():
    """A failed job must not wait for minutes of walks whose results will not be used."""
    t0 = time.perf_counter()
    with pytest.raises(RuntimeError, match="quick job failed"):
        map_in_processes(fail_fast_or_sleep, [120.0, 0.0], workers=2)
    assert time.perf_counter() - t0 < 60.0


def test_process_map_keeps_its_workers_between_calls_and_recovers_after_a_failure():
    with ProcessMap(2) as run:
        first = {pid for _, pid in run(pid_after, [0.2, 0.2])}
        second = {pid for _, pid in run(pid_after, [0.2, 0.2])}
        assert len(first | second) <= 2 and os.getpid() not in first
        with pytest.raises(KeyError):
            run(fail_on_three, [3, 1])
        assert run(fail_on_three, [1, 2]) == [1, 4]


def test_workers_are_checked():
    assert resolve_workers(None, 1000) == available_cores() and resolve_workers(None, 1) == 1
    assert resolve_workers(np.int64(3), 10) == 3
    for bad in (0, -1, 2.5, "2", True):
        with pytest.raises(ValueError, match="workers"):
            resolve_workers(bad, 4)


def test_a_brief_progress_log_never_goes_quiet_for_more_than_its_limit(monkeypatch):
    """With a line only at each quarter, 180 slow walks printed every 45 (minutes apart under load): a result
    arriving QUIET_LIMIT_S after the last line is logged too."""
    from cyberdog.analysis import parallel
    clock = [0.0]
    monkeypatch.setattr(parallel.time, "perf_counter", lambda: clock[0])
    lines = []
    on_result = parallel.progress_log(180, lambda r: str(r), lines.append, every_job=False)
    for done in range(1, 11):  # ten results, 4 s apart: 36 s in all, no quarter reached
        clock[0] += 4.0
        on_result(done - 1, done, done)
    assert [line.split("]")[0] for line in lines] == ["[4/180", "[8/180"]  # at 16 s and 32 s
    assert parallel.QUIET_LIMIT_S == 15.0
