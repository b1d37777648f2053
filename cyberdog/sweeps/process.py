"""How one sweep attempt runs: a training process started here ("local") or inside a Ray task ("ray").

Standard library only, on purpose: `RayBackend` ships this module's functions to the Ray workers by value
(`ray.cloudpickle.register_pickle_by_value`), so a worker starts the training process without importing torch
or the `cyberdog` package itself. The sweep folder is in `cyberdog.sweeps.folder`, the driver loop (queue,
status, retries) in `cyberdog.sweeps.run`.
"""
from __future__ import annotations

import json
import os
import re
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path
from typing import NamedTuple

LOG_FILE, ATTEMPT_FILE, SWEEP_FILE = "train.log", "sweep_attempt.json", "sweep.json"
ENTRY_POINT = "cyberdog.train_cli"  # the package's training command line: `python -m cyberdog.train_cli`
RAY_MISSING = ("--backend ray needs Ray, which is not installed: pip install -e '.[ray]' (or pip install 'ray>=2.9'),"
               " or use the default --backend local")


class SweepError(RuntimeError):
    """Bad sweep input or a sweep folder that cannot be used; the message says what to do."""


# ---- one attempt: a training process. Standard library only (shipped by value to Ray workers) ------------------
def _die_with_parent() -> None:  # pragma: no cover - runs in the child between fork and exec
    """Linux: the training process gets SIGTERM when the process that started it dies."""
    try:
        import ctypes
        ctypes.CDLL("libc.so.6", use_errno=True).prctl(1, signal.SIGTERM)  # PR_SET_PDEATHSIG = 1
    except Exception:
        pass


def _launch(cmd: list, cwd, run_dir: str, attempt: int, code_root: str | None = None) -> subprocess.Popen:
    """Start one training attempt with its output appended to <run_dir>/train.log; record pid and host in
    <run_dir>/sweep_attempt.json. `code_root` (the folder holding the `cyberdog` package) leads PYTHONPATH, so
    that the attempt imports the driver's own code, installed or not."""
    os.makedirs(run_dir, exist_ok=True)
    log_path = os.path.join(run_dir, LOG_FILE)
    with open(log_path, "ab") as log:
        offset = log.tell()
        header = f"\n=== attempt {attempt} on {socket.gethostname()} at {time.strftime('%Y-%m-%d %H:%M:%S')}: "
        log.write((header + " ".join(map(str, cmd)) + "\n").encode())
        log.flush()
        env = {**os.environ, "PYTHONUNBUFFERED": "1"}
        if code_root:
            env["PYTHONPATH"] = os.pathsep.join([code_root] + [p for p in [os.environ.get("PYTHONPATH")] if p])
        proc = subprocess.Popen([str(c) for c in cmd], cwd=cwd, stdout=log, stderr=subprocess.STDOUT,
                                stdin=subprocess.DEVNULL, env=env, start_new_session=True,
                                preexec_fn=_die_with_parent if sys.platform.startswith("linux") else None)
    proc.log_offset = offset
    info = {"attempt": attempt, "pid": proc.pid, "host": socket.gethostname(), "started": time.time(),
            "command": [str(c) for c in cmd], "log_offset": offset}
    tmp = os.path.join(run_dir, f".{ATTEMPT_FILE}.tmp")
    with open(tmp, "w") as f:
        json.dump(info, f)
    os.replace(tmp, os.path.join(run_dir, ATTEMPT_FILE))
    return proc


def _describe_exit(rc: int, run_dir: str, offset: int, lines: int = 4) -> str:
    """'killed by SIGKILL' / 'exit code 1', then the last lines this attempt wrote to train.log."""
    if rc < 0:
        try:
            what = f"killed by {signal.Signals(-rc).name}"
        except ValueError:
            what = f"killed by signal {-rc}"
    else:
        what = f"exit code {rc}"
    try:
        with open(os.path.join(run_dir, LOG_FILE), "rb") as f:
            f.seek(offset)
            text = f.read()[-20000:].decode(errors="replace")
        text = re.sub(r"\x1b\[[0-9;]*m", "", text).replace("\r", "\n")  # no terminal colours
        tail = [ln.strip() for ln in text.splitlines() if ln.strip() and not ln.startswith("=== attempt")][-lines:]
    except OSError:
        tail = []
    return what + (": " + " | ".join(tail) if tail else "")


def _ray_attempt(cmd: list, run_dir: str, sweep_file: str, attempt: int, code_root: str, entry_point: str) -> dict:
    """Body of the Ray task: run one training attempt on whichever node Ray chose and wait for it."""
    if not os.path.isfile(sweep_file):
        return {"rc": None, "host": socket.gethostname(),
                "error": f"the sweep folder {os.path.dirname(sweep_file)} is not visible on node "
                         f"{socket.gethostname()}: with a Ray cluster it must be on a file system shared by all "
                         f"nodes, at the same path"}
    if code_root == "shipped":  # the code travelled as the Ray job's working_dir, the task's current folder
        code_root = os.getcwd()
    proc = _launch([sys.executable, "-m", entry_point] + list(cmd), None, run_dir, attempt, code_root)
    rc = proc.wait()
    return {"rc": rc, "host": socket.gethostname(), "pid": proc.pid,
            "error": None if rc == 0 else _describe_exit(rc, run_dir, proc.log_offset)}


