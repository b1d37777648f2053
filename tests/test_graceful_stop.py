"""SIGINT and SIGTERM stop a training at its next safe point with a checkpoint that holds every env step
logged; the resume continues from it and ends with the counters of a run never stopped."""
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
import torch

from conftest import metrics_rows

ROOT = Path(__file__).resolve().parents[1]
SETS = ["train.stage1.max_env_steps=2000", "train.stage2.max_env_steps=200", "train.checkpoint_every=1000000"]
COUNTERS = ("stage", "env_steps", "stage_env_steps", "stage_updates")


def train(run_dir: Path, *extra: str) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, str(ROOT / "train.py"), "--config", "configs/tiny.yaml", "--run-dir",
                             str(run_dir), "--no-progress", *extra], cwd=ROOT, stdout=subprocess.PIPE,
                            stderr=subprocess.STDOUT, text=True)


def counters(run_dir: Path) -> dict:
    state = torch.load(run_dir / "checkpoint.pt", weights_only=True)
    return {k: state["counters"][k] for k in COUNTERS} | {"updates": state["agent"]["updates"]}


@pytest.fixture(scope="module")
def uninterrupted(tmp_path_factory) -> dict:
    run_dir = tmp_path_factory.mktemp("whole") / "run"
    proc = train(run_dir, "--set", *SETS)
    out = proc.communicate(timeout=600)[0]  # (and closes its pipe)
    assert proc.returncode == 0, out
    return counters(run_dir)


@pytest.mark.slow
@pytest.mark.parametrize("signum, code", [(signal.SIGINT, 130), (signal.SIGTERM, 143)], ids=["SIGINT", "SIGTERM"])
def test_a_stop_signal_checkpoints_every_logged_step_and_the_resume_loses_nothing(signum, code, tmp_path,
                                                                                   uninterrupted):
    run_dir = tmp_path / "run"
    proc = train(run_dir, "--set", *SETS)
    deadline = time.time() + 300
    while len(metrics_rows(run_dir)) < 10 and time.time() < deadline and proc.poll() is None:
        time.sleep(0.2)  # mid-stage 1: episodes are being logged
    assert proc.poll() is None, "the run ended before the signal"
    proc.send_signal(signum)
    out = proc.communicate(timeout=300)[0]
    assert proc.returncode == code, out
    assert f"continue with: python train.py --resume {run_dir}" in out
    stopped = counters(run_dir)
    rows = metrics_rows(run_dir)
    assert stopped["stage"] == 1 and 0 < stopped["env_steps"] < 2000
    assert max(int(r["env_steps"]) for r in rows) <= stopped["env_steps"]  # every logged step is in it
    state = torch.load(run_dir / "checkpoint.pt", weights_only=True)
    assert state["counters"]["csv_rows"] == len(rows)  # the resume keeps every logged row

    proc = subprocess.run([sys.executable, str(ROOT / "train.py"), "--resume", str(run_dir), "--no-progress"],
                          cwd=ROOT, capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert metrics_rows(run_dir)[:len(rows)] == rows  # nothing logged before the stop was cut back
    assert counters(run_dir) == uninterrupted


def test_a_stop_signal_ends_a_round_of_updates_after_the_update_in_hand_and_the_resume_pays_the_rest(tmp_path):
    """Under load one round of updates takes minutes: a signal stops it within one update; the updates it owed
    are kept as a credit in the checkpoint, and the resumed run makes them before anything else."""
    from conftest import tiny
    from cyberdog.rl.trainer import Trainer

    cfg = tiny(["train.init_random_frames=0", "train.stage1.max_env_steps=100", "train.updates_per_frame=1.0",
                "train.frames_per_batch=100", "train.batch_size=8"])
    trainer = Trainer(cfg, tmp_path, stages=(1,), progress=False)
    update, made = trainer.agent.update, []

    def update_then_signal(*args, **kwargs):
        made.append(1)
        if len(made) == 3:
            trainer._stop.signum = signal.SIGINT  # as the handler does
        return update(*args, **kwargs)

    trainer.agent.update = update_then_signal
    with pytest.raises(Exception, match="SIGINT|stopped"):
        trainer.run()
    state = torch.load(tmp_path / "checkpoint.pt", weights_only=True)
    assert len(made) == 3 and state["counters"]["stage_updates"] == 3
    assert state["counters"]["update_credit"] == pytest.approx(97.0)
    resumed = Trainer(cfg, tmp_path, resume=True, progress=False).run()
    assert resumed["updates"] == 100  # what the stage owes at 1 update per env step: none lost
