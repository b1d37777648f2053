"""`train.num_envs`: several env processes (TorchRL `ParallelEnv`) collect for one trainer; tiny budgets
(configs/tiny.yaml: 20-step episodes, batches of 50 env steps, 0.5 updates per env step)."""
from __future__ import annotations

import multiprocessing as mp
import os
from pathlib import Path

import pytest
import torch

from cyberdog import config as C
from cyberdog.rl.checkpoint import load_checkpoint
from cyberdog.rl.torchrl_env import worker_seed
from cyberdog.rl.trainer import Trainer
from conftest import metrics_rows, stop_after, tiny

ROOT = Path(__file__).resolve().parents[1]
TWO_ENVS = ["train.num_envs=2", "train.stage1.max_env_steps=300", "train.checkpoint_every=100"]


def test_num_envs_is_an_integer_of_at_least_one_that_divides_the_batch():
    for bad in (0, -2, 1.5, True, "2"):
        with pytest.raises(ValueError, match=r"TrainConfig\.num_envs must be an integer >= 1"):
            C.TrainConfig(num_envs=bad)
    with pytest.raises(ValueError, match=r"TrainConfig\.frames_per_batch must be a multiple of num_envs \(3\)"):
        C.TrainConfig(num_envs=3, frames_per_batch=200)
    with pytest.raises(ValueError, match="num_envs"):
        tiny(TWO_ENVS, ["train.num_envs=0"])
    assert tiny(TWO_ENVS, ["train.num_envs=5"]).train.num_envs == 5 and C.TrainConfig().num_envs == 1


def test_worker_seeds_are_distinct_per_worker_and_per_run_and_repeat():
    seeds = [worker_seed(7, i) for i in range(8)]
    assert len(set(seeds)) == 8 and seeds == [worker_seed(7, i) for i in range(8)]
    assert worker_seed(8, 0) not in seeds and worker_seed(6, 1) not in seeds  # not seed + index
    assert all(0 <= s < 2 ** 32 for s in seeds)


@pytest.fixture(scope="module")
def two_env_run(tmp_path_factory):
    """Stage 1 of configs/tiny.yaml with two env processes, 300 env steps; records, at each round of updates,
    the frames it was given, the batch shape and the live child processes."""
    torch.set_num_threads(1)
    run_dir = tmp_path_factory.mktemp("two_envs")
    trainer = Trainer(tiny(TWO_ENVS), run_dir, stages=(1,), progress=False)
    seen = {"frames": [], "shapes": [], "children": [], "updates": []}
    updates, bookkeep = trainer._updates, trainer._bookkeep

    def spy_updates(frames):
        seen["frames"].append(frames)
        seen["children"].append(sorted(p.pid for p in mp.active_children() if p.is_alive()))
        n = updates(frames)
        seen["updates"].append(n)
        return n

    def spy_bookkeep(batch, *args):
        seen["shapes"].append(tuple(batch.shape))
        bookkeep(batch, *args)

    trainer._updates, trainer._bookkeep = spy_updates, spy_bookkeep
    summary = trainer.run()
    return run_dir, summary, seen


def test_two_env_processes_collect_and_each_episode_is_logged_once(two_env_run):
    run_dir, summary, seen = two_env_run
    # two worker processes, other than this one, collected every batch: [2 envs, 25 steps each]
    assert all(len(pids) == 2 and os.getpid() not in pids for pids in seen["children"]), seen["children"]
    assert set(seen["shapes"]) == {(2, 25)} and len(seen["shapes"]) == 6
    # env steps count both envs; one round of updates per batch of 50 frames, 0.5 update per frame once the 100
    # random frames are collected, as the update plan of the config (and a run with one env) says
    assert summary["env_steps"] == summary["stage_env_steps"] == summary["buffer_size"] == 300
    assert seen["frames"] == [50] * 6 and seen["updates"] == [0] + [25] * 5
    assert summary["updates"] == 125 == C.planned_updates(tiny(TWO_ENVS), (1,))[1]
    # each env ran 150 steps: 7 whole 20-step episodes each, logged once, in the order they ended
    table = metrics_rows(run_dir)
    assert len(table) == summary["episodes"] == 14
    assert [int(r["episode"]) for r in table] == list(range(1, 15))
    assert {r["length"] for r in table} == {"20"}
    steps = [int(r["env_steps"]) for r in table]  # env 0's k-th episode ends at 40k - 1, env 1's at 40k
    assert steps == [40 * k + d for k in range(1, 8) for d in (-1, 0)]
    assert table[-1]["critic_loss"] != "nan" and float(table[-1]["energy_J"]) > 0
    # the two envs are different streams: their observations differ at every step of the first batch
    data = load_checkpoint(run_dir / "checkpoint.pt")["replay"]["data"]
    env0, env1 = data["next"]["observation"][:25], data["next"]["observation"][25:50]
    assert (env0 != env1).any(dim=-1).all()


