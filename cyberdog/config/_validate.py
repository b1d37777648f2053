"""Validation helpers shared by the config dataclasses: clear errors naming the field and the allowed range."""
from __future__ import annotations

import math
from typing import Any


def _check(cond: bool, name: str, rule: str, value: Any) -> None:
    if not cond:
        raise ValueError(f"{name} must be {rule}, got {value!r}")


def _positive(obj: Any, *names: str) -> None:
    for n in names:
        v = getattr(obj, n)
        _check(v > 0 and math.isfinite(v), f"{type(obj).__name__}.{n}", "> 0 and finite", v)


def _non_negative(obj: Any, *names: str) -> None:
    for n in names:
        v = getattr(obj, n)
        _check(v >= 0 and math.isfinite(v), f"{type(obj).__name__}.{n}", ">= 0 and finite", v)
