"""Collection of env steps, in this process (`train.collection="sync"`) or in a worker process ("async").

On a CPU the environment (PyBullet plus the trot controller in Python, which holds the GIL) and the gradient
updates each fill one core. In the synchronous mode they take turns: the pipeline's env steps per second at
one update per step are bounded by 1 / (env time + update time). `ProcessCollector` runs the environment and a
copy of the exploration policy in a separate process, so that the next batch of env steps is collected while
the trainer updates on the previous one: 1 / max(env time, update time) on two cores.

The two processes work in lock step, one batch ahead: when batch k arrives, the trainer sends the policy's
current weights (actor and exploration-noise state) with the request for batch k+1, then updates on batch k.
Batch k+1 is therefore collected by the policy as it was before the updates on batch k (a lag of one batch,
as in TorchRL's asynchronous collectors), and the data a run sees does not depend on timing: with the same seed
two asynchronous runs are identical too. The worker seeds its own RNG (exploration noise, initial random
actions) from the env seed it is given, so a resumed run is reproducible from its checkpoint, but it does
not draw the same numbers as a synchronous run.

**Several envs** (`train.num_envs` = N > 1): the env becomes TorchRL's `ParallelEnv` of N copies, one process
each (`cyberdog.rl.torchrl_env.make_batched_env`), inside the same single-process `Collector`; in the async mode that
collector, and so the `ParallelEnv`, lives in the worker process. A batch of `frames_per_batch` env steps is
then `frames_per_batch / N` steps of each env, shape [N, frames_per_batch / N]. Why this and not TorchRL's
multi-process collectors: `MultiaSyncDataCollector` hands over batches in the order the workers finish them,
so the replay buffer's contents would depend on timing; `MultiSyncDataCollector` is lock step too, but runs a
copy of the policy in each worker, whose weights (and exploration-noise state) would have to be shipped to N
processes after every round of updates. With a `ParallelEnv` there is one policy, on the trainer's device (a
GPU if there is one), evaluated on the N observations at once; it collects with the weights of the latest
update (sync) or one batch behind (async), exactly as with one env, and its exploration noise and initial
random actions come from one RNG, the trainer's (sync, restored by a resume) or the worker's (async, seeded).
The workers step in lock step, so for a fixed N a seed gives the same data; another N gives other data.
"""
from __future__ import annotations

import multiprocessing as mp
import pickle
import time
import traceback

import torch
from tensordict import TensorDictBase
from torchrl.collectors import Collector

from cyberdog.config import AgentConfig, EnvConfig, RewardConfig
from cyberdog.rl.exploration import make_exploration
from cyberdog.rl.networks import make_actor
from cyberdog.rl.stop import ignore_stop_signals
from cyberdog.rl.torchrl_env import make_batched_env, make_env

WORKER_START_TIMEOUT_S = 300.0  # first batch: the worker imports torch, builds the env and collects
WORKER_STOP_TIMEOUT_S = 60.0  # several envs: the batch in flight, then closing the env processes


def make_collector(env, policy, frames_per_batch: int, init_random_frames: int, device) -> Collector:
    """TorchRL's single-process collector, as both modes use it (the async mode inside its worker)."""
    return Collector(env, policy, frames_per_batch=frames_per_batch, total_frames=-1,
                     init_random_frames=init_random_frames or None, policy_device=device, env_device="cpu",
                     storing_device="cpu", auto_register_policy_transforms=False)


def _policy_state(policy: torch.nn.Module) -> dict:
    return {k: v.detach().cpu() for k, v in policy.state_dict().items()}


def make_env_for_collection(env_cfg: EnvConfig, reward: RewardConfig, seed: int, num_envs: int = 1,
                            training_steps: int = 0):
    """The env a collector steps: one `make_env` (batch size []), or N of them in `ParallelEnv` ([N]).
    `training_steps`: env steps of training already made (the trot prior's decay counts them), each step of
    an env then `num_envs` more (they step in lock step)."""
    if num_envs == 1:
        return make_env(env_cfg, reward, seed=seed, track_init=True, training_steps=training_steps)
    return make_batched_env(env_cfg, reward, seed, num_envs, track_init=True, training_steps=training_steps)


