"""Seeds at scale: one training run per seed, in parallel, with retries from the last checkpoint.

A sweep folder holds

    sweep.json            what the sweep is: seeds, stages, the original config file and overrides
    sweep_config.yaml     the resolved experiment config every seed trains with (train.seed set per seed)
    sweep_status.json     live status per seed: state, attempts, pid/host, stage, env steps, best score, errors
    seed<N>/              an ordinary run folder of `train.py` (+ train.log, sweep_attempt.json)
    aggregate.*, evaluation.json, learning_curves.*   written by `cyberdog.analysis.aggregate` at the end

Every attempt of a seed is a separate process, `python train.py --config sweep_config.yaml --seed N
--run-dir seed<N> --no-progress`, and a retry is `python train.py --resume seed<N>`. Why processes rather than
calling the trainer in a pool worker: a seed that segfaults in PyBullet, leaks memory or is killed cannot take
the sweep down with it; a retry starts from a clean interpreter exactly like a user's `--resume`; the two
backends differ only in *where* the process is started (here, or inside a Ray task on any node of a cluster).
The training process dies with the process that started it (Linux `PR_SET_PDEATHSIG`), so a killed sweep
leaves no orphan writing into its run folders.

Backends: "local" keeps up to `workers` training processes running on this machine; "ray" submits one Ray
task per attempt (1 CPU each) to a local Ray instance or to an existing cluster (`ray_address`). With a
cluster, the sweep folder must be on a file system that every node sees at the same path (the tasks write
the run folders there and the driver reads the status from them), and the code (`train.py` + `cyberdog/`) is
shipped to the nodes as the Ray job's working_dir; each node needs the project's dependencies installed.

This module imports only the standard library and `cyberdog.config`; the two backends and the attempt a Ray
worker runs are in `cyberdog.rl.sweep_process` (standard library only, shipped to Ray by value).
"""
from __future__ import annotations

import json
import os
import re
import signal
import socket
import threading
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path

from cyberdog import config as C
from cyberdog.runlock import break_lock
from cyberdog.rl.sweep_process import (ATTEMPT_FILE, LOG_FILE, SWEEP_FILE, LocalBackend, RayBackend, SweepError,
                                       available_cores)

FORMAT, VERSION = "cyberdog-sweep", 1
STATUS_FILE, CONFIG_FILE = "sweep_status.json", "sweep_config.yaml"
LOCK_FILE = ".sweep.lock"
BACKENDS = ("local", "ray")
STATUS_EVERY_S = 2.0  # s between rewrites of sweep_status.json (also at every start, end or failure of a seed)
# what a fresh attempt leaves in a seed folder before its first checkpoint (moved aside before a restart)
_KEEP_ON_RESTART = (LOG_FILE, ATTEMPT_FILE)



# ---- seeds and folders ---------------------------------------------------------------------------------------
def parse_seeds(text: str) -> list[int]:
    """'0-9' → [0, …, 9]; '0,3,7' → [0, 3, 7]; '0-2,5' → [0, 1, 2, 5]. Seeds are integers ≥ 0, no repeats."""
    seeds: list[int] = []
    for part in str(text).replace(" ", "").split(","):
        m = re.fullmatch(r"(\d+)(?:-(\d+))?", part)
        if not m:
            raise SweepError(f"--seeds {text!r}: {part!r} is not a seed (integer >= 0) or a range such as 0-9")
        lo, hi = int(m[1]), int(m[2]) if m[2] is not None else int(m[1])
        if hi < lo:
            raise SweepError(f"--seeds {text!r}: range {part!r} is empty (write low-high with low <= high)")
        seeds.extend(range(lo, hi + 1))
    repeated = sorted({s for s in seeds if seeds.count(s) > 1})
    if repeated:
        raise SweepError(f"--seeds {text!r}: seed(s) {repeated} given more than once")
    return seeds



def is_sweep_dir(path) -> bool:
    return (Path(path) / SWEEP_FILE).is_file()


def seed_dir(sweep_dir, seed: int) -> Path:
    return Path(sweep_dir) / f"seed{seed}"


@dataclass
class SweepSpec:
    """The contents of sweep.json."""

    seeds: list
    stage: str  # "both" or "1"
    source_config: str | None  # the config file the sweep was made from (informative; sweep_config.yaml rules)
    overrides: list = field(default_factory=list)
    created: str = ""
    format: str = FORMAT
    version: int = VERSION

    @property
    def last_stage(self) -> int:
        return 2 if self.stage == "both" else int(self.stage)


