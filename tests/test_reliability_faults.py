"""Fault injection: a tiny training SIGKILLed at many moments (between batches, inside checkpoint and actor
writes, between a write and its rename, right after a rename) and resumed after each kill.

Every resume either continues (it is then killed again, or finishes) or is refused with one clear line (a kill
before the first checkpoint: the test then starts the run again, as a user would); no kill loses more than the
env steps since the last checkpoint that was completely written; and the final counters equal those of an
uninterrupted run. The figures (kills, resumes, steps lost at most, wall time) are printed (`pytest -s`).
"""
from __future__ import annotations

import csv
import json
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from cyberdog import config as C
from cyberdog.rl.checkpoint import TEMPORARY_GLOB, load_checkpoint
from cyberdog.rl.trainer import Trainer
from cyberdog.runlock import LOCK_FILE

ROOT = Path(__file__).resolve().parents[1]
TINY = ROOT / "configs" / "tiny.yaml"
SETS = ["train.stage1.max_env_steps=600", "train.stage2.max_env_steps=400", "train.checkpoint_every=100"]
CHECKPOINT_EVERY, FRAMES_PER_BATCH = 100, 50  # from SETS and tiny.yaml

# One process that imports torch once and forks each training attempt (a fresh train.py process costs seconds
# of imports): an attempt installs its kill moment (see KILLS), runs train.py's main and is SIGKILLed there,
# printing the env steps collected and those of the last checkpoint.pt it completed; the driver prints a JSON
# line per attempt with the env steps of the checkpoint.pt left on disk.
DRIVER = r"""
import io, json, os, runpy, signal, sys
root, run_dir, plan = sys.argv[1], sys.argv[2], json.loads(sys.argv[3])
fresh_args = sys.argv[4:]
sys.path.insert(0, root)
import torch  # imported once here; each attempt is a fork of this process, which has run no torch op yet
import cyberdog.rl.trainer as tr


def install(mode, n):
    count = {"batch": 0, "save": 0}
    state = {"trainer": None, "done": None}

    def die(where):
        t = state["trainer"]
        steps = t.progress.env_steps if t is not None else 0
        print(f"KILLED {mode} {n} at env_steps={steps} last_checkpoint_done={state['done']} in {where}",
              file=sys.stderr, flush=True)
        os.kill(os.getpid(), signal.SIGKILL)

    updates = tr.Trainer._updates
    def counted_updates(self, frames):
        state["trainer"] = self
        count["batch"] += 1
        if mode == "batch" and count["batch"] == n:
            die("batch")
        return updates(self, frames)
    tr.Trainer._updates = counted_updates

    real_save, real_replace = torch.save, os.replace
    def dying_save(obj, f, *a, **k):
        count["save"] += 1
        if mode == "save-mid" and count["save"] == n:
            buf = io.BytesIO()
            real_save(obj, buf)
            f.write(buf.getvalue()[: buf.tell() // 2])
            f.flush()
            die(f"torch.save of {os.path.basename(os.readlink(f'/proc/self/fd/{f.fileno()}'))}")
        return real_save(obj, f, *a, **k)
    torch.save = dying_save

    def dying_replace(src, dst, *a, **k):
        name = os.path.basename(str(src))
        ours = name.endswith(".tmp") and ".pt." in name  # a file of save_atomic
        if ours and mode == "save-rename" and count["save"] == n:
            die(f"rename to {os.path.basename(str(dst))}")
        real_replace(src, dst, *a, **k)
        if ours and os.path.basename(str(dst)) == "checkpoint.pt" and state["trainer"] is not None:
            state["done"] = state["trainer"].progress.last_checkpoint
        if ours and mode == "save-after" and count["save"] == n:
            die(f"just after the rename to {os.path.basename(str(dst))}")
    os.replace = dying_replace


def attempt(i, mode, n, args):
    log = os.path.join(os.path.dirname(run_dir), f"attempt{i}.log")
    pid = os.fork()
    if pid == 0:
        fd = os.open(log, os.O_WRONLY | os.O_CREAT | os.O_TRUNC)
        os.dup2(fd, 1)
        os.dup2(fd, 2)
        code = 0
        try:
            if mode:
                install(mode, n)
            sys.argv = [os.path.join(root, "train.py")] + args
            runpy.run_path(sys.argv[0], run_name="__main__")
        except SystemExit as e:
            code = e.code if isinstance(e.code, int) else (0 if e.code is None else (print(e.code, file=sys.stderr) or 1))
        except BaseException:
            import traceback
            traceback.print_exc()
            code = 1
        sys.stdout.flush(); sys.stderr.flush()
        os._exit(code)
    _, status = os.waitpid(pid, 0)
    rc = -os.WTERMSIG(status) if os.WIFSIGNALED(status) else os.WEXITSTATUS(status)
    ckpt = os.path.join(run_dir, "checkpoint.pt")
    on_disk = None
    if os.path.isfile(ckpt):
        on_disk = int(torch.load(ckpt, map_location="cpu", weights_only=True)["counters"]["env_steps"])
    print(json.dumps({"i": i, "mode": mode, "n": n, "args": args, "rc": rc, "log": log, "checkpoint_steps": on_disk}),
          flush=True)
    return rc


resume = ["--resume", run_dir, "--no-progress"]
i = 0
for mode, n in plan:
    if os.path.isfile(os.path.join(run_dir, "checkpoint.pt")):
        rc = attempt(i, mode, n, resume)
    else:
        if os.path.isdir(run_dir):  # killed before its first checkpoint: a resume is refused, then a new start
            i += 1
            attempt(i, None, 0, resume)
            import shutil
            shutil.rmtree(run_dir)
            i += 1
        rc = attempt(i, mode, n, fresh_args)
    i += 1
    if rc == 0:
        break
attempt(i, None, 0, resume)  # the last resume runs to the end
"""

