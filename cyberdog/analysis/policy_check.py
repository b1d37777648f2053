"""Does a policy walk, alone, at the paper's speeds, and does its stage 2 spend less than its stage 1?

The closed-loop check of a trained actor (any action mode; the paper's torque agent above all): for each
actor and commanded speed, one deterministic walk of `duration` s from the stand in the env it was trained in,
without exploration noise and without the trot prior a torque policy may have trained with
(`cyberdog.rl.rollout`). A walk *walks* when it does not fall and its mean speed over the last half is within
±5 % of the command (`speed_within_band`, the band of Table 5). For a seed's stage-1 and stage-2 actors at the
same speed, the Eq. 7 reduction is 1 − E₂/E₁ over the same duration, and per metre walked, 1 − (E₂/d₂)/(E₁/d₁)
(both must walk for it to mean anything; per metre, a policy that walks slower is not credited for it). The trot
controller's own walk at each speed (trajectory + IK + PD at the controller rate, what a torque policy's prior
came from) is the reference row, label "trot" and stage 0 (`check_trot`).
"""
from __future__ import annotations

import math
import time
from pathlib import Path

from cyberdog.config.paper import speed_within_band

COLUMNS = ["label", "stage", "speed_command_mps", "walks", "fell", "duration_s", "mean_speed_mps", "in_band",
           "energy_J", "electrical_energy_J", "energy_per_metre_J", "cost_of_transport", "score"]


def check_actor(job: tuple) -> dict:
    """One walk → one row. job: (label, stage, actor file, speed m/s, duration s, env seed)."""
    from cyberdog.rl.rollout import load_actor, rollout

    label, stage, path, speed, duration, seed = job
    t0 = time.perf_counter()
    r = rollout(load_actor(path), speed=speed, duration=duration, seed=seed)
    in_band = speed_within_band(r.mean_speed, speed) if math.isfinite(r.mean_speed) else False
    return {"label": label, "stage": stage, "actor": str(path), "speed_command_mps": speed,
            "walks": bool(not r.fell and in_band), "fell": bool(r.fell), "duration_s": r.duration,
            "mean_speed_mps": r.mean_speed, "in_band": in_band, "energy_J": r.energy,
            "electrical_energy_J": r.electrical_energy, "energy_per_metre_J": r.energy_per_metre,
            "cost_of_transport": r.cost_of_transport, "score": r.score, "wall_s": time.perf_counter() - t0}


def check_trot(job: tuple) -> dict:
    """The trot controller's own walk → one row like `check_actor`'s. job: (speed m/s, duration s, the env's
    `WalkConfig`: the trot the env's controller, and a torque policy's prior, runs)."""
    import dataclasses

    from cyberdog.analysis.walk import walk

    speed, duration, cfg = job
    t0 = time.perf_counter()
    r = walk(dataclasses.replace(cfg, gait=dataclasses.replace(cfg.gait, speed=float(speed))), duration=duration)
    in_band = speed_within_band(r.mean_speed, speed) if math.isfinite(r.mean_speed) else False
    return {"label": "trot", "stage": 0, "actor": "", "speed_command_mps": speed,
            "walks": bool(not r.fell and in_band), "fell": bool(r.fell), "duration_s": r.duration,
            "mean_speed_mps": r.mean_speed, "in_band": in_band, "energy_J": r.energy,
            "electrical_energy_J": r.electrical_energy, "energy_per_metre_J": r.energy_per_metre,
            "cost_of_transport": r.cost_of_transport, "score": math.nan, "wall_s": time.perf_counter() - t0}


def check_jobs(actors: dict[str, dict[int, str | Path]], speeds, duration: float, seed: int = 0) -> list[tuple]:
    """The walks to make: `actors` maps a label (a seed) to {stage: actor file}."""
    if not actors:
        raise ValueError("no actor to check")
    if not (math.isfinite(duration) and duration > 0):
        raise ValueError(f"duration must be > 0 s, got {duration!r}")
    bad = [v for v in speeds if not (math.isfinite(v) and v > 0)]
    if bad or not speeds:
        raise ValueError(f"speeds must be > 0 m/s (one or more), got {list(speeds)!r}")
    for label, stages in actors.items():
        for stage, path in stages.items():
            if not Path(path).is_file():
                raise FileNotFoundError(f"{label} stage {stage}: no actor file {path}")
    return [(label, stage, str(path), float(v), float(duration), seed)
            for label, stages in actors.items() for stage, path in sorted(stages.items()) for v in speeds]


def stage_reductions(rows: list[dict]) -> list[dict]:
    """Per label and speed with both stages: the Eq. 7 reduction of stage 2 against stage 1, 1 − E₂/E₁ (%), over
    walks of the same duration, and whether both walked (only then is it a reduction at the same speed)."""
    by_key = {(r["label"], r["stage"], r["speed_command_mps"]): r for r in rows}
    out = []
    for (label, stage, speed), one in by_key.items():
        two = by_key.get((label, 2, speed))
        if stage != 1 or two is None:
            continue
        same = one["duration_s"] == two["duration_s"]
        out.append({"label": label, "speed_command_mps": speed, "both_walk": one["walks"] and two["walks"],
                    "energy_stage1_J": one["energy_J"], "energy_stage2_J": two["energy_J"],
                    "reduction_pct": 100.0 * (1.0 - two["energy_J"] / one["energy_J"]) if same else math.nan,
                    "reduction_per_metre_pct": 100.0 * (1.0 - two["energy_per_metre_J"] / one["energy_per_metre_J"])})
    return out


__all__ = ["COLUMNS", "check_actor", "check_jobs", "check_trot", "stage_reductions"]
