"""Per-episode metrics to a CSV file and TensorBoard scalars, both resumable; TorchRL's console lines in
colour only on a terminal."""
from __future__ import annotations

import csv
import logging
import os
import re
import warnings
from pathlib import Path

from cyberdog.config import REWARD_TERM_NAMES

COLUMNS = (("stage", "episode", "stage_episode", "env_steps", "length", "score")
           + tuple(f"reward_{n}" for n in REWARD_TERM_NAMES)
           + ("energy_J", "mean_speed", "window_mean_score", "actor_loss", "critic_loss", "q_mean", "q_max",
              "updates", "env_steps_per_s", "updates_per_s", "wall_time_s",
              "fell", "prior_weight"))  # 1 if the episode ended in a fall; the trot prior's mean weight in it
TIMING_COLUMNS = ("env_steps_per_s", "updates_per_s", "wall_time_s")  # differ between identical reruns


ANSI_ESCAPE = re.compile(r"\x1b\[[0-9;]*[A-Za-z]")  # terminal colour and cursor codes


class _ColourOnTerminal(logging.Formatter):
    """TorchRL's own console format, with its colour codes removed unless the stream is a terminal: a
    train.log or a redirected stdout gets plain text (NO_COLOR, https://no-color.org, removes them always)."""

    def __init__(self, coloured: logging.Formatter, stream):
        super().__init__()
        self.coloured, self.stream = coloured, stream

    def format(self, record: logging.LogRecord) -> str:
        text = self.coloured.format(record)
        try:
            terminal = self.stream.isatty() and not os.environ.get("NO_COLOR")
        except (AttributeError, ValueError):  # a closed or file-less stream
            terminal = False
        return text if terminal else ANSI_ESCAPE.sub("", text)


def quiet_plain_torchrl_log() -> None:
    """TorchRL's log as a training run prints it. TorchRL logs at INFO to stdout (e.g. each replay buffer's storage
    allocation), which the run's own progress lines need not carry: its logger says warnings only, unless
    TorchRL's own variable RL_LOGGING_LEVEL asks for more. And the formatter of its console handler (installed
    when torchrl is imported; it colours every line with ANSI codes whatever the stream) is wrapped in
    `_ColourOnTerminal`. Idempotent."""
    import torchrl  # noqa: F401  the "torchrl" logger and its handler are created by this import

    log = logging.getLogger("torchrl")
    if "RL_LOGGING_LEVEL" not in os.environ:
        log.setLevel(logging.WARNING)
    for handler in log.handlers:
        if handler.formatter is not None and not isinstance(handler.formatter, _ColourOnTerminal):
            handler.setFormatter(_ColourOnTerminal(handler.formatter, getattr(handler, "stream", None)))


quiet_plain_torchrl_log()  # every training process (train.py, a sweep's seed) imports this module


class EpisodeLogger:
    """Appends one row per finished episode to `metrics.csv` and mirrors it to TensorBoard (`tb/`).

    On resume the CSV is cut back to the `rows` the checkpoint knew of, and TensorBoard events after the
    checkpoint's step are purged, so a killed and resumed run logs every episode exactly once. A CSV that
    lost rows the checkpoint knew of (cut, emptied or deleted) keeps its complete rows, drops a partial last
    line, warns which episodes are lost, and logging goes on after them.
    """

    def __init__(self, run_dir: Path, rows: int = 0, purge_step: int | None = None, tensorboard: bool = True):
        self.path = Path(run_dir) / "metrics.csv"
        self.rows = rows
        if purge_step is not None:
            self._cut(rows)
        new = not self.path.exists() or self.path.stat().st_size == 0
        self.file = open(self.path, "a", newline="")
        self.writer = csv.DictWriter(self.file, fieldnames=COLUMNS)
        if new:
            self.writer.writeheader()
            self.file.flush()
        self.tb = None
        if tensorboard:
            from torch.utils.tensorboard import SummaryWriter
            self.tb = SummaryWriter(str(Path(run_dir) / "tb"), purge_step=purge_step)

    def _cut(self, rows: int) -> None:
        """Keep the header and the first `rows` complete rows (atomically)."""
        if not self.path.exists():
            if rows:
                warnings.warn(f"{self.path} is missing: the {rows} episodes logged before the checkpoint are lost; "
                              f"a new file is started", RuntimeWarning, stacklevel=3)
                self.rows = 0
            return
        lines = self.path.read_bytes().split(b"\n")[:-1]  # complete lines; a partial last line is dropped
        header = ",".join(COLUMNS).encode()
        older = lines[0].rstrip(b"\r").split(b",") if lines else []
        if lines and older != header.split(b",") and older == header.split(b",")[:len(older)]:
            # a run logged by a version with fewer columns: they are appended, empty in its first rows
            missing = b"," * (len(COLUMNS) - len(older))
            lines = [header] + [line.rstrip(b"\r") + missing for line in lines[1:]]
        if lines and lines[0].rstrip(b"\r") != header:
            raise ValueError(f"{self.path}: its first line is not the metrics header this code writes (a file of "
                             f"another version, or damaged); move it aside to resume with a new one")
        kept = lines[:rows + 1]
        if len(kept) < rows + 1:
            have = max(0, len(kept) - 1)
            warnings.warn(f"{self.path} was cut: it holds {have} complete rows but the checkpoint logged {rows} "
                          f"episodes; rows {have + 1}-{rows} are lost, and logging goes on after row {have}",
                          RuntimeWarning, stacklevel=3)
            self.rows = have
        tmp = self.path.with_name(f".{self.path.name}.tmp")
        tmp.write_bytes(b"".join(line + b"\n" for line in kept))
        os.replace(tmp, self.path)

    def log(self, row: dict) -> None:
        self.writer.writerow({k: row.get(k, "") for k in COLUMNS})
        self.file.flush()
        self.rows += 1
        if self.tb is not None:
            step = int(row["env_steps"])
            for k in COLUMNS[4:]:
                v = row.get(k)
                if isinstance(v, (int, float)) and v == v:  # skip NaN (no update yet)
                    self.tb.add_scalar(f"stage{row['stage']}/{k}", v, step)

    def flush(self) -> None:
        self.file.flush()
        if self.tb is not None:
            self.tb.flush()

    def close(self) -> None:
        self.file.close()
        if self.tb is not None:
            self.tb.close()