class AttemptEnd(NamedTuple):
    """How a training attempt ended: `ok` (exit 0), else its `error` (how it ended, its log's last lines) and
    whether it was `interrupted` (exit 130 or SIGINT: a Ctrl-C of that process, which a sweep does not retry)."""

    seed: int
    ok: bool
    error: str | None = None
    interrupted: bool = False


def attempt_end(seed: int, rc: int, error: str | None) -> AttemptEnd:
    return AttemptEnd(seed, rc == 0, error, rc in INTERRUPTED_EXITS)


INTERRUPTED_EXITS = (130, -signal.SIGINT)  # train.py's exit on Ctrl-C; a process killed by SIGINT


# ---- backends ----------------------------------------------------------------------------------------------------
class LocalBackend:
    """Up to `workers` training processes on this machine."""

    name = "local"

    def __init__(self, workers: int, code_root: Path, entry_point: str = ENTRY_POINT):
        self.capacity, self.code_root, self.entry_point = workers, str(code_root), entry_point
        self.procs: dict[int, tuple[subprocess.Popen, str]] = {}  # seed -> (process, run folder)

    def submit(self, seed: int, args: list, run_dir: Path, attempt: int) -> None:
        proc = _launch([sys.executable, "-m", self.entry_point] + args, None, str(run_dir), attempt, self.code_root)
        self.procs[seed] = (proc, str(run_dir))

    def wait(self, timeout: float) -> list[AttemptEnd]:
        deadline = time.monotonic() + timeout
        while True:
            finished = [s for s, (p, _) in self.procs.items() if p.poll() is not None]
            if finished or time.monotonic() >= deadline:
                break
            time.sleep(min(0.1, timeout))
        out = []
        for seed in finished:
            p, run_dir = self.procs.pop(seed)
            rc = p.returncode
            out.append(attempt_end(seed, rc, None if rc == 0 else _describe_exit(rc, run_dir, p.log_offset)))
        return out

    def stop(self) -> None:
        for p, _ in self.procs.values():
            if p.poll() is None:
                p.terminate()
        for p, _ in self.procs.values():
            try:
                p.wait(timeout=10)
            except subprocess.TimeoutExpired:
                p.kill()
                p.wait()
        self.procs.clear()

    def close(self) -> None:
        self.stop()


class RayBackend:
    """One Ray task (1 CPU) per attempt, on a local Ray instance or an existing cluster."""

    name = "ray"

    def __init__(self, workers: int | None, address: str | None, code_root: Path, entry_point: str = ENTRY_POINT,
                 local_cpus: int = 1, echo=print):
        """local_cpus: CPUs of a Ray instance started here when neither `workers` nor `address` is given."""
        try:
            import ray
        except ImportError as e:
            raise SweepError(RAY_MISSING) from e
        self.ray, self.owns = ray, False
        ship = False
        if not ray.is_initialized():
            kwargs = dict(include_dashboard=False, log_to_driver=False)
            if address:
                root = Path(code_root).resolve()
                ship = (root / "setup.cfg").is_file()  # a checkout; an installed package must be on every node
                if ship:  # the nodes get this checkout's code; the runs themselves stay out of the upload
                    kwargs["runtime_env"] = {"working_dir": str(root), "excludes": [
                        ".venv", ".venv/**", "runs", "runs/**", ".git", ".git/**", "plots", "**/__pycache__",
                        "*.egg-info", ".pytest_cache"]}
                echo(f"sweep: joining the Ray cluster at {address}" + (f" (shipping {root})" if ship else ""))
                ray.init(address=address, **kwargs)
            else:
                ray.init(num_cpus=workers or local_cpus, **kwargs)
            self.owns = True
        elif address:
            echo(f"sweep: Ray is already initialised in this process; --ray-address {address} is not used")
        self.code_root = "shipped" if ship else str(Path(code_root).resolve())
        self.entry_point = entry_point
        cpus = int(ray.cluster_resources().get("CPU", 1))
        self.capacity = max(1, min(workers, cpus) if workers else cpus)
        # ship this module's functions by value: Ray workers need neither torch nor the package on their path
        ray.cloudpickle.register_pickle_by_value(sys.modules[__name__])
        self.task = ray.remote(num_cpus=1, max_retries=0)(_ray_attempt)
        self.refs: dict = {}  # ObjectRef of a running attempt -> seed

    def submit(self, seed: int, args: list, run_dir: Path, attempt: int) -> None:
        sweep_file = str(run_dir.parent / SWEEP_FILE)
        ref = self.task.remote(args, str(run_dir), sweep_file, attempt, self.code_root, self.entry_point)
        self.refs[ref] = seed

    def wait(self, timeout: float) -> list[AttemptEnd]:
        if not self.refs:
            time.sleep(timeout)
            return []
        ready, _ = self.ray.wait(list(self.refs), num_returns=len(self.refs), timeout=timeout)
        out = []
        for ref in ready:
            seed = self.refs.pop(ref)
            try:
                r = self.ray.get(ref)
                out.append(attempt_end(seed, r["rc"], r["error"]))
            except self.ray.exceptions.RayError as e:  # the worker or its node died
                out.append(AttemptEnd(seed, False, f"Ray task failed: {type(e).__name__}: "
                                                   f"{str(e).strip().splitlines()[0]}"))
        return out

    def stop(self) -> None:
        for ref in list(self.refs):
            self.ray.cancel(ref, force=True)  # kills the worker; its training process follows (PDEATHSIG)
        self.refs.clear()

    def close(self) -> None:
        self.stop()
        if self.owns:
            self.ray.shutdown()