def test_two_env_runs_repeat_bit_for_bit_and_resume_to_the_same_counters(two_env_run, tmp_path):
    """A second run with the same seed, stopped after its checkpoint at 200 env steps, holds the same replay
    buffer and logged the same episodes as the first up to there; resumed, it ends with the same counters."""
    ref_dir, ref, _ = two_env_run
    ref_state = load_checkpoint(ref_dir / "checkpoint.pt")

    stop_after(Trainer(tiny(TWO_ENVS), tmp_path, stages=(1,), progress=False), 200)  # after its checkpoint at 200
    state = load_checkpoint(tmp_path / "checkpoint.pt")
    assert state["counters"]["env_steps"] == 200 and state["replay"]["size"] == 200
    ref_data, data = ref_state["replay"]["data"], state["replay"]["data"]
    for key in ("observation", "action"):
        assert torch.equal(data[key], ref_data[key][:200]), key
    for key in ("observation", "reward", "done", "energy_J"):
        assert torch.equal(data["next"][key], ref_data["next"][key][:200]), key
    logged = state["counters"]["episodes"]
    assert logged == 10 and metrics_rows(tmp_path)[:logged] == metrics_rows(ref_dir)[:logged]

    resumed = Trainer(tiny(TWO_ENVS), tmp_path, resume=True, progress=False).run()
    state = load_checkpoint(tmp_path / "checkpoint.pt")
    for k in ("env_steps", "stage_env_steps", "finished"):
        assert state["counters"][k] == ref_state["counters"][k], k
    assert resumed["updates"] == ref["updates"] and resumed["buffer_size"] == ref["buffer_size"]
    table = metrics_rows(tmp_path)  # every logged episode once; the two episodes running at the interruption are not
    assert [int(r["episode"]) for r in table] == list(range(1, state["counters"]["episodes"] + 1))
    assert table[:logged] == metrics_rows(ref_dir)[:logged]


@pytest.mark.slow
def test_async_collection_with_two_envs_runs_the_same_schedule_reproducibly(two_env_run, tmp_path):
    """train.collection=async with two envs (a ParallelEnv inside the collector process): the counters of the
    synchronous run, and a rerun with the seed sees the same data."""
    _, ref, _ = two_env_run
    cfg = tiny(TWO_ENVS, ["train.collection=async"])
    first = Trainer(cfg, tmp_path / "a", stages=(1,), progress=False).run()
    for k in ("env_steps", "stage_env_steps", "episodes", "updates", "buffer_size"):
        assert first[k] == ref[k], k
    Trainer(tiny(TWO_ENVS, ["train.collection=async", "train.stage1.max_env_steps=100"]), tmp_path / "b", stages=(1,),
            progress=False).run()
    rerun, table = metrics_rows(tmp_path / "b"), metrics_rows(tmp_path / "a")
    assert len(rerun) == 4 and rerun == table[:4]
    a = load_checkpoint(tmp_path / "a" / "checkpoint.pt")["replay"]["data"]["action"]
    b = load_checkpoint(tmp_path / "b" / "checkpoint.pt")["replay"]["data"]["action"]
    assert torch.equal(a[:100], b)
