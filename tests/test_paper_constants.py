"""The paper's constants live in cyberdog/config/paper.py only: the experiment modules import them."""
from __future__ import annotations

import ast
import importlib
from pathlib import Path

import numpy as np
import pytest

from cyberdog.config import paper

ROOT = Path(__file__).resolve().parents[1]
CONSTANTS = ("PAPER_SPEEDS", "PAPER_LIFT_HEIGHT", "PAPER_WALK_DURATION", "PAPER_DISTANCE_M", "SPEED_BAND",
             "SPEED_TOLERANCE")
USERS = ("analysis/baselines", "analysis/compare", "analysis/prototype", "core/path_shape", "analysis/shape_search",
         "analysis/extract", "analysis/table5")


def assigned_names(path: Path) -> set[str]:
    """Names bound by a module-level assignment in a source file."""
    names = set()
    for node in ast.parse(path.read_text()).body:
        targets = node.targets if isinstance(node, ast.Assign) else [node.target] if isinstance(
            node, ast.AnnAssign) else []
        names.update(t.id for t in targets if isinstance(t, ast.Name))
    return names


@pytest.mark.parametrize("module", USERS)
def test_experiment_modules_import_the_paper_constants(module):
    path = ROOT / "cyberdog" / f"{module}.py"
    redefined = assigned_names(path) & set(CONSTANTS) - {"SPEED_TOLERANCE"}  # an alias name, checked below
    assert not redefined, f"{path.name} defines {sorted(redefined)}: import them from cyberdog.config.paper"
    mod = importlib.import_module(f"cyberdog.{module.replace('/', '.')}")
    for name in CONSTANTS:
        if hasattr(mod, name):
            expected = paper.SPEED_BAND if name == "SPEED_TOLERANCE" else getattr(paper, name)
            assert getattr(mod, name) is expected, f"cyberdog.{module}.{name} is a copy"
    assert assigned_names(ROOT / "cyberdog" / "config" / "paper.py") >= set(CONSTANTS) - {"SPEED_TOLERANCE"}


def test_speed_band():
    assert paper.speed_within_band(1.04, 1.0) and not paper.speed_within_band(1.06, 1.0)
    assert paper.speed_within_band(0.96, 1.0) and not paper.speed_within_band(0.94, 1.0)
    assert paper.speed_within_band(1.15, 1.0, band=0.2)
    assert type(paper.speed_within_band(np.float64(1.0), np.float64(1.0))) is bool  # JSON-ready
