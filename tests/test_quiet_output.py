"""What the two command lines print: no PyBullet banner or per-connection lines, no terminal colour codes in a
log file, and a last line that names the output folder; PyBullet's other lines still come through."""
from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from cyberdog.sim.quiet import quiet_pybullet

ROOT = Path(__file__).resolve().parents[1]
NOISE = ("pybullet build time", "argv[0]=")


def run(*args, cwd=ROOT) -> subprocess.CompletedProcess:
    env = {**os.environ, "PYTHONUNBUFFERED": "1"}
    env.pop("NO_COLOR", None)
    return subprocess.run([sys.executable, *map(str, args)], cwd=cwd, env=env, capture_output=True, text=True,
                          timeout=600)


def assert_quiet(proc: subprocess.CompletedProcess) -> None:
    text = proc.stdout + proc.stderr
    assert proc.returncode == 0, text[-2000:]
    for noise in NOISE:
        assert noise not in text, f"{noise!r} printed:\n{text[-2000:]}"


def test_only_pybullets_own_lines_are_dropped_at_the_file_descriptors(capfd):
    with quiet_pybullet():  # written as the C code writes: straight to descriptors 1 and 2
        os.write(1, b"argv[0]=\nsolver: 10 iterations\n")
        os.write(2, b"pybullet build time: Jan 29 2025\nb3Warning: no inertia\n")
    out, err = capfd.readouterr()
    assert out == "solver: 10 iterations\n"
    assert err == "b3Warning: no inertia\n"
    os.write(1, b"argv[0]=\n")  # outside the block nothing is filtered
    assert capfd.readouterr().out == "argv[0]=\n"


def test_help_imports_no_simulator():
    code = ("import sys, evaluate\n"
            "try:\n    evaluate.main(['baselines', '--help'])\nexcept SystemExit:\n    pass\n"
            "print('pybullet' in sys.modules, 'torch' in sys.modules)")
    proc = run("-c", code)
    assert_quiet(proc)
    assert proc.stdout.strip().splitlines()[-1] == "False False"


def test_an_evaluation_with_walk_workers_prints_no_pybullet_lines_and_ends_with_its_folder(tmp_path):
    """`compare` walks in two spawned worker processes: each imports pybullet and connects."""
    from test_evaluate import FAST, learned_file

    out = tmp_path / "out"
    proc = run(ROOT / "evaluate.py", "compare", "--learned", learned_file(tmp_path / "learned.json"),
               "--speeds", "1.0", "--duration", "0.5", "--workers", "2", "--no-reference", "--out", out, *FAST)
    assert_quiet(proc)
    assert "[1/5]" in proc.stdout  # the walks ran (in the workers)
    assert proc.stdout.rstrip().splitlines()[-1] == f"output folder: {out}/"


@pytest.mark.parametrize("torchrl_level", [None, "INFO"])
def test_a_training_log_file_has_no_colour_codes_and_ends_with_the_run_folder(tmp_path, torchrl_level):
    """As a sweep writes train.log: train.py's stdout and stderr into a file, not a terminal. TorchRL's INFO lines
    (a replay buffer's allocation) are left out unless its RL_LOGGING_LEVEL asks for them, and then in plain text."""
    run_dir = tmp_path / "run"
    log = tmp_path / "train.log"
    env = {k: v for k, v in os.environ.items() if k != "RL_LOGGING_LEVEL"}
    with open(log, "w") as f:
        proc = subprocess.run([sys.executable, str(ROOT / "train.py"), "--config", str(ROOT / "configs/tiny.yaml"),
                               "--stage", "1", "--run-dir", str(run_dir), "--no-progress"], cwd=ROOT, stdout=f,
                              stderr=subprocess.STDOUT, timeout=600,
                              env=env if torchrl_level is None else {**env, "RL_LOGGING_LEVEL": torchrl_level})
    text = log.read_text()
    assert proc.returncode == 0, text[-2000:]
    assert ("[torchrl][INFO]" in text) == (torchrl_level == "INFO")
    assert "\x1b[" not in text
    assert not any(noise in text for noise in NOISE)
    assert text.rstrip().splitlines()[-1] == f"run folder: {run_dir}/"
