"""Every relative link of the project's pages (README, docs/, results/) reaches a file, and every anchor a heading of
that file (as GitHub names a heading's anchor): text moved between pages must not leave a link behind. Links into the
research log, which the product does not need and a copy of it may lack, are checked by the log's own tests."""
from __future__ import annotations

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PAGES = sorted([ROOT / "README.md", ROOT / "results" / "README.md", *ROOT.glob("docs/*.md")])
LINK = re.compile(r"\]\(([^)\s]+)\)")
LOG = ROOT / "notebook"  # the research log's folder


def anchors(page: Path) -> set[str]:
    """GitHub's anchors of a Markdown page's headings: lower case, punctuation dropped, spaces as hyphens."""
    out = set()
    in_code = False
    for line in page.read_text().splitlines():
        if line.startswith("```"):
            in_code = not in_code
        if in_code or not line.startswith("#"):
            continue
        title = line.lstrip("#").strip().lower()
        out.add(re.sub(r"[^\w\- ]", "", title).replace(" ", "-"))
    return out


def test_the_anchor_rule_drops_punctuation_and_keeps_words(tmp_path):
    page = tmp_path / "p.md"
    page.write_text("# Title\n## The controller's rate\n```\n# not a heading\n```\n## Table 5 (Eq. 7, ideal)\n")
    assert anchors(page) == {"title", "the-controllers-rate", "table-5-eq-7-ideal"}


def broken_links(page: Path, skip: tuple[Path, ...] = ()) -> list[str]:
    """The relative links of `page` that reach no file, or no heading of the file they name; links into a folder of
    `skip` are left out."""
    broken = []
    for target in LINK.findall(page.read_text()):
        if target.startswith(("http://", "https://", "mailto:")):
            continue
        path, _, anchor = target.partition("#")
        file = (page.parent / path).resolve() if path else page
        if any(file.is_relative_to(folder) for folder in skip):
            continue
        if not file.exists():
            broken.append(f"{target}: no file {file}")
        elif anchor and file.suffix == ".md" and anchor not in anchors(file):
            shown = file.relative_to(ROOT) if file.is_relative_to(ROOT) else file
            broken.append(f"{target}: no heading with anchor '{anchor}' in {shown}")
    return broken


def test_a_missing_file_and_a_missing_heading_are_found(tmp_path):
    (tmp_path / "other.md").write_text("# Other page\n")
    page = tmp_path / "page.md"
    page.write_text("# Page\n[a](other.md) [b](other.md#other-page) [c](#page) [d](https://x.org/none.md)\n"
                    "[e](gone.md) [f](other.md#nowhere) [g](#nowhere)\n")
    found = broken_links(page)
    assert len(found) == 3 and [f.split(":")[0] for f in found] == ["gone.md", "other.md#nowhere", "#nowhere"]
    (tmp_path / "log").mkdir()
    page.write_text("# Page\n[a](log/gone.md) [b](gone.md)\n")
    assert [f.split(":")[0] for f in broken_links(page, skip=(tmp_path / "log",))] == ["gone.md"]


@pytest.mark.parametrize("page", PAGES, ids=lambda p: str(p.relative_to(ROOT)))
def test_every_relative_link_and_anchor_resolves(page):
    assert broken_links(page, skip=(LOG,)) == []
