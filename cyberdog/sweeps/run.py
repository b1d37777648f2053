"""The sweep driver: keep the backend busy with the seeds that are not done, retry failed attempts from their
checkpoint, and keep sweep_status.json, the progress bar or the log line current.

`run_sweep` checks its options, takes the sweep folder's lock and hands over to `SweepDriver`, whose loop is
three steps repeated every `poll_s`: start attempts while the backend has room, collect the attempts that
ended (done, or failed → retried or given up), and refresh the running seeds' metrics and process ids.
"""
from __future__ import annotations

import signal
import threading
import time
from contextlib import contextmanager
from pathlib import Path

from cyberdog import config as C
from cyberdog.analysis.parallel import available_cores
from cyberdog.runlock import break_lock
from cyberdog.sweeps.folder import (CONFIG_FILE, LOCK_FILE, STATUS_FILE, SweepSpec, attempt_args, load_sweep,
                                    read_attempt, seed_dir, sweep_budget)
from cyberdog.sweeps.process import ENTRY_POINT, LOG_FILE, LocalBackend, RayBackend, SweepError
from cyberdog.sweeps.status import SweepStatus, seed_statuses

BACKENDS = ("local", "ray")
STATUS_EVERY_S = 2.0  # s between rewrites of sweep_status.json (also at every start, end or failure of a seed)
PID_RECORD_SLACK_S = 30.0  # s: a sweep_attempt.json older than the attempt's start by more is a previous one's


def run_sweep(sweep_dir, backend: str = "local", workers: int | None = None, max_retries: int = 2,
              ray_address: str | None = None, progress: bool = True, poll_s: float = 0.5,
              log_every_s: float = 30.0, echo=print, entry_point: str = ENTRY_POINT) -> dict:
    """Train every seed of the sweep in `sweep_dir` that is not done yet; returns the final status dict.

    A failed attempt (non-zero exit, killed, Ray task lost) is reported with its error and retried, from the
    seed's last checkpoint, up to `max_retries` times; then the seed is marked failed and the others go on.
    The status is kept in sweep_status.json (atomically rewritten) and shown as a progress bar, or with
    `progress=False` as a log line every `log_every_s` seconds. Each attempt is a process of the package's
    entry point, `python -m cyberdog.train_cli` (`entry_point`), importing this same `cyberdog` (its folder leads
    PYTHONPATH).
    """
    sweep_dir = Path(sweep_dir)
    _check_options(backend, workers, max_retries, ray_address)
    spec = load_sweep(sweep_dir)
    cfg = C.load(C.ExperimentConfig, sweep_dir / CONFIG_FILE)
    code_root = Path(__file__).resolve().parents[2]  # the folder holding this `cyberdog` package
    with _driver_lock(sweep_dir):
        budget = sweep_budget(sweep_dir, spec, cfg)
        info = {"sweep_dir": str(sweep_dir.resolve()), "backend": backend, "max_retries": max_retries,
                "started": time.strftime("%Y-%m-%d %H:%M:%S"), "budget_env_steps_per_seed": budget}
        status = SweepStatus(sweep_dir, seed_statuses(sweep_dir, spec), budget, info)
        driver = SweepDriver(sweep_dir, spec, status, max_retries, poll_s, log_every_s, echo)
        with _sigterm_as_interrupt():
            return driver.run(lambda queued: _make_backend(backend, workers, ray_address, (code_root, entry_point),
                                                           queued, echo),
                              progress)


def _check_options(backend: str, workers: int | None, max_retries: int, ray_address: str | None) -> None:
    if backend not in BACKENDS:
        raise SweepError(f"backend must be one of {BACKENDS}, got {backend!r}")
    if workers is not None and workers < 1:
        raise SweepError(f"--workers must be >= 1, got {workers}")
    if max_retries < 0:
        raise SweepError(f"--max-retries must be >= 0, got {max_retries}")
    if ray_address and backend != "ray":
        raise SweepError("--ray-address needs --backend ray")


