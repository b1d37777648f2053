"""Reliability and clean failure: one process per run folder, headless rendering, config errors that name the
field, command lines without tracebacks, output folders that never mix, no silent zero-update stages, small
stage-final files, and resumes that survive a damaged metrics.csv or checkpoint.pt."""
from __future__ import annotations

import csv
import json
import os
import signal
import socket
import subprocess
import sys
import time
import warnings
from pathlib import Path

import pytest
import torch

from cyberdog import config as C
from cyberdog.output_folder import MANIFEST
from cyberdog.rl.checkpoint import CheckpointError, load_checkpoint
from cyberdog.rl.trainer import Trainer
from cyberdog.runlock import LOCK_FILE, RunLock, RunLockedError, break_lock, read_lock
from conftest import tiny

ROOT = Path(__file__).resolve().parents[1]
TINY = ROOT / "configs" / "tiny.yaml"
PY = sys.executable


def run(args, timeout=120, env=None, **kw) -> subprocess.CompletedProcess:
    return subprocess.run([PY, *map(str, args)], cwd=ROOT, capture_output=True, text=True, timeout=timeout,
                          env=env, **kw)


def error_lines(stderr: str) -> list[str]:
    """stderr's lines, without the line pybullet's C library prints when it is imported."""
    return [ln for ln in stderr.splitlines() if ln.strip() and not ln.startswith("pybullet build time")]


def assert_one_clear_line(proc: subprocess.CompletedProcess, *words: str) -> str:
    assert proc.returncode != 0, proc.stdout[-500:]
    assert "Traceback" not in proc.stderr, proc.stderr
    lines = error_lines(proc.stderr)
    assert len(lines) == 1, proc.stderr
    for w in words:
        assert w in lines[0], (w, lines[0])
    return lines[0]


# ---- config errors name the field, the value and what is allowed --------------------------------------------
@pytest.mark.parametrize("override, words", [
    ("agent.hidden_sizes=abc", ["AgentConfig.hidden_sizes", "agent.hidden_sizes", "'abc'", "list of integers"]),
    ("agent.hidden_sizes=64", ["agent.hidden_sizes", "64", "list of integers"]),
    ("train.batch_size=x", ["TrainConfig.batch_size", "'x'", "an integer"]),
    ("train.batch_size=2.5", ["train.batch_size", "2.5", "an integer"]),
    ("agent.gamma=true", ["AgentConfig.gamma", "True", "a number"]),
    ("train.deterministic=1", ["train.deterministic", "true or false"]),
    ("train.stage1.reward.energy=x", ["RewardConfig.energy", "'x'", "a number"]),
    ("env.walk.pid.kp=[1, 2]", ["PIDConfig.kp", "3 numbers", "[1, 2]"]),
    ("agent.algorithm=3", ["AgentConfig.algorithm", "a string", "3"]),
    ("train.stage1=5", ["train.stage1", "mapping", "5"]),
])
def test_a_wrong_type_names_the_field_the_value_and_what_is_allowed(override, words):
    with pytest.raises(ValueError) as err:
        tiny([override])
    for w in words:
        assert w in str(err.value), (w, str(err.value))


def test_numbers_yaml_reads_as_strings_are_numbers_and_ints_become_floats():
    cfg = tiny(["agent.actor_lr=1e-5", "train.checkpoint_every=1e3", "env.target_speed=1"])
    assert cfg.agent.actor_lr == 1e-5 and cfg.train.checkpoint_every == 1000
    assert isinstance(cfg.train.checkpoint_every, int) and isinstance(cfg.env.target_speed, float)


