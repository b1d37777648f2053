"""An installed package is complete: every module of the source tree and the robot's URDF are in the wheel,
and the URDF is found through the package, not through a checkout's folders."""
from __future__ import annotations

import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

from cyberdog.config import ActuatorConfig, RobotConfig, SimConfig
from cyberdog.sim.robot import PACKAGE_DIR, Robot, resolve_path

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "cyberdog"
SHIPPED_URDF = "cyberdog/urdf/cyberdog.urdf"
# what `setup.cfg` reads to build (long_description = file: README.md; the license file is picked up too)
BUILD_INPUTS = ("setup.cfg", "pyproject.toml", "README.md", "LICENSE")


def source_modules() -> set[str]:
    return {p.relative_to(ROOT).as_posix() for p in PACKAGE.rglob("*.py") if "__pycache__" not in p.parts}


def test_every_folder_of_modules_is_a_package():
    """`packages = find:` only finds folders with an __init__.py; one without is silently left out of a wheel."""
    folders = {p.parent for p in PACKAGE.rglob("*.py") if "__pycache__" not in p.parts}
    assert sorted(str(f.relative_to(ROOT)) for f in folders if not (f / "__init__.py").is_file()) == []


def test_the_urdf_is_found_through_the_package():
    default = RobotConfig().urdf
    assert not Path(default).is_absolute()
    assert resolve_path(default) == PACKAGE_DIR / default
    assert (ROOT / SHIPPED_URDF).is_file() and resolve_path(default) == (ROOT / SHIPPED_URDF).resolve()
    # the checkout's top-level urdf/ shows the same file (a link into the package)
    assert (ROOT / default).resolve() == (ROOT / SHIPPED_URDF).resolve()
    absolute = (ROOT / SHIPPED_URDF).resolve()
    assert resolve_path(str(absolute)) == absolute
    with pytest.raises(FileNotFoundError, match="RobotConfig.urdf = 'urdf/nothing.urdf'"):
        Robot(RobotConfig(urdf="urdf/nothing.urdf"), ActuatorConfig(), SimConfig())


def test_the_wheel_holds_every_module_and_the_urdf(tmp_path):
    """Built from a copy of the source tree: an in-tree build would reuse build/lib, where modules that were
    moved or deleted since the last build linger and would be packed too."""
    src = tmp_path / "src"
    shutil.copytree(PACKAGE, src / "cyberdog", ignore=shutil.ignore_patterns("__pycache__", "*.pyc"))
    for name in BUILD_INPUTS:
        shutil.copy(ROOT / name, src / name)
    # no build isolation: the build uses this environment's setuptools, so the test needs no package index
    out = subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation", "-q",
                          str(src), "-w", str(tmp_path / "dist")], capture_output=True, text=True)
    assert out.returncode == 0, out.stdout[-3000:] + out.stderr[-3000:]
    wheels = list((tmp_path / "dist").glob("cyberdog-*.whl"))
    assert len(wheels) == 1, wheels
    with zipfile.ZipFile(wheels[0]) as whl:
        names = set(whl.namelist())
        missing = sorted(source_modules() - names)
        assert missing == [], f"modules left out of the wheel: {missing}"
        assert SHIPPED_URDF in names
        assert whl.read(SHIPPED_URDF) == (ROOT / SHIPPED_URDF).read_bytes()
    top = {n.split("/")[0] for n in names}
    assert {t for t in top if not t.endswith(".dist-info")} == {"cyberdog"}, top
