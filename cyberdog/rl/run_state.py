"""What a training run saves and restores (`cyberdog.rl.trainer.Trainer`'s files): `checkpoint.pt` (the agent,
optimizers, counters, RNG states and the replay buffer), the stage-final files (`stage<N>_final.pt`, without
the buffer and the Adam moments), the actor files, and the resume of a stage under a changed budget."""
from __future__ import annotations

import dataclasses
import sys
from dataclasses import dataclass
from pathlib import Path

from cyberdog import config as C
from cyberdog.rl.checkpoint import (CheckpointError, budget_change, check_shapes, rng_state, save_atomic,
                                    save_checkpoint, saved_config, set_rng_state)
from cyberdog.rl.replay import buffer_state, load_buffer_state


@dataclass
class Progress:
    """Where a training run stands: the trainer's counters (a checkpoint's "counters", as a plain dict)."""

    stage: int  # the stage being trained
    env_steps: int = 0  # env steps collected, all stages together
    stage_env_steps: int = 0  # env steps collected in this stage
    episodes: int = 0  # episodes finished, all stages together
    stage_episodes: int = 0  # episodes finished in this stage
    stage_updates: int = 0  # gradient updates made in this stage
    update_credit: float = 0.0  # updates owed: the fraction of the next one, or those a stop interrupted
    csv_rows: int = 0  # rows of metrics.csv written
    last_checkpoint: int = 0  # env_steps at the latest checkpoint
    finished: bool = False  # every stage has ended

    def as_dict(self) -> dict:
        return dataclasses.asdict(self)

    @classmethod
    def from_dict(cls, counters: dict) -> Progress:
        """A checkpoint's counters (a field it lacks, e.g. `update_credit`, takes its default)."""
        names = {f.name for f in dataclasses.fields(cls)}
        return cls(**{k: v for k, v in counters.items() if k in names})


def resumed_code(recorded: list | None, now: dict) -> list:
    """A resumed run's `trained_at`: the commits its checkpoint records (one entry saying "not recorded" for a
    checkpoint written before they were), then this process's commit where it differs from the last one."""
    recorded = list(recorded) if recorded else [{"git_commit": "not recorded", "git_dirty": None}]
    return recorded + ([now] if now != recorded[-1] else [])


