"""Independent jobs (walks, rollouts) over worker processes: the one process pool of the project.

Why processes and why "spawn": every walk owns a PyBullet client and the physics is single-threaded, so
walks scale with processes, not threads; "spawn" gives each worker a fresh interpreter (no forked PyBullet
or torch state, the same behaviour on Linux and macOS). Workers cost an interpreter start and the imports
(about 1–3 s each), so one job, or `workers=1`, runs in this process instead, which also keeps tracebacks
and debuggers simple.

`fn` and the jobs must be picklable (a module-level function, `functools.partial` of one, dataclasses).
Results come back in job order whatever order the workers finish in. A job that raises stops the map; the
exception keeps its type and gains a note naming the job (index and description), and jobs not yet started
are cancelled and running ones stopped. A worker whose parent is gone (killed by a signal it could not catch,
SIGTERM or SIGKILL, which leaves no time to stop the pool) ends itself within `PARENT_CHECK_S`: otherwise it
would run its job, minutes of walks or an extraction's replay checks, to the end for nobody.

`ProcessMap` keeps its workers between calls, for callers that map many small batches (an optimiser's
evaluations); `map_in_processes` is the one-shot form.
"""
from __future__ import annotations

import multiprocessing
import operator
import os
import threading
import time
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from typing import Any, Callable, Sequence

DESCRIPTION_CHARS = 200  # a job's repr is cut to this many characters in an error note
PARENT_CHECK_S = 1.0  # s: how often a worker looks whether the process that started it still runs


