"""Seeds at scale: `train.py --seeds`, both backends, a SIGKILLed seed resumed from its checkpoint, aggregation.

Every sweep here trains 2 seeds of configs/tiny.yaml, shortened to 100 + 50 env steps; the test of each backend
kills the training process of seed 1 (a real SIGKILL) after its first checkpoint and expects the sweep to finish
it with `--resume`. Ray runs on one local instance with 2 CPUs shared by the module.
"""
from __future__ import annotations

import ast
import csv
import importlib.util
import json
import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest

from cyberdog import config as C
from cyberdog.analysis.stats import mean_ci
from cyberdog.rl.checkpoint import load_checkpoint
from cyberdog.sweeps import (STATUS_FILE, SweepError, create_sweep, load_sweep, parse_seeds, run_sweep,
                             stage_budget)
from cyberdog.sweeps.aggregate import aggregate_sweep, learning_curves, stage_curves
from plots.learning_curves import learning_curves as draw_learning_curves

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "cyberdog"
TINY = ROOT / "configs/tiny.yaml"
SHORT = ["train.stage1.max_env_steps=100", "train.stage2.max_env_steps=50", "train.checkpoint_every=50",
         "train.init_random_frames=50"]
BUDGET = 150


def sweep_args(sweep_dir: Path, *extra: str) -> list[str]:
    return ["--config", str(TINY), "--seeds", "0-1", "--run-dir", str(sweep_dir), "--no-progress",
            *[a for s in SHORT for a in ("--set", s)], *extra]


