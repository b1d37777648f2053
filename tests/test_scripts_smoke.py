"""Every script under bench/ and tools/ runs as a command, with a tiny budget, on shipped results/ files or on
inputs made here: exit 0, and the numbers or files it exists to make are there. Outputs go to tmp_path (TMPDIR
too, for the scripts that work in a temporary folder)."""
from __future__ import annotations

import csv
import json
import math
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "results"
NUMBER = r"([-+]?\d+(?:\.\d+)?)"
COVERED = {"bench/driver_rate.py", "bench/env_throughput.py", "bench/readme_times.py", "bench/sb3_registered_task.py",
           "bench/train_throughput.py", "bench/walk_throughput.py", "tools/curve_table.py",
           "tools/make_readme_tables.py", "tools/make_urdf.py", "tools/merge_walks.py", "tools/optimize_trajectory.py",
           "tools/ship.py", "tools/ship_searched.py"}


def script(tmp_path: Path, path: str, *args, timeout: float = 600) -> str:
    """Run `path` from the repository root with `args`; its stdout and stderr, after asserting exit 0."""
    env = dict(os.environ, TMPDIR=str(tmp_path), PYTHONUNBUFFERED="1")
    done = subprocess.run([sys.executable, path, *map(str, args)], cwd=ROOT, env=env, capture_output=True, text=True,
                          timeout=timeout)
    out = done.stdout + done.stderr
    assert done.returncode == 0, f"{path} exited {done.returncode}:\n{out[-3000:]}"
    return out


def numbers(pattern: str, text: str) -> list[float]:
    """The numbers of the first match of `pattern` (groups of NUMBER), asserting there is one and all are finite."""
    m = re.search(pattern, text)
    assert m, f"no match of {pattern!r} in:\n{text[-3000:]}"
    values = [float(g) for g in m.groups()]
    assert all(math.isfinite(v) for v in values), m.group(0)
    return values


def test_every_script_of_bench_and_tools_has_a_smoke_test():
    found = {str(p.relative_to(ROOT)) for d in ("bench", "tools") for p in (ROOT / d).glob("*.py")}
    assert found == COVERED, f"new: {sorted(found - COVERED)}; gone: {sorted(COVERED - found)}"


# ---- bench/ ------------------------------------------------------------------------------------------------------
def test_walk_throughput(tmp_path):
    out = script(tmp_path, "bench/walk_throughput.py", "--duration", "0.2", "--repeats", "1")
    rate, cpu_rate = numbers(rf"best: {NUMBER} controller periods/s, by CPU time {NUMBER}", out)
    assert rate > 0 and cpu_rate > 0


def test_env_throughput(tmp_path):
    out = script(tmp_path, "bench/env_throughput.py", "--steps", "20", "--repeats", "1")
    env, floor, ratio = numbers(rf"\[CPU time\] median env: {NUMBER} env steps/s; floor: {NUMBER} agent-step "
                                rf"equivalents/s; env / floor = {NUMBER}", out)
    assert env > 0 and floor > 0 and ratio == pytest.approx(env / floor, rel=0.01)


def test_driver_rate(tmp_path):
    out = script(tmp_path, "bench/driver_rate.py", "--speeds", "1.0", "--kp", "60", "--kd", "2", "--duration", "0.5")
    rate, picked, finer, deviation, battery = numbers(
        rf"\| 1 \| 60 \| 2 \| {NUMBER} Hz \| {NUMBER} \| {NUMBER} \| {NUMBER} % \| {NUMBER} \|", out)
    assert rate > 0 and picked > 0 and battery > 0
    assert deviation == pytest.approx(100 * (finer / picked - 1), abs=0.01)


@pytest.mark.slow
def test_train_throughput(tmp_path):
    out = script(tmp_path, "bench/train_throughput.py", "--no-sb3", "--steps", "200", "--repeats", "1",
                 "--frames-per-batch", "100", "--bare-updates", "10", "--env-steps", "20", "--collection", "sync",
                 "--num-envs", "1")
    assert numbers(rf"bare ours\s+{NUMBER}\s+{NUMBER}", out)[0] > 0
    steps, updates = numbers(rf"\n\s+1\s+{NUMBER}\s+{NUMBER}\n", out)  # the num_envs table's row
    assert steps > 0 and updates == pytest.approx(steps, rel=0.05)  # one update per env step


@pytest.mark.slow
def test_readme_times(tmp_path):
    out = script(tmp_path, "bench/readme_times.py", "--only", "tiny")
    assert re.search(r"machine: .+, \d+ cores", out)
    minutes, seconds, cpu_minutes, cpu_seconds = numbers(rf"tiny: {NUMBER} min {NUMBER} s wall, {NUMBER} min "
                                                         rf"{NUMBER} s CPU, ok", out)
    assert minutes * 60 + seconds > 0 and cpu_minutes * 60 + cpu_seconds > 0
    assert not list(tmp_path.glob("readme_times_*"))  # its temporary folder, removed


