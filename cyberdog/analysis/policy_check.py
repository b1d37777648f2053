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

Each walk is on a named robot (`ROBOTS`, `robot_env`): "ideal" (no hardware effect, no randomisation draw, whatever
the actor trained on) or "hardware:N", the hardware-like robot of draw N (`HARDWARE_LIKE` with seed N: its mass,
sensor noise and Kalman speed, latency and joint friction; the robot a scripted walk with that config walks), in
the physics engine the actor's env names or the one asked for (`SimConfig.engine`). The per-metre reductions are
on Eq. 7 and on the electrical energy (what the battery pays).
"""
from __future__ import annotations

import math
import time
from pathlib import Path

from cyberdog.config.paper import speed_within_band

COLUMNS = ["label", "stage", "robot", "speed_command_mps", "walks", "fell", "duration_s", "mean_speed_mps", "in_band",
           "energy_J", "electrical_energy_J", "energy_per_metre_J", "electrical_per_metre_J", "cost_of_transport",
           "score"]
ROBOTS = ("ideal", "hardware:N")  # the robots a check walks on (N: a hardware-like draw, 0, 1, ...)


def parse_robot(robot: str) -> int | None:
    """"ideal" → None; "hardware:N" → N (the hardware-like draw's seed). Anything else is a ValueError."""
    if robot == "ideal":
        return None
    head, _, draw = robot.partition(":")
    if head != "hardware" or not draw.isdigit():
        raise ValueError(f"a robot is 'ideal' or 'hardware:N' (N = 0, 1, ...: a hardware-like draw), got {robot!r}")
    return int(draw)


def robot_env(env, robot: str, engine: str | None = None):
    """(the env config, hardware_robot) a walk on `robot` runs with: `env` (an EnvConfig, the actor's) with no
    randomisation draw and the ideal robot's hardware, or the hardware-like robot of draw N; in the physics
    engine `engine` (None: the one `env` names)."""
    import dataclasses

    from cyberdog.config import HARDWARE_LIKE, HardwareConfig, RandomizationConfig

    draw = parse_robot(robot)
    hardware = HardwareConfig() if draw is None else dataclasses.replace(HARDWARE_LIKE, seed=draw)
    if engine is not None:
        env = dataclasses.replace(env, walk=dataclasses.replace(
            env.walk, sim=dataclasses.replace(env.walk.sim, engine=engine)))
    return dataclasses.replace(env, hardware=hardware, randomization=RandomizationConfig()), draw is not None


def _row(label, stage, robot, path, speed, r, engine: str) -> dict:
    in_band = speed_within_band(r.mean_speed, speed) if math.isfinite(r.mean_speed) else False
    return {"label": label, "stage": stage, "robot": robot, "engine": engine, "actor": str(path),
            "speed_command_mps": speed,
            "walks": bool(not r.fell and in_band), "fell": bool(r.fell), "duration_s": r.duration,
            "mean_speed_mps": r.mean_speed, "in_band": in_band, "energy_J": r.energy,
            "electrical_energy_J": r.electrical_energy, "energy_per_metre_J": r.energy_per_metre,
            "electrical_per_metre_J": r.electrical_energy / r.distance if r.distance > 0 else math.nan,
            "cost_of_transport": r.cost_of_transport, "score": r.score}


def check_actor(job: tuple) -> dict:
    """One walk → one row. job: (label, stage, actor file, speed m/s, duration s, env seed, robot, engine or None:
    the actor's own)."""
    from cyberdog.rl.rollout import load_actor, rollout

    label, stage, path, speed, duration, seed, robot, engine = job
    t0 = time.perf_counter()
    actor = load_actor(path)
    env, hardware_robot = robot_env(actor.config.env, robot, engine)
    r = rollout(actor, speed=speed, duration=duration, seed=seed, env_config=env, hardware_robot=hardware_robot)
    return {**_row(label, stage, robot, path, speed, r, env.walk.sim.engine), "wall_s": time.perf_counter() - t0}


def check_trot(job: tuple) -> dict:
    """The trot controller's own walk → one row like `check_actor`'s. job: (speed m/s, duration s, the env's
    `WalkConfig`: the trot the env's controller, and a torque policy's prior, runs; robot)."""
    import dataclasses

    from cyberdog.analysis.walk import walk
    from cyberdog.config import HARDWARE_LIKE

    speed, duration, cfg, robot = job
    draw = parse_robot(robot)
    t0 = time.perf_counter()
    r = walk(dataclasses.replace(cfg, gait=dataclasses.replace(cfg.gait, speed=float(speed))), duration=duration,
             hardware=None if draw is None else dataclasses.replace(HARDWARE_LIKE, seed=draw))
    return {**_row("trot", 0, robot, "", speed, r, cfg.sim.engine), "score": math.nan,
            "wall_s": time.perf_counter() - t0}


def check_jobs(actors: dict[str, dict[int, str | Path]], speeds, duration: float, seed: int = 0,
               robots=("ideal",), engine: str | None = None) -> list[tuple]:
    """The walks to make: `actors` maps a label (a seed) to {stage: actor file}; each walks on each robot, in
    `engine` (None: the engine each actor's env names)."""
    if not actors:
        raise ValueError("no actor to check")
    if not (math.isfinite(duration) and duration > 0):
        raise ValueError(f"duration must be > 0 s, got {duration!r}")
    bad = [v for v in speeds if not (math.isfinite(v) and v > 0)]
    if bad or not speeds:
        raise ValueError(f"speeds must be > 0 m/s (one or more), got {list(speeds)!r}")
    if not robots:
        raise ValueError("no robot to walk on")
    for robot in robots:
        parse_robot(robot)
    for label, stages in actors.items():
        for stage, path in stages.items():
            if not Path(path).is_file():
                raise FileNotFoundError(f"{label} stage {stage}: no actor file {path}")
    return [(label, stage, str(path), float(v), float(duration), seed, robot, engine)
            for label, stages in actors.items() for stage, path in sorted(stages.items()) for robot in robots
            for v in speeds]


def stage_reductions(rows: list[dict]) -> list[dict]:
    """Per label, robot and speed with both stages: stage 2 against stage 1, 1 − E₂/E₁ (%) of Eq. 7 over walks of
    the same duration and per metre walked, and of the electrical energy per metre; and whether both walked (only
    then is it a reduction at the same speed)."""
    by_key = {(r["label"], r["stage"], r.get("robot", "ideal"), r["speed_command_mps"]): r for r in rows}
    out = []
    for (label, stage, robot, speed), one in by_key.items():
        two = by_key.get((label, 2, robot, speed))
        if stage != 1 or two is None:
            continue
        same = one["duration_s"] == two["duration_s"]
        out.append({"label": label, "robot": robot, "speed_command_mps": speed,
                    "both_walk": one["walks"] and two["walks"],
                    "energy_stage1_J": one["energy_J"], "energy_stage2_J": two["energy_J"],
                    "reduction_pct": 100.0 * (1.0 - two["energy_J"] / one["energy_J"]) if same else math.nan,
                    "reduction_per_metre_pct": 100.0 * (1.0 - two["energy_per_metre_J"] / one["energy_per_metre_J"]),
                    "electrical_per_metre_stage1_J": one["electrical_per_metre_J"],
                    "electrical_per_metre_stage2_J": two["electrical_per_metre_J"],
                    "electrical_reduction_per_metre_pct":
                        100.0 * (1.0 - two["electrical_per_metre_J"] / one["electrical_per_metre_J"])})
    return out


__all__ = ["COLUMNS", "ROBOTS", "check_actor", "check_jobs", "check_trot", "parse_robot", "robot_env",
           "stage_reductions"]
