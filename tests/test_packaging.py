"""An installed package is complete: every module of the source tree and the robot's URDF are in the wheel,
and the URDF is found through the package, not through a checkout's folders."""
from __future__ import annotations

import os
import shutil
import subprocess
import sys
import sysconfig
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


def build_wheel(tmp_path: Path) -> Path:
    """The wheel, built from a copy of the source tree: an in-tree build would reuse build/lib, where modules
    that were moved or deleted since the last build linger and would be packed too."""
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
    return wheels[0]


def test_the_wheel_holds_every_module_and_the_urdf(tmp_path):
    with zipfile.ZipFile(build_wheel(tmp_path)) as whl:
        names = set(whl.namelist())
        missing = sorted(source_modules() - names)
        assert missing == [], f"modules left out of the wheel: {missing}"
        assert SHIPPED_URDF in names
        assert whl.read(SHIPPED_URDF) == (ROOT / SHIPPED_URDF).read_bytes()
    top = {n.split("/")[0] for n in names}
    assert {t for t in top if not t.endswith(".dist-info")} == {"cyberdog"}, top


@pytest.mark.slow
def test_an_installed_wheel_trains_a_sweep_and_aggregates_it(tmp_path):
    """The package on its own: the wheel installed (not editable) in a fresh virtual environment, run from a
    folder outside the checkout, trains a two-seed sweep of the tiny preset through `python -m cyberdog.train_cli`
    (each seed a process of that entry point) and aggregates it, with no top-level script or `plots/`."""
    wheel = build_wheel(tmp_path)
    venv = tmp_path / "venv"
    subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(venv)], check=True)
    py = venv / "bin" / "python"
    site = subprocess.run([py, "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
                          capture_output=True, text=True, check=True).stdout.strip()
    # the dependencies (torch, PyBullet, ...) from this environment, without its editable cyberdog: a plain path
    # in a .pth is put on sys.path, but the .pth files inside it (the editable finder) are not read
    deps = {sysconfig.get_paths()[k] for k in ("purelib", "platlib")}
    Path(site, "dependencies.pth").write_text("\n".join(sorted(deps)) + "\n")
    install = subprocess.run([sys.executable, "-m", "pip", "--python", str(py), "install", "--no-deps", "--no-index",
                              "-q", str(wheel)], capture_output=True, text=True)
    assert install.returncode == 0, install.stdout[-2000:] + install.stderr[-2000:]
    work = tmp_path / "elsewhere"
    work.mkdir()
    shutil.copy(ROOT / "configs" / "tiny.yaml", work / "tiny.yaml")
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    where = subprocess.run([py, "-c", "import cyberdog; print(cyberdog.__file__)"], cwd=work, env=env,
                           capture_output=True, text=True, check=True).stdout.strip()
    assert Path(where).is_relative_to(venv) and not Path(where).is_relative_to(ROOT), where
    sweep = subprocess.run([py, "-m", "cyberdog.train_cli", "--config", "tiny.yaml", "--seeds", "0-1", "--run-dir",
                            "sweep", "--workers", "2", "--no-progress", "--eval-duration", "0.5"], cwd=work, env=env,
                           capture_output=True, text=True, timeout=600)
    assert sweep.returncode == 0, sweep.stdout[-3000:] + sweep.stderr[-3000:]
    for seed in (0, 1):
        log = (work / "sweep" / f"seed{seed}" / "train.log").read_text()
        assert "-m cyberdog.train_cli" in log and (work / "sweep" / f"seed{seed}" / "stage2_final_actor.pt").is_file()
    assert (work / "sweep" / "learning_curves.csv").is_file() and (work / "sweep" / "aggregate.md").is_file()
    assert not (work / "sweep" / "learning_curves.png").exists()  # drawn by the checkout's plots/, not here
    again = subprocess.run([py, "-m", "cyberdog.train_cli", "--aggregate", "sweep", "--eval-duration", "0"], cwd=work,
                           env=env, capture_output=True, text=True, timeout=300)
    assert again.returncode == 0 and "# Sweep sweep: 2 seeds" in again.stdout, again.stdout[-2000:] + again.stderr
