"""Graceful stop of a training: SIGINT (Ctrl-C) and SIGTERM (what a cluster scheduler sends) end it at the
next safe point, within an update of the signal: the batch in hand is stored and logged, the updates it
still owes are kept as a credit that the resume pays first, and a checkpoint holds every env step logged, so
that `train.py --resume` loses nothing.

The trainer's process catches the signals (`StopSignals`); processes that only step envs for it ignore them
(`ignore_stop_signals`), so that a Ctrl-C in the terminal, which reaches the whole process group, does not
kill them under the trainer before it has saved. A second signal stops at once (KeyboardInterrupt), with
nothing saved since the last checkpoint.
"""
from __future__ import annotations

import multiprocessing
import signal
import threading

STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM)
EXIT_CODES = {signal.SIGINT: 130, signal.SIGTERM: 143}  # 128 + the signal's number, as a shell reports it


class TrainingInterrupted(Exception):
    """The training stopped on a signal at a safe point, after writing its checkpoint."""

    def __init__(self, signum: int, env_steps: int, checkpoint) -> None:
        self.signum, self.env_steps, self.checkpoint = signum, env_steps, checkpoint
        super().__init__(f"stopped by {signal.Signals(signum).name} after {env_steps} env steps; checkpoint "
                         f"{checkpoint} holds every step logged")

    @property
    def exit_code(self) -> int:
        return EXIT_CODES.get(self.signum, 1)


class StopSignals:
    """Within `with StopSignals() as stop:`, SIGINT and SIGTERM set `stop.signum` (the first one) instead of
    ending the process; a second one raises KeyboardInterrupt. Outside the main thread it does nothing (Python
    delivers signals to the main thread only)."""

    def __init__(self) -> None:
        self.signum: int | None = None
        self._previous: dict = {}

    def _handle(self, signum, frame) -> None:
        if self.signum is not None:  # the second signal: stop now
            raise KeyboardInterrupt
        self.signum = signum
        print(f"\n{signal.Signals(signum).name}: stopping at the next safe point (after the update in hand) with a "
              f"checkpoint; send it again to stop at once", flush=True)

    def __enter__(self) -> "StopSignals":
        if threading.current_thread() is threading.main_thread():
            for s in STOP_SIGNALS:
                self._previous[s] = signal.signal(s, self._handle)
        return self

    def __exit__(self, *exc) -> None:
        for s, handler in self._previous.items():
            signal.signal(s, handler)
        self._previous.clear()


def ignore_stop_signals() -> None:
    """In a process started by the trainer (an env worker): leave SIGINT and SIGTERM to the trainer, which
    stops the workers itself once it has saved. Does nothing in the main process."""
    if multiprocessing.parent_process() is not None:
        for s in STOP_SIGNALS:
            signal.signal(s, signal.SIG_IGN)


__all__ = ["EXIT_CODES", "StopSignals", "TrainingInterrupted", "ignore_stop_signals"]