def available_cores() -> int:
    """CPUs this process may run on (the affinity mask where the OS has one: a container's or `taskset`'s
    limit, not the machine's core count)."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # not Linux
        return max(1, os.cpu_count() or 1)


def resolve_workers(workers: int | None, n_jobs: int) -> int:
    """None → one worker per job, at most `available_cores()`; else the given count (an int ≥ 1)."""
    if workers is None:
        return max(1, min(n_jobs, available_cores()))
    try:
        count = operator.index(workers)  # int or numpy integer; not 2.5, not "2"
    except TypeError:
        raise ValueError(f"workers must be an integer >= 1 or None, got {workers!r}") from None
    if isinstance(workers, bool) or count < 1:
        raise ValueError(f"workers must be >= 1, got {workers!r}")
    return count


def _describe(job: Any, describe: Callable[[Any], str] | None) -> str:
    try:
        text = describe(job) if describe is not None else repr(job)
    except Exception as e:  # the note must never hide the job's own error
        text = f"<undescribable job: {type(e).__name__}>"
    return text if len(text) <= DESCRIPTION_CHARS else text[:DESCRIPTION_CHARS - 1] + "…"


def _exit_with_parent(parent_pid: int, every_s: float = PARENT_CHECK_S) -> None:
    """Worker initializer: a daemon thread ends this worker as soon as its parent process is gone (the worker
    is then re-parented, so its parent's pid changes). Polling works on every OS, unlike Linux's
    PR_SET_PDEATHSIG, and costs nothing measurable once a second."""
    def watch() -> None:
        while True:
            time.sleep(every_s)
            if os.getppid() != parent_pid:
                os._exit(1)  # no cleanup to wait for: the results have nowhere to go

    threading.Thread(target=watch, name="exit-with-parent", daemon=True).start()


def _note_failing_job(error: BaseException, index: int, n_jobs: int, job: Any, describe) -> BaseException:
    error.add_note(f"while running job {index} of {n_jobs} (0-based): {_describe(job, describe)}")
    return error


class ProcessMap:
    """`fn` over jobs in `workers` spawned processes that live until `close()` (or the end of a `with`).

    With `workers=1` nothing is spawned: every call runs in this process.
    """

    def __init__(self, workers: int):
        self.workers = resolve_workers(workers, 1)
        self._pool: ProcessPoolExecutor | None = None

    def _executor(self) -> ProcessPoolExecutor:
        if self._pool is None:  # started on first use: a map of one job never pays for a worker
            self._pool = ProcessPoolExecutor(self.workers, mp_context=multiprocessing.get_context("spawn"),
                                             initializer=_exit_with_parent, initargs=(os.getpid(),))
        return self._pool

    def __call__(self, fn: Callable[[Any], Any], jobs: Sequence, on_result: Callable[[int, Any, int], None] | None
                 = None, describe: Callable[[Any], str] | None = None) -> list:
        """[fn(job) for job in jobs], in job order. `on_result(index, result, done)` is called in this
        process as each job finishes (in finishing order; `done` counts finished jobs), e.g. for a progress
        line. `describe(job)` names a job in the note of a failure (default: its repr)."""
        jobs = list(jobs)
        results: list = [None] * len(jobs)
        if self.workers == 1 or len(jobs) <= 1:
            for i, job in enumerate(jobs):
                try:
                    results[i] = fn(job)
                except Exception as e:
                    raise _note_failing_job(e, i, len(jobs), job, describe)
                if on_result is not None:
                    on_result(i, results[i], i + 1)
            return results
        pool = self._executor()
        futures = {pool.submit(fn, job): i for i, job in enumerate(jobs)}
        pending, done_count = set(futures), 0
        try:
            while pending:
                finished, pending = wait(pending, return_when=FIRST_COMPLETED)
                # finished jobs in submission order, so that progress lines do not depend on timing ties
                for fut in sorted(finished, key=futures.__getitem__):
                    i = futures[fut]
                    error = fut.exception()
                    if error is not None:
                        raise _note_failing_job(error, i, len(jobs), jobs[i], describe)
                    results[i] = fut.result()
                    done_count += 1
                    if on_result is not None:
                        on_result(i, results[i], done_count)
        except BaseException:
            self._terminate()
            raise
        return results

    def _terminate(self) -> None:
        """Stop now: queued jobs never start and running ones are killed (an error or Ctrl-C must not wait
        for minutes of walks whose results will not be used). The next call starts fresh workers."""
        pool, self._pool = self._pool, None
        if pool is None:
            return
        if hasattr(pool, "terminate_workers"):  # Python >= 3.14
            pool.terminate_workers()
            return
        processes = list((getattr(pool, "_processes", None) or {}).values())
        pool.shutdown(wait=False, cancel_futures=True)
        for p in processes:
            p.terminate()
        for p in processes:
            p.join(timeout=10)

    def close(self) -> None:
        if self._pool is not None:
            self._pool.shutdown(wait=True, cancel_futures=True)
            self._pool = None

    def __enter__(self) -> "ProcessMap":
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def milestone(done: int, total: int, parts: int = 4) -> bool:
    """True when `done` of `total` jobs completes one of `parts` equal shares (the last job included): when a
    brief progress log prints a line."""
    return done == total or done * parts // total != (done - 1) * parts // total


QUIET_LIMIT_S = 15.0  # s: a brief progress log still prints a line at the first result after this long


def progress_log(total: int, line: Callable[[Any], str], log: Callable[[str], None] = print,
                 every_job: bool = True) -> Callable[[int, Any, int], None]:
    """An `on_result` callback that logs `[done/total] <line(result)> (… s; elapsed …, ETA …)` for every job,
    or with `every_job=False` at each quarter of them (`milestone`) and at the first result after
    `QUIET_LIMIT_S` without a line (long work never goes quiet for long on a loaded machine). `line` formats
    one result; the result's own "wall_s" (seconds) is shown where it has one. The clock starts when the
    callback is made."""
    t0 = time.perf_counter()
    last = [t0]  # when the latest line was logged

    def on_result(_i: int, result: Any, done: int) -> None:
        now = time.perf_counter()
        if not (every_job or milestone(done, total) or now - last[0] >= QUIET_LIMIT_S):
            return
        last[0] = now
        elapsed = now - t0
        eta = elapsed / done * (total - done)
        wall = f"{result['wall_s']:.0f} s; " if isinstance(result, dict) and "wall_s" in result else ""
        log(f"[{done}/{total}] {line(result)}  ({wall}elapsed {elapsed:.0f} s, ETA {eta:.0f} s)")

    return on_result


def map_in_processes(fn: Callable[[Any], Any], jobs: Sequence, workers: int | None = None,
                     on_result: Callable[[int, Any, int], None] | None = None,
                     describe: Callable[[Any], str] | None = None) -> list:
    """[fn(job) for job in jobs] in job order, over `workers` spawned processes (None: one per job, at most
    the available CPUs; 1 or a single job: in this process). See `ProcessMap.__call__` for the callbacks."""
    jobs = list(jobs)
    with ProcessMap(resolve_workers(workers, len(jobs))) as run:
        return run(fn, jobs, on_result=on_result, describe=describe)


__all__ = ["PARENT_CHECK_S", "QUIET_LIMIT_S", "ProcessMap", "available_cores", "map_in_processes", "milestone",
           "progress_log", "resolve_workers"]
