"""Live status of a sweep: one `SeedStatus` per seed, the whole sweep's counts, rate and ETA, and
sweep_status.json (rewritten atomically, so a reader never sees half a file).

A seed's env steps and scores come from its run's metrics.csv, read incrementally while it trains.
"""
from __future__ import annotations

import time
from dataclasses import asdict, dataclass, field
from pathlib import Path

from cyberdog import config as C
from cyberdog.sweeps.folder import (STATUS_FILE, SweepSpec, final_actor_file, load_previous_status, process_alive,
                                    read_attempt, seed_dir, write_json)
from cyberdog.sweeps.process import SweepError

STATES = ("pending", "running", "retrying", "done", "failed", "interrupted")


@dataclass
class SeedStatus:
    """One seed in sweep_status.json; fields starting with _ are the driver's own and not written."""

    seed: int
    run_dir: str
    state: str = "pending"  # pending, running, retrying, done, failed, interrupted
    attempts: int = 0  # attempts started, over every run of the sweep (a resumed sweep counts on)
    pid: int | None = None
    host: str | None = None
    stage: int | None = None
    env_steps: int = 0  # env steps at the end of the last logged episode (from metrics.csv; a lineage's: every
    #                     phase's so far, each phase's metrics.csv counting from 0)
    episodes: int = 0
    best_score: dict = field(default_factory=dict)  # stage ("1"/"2") -> best episode score
    window_score: float | None = None  # mean score over the trainer's score window, last episode
    wall_s: float = 0.0
    errors: list = field(default_factory=list)  # one line per failed attempt
    _started: float = 0.0  # monotonic clock at the start of the current attempt
    _started_wall: float = 0.0  # wall clock, to recognise this attempt's sweep_attempt.json
    _tries: int = 0  # attempts in this run of the sweep (the retry budget is per run)
    _csv: dict = field(default_factory=dict)  # incremental reader state of metrics.csv
    _phases: tuple = ()  # a lineage's phase names, read once: the driver reads metrics every poll

    def public(self) -> dict:
        return {k: v for k, v in asdict(self).items() if not k.startswith("_")}

    def reset_metrics(self) -> None:
        self._csv.clear()
        self.stage, self.env_steps, self.episodes, self.best_score, self.window_score = None, 0, 0, {}, None

    def read_metrics(self) -> None:
        """Steps, episodes and scores from the run's metrics.csv (read incrementally; a resumed run may have
        truncated it, in which case it is read again from the start). In a lineage, the phase training now is
        read, and the env steps of the phases before it are added (each phase's metrics.csv counts from 0)."""
        if not self._phases:
            self._phases = C.phase_names(self.run_dir)
        run = C.current_run(self.run_dir, self._phases)
        path = run / "metrics.csv"
        try:
            size = path.stat().st_size
        except OSError:
            size = -1
        st = self._csv
        if st and st["run"] != run:  # the lineage moved on to its next phase: its scores stay, its steps add up
            st.update(offset=0, header=None, run=run, before=_steps_before(Path(self.run_dir), run, self._phases))
        elif size < st.get("offset", 0) or not st:
            self.reset_metrics()
            st.update(offset=0, header=None, run=run, before=_steps_before(Path(self.run_dir), run, self._phases))
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
                self.env_steps, self.stage = st["before"] + int(cells[h["env_steps"]]), stage
                self.episodes = int(cells[h["episode"]])
                self.window_score = float(cells[h["window_mean_score"]])
            except (KeyError, IndexError, ValueError):
                continue
            key = str(stage)
            self.best_score[key] = max(self.best_score.get(key, -float("inf")), score)


def _steps_before(run_dir: Path, run: Path, phases: tuple[str, ...]) -> int:
    """Env steps of a lineage's phases (their names in order) before `run` (the last logged episode of each
    phase's metrics.csv); 0 for a run that is not a lineage's phase."""
    total = 0
    for name in phases:
        if run_dir / name == run:
            break
        total += _last_env_steps(run_dir / name / "metrics.csv")
    return total


def _last_env_steps(path: Path) -> int:
    """The env_steps of a metrics.csv's last complete row; 0 without one."""
    try:
        lines = path.read_text(errors="replace").split("\n")[:-1]  # complete rows only
    except OSError:
        return 0
    header = lines[0].split(",") if lines else []
    if "env_steps" not in header:
        return 0
    column = header.index("env_steps")
    for line in reversed(lines[1:]):
        try:
            return int(line.split(",")[column])
        except (IndexError, ValueError):
            continue
    return 0