def _make_backend(backend: str, workers: int | None, ray_address: str | None, code: tuple[Path, str], queued: int,
                  echo):
    """code: (the folder holding the package, the module each attempt runs)."""
    if backend == "local":
        return LocalBackend(min(workers or available_cores(), queued), *code)
    return RayBackend(workers, ray_address, *code, local_cpus=available_cores(), echo=echo)


@contextmanager
def _driver_lock(sweep_dir: Path):
    """One driver per sweep folder (an advisory lock on .sweep.lock, released when the driver ends or dies)."""
    import fcntl

    lock = open(sweep_dir / LOCK_FILE, "w")
    try:
        try:
            fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            raise SweepError(f"another sweep process is running in {sweep_dir}") from None
        yield
    finally:
        lock.close()


def _raise_interrupt(signum, frame):
    raise KeyboardInterrupt(f"signal {signal.Signals(signum).name}")


@contextmanager
def _sigterm_as_interrupt():
    """`kill PID` ends the sweep like Ctrl-C does: running seeds are stopped and marked interrupted.
    (Signal handlers can only be set from the main thread; a driver in another thread keeps the default.)"""
    previous = None
    if threading.current_thread() is threading.main_thread():
        previous = signal.signal(signal.SIGTERM, _raise_interrupt)
    try:
        yield
    finally:
        if previous is not None:
            signal.signal(signal.SIGTERM, previous)