@pytest.mark.slow
def test_sb3_registered_task(tmp_path):  # stable-baselines3 is in the [test] extra: this runs wherever tests do
    out = script(tmp_path, "bench/sb3_registered_task.py", "--steps", "100", "--learning-starts", "50",
                 "--episodes", "1")
    for title in ("the zero action \\(the trot\\)", "SB3 TD3 untrained", "SB3 TD3 after 100 steps"):
        length, falls, episodes, score = numbers(rf"{title}: mean length {NUMBER} steps, falls {NUMBER}/{NUMBER}, "
                                                 rf"mean score {NUMBER}", out)
        assert 1 <= length <= 400 and episodes == 1


# ---- tools/ ------------------------------------------------------------------------------------------------------
def test_curve_table_on_a_shipped_log(tmp_path):
    log = RESULTS / "table5" / "policy" / "seed0" / "metrics.csv"
    with open(log) as f:
        rows = list(csv.DictReader(f))
    out = script(tmp_path, "tools/curve_table.py", log, "--every", "50000", "--out", tmp_path / "curve.md")
    for stage in ("1", "2"):
        episodes = sum(r["stage"] == stage for r in rows)
        assert numbers(rf"stage {stage}: {NUMBER} episodes", out.replace(",", "")) == [episodes]
    written = (tmp_path / "curve.md").read_text()
    table = [line for line in written.splitlines() if line.startswith("| ") and "env steps" not in line]
    assert table and sum(int(line.split("|")[2].replace(",", "")) for line in table) == len(rows)


def test_make_readme_tables_prints_every_table_the_pages_mark(tmp_path):
    out = script(tmp_path, "tools/make_readme_tables.py")
    marked = {name for page in (ROOT / "README.md", ROOT / "docs" / "results.md")
              for name in re.findall(r"<!-- table:(\w+) -->", page.read_text())}
    printed = re.findall(r"<!-- table:(\w+) -->\n(\|.*?)\n<!-- /table:\1 -->", out, re.S)
    assert marked and marked <= {name for name, _ in printed}
    for name, table in printed:
        assert re.search(r"\d", table.splitlines()[-1]), f"{name}: no number in its last row"


def test_make_urdf_check(tmp_path):
    assert "up to date" in script(tmp_path, "tools/make_urdf.py", "--check")


def test_merge_walks_stiffness_and_gains(tmp_path):
    walks = json.loads((RESULTS / "figures_input" / "stiffness_walks.json").read_text())
    seeds = sorted({w["seed"] for w in walks})
    for name, part in (("a", seeds[:1]), ("b", seeds[1:])):
        (tmp_path / name).mkdir()
        (tmp_path / name / "stiffness_walks.json").write_text(json.dumps([w for w in walks if w["seed"] in part]))
    out = script(tmp_path, "tools/merge_walks.py", "stiffness", tmp_path / "a", tmp_path / "b",
                 "--out", tmp_path / "merged")
    assert numbers(rf"{NUMBER} walks of {NUMBER} seeds", out) == [len(walks), len(seeds)]
    assert {f.name for f in (tmp_path / "merged").iterdir()} >= {"stiffness.csv", "stiffness.json", "stiffness.md",
                                                                 "stiffness_walks.json"}
    summary = json.loads((tmp_path / "merged" / "stiffness.json").read_text())
    assert summary and all({"trajectory", "seeds"} <= set(row) for row in summary)

    prototype = json.loads((RESULTS / "figures_input" / "prototype.json").read_text())
    for name, pid in (("kp2", {"kp": [120.0] * 3}), ("kd2", {"kd": [4.0] * 3})):
        (tmp_path / name).mkdir()
        (tmp_path / name / "config.yaml").write_text(json.dumps({"pid": pid}))
        (tmp_path / name / "prototype.json").write_text(json.dumps(prototype))
    script(tmp_path, "tools/merge_walks.py", "gains", tmp_path / "kp2", tmp_path / "kd2",
           "--out", tmp_path / "gains_walks.json")
    gains = json.loads((tmp_path / "gains_walks.json").read_text())
    assert len(gains) == 2 * len(prototype)
    assert {(w["gain"], w["gain_scale"]) for w in gains} == {("kp", 2.0), ("kd", 2.0)}