def seed_statuses(sweep_dir: Path, spec: SweepSpec) -> dict[int, SeedStatus]:
    """Every seed's status at the start of a run of the sweep: done seeds (with their final actor) stay done,
    attempts and errors count on from sweep_status.json, metrics are read back. Refuses a seed whose training
    process is still alive (a previous driver was killed but its child was not)."""
    previous = load_previous_status(sweep_dir)
    seeds: dict[int, SeedStatus] = {}
    for s in spec.seeds:
        run_dir = seed_dir(sweep_dir, s)
        st = SeedStatus(seed=s, run_dir=str(run_dir))
        prev = previous.get(s, {})
        st.attempts, st.errors = int(prev.get("attempts", 0)), list(prev.get("errors", []))
        if prev.get("state") == "done" and final_actor_file(sweep_dir, spec, s).is_file():
            st.state, st.wall_s = "done", float(prev.get("wall_s", 0.0))
        elif process_alive(read_attempt(run_dir), run_dir.resolve()):
            raise SweepError(f"seed {s} is still being trained by process {read_attempt(run_dir)['pid']} "
                             f"(a previous sweep driver was killed?); stop it before resuming {sweep_dir}")
        st.read_metrics()
        seeds[s] = st
    return seeds


def format_eta(seconds: float) -> str:
    """h:mm:ss, or ? when unknown (no rate yet)."""
    if not seconds == seconds or seconds == float("inf"):
        return "?"
    seconds = int(seconds)
    return f"{seconds // 3600}:{seconds // 60 % 60:02d}:{seconds % 60:02d}"


class SweepStatus:
    """The seeds of one run of the sweep driver, and what is written to sweep_status.json and the log."""

    def __init__(self, sweep_dir: Path, seeds: dict[int, SeedStatus], budget: int, info: dict):
        self.sweep_dir, self.seeds, self.budget, self.info = sweep_dir, seeds, budget, info
        self.t_start = self.last_write = time.monotonic()
        self.steps0 = self.steps_done()  # done before this run: not counted in the rate

    def steps_done(self) -> int:
        """Env steps of every seed, a done seed counting its full budget."""
        return sum(self.budget if st.state == "done" else min(st.env_steps, self.budget)
                   for st in self.seeds.values())

    def count(self, state: str) -> int:
        return sum(st.state == state for st in self.seeds.values())

    def write(self, final: bool = False) -> dict:
        data = {**self.info, "updated": time.strftime("%Y-%m-%d %H:%M:%S"), "finished": final,
                "elapsed_s": round(time.monotonic() - self.t_start, 1), "counts": {k: self.count(k) for k in STATES},
                "seeds": [st.public() for st in self.seeds.values()]}
        write_json(self.sweep_dir / STATUS_FILE, data)
        self.last_write = time.monotonic()
        return data

    def postfix(self) -> str:
        """The progress bar's suffix."""
        return (f"done {self.count('done')}/{len(self.seeds)} running {self.count('running')} "
                f"failed {self.count('failed')}")

    def one_line(self) -> str:
        """The periodic log line: counts, env steps, rate, ETA and every seed's stage, steps and best score."""
        done_steps, total = self.steps_done(), self.budget * len(self.seeds)
        el = time.monotonic() - self.t_start
        rate = max(0.0, (done_steps - self.steps0) / el) if el > 0 else 0.0
        eta = (total - done_steps) / rate if rate > 0 else float("nan")
        per_seed = " | ".join(f"seed{st.seed} {st.state} s{st.stage or '-'} {st.env_steps} steps"
                              + (f" best {st.best_score[str(st.stage)]:.3g}" if str(st.stage) in st.best_score
                                 else "") for st in self.seeds.values())
        return (f"sweep: {self.count('done')}/{len(self.seeds)} done, {self.count('running')} running, "
                f"{self.count('failed')} failed; {done_steps}/{total} env steps, {rate:.0f} step/s, "
                f"ETA {format_eta(eta)}; {per_seed}")


__all__ = ["STATES", "SeedStatus", "SweepStatus", "format_eta", "seed_statuses"]