def create_sweep(sweep_dir, cfg: C.ExperimentConfig, seeds: list[int], stage: str = "both",
                 source_config=None, overrides=()) -> SweepSpec:
    """Make a new sweep folder (refusing one that exists and is not empty) with sweep.json and sweep_config.yaml."""
    sweep_dir = Path(sweep_dir)
    if stage not in ("both", "1"):
        raise SweepError(f"a sweep trains --stage both or 1, got {stage!r} (stage 2 alone needs a stage-1 agent "
                         f"per seed: run the stage-1 sweep with --stage both instead)")
    if not seeds:
        raise SweepError("a sweep needs at least one seed")
    if sweep_dir.exists() and (not sweep_dir.is_dir() or any(sweep_dir.iterdir())):
        hint = f"train.py --resume {sweep_dir}" if is_sweep_dir(sweep_dir) else "another --run-dir"
        raise SweepError(f"{sweep_dir} already exists and is not empty; a sweep never writes over it: use {hint}")
    sweep_dir.mkdir(parents=True, exist_ok=True)
    spec = SweepSpec(seeds=list(seeds), stage=stage, source_config=str(source_config) if source_config else None,
                     overrides=list(overrides), created=time.strftime("%Y-%m-%d %H:%M:%S"))
    C.save(cfg, sweep_dir / CONFIG_FILE)
    _write_json(sweep_dir / SWEEP_FILE, asdict(spec))
    return spec


def load_sweep(sweep_dir) -> SweepSpec:
    path = Path(sweep_dir) / SWEEP_FILE
    if not path.is_file():
        raise SweepError(f"{sweep_dir} is not a sweep folder (no {SWEEP_FILE})")
    try:
        data = json.loads(path.read_text())
        if data.get("format") != FORMAT:
            raise ValueError(f"format {data.get('format')!r}, expected {FORMAT!r}")
        if data.get("version") != VERSION:
            raise ValueError(f"version {data.get('version')!r}, this code reads {VERSION}")
        return SweepSpec(**data)
    except (ValueError, TypeError) as e:
        raise SweepError(f"{path} cannot be read: {e}") from e


def stage_budget(cfg: C.ExperimentConfig, stage: str) -> int:
    """Env steps one seed runs at most (stages can stop earlier at their stop_score)."""
    total = 0
    for s in ((1, 2) if stage == "both" else (int(stage),)):
        sc = getattr(cfg.train, f"stage{s}")
        total += sc.max_env_steps or sc.max_episodes * cfg.env.max_episode_steps
    return total


def _write_json(path: Path, data) -> None:
    """Atomic: readers (the user, a test, another tool) never see a half-written file."""
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    tmp.write_text(json.dumps(data, indent=1, default=str) + "\n")
    os.replace(tmp, path)


# ---- status ------------------------------------------------------------------------------------------------------
@dataclass
class SeedStatus:
    seed: int
    run_dir: str
    state: str = "pending"  # pending, running, retrying, done, failed, interrupted
    attempts: int = 0  # attempts started, over every run of the sweep (a resumed sweep counts on)
    pid: int | None = None
    host: str | None = None
    stage: int | None = None
    env_steps: int = 0  # total env steps at the end of the last logged episode (from metrics.csv)
    episodes: int = 0
    best_score: dict = field(default_factory=dict)  # stage ("1"/"2") -> best episode score
    window_score: float | None = None  # mean score over the trainer's score window, last episode
    wall_s: float = 0.0
    errors: list = field(default_factory=list)  # one line per failed attempt
    _started: float = 0.0  # monotonic clock at the start of the current attempt
    _started_wall: float = 0.0  # wall clock, to recognise this attempt's sweep_attempt.json
    _tries: int = 0  # attempts in this run of the sweep (the retry budget is per run)
    _csv: dict = field(default_factory=dict)  # incremental reader state of metrics.csv

    def public(self) -> dict:
        return {k: v for k, v in asdict(self).items() if not k.startswith("_")}

    def reset_metrics(self) -> None:
        self._csv.clear()
        self.stage, self.env_steps, self.episodes, self.best_score, self.window_score = None, 0, 0, {}, None

    def read_metrics(self) -> None:
        """Steps, episodes and scores from the run's metrics.csv (read incrementally; a resumed run may have
        truncated it, in which case it is read again from the start)."""
        path = Path(self.run_dir) / "metrics.csv"
        try:
            size = path.stat().st_size
        except OSError:
            size = -1
        st = self._csv
        if size < st.get("offset", 0) or not st:
            self.reset_metrics()
            st.update(offset=0, header=None)
        if size <= st["offset"]:
            return
        with open(path, "rb") as f:
            f.seek(st["offset"])
            chunk = f.read(size - st["offset"])
        end = chunk.rfind(b"\n") + 1
        st["offset"] += end
        for line in chunk[:end].decode(errors="replace").splitlines():
            cells = line.split(",")
            if st["header"] is None:
                st["header"] = {name: i for i, name in enumerate(cells)}
                continue
            h = st["header"]
            try:
                stage, score = int(cells[h["stage"]]), float(cells[h["score"]])
                self.env_steps, self.stage = int(cells[h["env_steps"]]), stage
                self.episodes = int(cells[h["episode"]])
                self.window_score = float(cells[h["window_mean_score"]])
            except (KeyError, IndexError, ValueError):
                continue
            key = str(stage)
            self.best_score[key] = max(self.best_score.get(key, -float("inf")), score)


