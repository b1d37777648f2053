"""The code's commit in what the project writes: `code_state` reads it from the checkout alone, a training run
records the commit of each process that trained it, and tools/ship.py carries it into metadata.json."""
from __future__ import annotations

import importlib.util
import json
import subprocess
from pathlib import Path

import pytest
import torch

from cyberdog.provenance import code_state
from cyberdog.rl.trainer import Trainer
from rl_helpers import tiny_config

ROOT = Path(__file__).resolve().parents[1]


def test_each_process_that_trains_a_run_records_its_commit(tmp_path, monkeypatch):
    """`trained_at`: the commit of the process that began the run, then of each resume at another commit, in the
    checkpoint and the actor files; a checkpoint from before the record says so rather than guessing."""
    from cyberdog.rl import trainer as trainer_module
    from cyberdog.rl.checkpoint import recorded_code
    from cyberdog.rl.rollout import load_actor
    from cyberdog.rl.run_state import resumed_code

    here = code_state()
    trainer = Trainer(tiny_config(), tmp_path / "run", progress=False)
    assert trainer.trained_at == [here]
    trainer.save()
    trainer.close()
    later = {"git_commit": "0" * 40, "git_dirty": True}
    monkeypatch.setattr(trainer_module, "code_state", lambda: later)
    resumed = Trainer(tiny_config(), tmp_path / "run", resume=True, progress=False)
    assert resumed.trained_at == [here, later]
    resumed._save_actor("actor.pt", 0.0)
    resumed.save()
    resumed.close()
    assert recorded_code(tmp_path / "run" / "actor.pt") == [here, later]
    assert load_actor(tmp_path / "run" / "actor.pt").meta["trained_at"] == [here, later]  # into a path's provenance
    again = Trainer(tiny_config(), tmp_path / "run", resume=True, progress=False)  # the same commit: no new entry
    assert again.trained_at == [here, later]
    again.close()
    assert resumed_code(None, later) == [{"git_commit": "not recorded", "git_dirty": None}, later]


def git(folder: Path, *args: str) -> str:
    return subprocess.run(["git", "-c", "user.name=t", "-c", "user.email=t@t", *args], cwd=folder, check=True,
                          capture_output=True, text=True).stdout.strip()


def test_the_commit_is_read_at_the_top_of_a_checkout_only(tmp_path):
    """HEAD's sha and whether anything differs from it; a folder inside a checkout (an installed package under
    someone's repository) or outside any reads as unknown, never as the commit around it."""
    repo = tmp_path / "repo"
    (repo / "pkg").mkdir(parents=True)
    (repo / "pkg" / "a.py").write_text("x = 1\n")
    git(repo, "init", "-q")
    git(repo, "add", ".")
    git(repo, "commit", "-qm", "one")
    assert code_state(repo) == {"git_commit": git(repo, "rev-parse", "HEAD"), "git_dirty": False}
    (repo / "results").mkdir()
    (repo / "results" / "shipped.json").write_text("{}")  # an output shipped into the checkout: not code
    assert code_state(repo)["git_dirty"] is False
    (repo / "pkg" / "a.py").write_text("x = 2\n")
    assert code_state(repo)["git_dirty"] is True
    unknown = {"git_commit": "unknown", "git_dirty": None}
    assert code_state(repo / "pkg") == unknown and code_state(tmp_path) == unknown


def actor_file(path: Path, trained_at=None) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    torch.save({"actor": {}, "score": 0.0, **({"trained_at": trained_at} if trained_at else {})}, path)
    return path


def finished_run(folder: Path, trained_at=None) -> Path:
    """A run folder tools/ship.py policy accepts: both stages' actor files, config.yaml, a one-row metrics.csv."""
    import yaml
    for stage in (1, 2):
        actor_file(folder / f"stage{stage}_final_actor.pt", trained_at)
    (folder / "config.yaml").write_text(yaml.safe_dump({"train": {"seed": 5}}))
    (folder / "metrics.csv").write_text("stage,wall_time_s,env_steps_per_s,length,window_mean_score,score,energy_J\n"
                                        "1,10.0,50.0,400,1.0,2.0,1000\n2,20.0,50.0,400,1.0,2.0,1000\n")
    return folder


def test_shipping_carries_the_commit_that_trained_the_actors_not_the_one_that_ships_them(tmp_path):
    spec = importlib.util.spec_from_file_location("ship", ROOT / "tools/ship.py")
    ship = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(ship)
    trained = [{"git_commit": "1" * 40, "git_dirty": False}]
    run = finished_run(tmp_path / "recorded", trained)
    with pytest.raises(SystemExit, match="record the commit"):  # a stated commit beside a recorded one: refused
        ship.main(["policy", str(run), "--out", str(tmp_path / "a"), "--trained-at", "HEAD"])
    assert not (tmp_path / "a").exists()
    assert ship.main(["policy", str(run), "--out", str(tmp_path / "a")]) == 0
    meta = json.loads((tmp_path / "a" / "metadata.json").read_text())
    assert meta["trained_at"] == {"stage1_actor.pt": trained, "stage2_actor.pt": trained}
    assert meta["shipped_at"] == code_state()

    old = finished_run(tmp_path / "old")  # actor files from before the record
    with pytest.raises(SystemExit, match="not a commit"):
        ship.main(["policy", str(old), "--out", str(tmp_path / "b"), "--trained-at", "no-such-commit"])
    assert ship.main(["policy", str(old), "--out", str(tmp_path / "b"), "--trained-at", "HEAD"]) == 0
    stated = json.loads((tmp_path / "b" / "metadata.json").read_text())["trained_at"]["stage2_actor.pt"]
    assert stated == [{"git_commit": git(ROOT, "rev-parse", "HEAD"), "git_dirty": None, "stated": "--trained-at"}]
    assert ship.main(["policy", str(old), "--out", str(tmp_path / "c")]) == 0
    assert json.loads((tmp_path / "c" / "metadata.json").read_text())["trained_at"]["stage1_actor.pt"] == \
        "not recorded"