# (mode, N) of each attempt in the chain, each killed at the N-th such moment of its own process:
#   batch N        at the start of the N-th round of updates (after the N-th batch of env steps was collected)
#   save-mid N     halfway through writing the N-th file of save_atomic (checkpoint, stage-final or actor file)
#   save-rename N  after the N-th file of save_atomic is written and synced, before its rename
#   save-after N   right after the N-th rename (the new file is in place; what follows it is not done yet)
KILLS = [("batch", 1), ("save-mid", 2), ("batch", 4), ("save-rename", 3), ("save-after", 2), ("batch", 3),
         ("save-mid", 5), ("save-rename", 6), ("batch", 5), ("save-after", 4), ("save-mid", 3), ("batch", 2),
         ("save-rename", 2), ("batch", 4)]


def csv_rows(run_dir: Path) -> list[dict]:
    with open(run_dir / "metrics.csv", newline="") as f:
        return list(csv.DictReader(f))


@pytest.mark.slow
def test_sigkill_at_many_moments_and_resume_each(tmp_path):
    t_start = time.perf_counter()
    cfg = C.override(C.load(C.ExperimentConfig, TINY), SETS)
    ref = Trainer(cfg, tmp_path / "reference", progress=False).run()
    ref_state = load_checkpoint(tmp_path / "reference" / "checkpoint.pt")

    driver = tmp_path / "driver.py"
    driver.write_text(DRIVER)
    run_dir = tmp_path / "run"
    fresh = ["--config", str(TINY), "--run-dir", str(run_dir), "--no-progress", *[a for s in SETS for a in ("--set", s)]]
    proc = subprocess.run([sys.executable, str(driver), str(ROOT), str(run_dir), json.dumps(KILLS), *fresh], cwd=ROOT,
                          capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr[-3000:]
    attempts = [json.loads(ln) for ln in proc.stdout.splitlines() if ln.startswith("{")]
    wall = time.perf_counter() - t_start

    kills, resumed, refused, lost, where = 0, 0, 0, [], []
    start_steps = 0  # the checkpoint the current attempt started from (0: a fresh start)
    for a in attempts:
        log = Path(a["log"]).read_text()
        assert "Traceback" not in log, log[-3000:]
        is_resume = "--resume" in a["args"]
        if a["mode"] is None and a is not attempts[-1]:  # a resume after a kill before the first checkpoint
            lines = [ln for ln in log.splitlines() if ln.strip() and not ln.startswith("pybullet build")]
            assert a["rc"] != 0 and len(lines) == 1 and "no checkpoint.pt" in lines[0], log
            refused += 1
            start_steps = 0
            continue
        if a["rc"] == 0:
            resumed += is_resume
            continue
        assert a["rc"] == -signal.SIGKILL, log[-3000:]
        kills += 1
        resumed += is_resume
        note = next(ln for ln in log.splitlines() if ln.startswith("KILLED"))
        where.append(note.split(" at ")[0][7:] + " in " + note.split(" in ")[-1])
        reached = int(note.split("env_steps=")[1].split()[0])
        done = note.split("last_checkpoint_done=")[1].split()[0]
        on_disk = a["checkpoint_steps"]
        if on_disk is None:  # killed before the run's first checkpoint
            assert reached < CHECKPOINT_EVERY + FRAMES_PER_BATCH, note
            lost.append(reached)
        else:
            # the next attempt starts from the last checkpoint completed before the kill (this attempt's, or the
            # one it started from): never an older one, never from scratch
            assert on_disk == (int(done) if done != "None" else start_steps), note
            assert reached - on_disk <= CHECKPOINT_EVERY + FRAMES_PER_BATCH, note
            lost.append(reached - on_disk)
        start_steps = on_disk or 0
    assert attempts[-1]["rc"] == 0

    state = load_checkpoint(run_dir / "checkpoint.pt")
    for k in ("stage", "env_steps", "stage_env_steps", "finished"):
        assert state["counters"][k] == ref_state["counters"][k], k
    assert state["agent"]["updates"] == ref["updates"] and state["replay"]["size"] == ref["buffer_size"]
    rows = csv_rows(run_dir)  # every logged episode once, in order, no torn line
    assert [int(r["episode"]) for r in rows] == list(range(1, state["counters"]["episodes"] + 1))
    assert all(None not in r and r["score"] for r in rows)
    steps = [int(r["env_steps"]) for r in rows]
    assert steps == sorted(steps) and steps[-1] <= ref_state["counters"]["env_steps"]
    for name in ("stage1_final.pt", "stage2_final.pt"):
        assert "replay" not in load_checkpoint(run_dir / name)
    assert not list(run_dir.glob(TEMPORARY_GLOB)) and not list((run_dir / "saved").glob(TEMPORARY_GLOB))
    assert not (run_dir / LOCK_FILE).exists()
    assert kills >= 10, where
    print(f"\nfault injection: {kills} SIGKILLs, {resumed} resumes succeeded, {refused} refused (no checkpoint yet; "
          f"the run was started again); env steps lost at most {max(lost)} (checkpoint every {CHECKPOINT_EVERY}); "
          f"{wall:.0f} s wall time")
    for w in where:
        print("  killed: " + w)
