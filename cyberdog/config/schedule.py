"""The update schedule of a training, in one place: when the trainer makes gradient updates, and what a
configuration's stages will make before any work starts (`check_planned_updates`)."""
from __future__ import annotations

from cyberdog.config.learning import ExperimentConfig, TrainConfig


def update_blockers(tc: TrainConfig, buffer_size: int, random_frames_left: int, agent_updates: int,
                    stage_env_steps: int) -> list[str]:
    """The one update gate: what still holds the updates back now, as the settings to name in a message (empty:
    update). The replay buffer holds fewer than `train.batch_size` transitions; uniform random actions are still
    being collected (`train.init_random_frames`); or no update was made yet and the stage has run fewer than
    `train.learning_starts` env steps. `cyberdog.rl.trainer.Trainer` asks it before every round of updates, and
    the plan below asks it of every batch a stage's budget allows."""
    return ([f"train.batch_size={tc.batch_size} transitions in the replay buffer"] * (buffer_size < tc.batch_size)
            + [f"train.init_random_frames={tc.init_random_frames} env steps of random actions"]
            * (random_frames_left > 0)
            + [f"train.learning_starts={tc.learning_starts} env steps"]
            * (agent_updates == 0 and stage_env_steps < tc.learning_starts))


def update_credit(credit: float, frames: int, updates_per_frame: float) -> tuple[int, float]:
    """(whole updates to make now, credit carried on) after `frames` env steps at `updates_per_frame`."""
    credit += frames * updates_per_frame
    n = int(credit)
    return n, credit - n


def _update_schedule(cfg: ExperimentConfig, stages, trained: bool) -> list[dict]:
    """The trainer's update schedule replayed on the counters alone, through the same gate and credit, per
    stage: updates made over its whole budget, and what still held them back at its last batch."""
    tc = cfg.train
    done = 1 if trained else 0  # only "any update yet?" matters to the schedule
    buffer, credit = 0, 0.0
    out = []
    for i, s in enumerate(stages):
        sc = getattr(tc, f"stage{s}")
        if i > 0 and tc.buffer_between_stages == "clear":
            buffer = 0
        budget = sc.max_env_steps or sc.max_episodes * cfg.env.max_episode_steps
        batches = -(-budget // tc.frames_per_batch)
        n_stage, blocked = 0, []
        for k in range(1, batches + 1):
            steps = k * tc.frames_per_batch
            buffer = min(buffer + tc.frames_per_batch, tc.buffer_size)
            random_left = max(0, tc.init_random_frames - steps) if i == 0 and not done else 0
            blocked = update_blockers(tc, buffer, random_left, done, steps)
            if blocked:
                continue
            n, credit = update_credit(credit, tc.frames_per_batch, tc.updates_per_frame)
            n_stage += n
            done += n
        if not blocked and n_stage == 0:
            blocked = [f"one update (train.updates_per_frame={tc.updates_per_frame} per env step)"]
        out.append({"stage": s, "updates": n_stage, "env_steps": batches * tc.frames_per_batch,
                    "budget": budget, "waiting_for": blocked})
    return out


def planned_updates(cfg: ExperimentConfig, stages=(1, 2), trained: bool = False) -> dict[int, int]:
    """Gradient updates each stage of `stages` makes if it runs its whole budget (no early stop at
    `stop_score`). `trained`: the agent starts with updates already made (`--init-from` a trained agent)."""
    return {d["stage"]: d["updates"] for d in _update_schedule(cfg, stages, trained)}


def check_planned_updates(cfg: ExperimentConfig, stages=(1, 2), trained: bool = False) -> dict[int, int]:
    """Raise `ValueError` before any work if a stage of `stages` would end without a single gradient update
    (its actor would be saved as "final" without any training); returns `planned_updates`."""
    schedule = _update_schedule(cfg, stages, trained)
    for d in schedule:
        if d["updates"] > 0:
            continue
        s = d["stage"]
        sc = getattr(cfg.train, f"stage{s}")
        source = (f"train.stage{s}.max_env_steps={sc.max_env_steps}" if sc.max_env_steps else
                  f"train.stage{s}.max_episodes={sc.max_episodes} of {cfg.env.max_episode_steps} steps")
        raise ValueError(
            f"train.stage{s} would make no gradient update: it runs at most {d['env_steps']} env steps ({source}, "
            f"in batches of train.frames_per_batch={cfg.train.frames_per_batch}) and is still waiting for "
            f"{' and '.join(d['waiting_for'])} at its end. Give the stage more env steps (--set "
            f"train.stage{s}.max_env_steps=N) or lower what it waits for; otherwise its untrained actor would be "
            f"saved as stage{s}_final")
    return {d["stage"]: d["updates"] for d in schedule}


__all__ = ["check_planned_updates", "planned_updates", "update_blockers", "update_credit"]