def test_unknown_keys_and_bad_yaml_are_clear(tmp_path):
    with pytest.raises(ValueError, match="did you mean 'lift_height'"):
        C.override(C.WalkConfig(), ["gait.lift_hieght=0.1"])
    with pytest.raises(ValueError, match="not valid YAML"):
        C.override(C.WalkConfig(), ["gait.lift_height=[0.1"])
    bad = tmp_path / "bad.yaml"
    bad.write_text("agent: {hidden_sizes: [1, 2\n")
    with pytest.raises(ValueError, match="not valid YAML"):
        C.load(C.ExperimentConfig, bad)
    bad.write_text("- 1\n- 2\n")
    with pytest.raises(ValueError, match="mapping"):
        C.load(C.ExperimentConfig, bad)


# ---- both command lines answer user mistakes with one line, no traceback ------------------------------------
def test_train_cli_answers_user_mistakes_with_one_line(tmp_path):
    evaluation = tmp_path / "eval_out"  # an evaluate.py folder: a walk config and its hardware, no checkpoint
    evaluation.mkdir()
    C.save_walked(C.WalkedRobot(C.WalkConfig(), C.HARDWARE_LIKE), evaluation / "config.yaml")
    train = [ROOT / "train.py", "--no-progress"]
    cases = [
        (["--config", tmp_path / "missing.yaml"], ["missing.yaml"]),
        (["--config", TINY, "--set", "agent.hiden_sizes=[8]"], ["hiden_sizes", "allowed"]),
        (["--config", TINY, "--set", "agent.hidden_sizes=abc"], ["AgentConfig.hidden_sizes", "'abc'"]),
        (["--config", TINY, "--set", "train.batch_size=big"], ["TrainConfig.batch_size", "'big'"]),
        (["--resume", evaluation], ["not a training run", "evaluate.py"]),
        (["--resume", tmp_path], ["not a training run"]),
        (["--resume", tmp_path / "nowhere"], ["no such folder"]),
    ]
    for args, words in cases:
        assert_one_clear_line(run(train + args + (["--run-dir", tmp_path / "r"] if "--config" in args else [])),
                              *words)
    assert not (tmp_path / "r").exists()


def test_evaluate_cli_answers_user_mistakes_with_one_line(tmp_path):
    ev = [ROOT / "evaluate.py", "baselines", "--out", tmp_path / "o"]
    assert_one_clear_line(run(ev + ["--config", tmp_path / "missing.yaml"]), "config error", "missing.yaml")
    assert_one_clear_line(run(ev + ["--set", "gait.lift_hieght=0.1"]), "lift_hieght", "did you mean")
    assert_one_clear_line(run(ev + ["--set", "gait.lift_height=abc"]), "GaitConfig.lift_height", "'abc'")
    assert_one_clear_line(run(ev + ["--config", TINY]), "WalkConfig", "allowed")
    assert not (tmp_path / "o").exists()


# ---- evaluate.py: an --out folder that holds results is refused; --force replaces them; exact summary -------
def test_a_second_out_into_a_used_folder_is_refused_and_force_replaces_it(tmp_path, capsys):
    import evaluate

    out = tmp_path / "o"
    base = ["baselines", "--speeds", "1.0", "--trajectories", "cycloid", "--duration", "0.2", "--out", str(out)]
    assert evaluate.main(base) == 0
    first = capsys.readouterr().out
    written = sorted(p.relative_to(out).as_posix() for p in out.rglob("*") if p.is_file())
    assert written == ["baselines.csv", "baselines.json", "baselines.md", "config.yaml", MANIFEST]
    assert f"wrote {len(written)} files" in first
    config_before = (out / "config.yaml").read_text()
    # a second run with another lift height into the same folder: refused, nothing touched
    assert evaluate.main(base + ["--set", "gait.lift_height=0.1"]) == 2
    err = capsys.readouterr().err
    assert "already holds" in err and "--force" in err and len(error_lines(err)) == 1
    assert (out / "config.yaml").read_text() == config_before
    # --force: the earlier run's recorded files go; a file it did not write stays and is named
    (out / "my_notes.txt").write_text("mine")
    (out / "stale_table5.md").write_text("old")
    manifest = json.loads((out / MANIFEST).read_text())
    manifest["runs"][0]["files"].append("stale_table5.md")
    (out / MANIFEST).write_text(json.dumps(manifest))
    assert evaluate.main(base + ["--set", "gait.lift_height=0.1", "--force"]) == 0
    text = capsys.readouterr().out
    assert not (out / "stale_table5.md").exists() and (out / "my_notes.txt").read_text() == "mine"
    assert "my_notes.txt" in text and "removed 5 file(s)" in text
    assert C.load_walked(out / "config.yaml").walk.gait.lift_height == 0.1
    *listed, last = [ln.strip() for ln in text.split("wrote ")[-1].splitlines()[1:] if ln.strip()]
    assert last == f"output folder: {out}/"  # the last line names the folder
    assert sorted(Path(p).name for p in listed) == ["baselines.csv", "baselines.json", "baselines.md", "config.yaml",
                                                    MANIFEST]
    runs = json.loads((out / MANIFEST).read_text())["runs"]
    assert len(runs) == 1 and "my_notes.txt" not in runs[0]["files"] and "--force" in runs[0]["argv"]


