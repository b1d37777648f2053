"""Two-stage training loop (paper Section 3): collect with TorchRL's `Collector`, replay, update, log, save.

Collection runs in this process, taking turns with the updates (`train.collection="sync"`, the default), or
in a worker process one batch ahead, overlapping with them ("async", `cyberdog.rl.collect`); from one env, or
from `train.num_envs` envs in processes of their own, each with its running episode (see `_bookkeep`).

Stage 1 trains with the "stage1" reward (no energy term) until the mean score over `score_window`
episodes reaches `stage1.stop_score` or its budget is spent; stage 2 continues the same agent (actor,
critics, targets, optimizers) with the "stage2" reward. The replay buffer is cleared between the stages by
default (`train.buffer_between_stages="clear"`): its stored rewards were computed without the energy term.
With "relabel" it is kept and each stored reward is recomputed with stage 2's energy weight (from the step's
stored energy) and keep-moving weight, so that stage 2's critics start from all of stage 1's experience under
the right reward. A stage's first `critic_warmup_updates` updates train the critics only.

Checkpoints (`checkpoint.pt`, every `train.checkpoint_every` env steps and at the end of each stage; written and
read by `cyberdog.rl.run_state.RunState`) hold the agent, optimizers, counters, RNG states and the replay
buffer, so `resume=True` continues a run killed at any moment. SIGINT and SIGTERM do not kill it: the round
of updates stops after the update in hand (the updates it still owed are kept as a credit, paid first by the
resume), the batch in hand is stored and logged, a checkpoint is written and `run()` raises
`cyberdog.rl.stop.TrainingInterrupted`, so that the resume loses no step that was logged. A resumed run
starts a fresh episode: the interrupted episode's transitions stay in the buffer but it is not logged as an
episode. A resume may raise the current stage's budget (`max_env_steps`, `max_episodes`; nothing else may
differ), or lower it to a point the stage has not reached: the stage goes on to the new end, and a finished
one (raised only) keeps its previous stage-final files as `stage<N>_final*_<steps>steps.pt`. Only
`checkpoint.pt` carries the replay buffer and the Adam moments: the stage-final files (`stage<N>_final.pt`:
networks, targets, counters; `stage<N>_final_actor.pt`: the actor) hold what `--init-from` and the evaluation
need: about 1 MB with 128-unit layers.

One process per run folder: the trainer holds `cyberdog.runlock.RunLock` on `run_dir` from its construction
to the end of `run()` (or `close()`), and refuses, before any work, a stage that would end without a single
gradient update (`cyberdog.config.check_planned_updates`). A stage that still ends without one (it reached its
`stop_score` before learning started) saves its actor as `stage<N>_untrained_actor.pt`, with a warning, and
writes no stage-final files.
"""
from __future__ import annotations

import dataclasses
import math
import random
import sys
import time
from collections import deque
from pathlib import Path

import numpy as np
import torch
from tqdm import tqdm

from cyberdog import config as C
from cyberdog.config import REWARD_TERM_NAMES
from cyberdog.core import rewards
from cyberdog.envs.observation import actor_observation_scale, observation_typical_magnitude
from cyberdog.provenance import code_state
from cyberdog.rl.checkpoint import load_checkpoint, remove_stale_temporaries, save_checkpoint
from cyberdog.rl.collect import ProcessCollector, make_collector, make_env_for_collection
from cyberdog.rl.logger import EpisodeLogger
from cyberdog.rl.replay import TROT_ACTION_KEY, make_replay_buffer, relabel_rewards, sample_batches, transitions
from cyberdog.rl.run_state import Progress, RunState
from cyberdog.rl.stop import StopSignals, TrainingInterrupted
from cyberdog.rl.td3 import TD3, NonFiniteError, UpdateSettings, metrics_to_float
from cyberdog.runlock import RunFolderError, RunLock



def resolve_device(name: str) -> str:
    if name == "auto":
        return "cuda" if torch.cuda.is_available() else "cpu"
    if name == "cuda" and not torch.cuda.is_available():
        raise ValueError("train.device='cuda' but no CUDA device is available; use 'cpu' or 'auto'")
    return name


