"""Integration tests of `train.py` and the trainer with tiny budgets (configs/tiny.yaml)."""
from __future__ import annotations

import csv
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
import torch

from cyberdog import config as C
from cyberdog.rl.checkpoint import load_checkpoint
from cyberdog.rl.trainer import Trainer
from conftest import metrics_rows, stop_after, tiny

ROOT = Path(__file__).resolve().parents[1]
STAGE1 = ["train.stage1.max_env_steps=300", "train.checkpoint_every=100"]


@pytest.fixture(scope="module")
def reference_run(tmp_path_factory):
    """One uninterrupted stage-1 run of 300 env steps."""
    torch.set_num_threads(1)
    run_dir = tmp_path_factory.mktemp("ref")
    summary = Trainer(tiny(STAGE1), run_dir, stages=(1,), progress=False).run()
    return run_dir, summary


def test_short_run_writes_csv_tensorboard_and_checkpoint(reference_run):
    run_dir, summary = reference_run
    assert summary["env_steps"] == 300 and summary["updates"] > 0
    table = metrics_rows(run_dir)
    assert len(table) == summary["episodes"] >= 10
    assert {"score", "reward_speed", "reward_energy", "energy_J", "mean_speed", "actor_loss", "critic_loss",
            "q_mean"} <= set(table[0])
    assert float(table[-1]["energy_J"]) > 0 and table[-1]["critic_loss"] != "nan"
    assert list((run_dir / "tb").glob("events.out.tfevents.*"))
    state = load_checkpoint(run_dir / "checkpoint.pt")
    assert state["counters"]["env_steps"] == 300 and state["replay"]["size"] == 300
    assert C.load(C.ExperimentConfig, run_dir / "config.yaml") == tiny(STAGE1)
    assert (run_dir / "stage1_best_actor.pt").is_file() and (run_dir / "stage1_final.pt").is_file()


def agent_state(run_dir: Path) -> dict:
    return load_checkpoint(run_dir / "checkpoint.pt")["agent"]["loss"]


def test_same_seed_gives_identical_metrics_for_1000_steps(tmp_path):
    """Two runs of 1,000 env steps on the CPU (~500 updates): the same metrics, episode by episode, and the
    same weights at the end, bit for bit; another seed differs."""
    thousand = ["train.stage1.max_env_steps=1000", "train.checkpoint_every=500"]
    for name in ("a", "b"):
        summary = Trainer(tiny(STAGE1, thousand), tmp_path / name, stages=(1,), progress=False).run()
        assert summary["env_steps"] == 1000 and summary["updates"] >= 400
    table = metrics_rows(tmp_path / "a")
    assert len(table) >= 40 and table[-1]["env_steps"] == "1000"
    assert metrics_rows(tmp_path / "b") == table
    a, b = agent_state(tmp_path / "a"), agent_state(tmp_path / "b")
    assert all(torch.equal(a[k], b[k]) for k in a)
    other = tmp_path / "other_seed"
    Trainer(tiny(STAGE1, ["train.seed=1", "train.stage1.max_env_steps=100"]), other, stages=(1,), progress=False).run()
    assert metrics_rows(other)[:3] != table[:3]


@pytest.mark.slow  # about 20 s
def test_async_collection_runs_the_same_schedule_reproducibly_and_resumes(reference_run, tmp_path):
    """train.collection=async: the same counters as the synchronous run, identical reruns with a seed, and an
    interrupted run resumes (in a new collector process) to the same counters."""
    ref_dir, ref = reference_run
    ref_state = load_checkpoint(ref_dir / "checkpoint.pt")
    cfg = tiny(STAGE1, ["train.collection=async"])
    first = Trainer(cfg, tmp_path / "a", stages=(1,), progress=False).run()
    for k in ("env_steps", "stage_env_steps", "updates", "buffer_size"):
        assert first[k] == ref[k], k
    table = metrics_rows(tmp_path / "a")
    assert len(table) == first["episodes"] and table[-1]["critic_loss"] != "nan"

    stop_after(Trainer(cfg, tmp_path / "b", stages=(1,), progress=False), 200)
    assert load_checkpoint(tmp_path / "b" / "checkpoint.pt")["counters"]["env_steps"] == 200
    resumed = Trainer(cfg, tmp_path / "b", resume=True, progress=False).run()
    state = load_checkpoint(tmp_path / "b" / "checkpoint.pt")
    for k in ("env_steps", "stage_env_steps", "finished"):
        assert state["counters"][k] == ref_state["counters"][k], k
    assert resumed["updates"] == ref["updates"] and len(metrics_rows(tmp_path / "b")) == state["counters"]["episodes"]
    # a rerun from scratch sees the same data: identical to the first run (here its first 100 env steps)
    Trainer(tiny(STAGE1, ["train.collection=async", "train.stage1.max_env_steps=100"]), tmp_path / "c", stages=(1,),
            progress=False).run()
    rerun = metrics_rows(tmp_path / "c")
    assert len(rerun) >= 4 and rerun == table[:len(rerun)]


