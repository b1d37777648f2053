"""Per-episode metrics to a CSV file and TensorBoard scalars, both resumable."""
from __future__ import annotations

import csv
import os
import warnings
from pathlib import Path

from cyberdog.config import REWARD_TERM_NAMES

COLUMNS = (("stage", "episode", "stage_episode", "env_steps", "length", "score")
           + tuple(f"reward_{n}" for n in REWARD_TERM_NAMES)
           + ("energy_J", "mean_speed", "window_mean_score", "actor_loss", "critic_loss", "q_mean", "q_max",
              "updates", "env_steps_per_s", "updates_per_s", "wall_time_s"))
TIMING_COLUMNS = ("env_steps_per_s", "updates_per_s", "wall_time_s")  # differ between identical reruns


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