class RunState:
    """The save and restore half of the trainer, on its attributes (cfg, run_dir, stages, progress, agent, rb,
    scores, best_score, logger, prior_weight, trained_at). Every file records the trot prior's weight when it was
    written (torque mode; 0 without one): an actor saved while it was above 0 walked with its help; and
    `trained_at`, the code's commit (`cyberdog.provenance.code_state`) of every process that trained the run."""

    def _state(self) -> dict:
        return {"config": C.to_dict(self.cfg), "stages": self.stages, "counters": self.progress.as_dict(),
                "agent": self.agent.state_dict(), "replay": buffer_state(self.rb), "rng": rng_state(),
                "scores": list(self.scores), "best_score": self.best_score, "prior_weight": self.prior_weight,
                "trained_at": self.trained_at}

    def save(self, name: str = "checkpoint.pt") -> Path:
        self.logger.flush()
        self.progress.last_checkpoint = self.progress.env_steps
        return save_checkpoint(self._state(), self.run_dir / name)

    def _load_agent(self, state: dict, path) -> None:
        stage = self.cfg.train.stage2 if self.stages[0] == 2 else self.cfg.train.stage1
        if "actor" in state and ("agent" not in state or stage.fresh_critics):  # the actor only, new critics
            try:
                added = self.agent.load_actor(state["actor"])
            except ValueError as e:
                raise CheckpointError(f"{path}: {e}") from e
            what = "an actor file" if "agent" not in state else "its actor only (fresh_critics)"
            print(f"{path}: {what}; the actor starts from it, the critics anew"
                  + (f"; its first layer widened by {added} zero weights for inputs it did not observe"
                     if added else "")
                  + ("" if stage.critic_warmup_updates else " (with no critic_warmup_updates in this stage the "
                     "actor follows critics that have not yet learned its returns)"), file=sys.stderr)
            return
        if "agent" not in state:
            raise CheckpointError(f"{path} holds no agent; --init-from needs checkpoint.pt, stage<N>_final.pt of a "
                                  f"run or an actor file")
        agent = state["agent"]
        networks = {k: v for k, v in agent["loss"].items() if "_params." in k}  # the networks' tensors alone
        check_shapes(networks, self.agent.network_state(), "the agent", path)
        if "actor_optimizer" in agent:  # checkpoint.pt: the whole agent
            self.agent.load_state_dict(agent)
        else:  # stage<N>_final.pt: networks, targets, exploration and counters; new Adam moments
            self.agent.load_state_dict(agent, optimizers=False)
            if set(agent["exploration"]) == set(self.agent.policy.state_dict()):
                self.agent.policy.load_state_dict(agent["exploration"])
            else:  # e.g. --set agent.exploration=gaussian after an OU stage: this run's noise starts afresh
                print(f"{path}: its exploration noise is another kind than this run's "
                      f"({self.cfg.agent.exploration}); the new noise starts afresh", file=sys.stderr)
            self.agent.updates, self.agent.actor_updates = int(agent["updates"]), int(agent["actor_updates"])

    def _final_state(self, stage: int, score: float) -> dict:
        """stage<N>_final.pt: what `--init-from` needs (the agent's networks and their targets, exploration
        state, counters) and what the evaluation reads (`actor` and `config`, as in the actor files); not the
        replay buffer nor the Adam moments (half the agent's size), which only checkpoint.pt carries: a run
        started `--init-from` a stage-final file begins with new optimizer moments."""
        agent = {k: v for k, v in self.agent.state_dict().items() if not k.endswith("_optimizer")}
        return {"kind": "stage_final", "config": C.to_dict(self.cfg), "stages": self.stages,
                "counters": {**self.progress.as_dict(), "finished": True}, "agent": agent,
                "actor": self.agent.actor.state_dict(), "stage": stage, "score": score,
                "episode": self.progress.episodes, "env_steps": self.progress.env_steps,
                "stage_updates": self.progress.stage_updates, "scores": list(self.scores),
                "best_score": self.best_score, "prior_weight": self.prior_weight, "trained_at": self.trained_at}

    def _restore(self, state: dict, path) -> None:
        try:  # through the dataclasses, so that fields added to the code since (with defaults) still match
            saved = C.to_dict(saved_config(state.get("config")))
        except (ValueError, TypeError) as e:
            raise CheckpointError(f"{path}: its configuration does not load with this version ({e})") from e
        progress = Progress.from_dict(state["counters"])
        changes = budget_change(saved, C.to_dict(self.cfg), progress.stage, path,
                                done={"max_env_steps": progress.stage_env_steps,
                                      "max_episodes": progress.stage_episodes, "finished": progress.finished})
        self._load_agent(state, path)
        try:
            load_buffer_state(self.rb, state["replay"], self.extra_transition_keys)
        except (ValueError, KeyError, RuntimeError) as e:
            raise CheckpointError(f"{path}: replay buffer cannot be restored: {e}") from e
        self.stages = list(state["stages"])
        self.progress = progress
        self.scores.extend(state["scores"])
        self.best_score = float(state["best_score"])
        set_rng_state(state["rng"])
        self.trained_at = resumed_code(state.get("trained_at"), self.trained_at[-1])
        if changes:
            self._change_budget(changes)
        prior = f", trot prior's weight {self.prior_weight:.4f}" if self.cfg.env.prior_weight > 0 else ""
        print(f"resuming {path}: stage {progress.stage} at env step {progress.stage_env_steps} of the stage "
              f"({progress.env_steps} in all), episode {progress.episodes}, {self.agent.updates} updates{prior}",
              file=sys.stderr, flush=True)

    def _change_budget(self, changes: dict) -> None:
        """Continue the current stage under a changed budget (raised, or lowered to a point it has not
        reached). If the run had finished (the budget can then only be raised), its stage-final files
        are kept under the stage's step count (`stage2_final_actor_40000steps.pt`): a longer run never
        overwrites the result of the shorter one. config.yaml records the new budget."""
        stage, p = self.progress.stage, self.progress
        if p.finished:
            for name in (f"stage{stage}_final.pt", f"stage{stage}_final_actor.pt"):
                src = self.run_dir / name
                if src.is_file():
                    src.rename(src.with_name(f"{src.stem}_{p.stage_env_steps}steps.pt"))
            p.finished = False
        C.save(self.cfg, self.run_dir / "config.yaml")
        how = "raised" if self._raised(changes) else "lowered"
        print(f"stage {stage} continues past {p.stage_env_steps} env steps / {p.stage_episodes} episodes "
              f"under a {how} budget: " + ", ".join(f"{k} {a} -> {b}" for k, (a, b) in changes.items()),
              file=sys.stderr, flush=True)

    @staticmethod
    def _raised(changes: dict) -> bool:
        """Whether a budget change lets the stage run longer (0 steps: no step budget)."""
        return any(new == 0 or (old != 0 and new > old) for old, new in changes.values())

    def _save_actor(self, name: str, score: float) -> None:
        save_atomic({"actor": self.agent.actor.state_dict(), "score": score, "config": C.to_dict(self.cfg),
                     "stage": self.progress.stage, "episode": self.progress.episodes,
                     "env_steps": self.progress.env_steps, "stage_updates": self.progress.stage_updates,
                     "prior_weight": self.prior_weight, "trained_at": self.trained_at},
                    self.run_dir / name)


__all__ = ["Progress", "RunState", "resumed_code"]