def _worker(conn, env_cfg: EnvConfig, reward: RewardConfig, seed: int, agent_cfg: AgentConfig,
            observation_size: int, action_size: int, frames_per_batch: int, init_random_frames: int,
            num_envs: int = 1, training_steps: int = 0) -> None:
    """Worker process: build env and policy, then per request load the weights and collect one batch."""
    ignore_stop_signals()  # the trainer answers SIGINT and SIGTERM, and then stops this worker
    try:
        torch.set_num_threads(1)
        torch.manual_seed(seed)
        env = make_env_for_collection(env_cfg, reward, seed, num_envs, training_steps)
        policy = make_exploration(agent_cfg, make_actor(observation_size, action_size, agent_cfg.hidden_sizes),
                                  action_size)
        collector = make_collector(env, policy, frames_per_batch, init_random_frames, "cpu")
        batches = iter(collector)
        try:
            while True:
                state = pickle.loads(conn.recv_bytes())
                if state is None:
                    break
                policy.load_state_dict(state)
                t0, c0 = time.perf_counter(), time.process_time()
                batch = next(batches)
                conn.send_bytes(pickle.dumps(("batch", batch, (time.perf_counter() - t0,
                                                              time.process_time() - c0))))
        finally:
            collector.shutdown()
    except (EOFError, BrokenPipeError, KeyboardInterrupt):  # the trainer is gone: nothing to report to
        pass
    except BaseException:
        try:
            conn.send_bytes(pickle.dumps(("error", traceback.format_exc(), (0.0, 0.0))))
        except (OSError, BrokenPipeError):
            pass
    finally:
        conn.close()


class ProcessCollector:
    """Collects `frames_per_batch` env steps per batch in a worker process, one batch ahead of the trainer
    (from `num_envs` envs, each in a process of its own under the worker's, if `num_envs` > 1).

    Iterate it like TorchRL's `Collector`; call `prefetch()` as soon as the policy is ready to collect the next
    batch (before the updates), so that collection and updates overlap. `last_collect_time` and
    `last_collect_cpu` are the worker's wall-clock and CPU time spent collecting the latest batch (s). Errors
    in the worker are raised here as `RuntimeError`.
    """

    def __init__(self, env_cfg: EnvConfig, reward: RewardConfig, seed: int, agent_cfg: AgentConfig,
                 policy: torch.nn.Module, observation_size: int, action_size: int, frames_per_batch: int,
                 init_random_frames: int, num_envs: int = 1, training_steps: int = 0):
        self.policy = policy
        self.num_envs = num_envs
        self.last_collect_time = self.last_collect_cpu = 0.0
        self._in_flight = False
        self._first = True
        ctx = mp.get_context("spawn")  # a fresh interpreter: no forked OpenMP or PyBullet state
        self._conn, child = ctx.Pipe()
        # a daemon process may not start processes of its own (multiprocessing refuses), so with several envs
        # the worker is not one; `shutdown` (the trainer calls it in a `finally`) still ends it, and if the
        # trainer is killed the worker reads EOF on its pipe and closes its env processes
        self._proc = ctx.Process(target=_worker, name="cyberdog-collector", daemon=num_envs == 1,
                                 args=(child, env_cfg, reward, seed, agent_cfg, observation_size, action_size,
                                       frames_per_batch, init_random_frames, num_envs, training_steps))
        self._proc.start()
        child.close()

    def prefetch(self) -> None:
        """Ask for the next batch, collected with the policy's weights as they are now (no-op if asked)."""
        if not self._in_flight:
            self._conn.send_bytes(pickle.dumps(_policy_state(self.policy)))
            self._in_flight = True

    def __iter__(self):
        return self

    def __next__(self) -> TensorDictBase:
        self.prefetch()
        timeout = WORKER_START_TIMEOUT_S if self._first else None
        try:
            if timeout is not None and not self._conn.poll(timeout):
                raise RuntimeError(f"the collector process sent nothing in {timeout:.0f} s")
            kind, payload, seconds = pickle.loads(self._conn.recv_bytes())
        except (EOFError, ConnectionResetError) as e:
            raise RuntimeError(f"the collector process died (exit code {self._proc.exitcode})") from e
        self._in_flight, self._first = False, False
        if kind == "error":
            raise RuntimeError(f"the collector process failed:\n{payload}")
        self.last_collect_time, self.last_collect_cpu = seconds
        return payload

    def shutdown(self) -> None:
        """Stop the worker (a batch it is still collecting is dropped).

        With one env the worker is terminated if a batch is in flight. With several it is not: terminated, it
        could not close its env processes (they would only see their pipe close) nor release their semaphores,
        so the batch in flight (a fraction of a second) is received and dropped, then the worker stops itself."""
        if self._proc.is_alive():
            if self._in_flight and self.num_envs > 1:
                try:
                    if self._conn.poll(WORKER_STOP_TIMEOUT_S):
                        self._conn.recv_bytes()
                        self._in_flight = False
                except (EOFError, OSError):
                    pass
            try:
                self._conn.send_bytes(pickle.dumps(None))
            except (OSError, BrokenPipeError):
                pass
            self._proc.join(timeout=(WORKER_STOP_TIMEOUT_S if self.num_envs > 1 else 10.0) if not self._in_flight
                            else 0.5)
            if self._proc.is_alive():
                self._proc.terminate()
                self._proc.join(timeout=5.0)
        self._conn.close()