def load_train_cli():
    spec = importlib.util.spec_from_file_location("train_cli", ROOT / "train.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


train_cli = load_train_cli()


def cli_error(argv) -> str:
    """The message `train.py argv` exits with (in-process: no torch import per call)."""
    with pytest.raises(SystemExit) as e:
        train_cli.main([str(a) for a in argv])
    assert e.value.code not in (0, None), f"{argv} should fail"
    return str(e.value.code)


def kill_after_first_checkpoint(run_dir: Path, still_running, timeout: float = 240) -> int:
    """SIGKILL the training process of `run_dir` (pid from sweep_attempt.json) once it has a checkpoint;
    returns the env steps of that checkpoint (a kill mid-run: fewer than the budget)."""
    deadline = time.time() + timeout
    while time.time() < deadline and still_running():
        try:
            info = json.loads((run_dir / "sweep_attempt.json").read_text())
        except (OSError, ValueError):
            info = {}
        if info and (run_dir / "checkpoint.pt").is_file():
            cmdline = Path(f"/proc/{info['pid']}/cmdline").read_bytes().replace(b"\0", b" ").decode()
            assert "-m cyberdog.train_cli" in cmdline and str(run_dir) in cmdline, cmdline
            os.kill(info["pid"], signal.SIGKILL)
            return load_checkpoint(run_dir / "checkpoint.pt")["counters"]["env_steps"]
        time.sleep(0.05)
    raise AssertionError(f"{run_dir} never had a checkpoint to kill the run at")


def check_completed_sweep(sweep_dir: Path, killed_seed: int, killed_at: int, evaluated: bool) -> None:
    assert 0 < killed_at < BUDGET, "the seed was not killed mid-run"
    status = json.loads((sweep_dir / STATUS_FILE).read_text())
    assert status["finished"] and status["counts"]["done"] == 2
    by_seed = {s["seed"]: s for s in status["seeds"]}
    assert sorted(by_seed) == [0, 1] and killed_seed in by_seed
    for seed, st in by_seed.items():
        run_dir = sweep_dir / f"seed{seed}"
        # the status counts env steps at the last logged episode (20 steps each)
        assert st["state"] == "done" and BUDGET - 20 <= st["env_steps"] <= BUDGET and st["stage"] == 2
        assert set(st["best_score"]) == {"1", "2"}
        for name in ("stage1_final_actor.pt", "stage2_final_actor.pt", "config.yaml", "train.log"):
            assert (run_dir / name).is_file(), name
        state = load_checkpoint(run_dir / "checkpoint.pt")
        assert state["counters"]["finished"] and state["counters"]["env_steps"] == BUDGET
        assert state["config"]["train"]["seed"] == seed
        with open(run_dir / "metrics.csv") as f:
            assert len(list(csv.DictReader(f))) == state["counters"]["episodes"]  # every episode logged once
        headers = [ln for ln in (run_dir / "train.log").read_text().splitlines() if ln.startswith("=== attempt")]
        if seed == killed_seed:
            assert st["attempts"] == 2 and "SIGKILL" in st["errors"][0], st
            assert "--resume" in headers[1] and "--resume" not in headers[0]
        else:
            assert st["attempts"] == 1 and st["errors"] == [] and len(headers) == 1

    with open(sweep_dir / "aggregate.csv") as f:
        table = list(csv.DictReader(f))
    assert [r["seed"] for r in table] == ["0", "1", "mean", "ci95"]
    for r in table[:2]:  # env steps of the stage at its last logged episode (20 steps each)
        assert 100 - 20 <= int(r["stage1_env_steps"]) <= 100 and 50 - 20 <= int(r["stage2_env_steps"]) <= 50
    evaluation = json.loads((sweep_dir / "evaluation.json").read_text())
    assert [e["seed"] for e in evaluation["seeds"]] == [0, 1] and evaluation["missing"] == []
    assert "mean ± 95 % CI" in (sweep_dir / "aggregate.md").read_text()
    assert (sweep_dir / "learning_curves.png").stat().st_size > 1000
    with open(sweep_dir / "learning_curves.csv") as f:
        assert {r["stage"] for r in csv.DictReader(f)} == {"1", "2"}
    if evaluated:
        changes = []
        for e in evaluation["seeds"]:
            assert set(e["actors"]) == {"stage1", "stage2"} and all(Path(p).is_file() for p in e["actors"].values())
            m = e["metrics"]
            for stage in ("stage1", "stage2"):
                assert {"mean_speed_mps", "fell", "energy_per_m_J", "distance_m"} <= set(m[stage])
            e1, e2 = m["stage1"]["energy_per_m_J"], m["stage2"]["energy_per_m_J"]
            assert m["energy_per_m_change_pct"] == pytest.approx(100 * (e2 - e1) / e1)
            changes.append(m["energy_per_m_change_pct"])
        mean, half = mean_ci(changes)
        assert evaluation["mean_ci95"]["energy_per_m_change_pct"]["mean"] == pytest.approx(mean)
        assert evaluation["mean_ci95"]["energy_per_m_change_pct"]["ci95"] == pytest.approx(half)
        assert float(table[2]["energy_per_m_change_pct"]) == pytest.approx(mean)
    else:
        assert evaluation["evaluation"] is None and "stage1_energy_per_m_J" not in table[0]


# ---- the two backends, each with a killed seed --------------------------------------------------------------------
@pytest.fixture(scope="module")
def local_ray():
    try:
        import ray
    except ImportError as e:
        pytest.skip(f"Ray is not installed ({e}); pip install -e '.[ray]' to test the Ray backend")
    ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False)
    yield ray
    ray.shutdown()