def test_figures_into_their_own_folder_add_to_it_and_say_whose_files_are_whose(tmp_path, capsys):
    import evaluate

    out = tmp_path / "o"
    assert evaluate.main(["baselines", "--speeds", "1.0", "--trajectories", "cycloid", "--duration", "0.2",
                          "--out", str(out)]) == 0
    assert evaluate.main(["figures", "--from", str(out)]) == 0  # no --force needed: it draws from this folder
    text = capsys.readouterr().out.split("wrote ")[-1]
    assert "baselines.csv" not in text and "figure4" in text
    runs = json.loads((out / MANIFEST).read_text())["runs"]
    assert [r["command"] for r in runs] == ["baselines", "figures"]
    assert "baselines.csv" in runs[0]["files"] and any(f.startswith("figure4") for f in runs[1]["files"])


# ---- a stage that would make no gradient update ----------------------------------------------------------------
def test_a_stage_without_updates_is_refused_before_any_work(tmp_path):
    table5 = C.load_preset(ROOT / "configs" / "table5.yaml").config
    cfg = C.override(table5, ["train.stage1.max_env_steps=800", "train.stage2.max_env_steps=800"])
    with pytest.raises(ValueError, match="train.stage1 would make no gradient update.*learning_starts=2000"):
        Trainer(cfg, tmp_path / "r", progress=False)
    assert not (tmp_path / "r").exists()
    proc = run([ROOT / "train.py", "--config", ROOT / "configs" / "table5.yaml", "--set",
                "train.stage1.max_env_steps=800", "--set", "train.stage2.max_env_steps=800", "--run-dir",
                tmp_path / "r", "--no-progress"])
    assert_one_clear_line(proc, "no gradient update", "learning_starts")
    assert not (tmp_path / "r").exists()
    # the batch size and the random frames count too; and a trained agent (--init-from) waits for neither
    with pytest.raises(ValueError, match="batch_size=64"):
        C.check_planned_updates(tiny(["train.batch_size=64", "train.stage1.max_env_steps=50"]), (1,))
    with pytest.raises(ValueError, match="init_random_frames=100"):
        C.check_planned_updates(tiny(["train.stage1.max_env_steps=50"]), (1,))
    assert C.check_planned_updates(tiny(["train.learning_starts=1000", "train.stage2.max_env_steps=50"]), (2,),
                                   trained=True) == {2: 25}