class SweepDriver:
    """One run of the sweep: the queue of seeds to train, the backend that trains them, and the status."""

    def __init__(self, sweep_dir: Path, spec: SweepSpec, status: SweepStatus, max_retries: int, poll_s: float,
                 log_every_s: float, echo):
        self.sweep_dir, self.spec, self.status, self.seeds = sweep_dir, spec, status, status.seeds
        self.max_retries, self.poll_s, self.log_every_s, self.echo = max_retries, poll_s, log_every_s, echo
        self.queue = [s for s in spec.seeds if self.seeds[s].state != "done"]
        self.backend = None
        self.bar = None
        self.last_log = time.monotonic()

    def say(self, msg: str) -> None:
        """A line that must not break the progress bar."""
        if self.bar is not None:
            self.bar.write(msg)
        else:
            self.echo(msg)

    def run(self, make_backend, progress: bool) -> dict:
        """Train until every seed is done or failed; on any exception (Ctrl-C, SIGTERM, a backend error) stop
        the running attempts, mark them interrupted, write the status, and re-raise."""
        try:
            if not self.queue:
                self.echo(f"sweep: all {len(self.seeds)} seeds of {self.sweep_dir} are already done")
                return self.status.write(final=True)
            self.backend = make_backend(len(self.queue))
            self.echo(f"sweep: {len(self.queue)} of {len(self.seeds)} seeds to train in {self.sweep_dir} on the "
                      f"{self.backend.name} backend, {self.backend.capacity} at a time; status in "
                      f"{self.sweep_dir / STATUS_FILE}, logs in seed<N>/{LOG_FILE}")
            if progress:
                from tqdm import tqdm

                self.bar = tqdm(total=self.status.budget * len(self.seeds), initial=self.status.steps0, unit="step",
                                desc="sweep", dynamic_ncols=True, mininterval=2.0)
            self.last_log = time.monotonic()
            self.status.write()
            while self.queue or self.status.count("running"):
                self.start_attempts()
                self.collect_ended_attempts()
                self.refresh_running()
                self.show_progress()
            if self.bar is not None:
                self.bar.close()
                self.bar = None
            self.echo(self.status.one_line())
            return self.status.write(final=True)
        except BaseException:
            for st in self.seeds.values():
                if st.state in ("running", "retrying"):
                    st.state = "interrupted"
            if self.backend is not None:
                self.backend.stop()
            self.status.write()
            raise
        finally:
            if self.bar is not None:
                self.bar.close()
            if self.backend is not None:
                self.backend.close()

    def start_attempts(self) -> None:
        """Start queued seeds while the backend has room: a retry resumes from the seed's checkpoint."""
        while self.queue and self.status.count("running") < self.backend.capacity:
            s = self.queue.pop(0)
            st = self.seeds[s]
            st.attempts += 1
            st._tries += 1
            args = attempt_args(self.sweep_dir, self.spec, s)
            if "--resume" not in args:  # a fresh start: the previous attempt's metrics were moved aside
                st.reset_metrics()
            # a recipe's lineage is always started with --resume (it finds its phase); it resumes only with a checkpoint
            resuming = "--resume" in args and any(seed_dir(self.sweep_dir, s).rglob("checkpoint.pt"))
            st._started_wall = time.time()
            self.backend.submit(s, args, seed_dir(self.sweep_dir, s).resolve(), st.attempts)
            st.state, st.pid, st.host, st._started = "running", None, None, time.monotonic()
            self.say(f"sweep: seed {s} attempt {st.attempts} started"
                     + (" (resuming from its checkpoint)" if resuming else ""))
            self.status.write()

    def collect_ended_attempts(self) -> None:
        """Wait up to poll_s for attempts to end; a failed one goes back to the front of the queue while its
        seed has retries left, else the seed is marked failed; an interrupted one (Ctrl-C) is marked interrupted."""
        for end in self.backend.wait(self.poll_s):
            s, error = end.seed, end.error
            st = self.seeds[s]
            st.wall_s += time.monotonic() - st._started
            st.read_metrics()
            if end.ok:
                st.state = "done"
                score = "-" if st.window_score is None else f"{st.window_score:.4g}"
                self.say(f"sweep: seed {s} done: {st.env_steps} env steps, {st.episodes} episodes, "
                         f"window score {score}, {st.wall_s:.0f} s")
            else:
                st.errors.append(f"attempt {st.attempts}: {error}")
                # the attempt has ended: its run-folder lock must not block the retry, on whichever node
                a = read_attempt(Path(st.run_dir))
                if a.get("attempt") == st.attempts:
                    break_lock(st.run_dir, a.get("pid"), a.get("host"))
                if end.interrupted:  # a Ctrl-C of that seed's process: stopped on purpose, not retried
                    st.state = "interrupted"
                    self.say(f"sweep: seed {s} attempt {st.attempts} interrupted ({error.splitlines()[0]}); not "
                             "retried: train.py --resume SWEEP_DIR continues it")
                elif st._tries <= self.max_retries:
                    st.state = "retrying"
                    self.queue.insert(0, s)
                    self.say(f"sweep: seed {s} attempt {st.attempts} failed ({error}); retrying "
                             f"({st._tries}/{self.max_retries} retries used)")
                else:
                    st.state = "failed"
                    self.say(f"sweep: seed {s} FAILED after {st._tries} attempt(s): {error}")
            self.status.write()

    def refresh_running(self) -> None:
        """Read the running seeds' new metrics; learn each attempt's pid and host once its process wrote them."""
        for st in self.seeds.values():
            if st.state == "running":
                st.read_metrics()
                if st.pid is None:
                    a = read_attempt(Path(st.run_dir))
                    fresh = a.get("started", 0) >= st._started_wall - PID_RECORD_SLACK_S
                    if a.get("attempt") == st.attempts and fresh:
                        st.pid, st.host = a.get("pid"), a.get("host")
                        self.status.write()
        if time.monotonic() - self.status.last_write >= STATUS_EVERY_S:
            self.status.write()

    def show_progress(self) -> None:
        if self.bar is not None:
            postfix = self.status.postfix()
            if postfix != self.bar.postfix:
                self.bar.set_postfix_str(postfix, refresh=False)
            self.bar.update(self.status.steps_done() - self.bar.n)  # tqdm redraws at most every mininterval
        elif time.monotonic() - self.last_log >= self.log_every_s:
            self.echo(self.status.one_line())
            self.last_log = time.monotonic()


__all__ = ["BACKENDS", "STATUS_EVERY_S", "SweepDriver", "run_sweep"]