def _load_previous_status(sweep_dir: Path) -> dict:
    try:
        data = json.loads((sweep_dir / STATUS_FILE).read_text())
        return {int(s["seed"]): s for s in data.get("seeds", [])}
    except (OSError, ValueError, KeyError, TypeError):
        return {}


def _process_alive(info: dict, run_dir: Path) -> bool:
    """Is the training process recorded in sweep_attempt.json still running on this machine?"""
    if info.get("host") != socket.gethostname() or not info.get("pid"):
        return False
    try:
        cmdline = Path(f"/proc/{int(info['pid'])}/cmdline").read_bytes().replace(b"\0", b" ").decode(errors="replace")
    except OSError:
        return False
    return str(run_dir) in cmdline and "train.py" in cmdline


def _read_attempt(run_dir: Path) -> dict:
    try:
        return json.loads((run_dir / ATTEMPT_FILE).read_text())
    except (OSError, ValueError):
        return {}


# ---- the sweep ---------------------------------------------------------------------------------------------------
def attempt_args(sweep_dir: Path, spec: SweepSpec, seed: int) -> list[str]:
    """train.py arguments of the next attempt of `seed`: --resume from its checkpoint if it has one, else a fresh
    start (whatever a killed attempt left before its first checkpoint is moved to seed<N>/discarded_<k>/)."""
    run_dir = seed_dir(sweep_dir, seed).resolve()
    if (run_dir / "checkpoint.pt").is_file():
        return ["--resume", str(run_dir), "--no-progress"]
    leftovers = [p for p in run_dir.iterdir() if p.name not in _KEEP_ON_RESTART
                 and not p.name.startswith(("discarded_", "."))] if run_dir.is_dir() else []
    if leftovers:
        k = 1 + sum(1 for p in run_dir.iterdir() if p.name.startswith("discarded_"))
        aside = run_dir / f"discarded_{k}"
        aside.mkdir()
        for p in leftovers:
            os.replace(p, aside / p.name)
    return ["--config", str((sweep_dir / CONFIG_FILE).resolve()), "--seed", str(seed), "--run-dir", str(run_dir),
            "--stage", spec.stage, "--no-progress"]


def _raise_interrupt(signum, frame):
    raise KeyboardInterrupt(f"signal {signal.Signals(signum).name}")


def _fmt_eta(seconds: float) -> str:
    if not seconds == seconds or seconds == float("inf"):
        return "?"
    seconds = int(seconds)
    return f"{seconds // 3600}:{seconds // 60 % 60:02d}:{seconds % 60:02d}"


