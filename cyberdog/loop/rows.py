"""The walker's records: rows appended at the physics rate, read per physics step or per controller period."""
from __future__ import annotations

import numpy as np


class Rows:
    """A growing (n, *shape) float array. Rows appended (`append`, `extend`: lists or arrays) wait in a list
    and are copied into the array in one call when read or when `FLUSH` of them wait: appending at the physics
    rate then costs a list append."""

    FLUSH = 256  # rows waiting at most

    def __init__(self, shape: tuple, dtype=float, capacity: int = 1024) -> None:
        self.data = np.zeros((capacity, *shape), dtype=dtype)
        self._n = 0  # rows in `data`
        self._waiting: list = []

    @property
    def n(self) -> int:
        """Rows appended."""
        return self._n + len(self._waiting)

    def append(self, row) -> None:
        self._waiting.append(row)
        if len(self._waiting) >= self.FLUSH:
            self._flush()

    def extend(self, rows: list) -> None:
        self._waiting.extend(rows)
        if len(self._waiting) >= self.FLUSH:
            self._flush()

    def _flush(self) -> None:
        rows, self._waiting = self._waiting, []
        end = self._n + len(rows)
        while end > len(self.data):
            self.data = np.concatenate([self.data, np.zeros_like(self.data)])
        self.data[self._n:end] = rows
        self._n = end

    def view(self, start: int = 0) -> np.ndarray:
        if self._waiting:
            self._flush()
        return self.data[start:self._n]


class PeriodMean:
    """Per controller period, the mean of `substeps` consecutive physics-step rows (the motor torque applied
    over each period): `view(start)` is (periods − start, 12) from period `start` on."""

    def __init__(self, rows: Rows, substeps: int) -> None:
        self.rows, self.substeps = rows, substeps

    def view(self, start: int = 0) -> np.ndarray:
        n = self.substeps
        physics = self.rows.view(start * n)
        return physics.reshape(-1, n, *physics.shape[1:]).mean(axis=1)


class PeriodEnds:
    """Per controller period, the physics-step row at its end, after a first row at the reset (the joint angles):
    `view(start)` is (periods − start + 1, 12), the start of period `start` first."""

    def __init__(self, rows: Rows, substeps: int) -> None:
        self.rows, self.substeps = rows, substeps

    def view(self, start: int = 0) -> np.ndarray:
        return self.rows.view(start * self.substeps)[::self.substeps]