def test_the_update_plan_matches_the_trainer_and_an_untrained_stage_is_not_final(tmp_path):
    cfg = tiny(["train.stage1.max_env_steps=150", "train.stage2.max_env_steps=100"])
    summary = Trainer(cfg, tmp_path / "a", progress=False).run()
    assert summary["updates"] == sum(C.planned_updates(cfg).values()) > 0
    # the stop score is reached (at the first full score window) before learning_starts: no update happens
    early = tiny(["train.stage1.stop_score=-1e9", "train.learning_starts=1000", "train.stage1.max_env_steps=2000"])
    Trainer(early, tmp_path / "b", stages=(1,), progress=False).run()
    assert (tmp_path / "b" / "stage1_untrained_actor.pt").is_file()
    assert not (tmp_path / "b" / "stage1_final.pt").exists()
    assert not (tmp_path / "b" / "stage1_final_actor.pt").exists()


# ---- stage-final files: no replay buffer, what --init-from and evaluation need, < 2 MB for Table 5's preset ---
def test_stage_final_file_of_the_table5_preset_is_small_and_serves_init_from_and_evaluation(tmp_path):
    from cyberdog.rl.rollout import load_actor

    table5 = C.load_preset(ROOT / "configs" / "table5.yaml").config
    # the preset's networks and buffer capacity, on a budget of one batch with updates
    cfg = C.override(table5, ["train.learning_starts=0", "train.stage1.max_env_steps=200", "train.batch_size=64",
                             "env.episode_time=0.5"])
    Trainer(cfg, tmp_path / "q", stages=(1,), progress=False).run()
    final = tmp_path / "q" / "stage1_final.pt"
    size = final.stat().st_size
    print(f"table5 preset: stage1_final.pt {size} B, checkpoint.pt {(tmp_path / 'q' / 'checkpoint.pt').stat().st_size} B")
    assert size < 2_000_000
    state = load_checkpoint(final)
    assert "replay" not in state and "actor_optimizer" not in state["agent"] and state["agent"]["updates"] == 100
    ckpt = load_checkpoint(tmp_path / "q" / "checkpoint.pt")
    assert ckpt["replay"]["size"] == 200 and "actor_optimizer" in ckpt["agent"]
    # a slice of the preallocated 100,000-transition storage is saved as its 200 transitions only
    assert (tmp_path / "q" / "checkpoint.pt").stat().st_size < size + 2_000_000
    actor = load_actor(final)  # evaluation reads stage-final files as it reads actor files
    assert actor.meta["stage"] == 1 and actor.config == cfg
    # --init-from a stage-final file: the same networks, counters and exploration state; new Adam moments
    t2 = Trainer(C.override(cfg, ["train.stage2.max_env_steps=200"]), tmp_path / "s2", stages=(2,), init_from=final,
                 progress=False)
    try:
        assert t2.agent.updates == 100
        mine, saved = t2.agent.network_state(), state["agent"]["loss"]
        assert all(torch.equal(mine[k], saved[k]) for k in saved)
    finally:
        t2.close()
    # another exploration noise for stage 2 (the preset's is OU): the networks load, the new noise starts afresh
    gaussian = C.override(cfg, ["train.stage2.max_env_steps=200", "agent.exploration=gaussian"])
    t3 = Trainer(gaussian, tmp_path / "s2g", stages=(2,), init_from=final, progress=False)
    try:
        mine = t3.agent.network_state()
        assert all(torch.equal(mine[k], saved[k]) for k in saved)
        assert "sigma" in t3.agent.policy[-1].state_dict() and "eps" not in t3.agent.policy[-1].state_dict()
    finally:
        t3.close()
    with pytest.raises(CheckpointError, match="an actor file.*not a checkpoint"):
        load_checkpoint(tmp_path / "q" / "stage1_final_actor.pt")  # a resume needs a whole checkpoint
    # --init-from an actor file: tests/test_actor_anchor.py


