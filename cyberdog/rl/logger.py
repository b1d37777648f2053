"""Per-episode metrics to a CSV file and TensorBoard scalars, both resumable."""
from __future__ import annotations

import csv
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
    checkpoint's step are purged, so a killed and resumed run logs every episode exactly once.
    """

    def __init__(self, run_dir: Path, rows: int = 0, purge_step: int | None = None, tensorboard: bool = True):
        self.path = Path(run_dir) / "metrics.csv"
        self.rows = rows
        if purge_step is not None and self.path.exists():
            lines = self.path.read_text().splitlines(keepends=True)
            self.path.write_text("".join(lines[:rows + 1]))
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