def _train(*args: str) -> list[str]:
    return [sys.executable, str(ROOT / "train.py"), "--config", str(ROOT / "configs/tiny.yaml"), "--stage", "1",
            "--no-progress", *[a for s in STAGE1 for a in ("--set", s)], *args]


def test_killed_run_resumes_to_the_same_counters(reference_run, tmp_path):
    ref_dir, ref = reference_run
    run_dir = tmp_path / "killed"
    proc = subprocess.Popen(_train("--run-dir", str(run_dir)), cwd=ROOT, stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL)
    deadline = time.time() + 60
    while not (run_dir / "checkpoint.pt").exists() and proc.poll() is None and time.time() < deadline:
        time.sleep(0.05)
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    assert proc.returncode == -signal.SIGKILL, "the run finished before it could be killed"
    killed_at = load_checkpoint(run_dir / "checkpoint.pt")["counters"]["env_steps"]
    assert 0 < killed_at < 300
    done = subprocess.run([sys.executable, str(ROOT / "train.py"), "--resume", str(run_dir), "--no-progress"],
                          cwd=ROOT, capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr[-2000:]
    state = load_checkpoint(run_dir / "checkpoint.pt")
    ref_state = load_checkpoint(ref_dir / "checkpoint.pt")
    for k in ("env_steps", "stage_env_steps", "finished"):
        assert state["counters"][k] == ref_state["counters"][k], k
    assert state["agent"]["updates"] == ref_state["agent"]["updates"] == ref["updates"]
    assert state["replay"]["size"] == ref_state["replay"]["size"] == ref["buffer_size"]
    assert len(metrics_rows(run_dir)) == state["counters"]["episodes"]  # every logged episode exactly once


def test_cli_errors_are_clear(tmp_path):
    bad = subprocess.run(_train("--set", "agent.algorithm=ppo", "--run-dir", str(tmp_path)), cwd=ROOT,
                         capture_output=True, text=True)
    assert bad.returncode != 0 and "AgentConfig.algorithm" in bad.stderr
    missing = subprocess.run([sys.executable, str(ROOT / "train.py"), "--resume", str(tmp_path / "nothing")],
                             cwd=ROOT, capture_output=True, text=True)
    assert missing.returncode != 0 and "config.yaml" in missing.stderr


def test_help_documents_every_option():
    out = subprocess.run([sys.executable, str(ROOT / "train.py"), "--help"], capture_output=True, text=True)
    for opt in ("--config", "--stage", "--seed", "--run-dir", "--set", "--resume", "--init-from", "--device"):
        assert opt in out.stdout


@pytest.mark.parametrize("preset", sorted(p.name for p in (ROOT / "configs").glob("*.yaml")))
def test_every_shipped_preset_is_a_valid_config(preset):
    preset = C.load_preset(ROOT / "configs" / preset)
    assert preset.summary, "train.py --help lists every preset with its one line"
    for phase in preset.phases:
        cfg = phase.config
        assert cfg.env.max_episode_steps >= 1 and cfg.train.stage2.reward.energy < 0 == cfg.train.stage1.reward.energy
        C.check_planned_updates(cfg, (1, 2) if phase.stage == "both" else (int(phase.stage),))


def test_a_foot_mode_run_trains_and_its_actor_moves_the_feet(tmp_path):
    """The trainer end to end in action_mode="foot" with the previous action observed (62 inputs, tiny
    budget): it updates, and the trained actor's actions move the foot targets (a rollout differs from the
    zero-action trot)."""
    from cyberdog.rl.rollout import load_actor, rollout
    cfg = tiny(STAGE1, ["env.action_mode=foot", "agent.exploration_sigma=0.5", "agent.exploration_sigma_end=0.5",
                "env.observe_last_action=true"])
    summary = Trainer(cfg, tmp_path, stages=(1,), progress=False).run()
    assert summary["updates"] > 0
    actor = load_actor(tmp_path / "stage1_final_actor.pt")
    assert actor.config.env.action_mode == "foot" and actor.config.env.observe_last_action
    moved = rollout(actor, speed=1.0, duration=0.2)
    zero = rollout(type(actor)(lambda obs: torch.zeros(12), actor.config), speed=1.0, duration=0.2)
    assert abs(moved.energy - zero.energy) > 1e-6


@pytest.mark.slow  # about 20 s
def test_a_finished_stage_trains_longer_under_a_raised_budget_and_keeps_its_earlier_result(reference_run, tmp_path):
    import shutil
    run_dir = tmp_path / "longer"
    shutil.copytree(reference_run[0], run_dir)
    before = {p.name: p.read_bytes() for p in run_dir.glob("stage1_final*.pt")}
    assert set(before) == {"stage1_final.pt", "stage1_final_actor.pt"}
    config_before = (run_dir / "config.yaml").read_text()

    def resume(*sets):
        return subprocess.run([sys.executable, str(ROOT / "train.py"), "--resume", str(run_dir), "--no-progress",
                               *[a for s in sets for a in ("--set", s)]],
                              cwd=ROOT, capture_output=True, text=True, timeout=120)

    for refused, words in ((["train.stage1.max_env_steps=200"], "not lower it"),  # finished: raise only
                           (["train.stage1.max_env_steps=500", "agent.actor_lr=0.01"], "agent.actor_lr"),
                           (["train.stage2.max_env_steps=500"], "current stage's budget")):
        proc = resume(*refused)
        assert proc.returncode != 0 and words in proc.stderr, proc.stderr[-1500:]
        assert (run_dir / "config.yaml").read_text() == config_before  # nothing touched
        assert {p.name: p.read_bytes() for p in run_dir.glob("stage1_final*.pt")} == before

    done = resume("train.stage1.max_env_steps=1100")
    assert done.returncode == 0, done.stderr[-2000:]
    assert "raised budget" in done.stderr
    state = load_checkpoint(run_dir / "checkpoint.pt")
    assert state["counters"]["finished"] and state["counters"]["stage_env_steps"] >= 1100
    assert C.load(C.ExperimentConfig, run_dir / "config.yaml").train.stage1.max_env_steps == 1100
    for name, data in before.items():  # the 300-step result, kept under its step count
        assert (run_dir / name.replace(".pt", "_300steps.pt")).read_bytes() == data
    actor = torch.load(run_dir / "stage1_final_actor.pt", weights_only=True)
    assert actor["env_steps"] >= 1100 and state["agent"]["updates"] > reference_run[1]["updates"]
    assert len(metrics_rows(run_dir)) == state["counters"]["episodes"]  # the log continues, no episode twice
    with open(run_dir / "metrics.csv") as f:
        log = list(csv.DictReader(f))
    after_rates = [float(r["env_steps_per_s"]) for r in log if int(r["env_steps"]) > 300]
    # the resumed process's rate counts its own steps, not the 300 the earlier process made: counted with them, its
    # first row (~40 own steps) would read ~8x its rate and its last (800 own steps) ~1.4x, the first several times
    # the last; compared within the one process, a change of the machine's load between the two processes cannot
    # fail it, and the first batch's start-up only lowers the first
    assert len(after_rates) > 1 and after_rates[0] < 3 * after_rates[-1], after_rates


def test_a_resume_may_end_an_unfinished_stage_sooner_but_not_before_where_it_is(tmp_path):
    """A budget lowered on resume, to a point the stage has not reached, ends the stage there with its final
    files and the config recording the new budget; lowered to or below the steps made, it is refused and
    nothing changes."""
    from cyberdog.rl.checkpoint import CheckpointError
    stop_after(Trainer(tiny(["train.stage1.max_env_steps=600", "train.checkpoint_every=100"]), tmp_path,
                       stages=(1,), progress=False), 200)
    made = load_checkpoint(tmp_path / "checkpoint.pt")["counters"]["stage_env_steps"]
    assert 200 <= made < 300
    config_before = (tmp_path / "config.yaml").read_text()
    with pytest.raises(CheckpointError, match="not lower it"):
        Trainer(tiny(["train.stage1.max_env_steps=" + str(made), "train.checkpoint_every=100"]), tmp_path,
                resume=True, progress=False)
    assert (tmp_path / "config.yaml").read_text() == config_before
    summary = Trainer(tiny(STAGE1), tmp_path, resume=True, progress=False).run()
    state = load_checkpoint(tmp_path / "checkpoint.pt")["counters"]
    assert state["finished"] and 300 <= state["stage_env_steps"] < 600, state
    assert summary["env_steps"] == state["env_steps"]
    assert C.load(C.ExperimentConfig, tmp_path / "config.yaml").train.stage1.max_env_steps == 300
    assert (tmp_path / "stage1_final_actor.pt").is_file()


def test_a_resume_says_from_which_step_and_the_progress_line_shows_length_and_falls(tmp_path, capsys):
    cfg = tiny(STAGE1)
    stop_after(Trainer(cfg, tmp_path, stages=(1,), progress=False), 200)
    resumed = Trainer(cfg, tmp_path, resume=True, progress=False)
    err = capsys.readouterr().err
    assert "resuming" in err and "stage 1 at env step 200 of the stage (200 in all)" in err
    fields = resumed._progress_fields({"updates_per_s": 10.0})
    assert {"ep", "score", "len", "falls", "upd_s"} <= set(fields) and fields["falls"].endswith("%")
    resumed.close()