# ---- the run-folder lock ---------------------------------------------------------------------------------------
def test_the_lock_refuses_a_second_holder_names_it_and_takes_over_a_dead_one(tmp_path):
    with RunLock(tmp_path) as lock:
        info = read_lock(tmp_path)
        assert info["pid"] == os.getpid() and info["host"] == socket.gethostname() and info["started"] > 0
        with pytest.raises(RunLockedError, match=f"pid {os.getpid()} on host {socket.gethostname()}, started"):
            RunLock(tmp_path).acquire()
        with pytest.raises(RunLockedError):  # a second Trainer on the folder, in this process too
            Trainer(tiny(), tmp_path, progress=False)
        assert lock.held
    assert not (tmp_path / LOCK_FILE).exists()
    # a lock file left by a dead process of this host: taken over, with a warning naming it
    dead = subprocess.Popen([PY, "-c", "pass"])
    dead.wait()
    (tmp_path / LOCK_FILE).write_text(json.dumps({"pid": dead.pid, "host": socket.gethostname(), "started": 1.0}))
    with pytest.warns(RuntimeWarning, match=f"taking over the lock left by pid {dead.pid}"):
        lock = RunLock(tmp_path).acquire()
    assert lock.taken_over["pid"] == dead.pid and read_lock(tmp_path)["pid"] == os.getpid()
    lock.release()
    # a lock file a process of another host wrote: this host cannot see it, so it is refused, with the way out
    (tmp_path / LOCK_FILE).write_text(json.dumps({"pid": 4242, "host": "node-17", "started": time.time()}))
    with pytest.raises(RunLockedError, match=f"pid 4242 on host node-17.*delete {tmp_path / LOCK_FILE}"):
        RunLock(tmp_path).acquire()
    assert not break_lock(tmp_path, 4243, "node-17") and break_lock(tmp_path, 4242, "node-17")
    # a lock file cut while being written: taken over
    (tmp_path / LOCK_FILE).write_text('{"pid": 12')
    with pytest.warns(RuntimeWarning, match="unreadable"):
        RunLock(tmp_path).acquire().release()


@pytest.mark.slow
def test_two_processes_on_one_run_folder(tmp_path):
    """The second process (a resume, or a fresh start) is refused while the first lives; after the first is
    SIGKILLed, a resume takes its lock over and finishes the run."""
    run_dir = tmp_path / "run"
    sets = ["train.stage1.max_env_steps=300", "train.checkpoint_every=100"]
    first = subprocess.Popen([PY, ROOT / "train.py", "--config", TINY, "--stage", "1", "--no-progress", "--run-dir",
                              run_dir, *[a for s in sets for a in ("--set", s)]], cwd=ROOT,
                             stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        deadline = time.time() + 120
        while not (run_dir / "checkpoint.pt").exists() and first.poll() is None and time.time() < deadline:
            time.sleep(0.02)
        first.send_signal(signal.SIGSTOP)  # alive, holding the lock, and not finishing meanwhile
        assert first.poll() is None, "the first run ended before the test could stop it"
        second = run([ROOT / "train.py", "--resume", run_dir, "--no-progress"])
        assert_one_clear_line(second, "in use by", f"pid {first.pid}", socket.gethostname(), "started")
        third = run([ROOT / "train.py", "--config", TINY, "--run-dir", run_dir, "--no-progress"])
        assert third.returncode != 0 and "Traceback" not in third.stderr
        first.send_signal(signal.SIGKILL)
        first.wait()
    finally:
        if first.poll() is None:
            first.kill()
            first.wait()
    assert read_lock(run_dir)["pid"] == first.pid  # left behind by the killed process
    done = run([ROOT / "train.py", "--resume", run_dir, "--no-progress"])
    assert done.returncode == 0, done.stderr[-2000:]
    assert f"taking over the lock left by pid {first.pid}" in done.stderr
    assert load_checkpoint(run_dir / "checkpoint.pt")["counters"]["env_steps"] == 300
    assert not (run_dir / LOCK_FILE).exists()


# ---- headless human rendering ----------------------------------------------------------------------------------
HEADLESS = """
import warnings
import gymnasium
import cyberdog
from gymnasium.utils.env_checker import check_env
with warnings.catch_warnings(record=True) as caught:
    warnings.simplefilter("always")
    env = gymnasium.make("CyberDog-v0", render_mode="human")
    env.reset(seed=0)
    env.step(env.action_space.sample())
    assert env.render() is None and env.unwrapped.walker.robot.gui is False
    env.close()
assert any("no window for the simulation" in str(w.message) for w in caught), [str(w.message) for w in caught]
check_env(gymnasium.make("CyberDog-v0").unwrapped)
print("CHECK_ENV_PASSED")
"""


@pytest.mark.parametrize("display", [None, ":93"], ids=["no-display", "unreachable-display"])
def test_human_render_mode_without_a_display_keeps_python_alive_and_check_env_passes(display):
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT), env.get("PYTHONPATH", "")])
    if display:
        env["DISPLAY"] = display
    proc = run(["-c", HEADLESS], env=env, timeout=300)
    assert proc.returncode == 0, proc.stdout[-2000:] + proc.stderr[-2000:]
    assert "CHECK_ENV_PASSED" in proc.stdout