def test_optimize_trajectory_on_a_tiny_budget(tmp_path):
    out_dir = tmp_path / "opt"
    script(tmp_path, "tools/optimize_trajectory.py", "--speeds", "1.0", "--duration", "1.0", "--measure-from", "0.5",
           "--max-evals", "2", "--workers", "1", "--replay-duration", "1.0", "--out", out_dir,
           "--result", tmp_path / "shape.json")
    assert {"history.csv", "optimized_trajectory.json", "summary.json", "table.csv", "table.md"} <= \
        {f.name for f in out_dir.iterdir()}
    summary = json.loads((out_dir / "summary.json").read_text())
    assert 1 <= summary["evaluations"] <= 2 and math.isfinite(summary["objective_J"])
    assert [r["trajectory"] for r in summary["replay"]][0] == "optimized"
    assert all(r["energy_J"] > 0 for r in summary["replay"])
    from cyberdog.core.trajectories import SampledTrajectory
    shape = SampledTrajectory.load(tmp_path / "shape.json")
    assert shape.provenance["shape_params"] == summary["shape_params"]


def test_ship_policy_from_a_finished_run(tmp_path):
    shipped = RESULTS / "table5" / "policy" / "seed0"
    run = tmp_path / "run"  # a finished train.py run: its final actors, config and log
    run.mkdir()
    for name in ("config.yaml", "metrics.csv"):
        shutil.copy(shipped / name, run / name)
    for stage in (1, 2):
        shutil.copy(shipped / f"stage{stage}_actor.pt", run / f"stage{stage}_final_actor.pt")
    script(tmp_path, "tools/ship.py", "policy", run, "--out", tmp_path / "seed0")
    out = tmp_path / "seed0"
    assert {f.name for f in out.iterdir()} == {"stage1_actor.pt", "stage2_actor.pt", "config.yaml", "metrics.csv",
                                               "metadata.json"}
    meta = json.loads((out / "metadata.json").read_text())
    with open(run / "metrics.csv") as f:
        rows = list(csv.DictReader(f))
    for stage in (1, 2):
        mine = [r for r in rows if r["stage"] == str(stage)]
        assert meta[f"stage{stage}"]["episodes"] == len(mine)
        assert meta[f"stage{stage}"]["env_steps"] == sum(int(r["length"]) for r in mine)
        assert meta[f"stage{stage}"]["wall_time_s"] > 0


@pytest.mark.slow
def test_ship_torque_quick_on_a_shipped_seed(tmp_path):
    results = tmp_path / "results"
    script(tmp_path, "tools/ship.py", "torque", RESULTS / "torque" / "policy" / "seed0", "--work", tmp_path / "work",
           "--results", results, "--workers", "1", "--quick")
    assert (results / "torque" / "policy" / "seed0" / "stage2_actor.pt").is_file()
    assert [p.name for p in (results / "torque" / "paths").iterdir()] == ["seed0.json"]
    for name, key in (("torque_check.json", "speed_command_mps"), ("comparison_torque.json", "speed_command_mps"),
                      ("prototype_torque.json", "speed_mps")):
        rows = json.loads((results / "figures_input" / name).read_text())
        rows = rows["walks"] if isinstance(rows, dict) else rows
        assert rows and {r[key] for r in rows} == {1.0}, name  # each step walked, at --quick's one speed


@pytest.mark.slow
def test_ship_searched_quick_on_a_shipped_path(tmp_path):
    learned, results = tmp_path / "learned", tmp_path / "results"
    learned.mkdir()
    shutil.copyfile(RESULTS / "battery_searched_wide" / "paths" / "seed30_1mps.json", learned / "seed30_1mps.json")
    # twenty evaluate.py processes: about 3.5 min of CPU, several times that on a machine busy with other work
    script(tmp_path, "tools/ship_searched.py", "searched_wide", "--learned", learned, "--work", tmp_path / "work",
           "--results", results, "--workers", "1", "--quick", timeout=1800)
    figures = results / "figures_input"
    for name in ("prototype", "comparison", "prototype_mujoco", "prototype_own", "prototype_inset", "gains",
                 "gains_own"):
        kind, _, twin = name.partition("_")
        rows = json.loads((figures / f"{kind}_searched_wide{'_' + twin if twin else ''}.json").read_text())
        key = "speed_command_mps" if kind == "comparison" else "speed_mps"
        assert rows and {r[key] for r in rows} == {1.0} and {r["seed"] for r in rows} >= {"seed30"}, name
    gains = json.loads((figures / "gains_searched_wide.json").read_text())
    assert len({(r["gain"], r["gain_scale"], r["pd_matched"]) for r in gains}) == 8  # 2 gains x 2 factors x 2 kinds
    conditions = json.loads((figures / "conditions_searched_wide.json").read_text())
    assert {(r["condition"], r["condition_value"]) for r in conditions} == {
        ("robot.payload", 3.0), ("sim.ground_friction", 0.4), ("sim.ground_friction", 1.2)}
    assert {r["seed"] for r in conditions} >= {"seed30"}