class Trainer(RunState):
    """Runs `stages` (e.g. (1, 2)) of one experiment in `run_dir`, which it locks until `run()` ends (or
    `close()`): a second process (or a second Trainer) on the same folder raises `RunLockedError`.

    It owns the loop and its counters (`progress`, a `Progress`); the agent (`agent`, a `TD3`) owns the networks
    and makes the updates, with the stage's `settings`, resolved once as the stage starts or resumes."""

    def __init__(self, cfg: C.ExperimentConfig, run_dir: str | Path, stages=(1, 2), resume: bool = False,
                 init_from: str | Path | None = None, progress: bool = True):
        self.cfg, self.run_dir, self.show_progress = cfg, Path(run_dir), progress
        self.lock = None
        self._stop = StopSignals()  # entered by run(): SIGINT and SIGTERM then stop at a safe point
        init_state = None
        if not resume:  # bad settings fail here, before the folder is touched
            if init_from is not None:
                init_state = load_checkpoint(init_from, actor_file=True)
            trained = init_state is not None and int((init_state.get("agent") or {}).get("updates", 0)) > 0
            C.check_planned_updates(cfg, tuple(stages), trained=trained)
        self.lock = RunLock(self.run_dir).acquire()
        try:
            self._setup(cfg, stages, resume, init_from, init_state)
        except BaseException:
            self.close()
            raise

    def _setup(self, cfg, stages, resume, init_from, init_state) -> None:
        tc = cfg.train
        if tc.num_threads:
            torch.set_num_threads(tc.num_threads)
        elif (tc.collection == "async" or tc.num_envs > 1) and torch.get_num_threads() > 1:
            # a core for each env process, and one for the async collector, which waits for its envs busily
            busy = tc.num_envs + (tc.collection == "async" and tc.num_envs > 1)
            torch.set_num_threads(max(1, torch.get_num_threads() - busy))
        if tc.deterministic:
            torch.use_deterministic_algorithms(True)
        self.device = resolve_device(tc.device)
        torch.manual_seed(tc.seed)  # network initialisation; a resume restores every RNG state below
        np.random.seed(tc.seed)
        random.seed(tc.seed)
        obs_scale = observation_typical_magnitude(cfg.env)
        self.observation_size = len(obs_scale)
        self.agent = TD3(cfg.agent, self.observation_size, cfg.env.action_size, self.device, obs_scale,
                         actor_observation_scale(cfg.env, cfg.agent.actor_observation))
        self.rb = make_replay_buffer(tc.buffer_size)
        self.stages = list(stages)
        self.progress = Progress(stage=self.stages[0])
        self.settings: UpdateSettings | None = None  # the current stage's, resolved when it starts or resumes
        self.scores: deque = deque(maxlen=tc.score_window)
        self.recent: deque = deque(maxlen=100)  # (length, fell) of the latest episodes, for the progress line
        self.best_score = -math.inf
        self.logger = None
        self.trained_at = [code_state()]  # the commit of each process that trains the run (a resume adds its own)
        self.run_dir.mkdir(parents=True, exist_ok=True)
        remove_stale_temporaries(self.run_dir)  # half-written files of a process killed while saving
        if resume:
            self._restore(load_checkpoint(self.run_dir / "checkpoint.pt"), self.run_dir / "checkpoint.pt")
        else:
            self._check_empty()
            if init_state is not None:
                self._load_agent(init_state, init_from)
            C.save(cfg, self.run_dir / "config.yaml")
        self.logger = EpisodeLogger(self.run_dir, rows=self.progress.csv_rows,
                                    purge_step=self.progress.env_steps if resume else None)
        self.progress.csv_rows = self.logger.rows  # fewer if metrics.csv lost rows (the logger warned)
        self.last = {"actor_loss": math.nan, "critic_loss": math.nan, "q_mean": math.nan, "q_max": math.nan}

    def _check_empty(self) -> None:
        """A fresh start never appends to a previous run's logs."""
        if (self.run_dir / "checkpoint.pt").exists():
            raise RunFolderError(f"{self.run_dir} already holds a run (checkpoint.pt): continue it (train.py --resume "
                                 f"{self.run_dir}; Trainer(..., resume=True)), or train in another folder")
        metrics = self.run_dir / "metrics.csv"
        if metrics.exists() and metrics.stat().st_size > 0:
            raise RunFolderError(f"{self.run_dir} holds the logs of a previous run stopped before its first "
                                 f"checkpoint (metrics.csv but no checkpoint.pt): delete the folder (or its "
                                 f"metrics.csv and tb/) to start it again, or choose another --run-dir")

    def close(self) -> None:
        """Close the logs and release the run folder (idempotent; `run()` does it when it ends)."""
        if getattr(self, "logger", None) is not None:
            self.logger.close()
        if self.lock is not None:
            self.lock.release()

    # ---- the loop --------------------------------------------------------------------------------------
    def run(self) -> dict:
        """Train the stages to their ends; on SIGINT or SIGTERM, stop after the batch in hand with a checkpoint
        and raise `TrainingInterrupted` (`cyberdog.rl.stop`)."""
        try:
            with self._stop:
                self._run_stages()
        finally:
            self.close()
        return {**self.progress.as_dict(), "updates": self.agent.updates, "buffer_size": len(self.rb),
                "window_mean_score": float(np.mean(self.scores)) if self.scores else math.nan}

    def _stop_if_asked(self, saved: Path | None = None) -> None:
        """At a safe point: if a stop signal came, write the checkpoint (unless `saved` just was) and stop."""
        if self._stop.signum is not None:
            raise TrainingInterrupted(self._stop.signum, self.progress.env_steps, saved or self.save())

    def _run_stages(self) -> None:
        """Each stage from where the counters stand, with its final files, then the next."""
        while not self.progress.finished:
            stage = self.progress.stage
            self._run_stage(stage)
            score = self.scores[-1] if self.scores else math.nan
            if self.progress.stage_updates > 0:
                self._save_actor(f"stage{stage}_final_actor.pt", score)
                save_checkpoint(self._final_state(stage, score), self.run_dir / f"stage{stage}_final.pt")
            else:  # e.g. its stop_score was reached before learning started: not a trained actor
                self._save_actor(f"stage{stage}_untrained_actor.pt", score)
                print(f"WARNING: stage {stage} ended after {self.progress.stage_env_steps} env steps without a single "
                      f"gradient update; its actor is saved as stage{stage}_untrained_actor.pt, and no "
                      f"stage{stage}_final files are written", file=sys.stderr, flush=True)
            rest = [s for s in self.stages if s > stage]
            if rest:  # next stage: same agent, fresh counters and score window
                self.progress = dataclasses.replace(self.progress, stage=rest[0], stage_env_steps=0,
                                                    stage_episodes=0, stage_updates=0)
                self.scores.clear()
                self.best_score = -math.inf
                self._carry_buffer(stage, rest[0])
            else:
                self.progress.finished = True
            saved = self.save()
            if not self.progress.finished:
                self._stop_if_asked(saved)

    def _carry_buffer(self, old: int, new: int) -> None:
        """The replay buffer at the switch from stage `old` to stage `new` (`train.buffer_between_stages`)."""
        policy = self.cfg.train.buffer_between_stages
        if policy == "clear":
            self.rb.empty()
        elif policy == "relabel":  # the stages differ in these two terms only (`TrainConfig` checks it)
            w_old, w_new = (C.stage_reward(getattr(self.cfg.train, f"stage{s}")).weights for s in (old, new))
            keep_moving = rewards.keep_moving_term(self.cfg.env.control_dt, self.cfg.env.episode_time)
            relabel_rewards(self.rb, w_new["energy"] - w_old["energy"],
                            (w_new["keep_moving"] - w_old["keep_moving"]) * keep_moving)

    def _stage_done(self, sc: C.StageConfig) -> bool:
        p = self.progress
        if p.stage_episodes >= sc.max_episodes or (sc.max_env_steps and p.stage_env_steps >= sc.max_env_steps):
            return True
        return len(self.scores) == self.scores.maxlen and float(np.mean(self.scores)) >= sc.stop_score

    def _run_stage(self, stage: int) -> None:
        tc, sc, p = self.cfg.train, getattr(self.cfg.train, f"stage{stage}"), self.progress
        self._begin_stage(sc)
        if p.update_credit >= 1:  # a run stopped within a round of updates: it owes them (at most a batch's)
            self._updates(0)
        if self._stage_done(sc):
            return
        seed, reward = tc.seed + 100_003 * stage + p.env_steps, C.stage_reward(sc)
        threads = torch.get_num_threads()  # closing a ParallelEnv raises them by its worker count: restored below
        collector = self._collector(reward, seed, self._random_frames_left(stage))
        budget = sc.max_env_steps or sc.max_episodes * self.cfg.env.max_episode_steps
        bar = tqdm(total=budget, initial=min(p.stage_env_steps, budget), unit="step", desc=f"stage {stage}",
                   disable=not self.show_progress, dynamic_ncols=True)
        episodes = [self._new_episode() for _ in range(tc.num_envs)]  # the running episode of each env
        t_env = t_upd = 0.0
        n_upd, n_env = 0, 0  # in this process: a resumed stage's rates count only what it did itself
        try:
            t0 = time.perf_counter()
            for batch in collector:
                is_async = isinstance(collector, ProcessCollector)
                t_env += collector.last_collect_time if is_async else time.perf_counter() - t0
                if not torch.isfinite(batch["action"]).all():
                    raise NonFiniteError("action is not finite (NaN or inf); training stopped")
                self.rb.extend(transitions(batch, self.extra_transition_keys))
                n = batch.numel()
                self.agent.policy[-1].step(n)  # anneal the exploration noise
                p.env_steps += n
                p.stage_env_steps += n
                n_env += n
                if is_async:
                    collector.prefetch()  # the next batch is collected while we update on this one
                t1 = time.perf_counter()
                n_upd += self._updates(n)
                t_upd += time.perf_counter() - t1
                rates = {"env_steps_per_s": n_env / max(t_env, 1e-9),
                         "updates_per_s": n_upd / t_upd if t_upd > 0 else math.nan}
                self._bookkeep(batch, episodes, stage, sc, rates)
                bar.update(min(n, max(0, budget - bar.n)))
                bar.set_postfix(self._progress_fields(rates), refresh=False)
                if p.env_steps - p.last_checkpoint >= tc.checkpoint_every:
                    self.save()
                self._stop_if_asked()  # the batch is stored, learned from and logged: a safe point
                if self._stage_done(sc):
                    break
                t0 = time.perf_counter()
        except NonFiniteError as e:
            path = self.save("diagnostic.pt")
            raise NonFiniteError(f"{e}; diagnostic checkpoint written to {path}") from None
        finally:
            bar.close()
            collector.shutdown()
            torch.set_num_threads(threads)

    def _progress_fields(self, rates: dict) -> dict:
        """The progress line: what tells learning from failing (episode length and falls over the latest 100
        episodes), not only the score; the trot prior's weight while there is one."""
        length, fell = np.mean(self.recent, axis=0) if self.recent else (0.0, 0.0)
        prior = {"prior": f"{self.prior_weight:.3f}"} if self.cfg.env.prior_weight > 0 else {}
        return {"ep": self.progress.stage_episodes, "score": f"{np.mean(self.scores) if self.scores else 0:.2f}",
                "len": f"{length:.0f}", "falls": f"{100 * fell:.0f}%", **prior,
                "upd_s": f"{rates['updates_per_s']:.0f}"}

    def _collector(self, reward, seed: int, random_frames: int):
        """The stage's collector: the env(s) in a worker process one batch ahead of the updates ("async"), or
        here, with the policy on self.device acting on the observations of all envs at once."""
        tc, env_cfg, done = self.cfg.train, self._collection_env(), self.progress.stage_env_steps
        if tc.collection == "async":
            return ProcessCollector(env_cfg, reward, seed, self.cfg.agent, self.agent.policy,
                                    self.observation_size, env_cfg.action_size, tc.frames_per_batch, random_frames,
                                    tc.num_envs, done)
        return make_collector(make_env_for_collection(env_cfg, reward, seed, tc.num_envs, done), self.agent.policy,
                              tc.frames_per_batch, random_frames, self.device)

    @property
    def extra_transition_keys(self) -> tuple:
        """What a transition keeps beyond TRANSITION_KEYS: the trot's torque when the actor is pulled toward it."""
        return (TROT_ACTION_KEY,) if self.cfg.imitates_trot else ()

    def _collection_env(self) -> C.EnvConfig:
        """The env config the stage collects in: the trot prior (torque mode, `EnvConfig.prior_weight`) decays
        over stage 1's env steps, whose count the collector's envs are given (`CyberDogEnv.set_training_progress`:
        a resume goes on with the same weight); later stages have no prior."""
        env = self.cfg.env
        if env.prior_weight == 0 or self.progress.stage == 1:
            return env
        return dataclasses.replace(env, prior_weight=0.0, prior_decay_steps=0)

    @property
    def prior_weight(self) -> float:
        """The trot prior's weight now (0 without one, and in every stage after the first)."""
        return self._collection_env().prior_weight_at(self.progress.stage_env_steps)

    def _random_frames_left(self, stage: int) -> int:
        """Uniform random actions only at the very start (stage 1, or a stage run without a trained agent or
        an actor file's actor)."""
        if stage != self.stages[0] or self.agent.updates > 0 or self.agent.actor_from_file:
            return 0
        return max(0, self.cfg.train.init_random_frames - self.progress.stage_env_steps)

    def _begin_stage(self, sc: C.StageConfig) -> None:
        """The stage's update settings, resolved once as it starts or resumes (its critic warm-up counted from the
        agent's updates at its start); at its very start the agent begins it (anchor, fresh actor optimizer), on a
        resume the optimizers take its learning rates (the anchor and the Adam moments come from the checkpoint)."""
        p = self.progress
        self.settings = UpdateSettings.of(self.cfg.agent, sc, updates_done=self.agent.updates - p.stage_updates)
        if p.stage_env_steps == 0:
            self.agent.begin_stage(self.settings, fresh_actor_optimizer=sc.fresh_actor_optimizer)
        else:
            self.agent.set_learning_rates(self.settings)

    def _updates(self, frames: int) -> int:
        tc, p = self.cfg.train, self.progress
        if C.update_blockers(tc, len(self.rb), self._random_frames_left(p.stage), self.agent.updates,
                             p.stage_env_steps):
            return 0
        n, p.update_credit = C.update_credit(p.update_credit, frames, tc.updates_per_frame)
        prior_weight = self.prior_weight
        metrics = []
        for done, b in enumerate(sample_batches(self.rb, n, tc.batch_size)):
            if self._stop.signum is not None:  # a stop signal: the round's other updates are owed, not lost
                p.update_credit += n - done
                n = done
                break
            metrics.append(self.agent.update(b, self.settings, prior_weight))
            p.stage_updates += 1
        if n:  # tensors until here: one conversion per round of updates, not four per update
            self.last = metrics_to_float(metrics)
            self.last["actor_loss"] = self.agent.last_actor_loss
        return n

    @staticmethod
    def _new_episode() -> dict:
        return {"length": 0, "score": 0.0, "energy_J": 0.0, "speed_sum": 0.0, "prior_sum": 0.0, "fell": 0,
                **{f"reward_{n}": 0.0 for n in REWARD_TERM_NAMES}}

    def _bookkeep(self, batch, episodes: list[dict], stage: int, sc: C.StageConfig, rates: dict) -> None:
        """Accumulate each step into its env's running episode; log, score and save at every episode end.

        `batch` is [T] steps of one env or [N, T] of N envs (`episodes[i]` is env i's); the steps are taken
        time-major (step t of every env, then t+1), which is also the order of the logged `env_steps`."""
        n_envs = len(episodes)
        nxt = batch["next"]
        cols = {k: nxt[k].reshape(n_envs, -1).tolist() for k in ["reward", "energy_J", "forward_speed",
                                                                   "prior_weight", "terminated"]
                + [f"reward_{n}" for n in REWARD_TERM_NAMES]}
        done = nxt["done"].reshape(n_envs, -1).tolist()
        first_step = self.progress.env_steps - n_envs * len(done[0])
        for t in range(len(done[0])):
            for i, ep in enumerate(episodes):
                ep["length"] += 1
                ep["score"] += cols["reward"][i][t]
                ep["energy_J"] += cols["energy_J"][i][t]
                ep["speed_sum"] += cols["forward_speed"][i][t]
                ep["prior_sum"] += cols["prior_weight"][i][t]
                for n in REWARD_TERM_NAMES:
                    ep[f"reward_{n}"] += cols[f"reward_{n}"][i][t]
                if done[i][t]:
                    ep["fell"] = int(bool(cols["terminated"][i][t]))  # fallen or non-finite, not the time limit
                    self._episode_end(ep, stage, sc, rates, first_step + t * n_envs + i + 1)
                    ep.update(self._new_episode())

    def _episode_end(self, ep: dict, stage: int, sc: C.StageConfig, rates: dict, env_steps: int) -> None:
        p = self.progress
        p.episodes += 1
        p.stage_episodes += 1
        self.scores.append(ep["score"])
        self.recent.append((ep["length"], ep["fell"]))
        row = {**{k: v for k, v in ep.items() if k not in ("speed_sum", "prior_sum")}, **self.last, **rates,
               "stage": stage, "episode": p.episodes, "stage_episode": p.stage_episodes,
               "env_steps": env_steps, "mean_speed": ep["speed_sum"] / ep["length"],
               "prior_weight": ep["prior_sum"] / ep["length"],
               "window_mean_score": float(np.mean(self.scores)), "updates": self.agent.updates,
               "wall_time_s": time.time()}
        self.logger.log(row)
        p.csv_rows = self.logger.rows
        if row["prior_weight"] > 0:  # the trot prior helped: not the policy's own score (no best or saved actor)
            return
        if ep["score"] > self.best_score:
            self.best_score = ep["score"]
            self._save_actor(f"stage{stage}_best_actor.pt", ep["score"])
        if ep["score"] >= sc.save_score:
            self._save_actor(f"saved/stage{stage}_episode{p.episodes:06d}_actor.pt", ep["score"])