def run_sweep(sweep_dir, backend: str = "local", workers: int | None = None, max_retries: int = 2,
              ray_address: str | None = None, progress: bool = True, train_script=None, poll_s: float = 0.5,
              log_every_s: float = 30.0, echo=print) -> dict:
    """Train every seed of the sweep in `sweep_dir` that is not done yet; returns the final status dict.

    A failed attempt (non-zero exit, killed, Ray task lost) is reported with its error and retried, from the
    seed's last checkpoint, up to `max_retries` times; then the seed is marked failed and the others go on.
    The status is kept in sweep_status.json (atomically rewritten) and shown as a progress bar, or with
    `progress=False` as a log line every `log_every_s` seconds.
    """
    import fcntl

    from tqdm import tqdm

    sweep_dir = Path(sweep_dir)
    if backend not in BACKENDS:
        raise SweepError(f"backend must be one of {BACKENDS}, got {backend!r}")
    if workers is not None and workers < 1:
        raise SweepError(f"--workers must be >= 1, got {workers}")
    if max_retries < 0:
        raise SweepError(f"--max-retries must be >= 0, got {max_retries}")
    if ray_address and backend != "ray":
        raise SweepError("--ray-address needs --backend ray")
    spec = load_sweep(sweep_dir)
    cfg = C.load(C.ExperimentConfig, sweep_dir / CONFIG_FILE)
    script = Path(train_script) if train_script else Path(__file__).resolve().parents[2] / "train.py"
    if not script.is_file():
        raise SweepError(f"cannot find train.py at {script}; pass train_script")
    lock = open(sweep_dir / LOCK_FILE, "w")
    try:
        fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError:
        lock.close()
        raise SweepError(f"another sweep process is running in {sweep_dir}") from None

    previous = _load_previous_status(sweep_dir)
    final_actor = f"stage{spec.last_stage}_final_actor.pt"
    seeds: dict[int, SeedStatus] = {}
    for s in spec.seeds:
        run_dir = seed_dir(sweep_dir, s)
        st = SeedStatus(seed=s, run_dir=str(run_dir))
        prev = previous.get(s, {})
        st.attempts, st.errors = int(prev.get("attempts", 0)), list(prev.get("errors", []))
        if prev.get("state") == "done" and (run_dir / final_actor).is_file():
            st.state, st.wall_s = "done", float(prev.get("wall_s", 0.0))
        elif _process_alive(_read_attempt(run_dir), run_dir.resolve()):
            lock.close()
            raise SweepError(f"seed {s} is still being trained by process {_read_attempt(run_dir)['pid']} "
                             f"(a previous sweep driver was killed?); stop it before resuming {sweep_dir}")
        st.read_metrics()
        seeds[s] = st

    budget = stage_budget(cfg, spec.stage)
    t_start = last_write = time.monotonic()
    info = {"sweep_dir": str(sweep_dir.resolve()), "backend": backend, "max_retries": max_retries,
            "started": time.strftime("%Y-%m-%d %H:%M:%S"), "budget_env_steps_per_seed": budget}

    def steps_done() -> int:
        return sum(budget if st.state == "done" else min(st.env_steps, budget) for st in seeds.values())

    def write_status(final: bool = False) -> dict:
        nonlocal last_write
        counts = {k: sum(st.state == k for st in seeds.values()) for k in
                  ("pending", "running", "retrying", "done", "failed", "interrupted")}
        data = {**info, "updated": time.strftime("%Y-%m-%d %H:%M:%S"), "finished": final,
                "elapsed_s": round(time.monotonic() - t_start, 1), "counts": counts,
                "seeds": [st.public() for st in seeds.values()]}
        _write_json(sweep_dir / STATUS_FILE, data)
        last_write = time.monotonic()
        return data

    def say(msg: str) -> None:
        if bar is not None:
            bar.write(msg)
        else:
            echo(msg)

    def one_line() -> str:
        c = [st.state for st in seeds.values()]
        done_steps = steps_done()
        el = time.monotonic() - t_start
        rate = max(0.0, (done_steps - steps0) / el) if el > 0 else 0.0
        eta = (budget * len(seeds) - done_steps) / rate if rate > 0 else float("nan")
        per_seed = " | ".join(f"seed{st.seed} {st.state} s{st.stage or '-'} {st.env_steps} steps"
                              + (f" best {st.best_score[str(st.stage)]:.3g}" if str(st.stage) in st.best_score
                                 else "") for st in seeds.values())
        return (f"sweep: {c.count('done')}/{len(c)} done, {c.count('running')} running, {c.count('failed')} failed; "
                f"{done_steps}/{budget * len(seeds)} env steps, {rate:.0f} step/s, ETA {_fmt_eta(eta)}; {per_seed}")

    bar = None
    be = None
    queue = [s for s in spec.seeds if seeds[s].state != "done"]
    previous_sigterm = None
    if threading.current_thread() is threading.main_thread():  # `kill PID` ends the sweep like Ctrl-C does
        previous_sigterm = signal.signal(signal.SIGTERM, _raise_interrupt)
    steps0 = steps_done()
    try:
        if not queue:
            echo(f"sweep: all {len(seeds)} seeds of {sweep_dir} are already done")
            return write_status(final=True)
        if backend == "local":
            be = LocalBackend(min(workers or available_cores(), len(queue)), script)
        else:
            be = RayBackend(workers, ray_address, script, echo=echo)
        echo(f"sweep: {len(queue)} of {len(seeds)} seeds to train in {sweep_dir} on the {be.name} backend, "
             f"{be.capacity} at a time; status in {sweep_dir / STATUS_FILE}, logs in seed<N>/{LOG_FILE}")
        bar = tqdm(total=budget * len(seeds), initial=steps0, unit="step", desc="sweep", dynamic_ncols=True,
                   mininterval=2.0) if progress else None
        last_log = time.monotonic()
        write_status()
        while queue or any(st.state == "running" for st in seeds.values()):
            while queue and sum(st.state == "running" for st in seeds.values()) < be.capacity:
                s = queue.pop(0)
                st = seeds[s]
                st.attempts += 1
                st._tries += 1
                args = attempt_args(sweep_dir, spec, s)
                if "--resume" not in args:  # a fresh start: earlier metrics were moved aside
                    st.reset_metrics()
                st._started_wall = time.time()
                be.submit(s, args, seed_dir(sweep_dir, s).resolve(), st.attempts)
                st.state, st.pid, st.host, st._started = "running", None, None, time.monotonic()
                say(f"sweep: seed {s} attempt {st.attempts} started"
                    + (" (resuming from its checkpoint)" if "--resume" in args else ""))
                write_status()
            for s, ok, error in be.wait(poll_s):
                st = seeds[s]
                st.wall_s += time.monotonic() - st._started
                st.read_metrics()
                if ok:
                    st.state = "done"
                    score = "-" if st.window_score is None else f"{st.window_score:.4g}"
                    say(f"sweep: seed {s} done: {st.env_steps} env steps, {st.episodes} episodes, "
                        f"window score {score}, {st.wall_s:.0f} s")
                else:
                    st.errors.append(f"attempt {st.attempts}: {error}")
                    # the attempt has ended: its run-folder lock must not block the retry, on whichever node
                    a = _read_attempt(Path(st.run_dir))
                    if a.get("attempt") == st.attempts:
                        break_lock(st.run_dir, a.get("pid"), a.get("host"))
                    if st._tries <= max_retries:
                        st.state = "retrying"
                        queue.insert(0, s)
                        say(f"sweep: seed {s} attempt {st.attempts} failed ({error}); retrying "
                            f"({st._tries}/{max_retries} retries used)")
                    else:
                        st.state = "failed"
                        say(f"sweep: seed {s} FAILED after {st._tries} attempt(s): {error}")
                write_status()
            for st in seeds.values():
                if st.state == "running":
                    st.read_metrics()
                    if st.pid is None:
                        a = _read_attempt(Path(st.run_dir))
                        if a.get("attempt") == st.attempts and a.get("started", 0) >= st._started_wall - 30:
                            st.pid, st.host = a.get("pid"), a.get("host")
                            write_status()
            if time.monotonic() - last_write >= STATUS_EVERY_S:
                write_status()
            if bar is not None:
                c = [st.state for st in seeds.values()]
                postfix = f"done {c.count('done')}/{len(c)} running {c.count('running')} failed {c.count('failed')}"
                if postfix != bar.postfix:
                    bar.set_postfix_str(postfix, refresh=False)
                bar.update(steps_done() - bar.n)  # tqdm redraws at most every mininterval
            elif time.monotonic() - last_log >= log_every_s:
                echo(one_line())
                last_log = time.monotonic()
        if bar is not None:
            bar.close()
            bar = None
        echo(one_line())
        return write_status(final=True)
    except BaseException:
        for st in seeds.values():
            if st.state in ("running", "retrying"):
                st.state = "interrupted"
        if be is not None:
            be.stop()
        write_status()
        raise
    finally:
        if previous_sigterm is not None:
            signal.signal(signal.SIGTERM, previous_sigterm)
        if bar is not None:
            bar.close()
        if be is not None:
            be.close()
        lock.close()