@pytest.mark.slow
@pytest.mark.parametrize("backend", ["local", "ray"])
def test_sweep_finishes_a_killed_seed_through_resume(backend, request, tmp_path, capsys):
    """`train.py --seeds 0-1` (driver in this process, seeds in their own processes) while another thread
    SIGKILLs seed 1's training process after its first checkpoint."""
    ray = request.getfixturevalue("local_ray") if backend == "ray" else None
    sweep_dir = tmp_path / f"sweep_{backend}"
    result: dict = {}

    def killer():
        try:
            result["killed_at"] = kill_after_first_checkpoint(sweep_dir / "seed1", lambda: "rc" not in result)
        except BaseException as e:  # reported by the main thread
            result["error"] = e

    thread = threading.Thread(target=killer, daemon=True)
    thread.start()
    evaluated = backend == "local"  # the rollouts do not depend on the backend: once is enough
    try:
        result["rc"] = train_cli.main(sweep_args(sweep_dir, "--backend", backend,  # as train.py runs it
                                                 "--eval-duration", "0.3" if evaluated else "0"),
                                      draw_learning_curves=train_cli.draw_learning_curves)
    finally:
        result.setdefault("rc", None)
        thread.join(timeout=10)
    if "error" in result:
        raise result["error"]
    out = capsys.readouterr().out
    assert result["rc"] == 0, out[-3000:]
    assert "seed 1 attempt 1 failed (killed by SIGKILL" in out and "resuming from its checkpoint" in out
    check_completed_sweep(sweep_dir, killed_seed=1, killed_at=result["killed_at"], evaluated=evaluated)
    if ray is not None:
        assert ray.is_initialized(), "the sweep must not shut down a Ray instance it did not start"
        return
    # resuming a finished sweep trains nothing; re-aggregating rewrites the outputs
    mtime = (sweep_dir / "seed0" / "checkpoint.pt").stat().st_mtime
    assert train_cli.main(["--resume", str(sweep_dir), "--eval-duration", "0", "--no-progress"]) == 0
    assert (sweep_dir / "seed0" / "checkpoint.pt").stat().st_mtime == mtime
    assert "already done" in capsys.readouterr().out
    assert json.loads((sweep_dir / "evaluation.json").read_text())["evaluation"] is None


def test_missing_ray_is_a_clear_error(tmp_path, monkeypatch):
    create_sweep(tmp_path / "s", C.load(C.ExperimentConfig, TINY), [0])
    monkeypatch.setitem(sys.modules, "ray", None)  # import ray → ImportError
    with pytest.raises(SweepError, match=r"needs Ray, which is not installed: pip install"):
        run_sweep(tmp_path / "s", backend="ray", progress=False)
    assert json.loads((tmp_path / "s" / STATUS_FILE).read_text())["seeds"][0]["state"] == "pending"


def _stand_in_sweep(tmp_path: Path, monkeypatch, before_training: str) -> Path:
    """A sweep of seeds 0 and 1 whose trainer is a stand-in module (`fake_train`, fast): it runs `before_training`
    (Python, with `run` the seed's run folder) and then writes the seed's final actor as a trained seed does."""
    monkeypatch.setenv("PYTHONPATH", str(tmp_path))  # after the package's own folder: `-m fake_train` finds it
    (tmp_path / "fake_train.py").write_text("import pathlib, sys\n"
                                            "run = pathlib.Path(sys.argv[sys.argv.index('--run-dir') + 1])\n"
                                            + before_training + "(run / 'stage2_final_actor.pt').write_bytes(b'')\n")
    sweep = tmp_path / "s"
    create_sweep(sweep, C.load(C.ExperimentConfig, TINY), [0, 1])
    return sweep


def test_failing_seed_is_retried_a_bounded_number_of_times_then_reported(tmp_path, monkeypatch):
    """A stand-in for the training entry point (fast): seed 0 trains fine, seed 1 always fails with an error."""
    sweep = _stand_in_sweep(tmp_path, monkeypatch, "if run.name == 'seed1':\n"
                                                   "    sys.exit('error: checkpoint seed1/checkpoint.pt is corrupt')\n")
    status = run_sweep(sweep, backend="local", workers=2, max_retries=2, progress=False, entry_point="fake_train",
                       poll_s=0.05)
    by_seed = {s["seed"]: s for s in status["seeds"]}
    assert by_seed[0]["state"] == "done" and by_seed[0]["attempts"] == 1
    assert by_seed[1]["state"] == "failed" and by_seed[1]["attempts"] == 3
    assert len(by_seed[1]["errors"]) == 3
    assert all("exit code 1: error: checkpoint seed1/checkpoint.pt is corrupt" in e for e in by_seed[1]["errors"])
    assert status["counts"] == {"pending": 0, "running": 0, "retrying": 0, "done": 1, "failed": 1, "interrupted": 0}
    assert json.loads((sweep / STATUS_FILE).read_text()) == status
    # a resumed sweep leaves the done seed alone and gives the failed one a fresh retry budget
    status = run_sweep(sweep, backend="local", max_retries=0, progress=False, entry_point="fake_train", poll_s=0.05)
    assert [s["attempts"] for s in status["seeds"]] == [1, 4] and status["seeds"][1]["state"] == "failed"


