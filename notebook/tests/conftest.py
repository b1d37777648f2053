"""The log's tests (its study scripts, notebook/tools/, and the search's presets, notebook/configs/), run apart from
the product's: `python -m pytest -q notebook/tests` (the product's `pytest -q` collects tests/ only).

The builders they share are the product's (tests/conftest.py), loaded here under another name so that
`from conftest import ...` in these modules finds them.
"""
from __future__ import annotations

import importlib.util
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]

_spec = importlib.util.spec_from_file_location("product_conftest", ROOT / "tests" / "conftest.py")
_product = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(_product)

assert_made_by = _product.assert_made_by
walk_config = _product.walk_config
