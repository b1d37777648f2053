"""The sweep folder: its files, what sweep.json says, and the seed folders an attempt starts from.

    sweep.json            what the sweep is: seeds, stages, the original config file and overrides
    sweep_config.yaml     the resolved experiment config every seed trains with (train.seed set per seed)
    sweep_status.json     live status per seed (written by `cyberdog.sweeps.run`)
    seed<N>/              an ordinary run folder of `train.py` (+ train.log, sweep_attempt.json)

Standard library and `cyberdog.config` only.
"""
from __future__ import annotations

import json
import os
import re
import socket
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path

from cyberdog import config as C
from cyberdog.sweeps.process import ATTEMPT_FILE, LOG_FILE, SWEEP_FILE, SweepError

FORMAT, VERSION = "cyberdog-sweep", 1
STATUS_FILE, CONFIG_FILE = "sweep_status.json", "sweep_config.yaml"
LOCK_FILE = ".sweep.lock"
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
    stage: str  # "both", "1", or "phases" (each seed folder is a lineage: phases.yaml, one run folder per phase)
    source_config: str | None  # the config file the sweep was made from (informative; sweep_config.yaml rules)
    overrides: list = field(default_factory=list)
    created: str = ""
    format: str = FORMAT
    version: int = VERSION

    @property
    def last_stage(self) -> int:
        return 1 if self.stage == "1" else 2


def create_sweep(sweep_dir, cfg: C.ExperimentConfig, seeds: list[int], stage: str = "both",
                 source_config=None, overrides=()) -> SweepSpec:
    """Make a new sweep folder (refusing one that exists and is not empty) with sweep.json and sweep_config.yaml."""
    sweep_dir = Path(sweep_dir)
    if stage not in ("both", "1", "phases"):
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
    write_json(sweep_dir / SWEEP_FILE, asdict(spec))
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


def final_actor_file(sweep_dir, spec: SweepSpec, seed: int) -> Path:
    """The actor file a seed of the sweep ends with (a lineage's: its last phase's)."""
    run = seed_dir(sweep_dir, seed)
    if spec.stage == "phases":
        last = C.read_phases(run)[0][-1]
        return run / last.name / f"stage{last.last_stage}_final_actor.pt"
    return run / f"stage{spec.last_stage}_final_actor.pt"


def sweep_budget(sweep_dir, spec: SweepSpec, cfg: C.ExperimentConfig) -> int:
    """Env steps one seed of the sweep runs at most (a lineage: every phase's)."""
    if spec.stage == "phases":
        phases = C.read_phases(seed_dir(sweep_dir, spec.seeds[0]))[0]
        return sum(stage_budget(p.config, p.stage) for p in phases)
    return stage_budget(cfg, spec.stage)


def stage_budget(cfg: C.ExperimentConfig, stage: str) -> int:
    """Env steps one seed runs at most (a stage stops sooner at its stop_score)."""
    total = 0
    for s in ((1, 2) if stage == "both" else (int(stage),)):
        sc = getattr(cfg.train, f"stage{s}")
        total += sc.max_env_steps or sc.max_episodes * cfg.env.max_episode_steps
    return total


def write_json(path: Path, data) -> None:
    """Atomic: readers (the user, a test, another tool) never see a half-written file."""
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    tmp.write_text(json.dumps(data, indent=1, default=str) + "\n")
    os.replace(tmp, path)


# ---- what previous attempts left ------------------------------------------------------------------------------
def load_previous_status(sweep_dir: Path) -> dict:
    try:
        data = json.loads((sweep_dir / STATUS_FILE).read_text())
        return {int(s["seed"]): s for s in data.get("seeds", [])}
    except (OSError, ValueError, KeyError, TypeError):
        return {}


def process_alive(info: dict, run_dir: Path) -> bool:
    """Is the training process recorded in sweep_attempt.json still running on this machine?"""
    if info.get("host") != socket.gethostname() or not info.get("pid"):
        return False
    try:
        cmdline = Path(f"/proc/{int(info['pid'])}/cmdline").read_bytes().replace(b"\0", b" ").decode(errors="replace")
    except OSError:
        return False
    return str(run_dir) in cmdline and ("cyberdog.train_cli" in cmdline or "train.py" in cmdline)


def read_attempt(run_dir: Path) -> dict:
    try:
        return json.loads((run_dir / ATTEMPT_FILE).read_text())
    except (OSError, ValueError):
        return {}


def attempt_args(sweep_dir: Path, spec: SweepSpec, seed: int) -> list[str]:
    """train.py arguments of the next attempt of `seed`: --resume from its checkpoint if it has one, else a fresh
    start (whatever a killed attempt left before its first checkpoint is moved to seed<N>/discarded_<k>/)."""
    run_dir = seed_dir(sweep_dir, seed).resolve()
    if spec.stage == "phases":  # a lineage resumes itself at the phase it reached (cyberdog.lineage)
        return ["--resume", str(run_dir), "--no-progress"]
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