def test_a_seed_stopped_by_ctrl_c_is_not_retried_and_a_resume_continues_it(tmp_path, monkeypatch, capsys):
    """A stand-in trainer: seed 1's process exits 130 (train.py's exit on Ctrl-C) the first time, then trains."""
    sweep = _stand_in_sweep(tmp_path, monkeypatch, f"marker = pathlib.Path({str(tmp_path / 'stopped_once')!r})\n"
                                                   "if run.name == 'seed1' and not marker.exists():\n"
                                                   "    marker.write_text('')\n"
                                                   "    sys.exit(130)\n")
    status = run_sweep(sweep, backend="local", workers=2, max_retries=2, progress=False, entry_point="fake_train",
                       poll_s=0.05)
    by_seed = {s["seed"]: s for s in status["seeds"]}
    assert by_seed[0]["state"] == "done"
    assert by_seed[1]["state"] == "interrupted" and by_seed[1]["attempts"] == 1
    assert "seed 1 attempt 1 interrupted (exit code 130); not retried" in capsys.readouterr().out
    status = run_sweep(sweep, backend="local", max_retries=0, progress=False, entry_point="fake_train", poll_s=0.05)
    assert [s["state"] for s in status["seeds"]] == ["done", "done"], status["seeds"][1]


# ---- inputs and errors ------------------------------------------------------------------------------------------
def test_parse_seeds():
    assert parse_seeds("0-9") == list(range(10))
    assert parse_seeds("0,3,7") == [0, 3, 7]
    assert parse_seeds("0-2, 5") == [0, 1, 2, 5]
    assert parse_seeds("4") == [4]
    for bad, message in [("3-1", "empty"), ("a", "not a seed"), ("1,1", "more than once"), ("0-2,2", "more than once"),
                         ("", "not a seed"), ("-1", "not a seed"), ("1.5", "not a seed")]:
        with pytest.raises(SweepError, match=message):
            parse_seeds(bad)


def test_cli_errors_are_clear(tmp_path):
    assert "range '3-1' is empty" in cli_error(["--config", TINY, "--seeds", "3-1", "--run-dir", tmp_path / "a"])
    assert "--resume" in cli_error(["--seeds", "0-1", "--resume", tmp_path])
    assert "--seed" in cli_error(["--seeds", "0-1", "--seed", "3", "--run-dir", tmp_path / "b"])
    assert "stage" in cli_error(["--seeds", "0-1", "--stage", "2", "--run-dir", tmp_path / "c"])
    assert "--workers must be >= 1" in cli_error(["--seeds", "0-1", "--workers", "0", "--run-dir", tmp_path / "d"])
    assert "--ray-address needs --backend ray" in cli_error(["--seeds", "0", "--ray-address", "auto"])
    assert "--max-retries" in cli_error(["--seeds", "0", "--max-retries", "-1"])
    assert "--eval-duration" in cli_error(["--seeds", "0", "--eval-duration", "-1"])
    assert "only apply to sweeps" in cli_error(["--config", TINY, "--workers", "2", "--run-dir", tmp_path / "e"])
    assert "AgentConfig.algorithm" in cli_error(["--seeds", "0", "--set", "agent.algorithm=ppo",
                                                 "--run-dir", tmp_path / "f"])
    assert "not a folder" in cli_error(["--aggregate", tmp_path / "nothing"])
    assert "--config" in cli_error(["--aggregate", tmp_path, "--config", TINY])
    for name in "abcdef":
        assert not (tmp_path / name).exists(), "a refused command must not create its output folder"
    # an existing sweep folder is never written over; --resume continues it and takes no new settings
    sweep = tmp_path / "sweep"
    create_sweep(sweep, C.load(C.ExperimentConfig, TINY), [0, 1])
    assert "use train.py --resume" in cli_error(["--config", TINY, "--seeds", "0-1", "--run-dir", sweep])
    assert "do not combine" in cli_error(["--resume", sweep, "--set", "train.seed=3"])
    (tmp_path / "other").mkdir()
    (tmp_path / "other" / "notes.txt").write_text("mine")
    assert "another --run-dir" in cli_error(["--config", TINY, "--seeds", "0", "--run-dir", tmp_path / "other"])


