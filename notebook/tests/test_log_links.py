"""Every relative link of the log's pages (notebook/*.md), and every link of the product's pages into the log, reaches
a file, and every anchor a heading of that file: the product's rule (tests/test_doc_links.py), which leaves the
product's links into the log out."""
from __future__ import annotations

import importlib.util
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
PAGES = sorted(ROOT.glob("notebook/*.md"))

_spec = importlib.util.spec_from_file_location("product_doc_links", ROOT / "tests" / "test_doc_links.py")
_links = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(_links)


def test_the_log_has_pages():
    assert len(PAGES) > 1


@pytest.mark.parametrize("page", PAGES + _links.PAGES, ids=lambda p: str(p.relative_to(ROOT)))
def test_every_relative_link_and_anchor_resolves(page):
    assert _links.broken_links(page) == []