# ---- damaged files on resume: clear error or recovery, never a silent fresh start -------------------------------
@pytest.fixture(scope="module")
def finished_run(tmp_path_factory):
    run_dir = tmp_path_factory.mktemp("finished")
    cfg = tiny(["train.stage1.max_env_steps=200", "train.checkpoint_every=100"])
    Trainer(cfg, run_dir, stages=(1,), progress=False).run()
    return run_dir


def _copy_run(src: Path, dst: Path) -> Path:
    import shutil
    shutil.copytree(src, dst)
    return dst


def test_a_damaged_checkpoint_is_a_clear_error_not_a_fresh_start(finished_run, tmp_path):
    run_dir = _copy_run(finished_run, tmp_path / "r")
    ckpt = run_dir / "checkpoint.pt"
    data = ckpt.read_bytes()
    metrics = (run_dir / "metrics.csv").read_bytes()
    ckpt.write_bytes(data[: len(data) // 3])  # truncated
    proc = run([ROOT / "train.py", "--resume", run_dir, "--no-progress"])
    assert_one_clear_line(proc, "corrupt", "checkpoint.pt")
    ckpt.write_bytes(b"")  # zero bytes
    with pytest.raises(CheckpointError, match="corrupt"):
        Trainer(C.load(C.ExperimentConfig, run_dir / "config.yaml"), run_dir, resume=True, progress=False)
    assert (run_dir / "metrics.csv").read_bytes() == metrics and ckpt.stat().st_size == 0  # nothing restarted
    assert not (run_dir / LOCK_FILE).exists()


def test_a_metrics_csv_cut_mid_line_is_recovered_with_a_warning(finished_run, tmp_path):
    run_dir = _copy_run(finished_run, tmp_path / "r")
    state = load_checkpoint(run_dir / "checkpoint.pt")
    rows = state["counters"]["csv_rows"]
    text = (run_dir / "metrics.csv").read_bytes()
    lines = text.split(b"\n")
    # cut in the middle of row rows-2: the last two complete rows and half of one are lost
    cut = b"\n".join(lines[:rows - 2]) + b"\n" + lines[rows - 2][:10]
    (run_dir / "metrics.csv").write_bytes(cut)
    cfg = C.load(C.ExperimentConfig, run_dir / "config.yaml")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        trainer = Trainer(cfg, run_dir, resume=True, progress=False)
        trainer.close()
    msg = " ".join(str(w.message) for w in caught)
    assert f"holds {rows - 3} complete rows but the checkpoint logged {rows}" in msg
    with open(run_dir / "metrics.csv", newline="") as f:
        table = list(csv.DictReader(f))
    assert len(table) == rows - 3 and all(len(r) == len(table[0]) and None not in r for r in table)
    assert [int(r["episode"]) for r in table] == list(range(1, rows - 2))