def test_help_documents_every_sweep_option():
    out = subprocess.run([sys.executable, str(ROOT / "train.py"), "--help"], capture_output=True, text=True)
    for opt in ("--seeds", "--backend", "--workers", "--ray-address", "--max-retries", "--aggregate",
                "--eval-duration", "--eval-speed", "--resume", "--config", "--run-dir"):
        assert opt in out.stdout, opt


def test_sweep_folder_records_config_and_seeds(tmp_path):
    cfg = C.override(C.load(C.ExperimentConfig, TINY), SHORT)
    spec = create_sweep(tmp_path / "s", cfg, [3, 5], source_config=TINY, overrides=SHORT)
    assert load_sweep(tmp_path / "s") == spec and spec.seeds == [3, 5] and spec.last_stage == 2
    assert C.load(C.ExperimentConfig, tmp_path / "s" / "sweep_config.yaml") == cfg
    assert stage_budget(cfg, "both") == BUDGET and stage_budget(cfg, "1") == 100
    with pytest.raises(SweepError, match="stage"):
        create_sweep(tmp_path / "t", cfg, [0], stage="2")


def test_resume_of_a_done_sweep_starts_nothing(tmp_path):
    sweep = tmp_path / "s"
    create_sweep(sweep, C.load(C.ExperimentConfig, TINY), [0])
    (sweep / "seed0").mkdir()
    (sweep / "seed0" / "stage2_final_actor.pt").write_bytes(b"")
    (sweep / STATUS_FILE).write_text(json.dumps({"seeds": [{"seed": 0, "state": "done", "wall_s": 1.0}]}))
    status = run_sweep(sweep, backend="local", progress=False)
    assert status["finished"] and status["seeds"][0]["state"] == "done" and status["seeds"][0]["attempts"] == 0


