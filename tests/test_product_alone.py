"""The product stands without the research log: no text file of the package, tests, configs, tools, benchmarks,
plots or shipped results names a file under the log's folder, or a path that leaves the repository (a relative path
climbing out of it, or the folder outside it that once held the robot's parameters, now docs/robot.md)."""
from __future__ import annotations

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PRODUCT = ("cyberdog", "tests", "configs", "tools", "bench", "plots", "results")
TEXT = {".py", ".yaml", ".md", ".json", ".cfg", ".toml"}
LOG = re.compile(r"(?<![\w.-])notebook/")
OUTSIDE = re.compile(r"(?<![\w.-])shared/robot\b")
CLIMB = re.compile(r"(?<![\w.])(?:\.\./)+[^\s`'\")\]]*")  # ../x, ../../y: a path relative to somewhere, upwards


def product_files() -> list[Path]:
    return sorted(p for top in PRODUCT for p in (ROOT / top).rglob("*")
                  if p.is_file() and p.suffix in TEXT and "__pycache__" not in p.parts
                  and p != Path(__file__).resolve())


def offences(text: str, file: Path) -> list[str]:
    """What `text` (the content of `file`) names outside the product. A Markdown page's relative path is resolved
    from the page's folder, as its links are, and so is a preset's (its `base:`, a path beside the file); elsewhere
    a path is relative to the repository root (or the working folder), so any path that climbs leaves the
    repository."""
    found = [f"names the log: {m.group(0)}..." for m in LOG.finditer(text)]
    found += [f"names a folder outside the repository: {m.group(0)}" for m in OUTSIDE.finditer(text)]
    for m in CLIMB.finditer(text):
        from_folder = file.suffix == ".md" or (file.suffix == ".yaml" and file.is_relative_to(ROOT / "configs"))
        inside = from_folder and (file.parent / m.group(0)).resolve().is_relative_to(ROOT)
        if not inside:
            found.append(f"a path out of the repository: {m.group(0)}")
    return found


def test_the_rule_finds_the_log_and_paths_out_and_keeps_links_inside():
    page, code = ROOT / "results" / "README.md", ROOT / "cyberdog" / "x.py"
    assert offences("[table](../docs/results.md#table-5) and runs/notebook_like/x", page) == []
    assert offences("see `notebook/configs/quick.yaml`", code) == ["names the log: notebook/..."]
    assert len(offences("sources: `../shared/robot/cyberdog1_parameters.yaml`", code)) == 2  # climbs and outside
    assert offences("(measured, `shared/robot/NOTES.md`)", code) == [
        "names a folder outside the repository: shared/robot"]
    assert offences("[x](../../elsewhere.md)", page) == ["a path out of the repository: ../../elsewhere.md"]
    assert offences("open('../docs/robot.md')", code) == ["a path out of the repository: ../docs/robot.md"]
    assert offences(".../<recipe>/seed<N>", code) == []  # an ellipsis, not a path
    preset = ROOT / "configs" / "candidates" / "x.yaml"
    assert offences("base: ../battery.yaml", preset) == []  # beside the preset's folder, inside configs/
    assert offences("base: ../../../x.yaml", preset) == ["a path out of the repository: ../../../x.yaml"]


def test_there_is_a_product_to_check():
    files = product_files()
    assert len(files) > 100 and ROOT / "results" / "README.md" in files


@pytest.mark.parametrize("top", PRODUCT)
def test_no_product_file_names_the_log_or_a_file_outside_the_repository(top):
    bad = {str(p.relative_to(ROOT)): found for p in product_files() if p.parts[len(ROOT.parts)] == top
           for found in [offences(p.read_text(errors="replace"), p)] if found}
    assert bad == {}