# ---- aggregation on hand-made metrics -----------------------------------------------------------------------------
def _fake_run(run_dir: Path, offset: float, episodes=(6, 4), length=20) -> None:
    run_dir.mkdir(parents=True)
    rows, steps, ep = [], 0, 0
    for stage, n in zip((1, 2), episodes):
        for i in range(n):
            steps += length
            ep += 1
            score = offset + 10 * stage + i
            rows.append({"stage": stage, "episode": ep, "stage_episode": i + 1, "env_steps": steps,
                         "length": length, "score": score, "window_mean_score": score - 0.5})
    with open(run_dir / "metrics.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)


def test_aggregate_bands_and_tables_from_metrics(tmp_path):
    for seed, offset in [(0, 0.0), (1, 2.0), (2, 7.0)]:
        _fake_run(tmp_path / f"seed{seed}", offset)
    curves = stage_curves(tmp_path / "seed1")
    assert curves[2]["env_steps"].tolist() == [20, 40, 60, 80]  # steps counted from the start of stage 2
    result = aggregate_sweep(tmp_path, eval_duration=0, progress=False)
    assert (tmp_path / "learning_curves.csv").is_file() and not (tmp_path / "learning_curves.png").exists()
    result = aggregate_sweep(tmp_path, eval_duration=0, progress=False,  # as train.py: the figure by plots/
                             draw_learning_curves=lambda folder: draw_learning_curves(folder, pdf=False))
    band = result["curves"]
    assert band[1]["env_steps"][0] == 20 and band[1]["env_steps"][-1] == 120
    x = band[1]["env_steps"][50]
    per_seed = [10 + (x - 20) / 20 + off for off in (0.0, 2.0, 7.0)]  # linear in steps between episodes
    mean, half = mean_ci(per_seed)
    assert band[1]["score_mean"][50] == pytest.approx(mean) and band[1]["score_ci95"][50] == pytest.approx(half)
    assert band[2]["window_score_mean"][-1] == pytest.approx(20 + 3 + 3 - 0.5)
    with open(tmp_path / "aggregate.csv") as f:
        table = {r["seed"]: r for r in csv.DictReader(f)}
    assert float(table["mean"]["stage2_final_window_score"]) == pytest.approx(23 - 0.5 + 3)
    assert float(table["ci95"]["stage1_episodes"]) == 0.0
    assert (tmp_path / "learning_curves.png").is_file()
    # seeds that reached different step counts share the common part of the grid only
    _fake_run(tmp_path / "seed3", 0.0, episodes=(3, 2))
    assert learning_curves([stage_curves(tmp_path / f"seed{s}") for s in (0, 3)])[1]["env_steps"][-1] == 60
    with pytest.raises(SweepError, match="eval-duration"):
        aggregate_sweep(tmp_path, eval_duration=-1)
    for seed in (0, 1):  # a sweep of stage 1 only
        _fake_run(tmp_path / "stage1_only" / f"seed{seed}", float(seed), episodes=(6,))
    only1 = aggregate_sweep(tmp_path / "stage1_only", eval_duration=0, progress=False)
    assert list(only1["curves"]) == [1] and not any("stage2" in c for c in only1["stats"])
    assert np.isfinite(result["stats"]["stage1_final_window_score"]["ci95"])


# ---- the sweeps layer ---------------------------------------------------------------------------------------------
def imported_modules(path: Path) -> set[str]:
    """Every module a source file imports, at any depth (`from cyberdog import sweeps` counts as cyberdog.sweeps)."""
    names = set()
    for node in ast.walk(ast.parse(path.read_text(), filename=str(path))):
        if isinstance(node, ast.Import):
            names.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            names.add(node.module)
            names.update(f"{node.module}.{a.name}" for a in node.names)
    return names


def test_no_layer_below_sweeps_imports_them():
    """Sweeps are the orchestration on top of the package (DESIGN.md layers): analysis, rl and everything
    else below never import them; only the training command line (cyberdog/train_cli.py) does."""
    offenders = {}
    for path in PACKAGE.rglob("*.py"):
        if (PACKAGE / "sweeps") in path.parents or path == PACKAGE / "train_cli.py":  # the command line: on top
            continue
        bad = sorted(m for m in imported_modules(path) if m == "cyberdog.sweeps" or m.startswith("cyberdog.sweeps."))
        if bad:
            offenders[str(path.relative_to(ROOT))] = bad
    assert offenders == {}
    assert imported_modules(PACKAGE / "sweeps" / "aggregate.py") >= {"cyberdog.analysis.parallel"}  # the check sees


def test_sweeps_import_without_torch():
    """A sweep driver (and a Ray node's attempt) needs neither torch nor PyBullet: only the trainings it starts do."""
    code = ("import sys, cyberdog.sweeps, cyberdog.sweeps.process, cyberdog.sweeps.aggregate\n"
            "print(sorted(m for m in ('torch', 'torchrl', 'pybullet') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT, check=True)
    assert out.stdout.strip() == "[]", out.stdout + out.stderr


def test_attempt_module_is_standard_library_only():
    """RayBackend ships cyberdog.sweeps.process to the workers by value: it must not need the package there."""
    stdlib = sys.stdlib_module_names
    outside = {m for m in imported_modules(PACKAGE / "sweeps" / "process.py") if m.split(".")[0] not in stdlib}
    assert outside <= {"__future__", "ray"}, outside
