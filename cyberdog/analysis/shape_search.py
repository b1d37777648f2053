"""The direct search for the energy-optimal foot-path shape over `cyberdog.core.path_shape`'s
five parameters.

Objective (`ShapeObjective`): the mean over the speeds (and over the joint PD's gains, `gains`: (kp, kd) factors
of the default PID, each shape walked under each) of the energy (Eq. 7, or the electrical energy with
`objective="electrical"`), J, of a `duration`-s walk
(`cyberdog.analysis.walk.walk` with WalkConfig(gait=GaitConfig(speed=v, lift_height=H)), the default trot
controller and simulator), integrated from `measure_from` s on so that the 1 s start-up ramp is left out.
A walk that falls costs FALL_PENALTY_J (plus more the sooner it fell); a walk whose mean speed over its
last half misses the command by more than 5 % costs its energy plus SPEED_MISS_PENALTY_J per % of excess:
an invalid gait is never cheaper than a valid one. The walks of one evaluation run in parallel processes.
The optimiser is scipy's bounded Nelder–Mead in coordinates scaled to [0, 1], started from the cycloid.

Results: at H = 0.10 m on Eq. (7) about 36 % less than the cycloid,
from a near constant-speed swing that Eq. (7) rewards and the battery does not (foot slip doubles, the torque
clip is reached); hence `objective="electrical"` and a `hardware` robot, the prototype run's reference row.
"""
from __future__ import annotations

import dataclasses
import math
import time
from dataclasses import dataclass, field
from typing import Callable, Sequence

import numpy as np

from cyberdog.analysis.parallel import ProcessMap
from cyberdog.core.path_shape import CYCLOID_PARAMS, ShapeParams, from_unit, shape_trajectory, to_unit
from cyberdog.config import HardwareConfig, WalkConfig
from cyberdog.config.paper import PAPER_SPEEDS, SPEED_BAND

FALL_PENALTY_J = 1.0e4  # J, objective of a fallen walk (about 10× a valid walk's window energy) …
SPEED_MISS_PENALTY_J = 100.0  # J per % of speed miss beyond the 5 % band (a valid walk's window: ~300–900 J)
# what a walk's window energy counts: Eq. (7)'s Σ∫|τ·ω|dt, or the electrical energy the battery pays (copper
# loss, friction, driver; cyberdog.core.energy.electrical_power), the prototype run's measure
OBJECTIVES = ("eq7", "electrical")
DEFAULT_GAINS = ((1.0, 1.0),)  # (kp, kd) factors of the joint PD a shape walks under: the default gains alone
GAIN_FACTOR_RANGE = (0.25, 4.0)  # each factor within: the drivers' physics step halves up to MAX_HALVINGS times


@dataclass(frozen=True)
class ShapeWalk:
    """One walk of an evaluation (pickled to a worker process)."""

    params: ShapeParams
    speed: float  # m/s
    lift_height: float  # m
    duration: float  # s
    measure_from: float  # s, energy integrated from here to the end
    base: WalkConfig = field(default_factory=WalkConfig)
    objective: str = "eq7"  # one of OBJECTIVES
    hardware: HardwareConfig | None = None  # the robot walked: None = ideal, else the hardware-like effects
    pd_factors: tuple[float, float] = (1.0, 1.0)  # the joint PD's kp and kd, times the walk config's
    foot_inset: float = 0.0  # m, every foot nearer the body's midline (the shape's stance width)


def check_objective_args(lift_height: float, speeds: Sequence[float], duration: float,
                          measure_from: float, objective: str = "eq7",
                          hardware: HardwareConfig | None = None, gains: Sequence = DEFAULT_GAINS) -> None:
    """ValueError (TypeError for `hardware`) naming the argument that is out of its range."""
    lo, hi = GAIN_FACTOR_RANGE
    if len(gains) == 0 or not all(len(g) == 2 and all(math.isfinite(f) and lo <= f <= hi for f in g) for g in gains):
        raise ValueError(f"gains must be a non-empty list of (kp, kd) factor pairs, each in [{lo:g}, {hi:g}], "
                         f"got {list(gains)!r}")
    if len(set(map(tuple, gains))) < len(gains):
        raise ValueError(f"gains lists a (kp, kd) pair twice: {list(gains)!r}")
    if objective not in OBJECTIVES:
        raise ValueError(f"objective must be one of {OBJECTIVES}, got {objective!r}")
    if hardware is not None and not isinstance(hardware, HardwareConfig):
        raise TypeError(f"hardware must be a HardwareConfig or None, got {type(hardware).__name__}")
    if not (math.isfinite(lift_height) and 0.02 <= lift_height <= 0.25):
        raise ValueError(f"lift_height must be in [0.02, 0.25] m, got {lift_height!r}")
    if len(speeds) == 0 or not all(math.isfinite(v) and 0.1 <= v <= 2.0 for v in speeds):
        raise ValueError(f"speeds must be a non-empty list of values in [0.1, 2.0] m/s, got {list(speeds)!r}")
    if not (math.isfinite(duration) and duration > 0):
        raise ValueError(f"duration must be > 0 s, got {duration!r}")
    if not (math.isfinite(measure_from) and 0 <= measure_from < duration):
        raise ValueError(f"measure_from must be in [0, duration = {duration}) s, got {measure_from!r}")


def walk_cost(job: ShapeWalk) -> dict:
    """Walk one shape at one speed; the window energy and its penalised cost (runs in a worker process)."""
    from cyberdog.analysis.walk import walk  # the simulator only where a walk runs
    from cyberdog.core.energy import electrical_power
    from cyberdog.sim.hardware_model import hardware_walk_config

    gait = dataclasses.replace(job.base.gait, speed=float(job.speed), lift_height=float(job.lift_height))
    kp, kd = job.pd_factors  # the drivers step at the physics rate these gains need (the walker sees to it)
    pid = dataclasses.replace(job.base.pid, kp=tuple(g * kp for g in job.base.pid.kp),
                              kd=tuple(g * kd for g in job.base.pid.kd))
    cfg = dataclasses.replace(job.base, gait=gait, pid=pid)
    traj = shape_trajectory(job.params, gait, foot_inset=job.foot_inset)
    t0 = time.process_time()
    r = walk(cfg, job.duration, trajectory=traj, record=True, hardware=job.hardware)
    dt = cfg.sim.controller_dt
    first = int(round(job.measure_from / dt))
    if job.objective == "electrical":  # the walker's own actuator model (friction on the hardware-like robot)
        walked = hardware_walk_config(cfg, job.hardware)
        energy_J = float(np.sum(electrical_power(r.traces["tau"][first:], r.traces["dq"][first:], walked.actuator,
                                                 walked.energy)) * dt)
    else:
        energy_J = float(r.traces["power"][first:].sum() * dt)  # Eq. (7) over the window
    miss_pct = 100.0 * abs(r.mean_speed - job.speed) / job.speed
    if r.fell or not math.isfinite(energy_J):
        cost, status = FALL_PENALTY_J * (2.0 - r.duration / job.duration), f"fell at {r.duration:.2f} s"
    elif miss_pct > 100.0 * SPEED_BAND:
        cost = energy_J + SPEED_MISS_PENALTY_J * (miss_pct - 100.0 * SPEED_BAND)
        status = f"speed miss ({r.mean_speed:.3f} m/s)"
    else:
        cost, status = energy_J, "ok"
    return {"speed_command_mps": job.speed, "kp_factor": kp, "kd_factor": kd, "mean_speed_mps": r.mean_speed,
            "fell": r.fell,
            "energy_window_J": energy_J, "energy_total_J": r.energy, "cost_J": cost, "status": status,
            "cpu_s": time.process_time() - t0}


@dataclass
class Evaluation:
    """One objective evaluation: the shape, the mean penalised cost over the speeds (J) and the walks."""

    index: int
    params: ShapeParams
    objective_J: float
    walks: list[dict]
    wall_s: float

    @property
    def valid(self) -> bool:
        return all(w["status"] == "ok" for w in self.walks)

    def row(self) -> dict:
        out = {"eval": self.index, **self.params.as_dict(), "objective_J": self.objective_J, "valid": self.valid,
               "wall_s": self.wall_s}
        for w in self.walks:
            v = walk_key(w)
            out[f"E_window_J@{v}"] = w["energy_window_J"]
            out[f"mean_speed_mps@{v}"] = w["mean_speed_mps"]
            out[f"status@{v}"] = w["status"]
        return out


def walk_key(w: dict) -> str:
    """"1.20" for a walk at 1.2 m/s under the default gains, "1.20 kp0.5 kd1" under others: a history column's
    and a per-walk summary's key."""
    v = f"{w['speed_command_mps']:.2f}"
    factors = (w.get("kp_factor", 1.0), w.get("kd_factor", 1.0))
    return v if factors == (1.0, 1.0) else f"{v} kp{factors[0]:g} kd{factors[1]:g}"


class ShapeObjective:
    """Callable objective over unit coordinates (see `to_unit`): runs the walks (in `pool`, a `ProcessMap`, if
    given; else in this process), records every evaluation in `history`, caches repeated points (Nelder–Mead
    revisits clipped corners)."""

    def __init__(self, lift_height: float = 0.10, speeds: Sequence[float] = PAPER_SPEEDS, duration: float = 6.0,
                 measure_from: float = 2.0, base: WalkConfig | None = None, pool: ProcessMap | None = None,
                 log: Callable[[str], None] | None = print, max_evals: int | None = None, objective: str = "eq7",
                 hardware: HardwareConfig | None = None, gains: Sequence = DEFAULT_GAINS,
                 foot_inset: float = 0.0) -> None:
        check_objective_args(lift_height, speeds, duration, measure_from, objective, hardware, gains)
        self.objective, self.hardware, self.foot_inset = objective, hardware, float(foot_inset)
        self.gains = tuple((float(kp), float(kd)) for kp, kd in gains)
        self.lift_height, self.speeds = float(lift_height), tuple(float(v) for v in speeds)
        self.duration, self.measure_from = float(duration), float(measure_from)
        self.base, self.log, self.max_evals = base or WalkConfig(), log, max_evals
        self.pool = pool if pool is not None else ProcessMap(1)
        self.history: list[Evaluation] = []
        self._cache: dict[tuple, float] = {}
        self._t0 = time.perf_counter()

    def evaluate(self, params: ShapeParams) -> Evaluation:
        jobs = [ShapeWalk(params, v, self.lift_height, self.duration, self.measure_from, self.base,
                          self.objective, self.hardware, g, self.foot_inset) for g in self.gains for v in self.speeds]
        t0 = time.perf_counter()
        walks = self.pool(walk_cost, jobs, describe=lambda j: f"{j.speed:g} m/s, PD {j.pd_factors} with {j.params}")
        ev = Evaluation(len(self.history), params, float(np.mean([w["cost_J"] for w in walks])), walks,
                        time.perf_counter() - t0)
        self.history.append(ev)
        if self.log is not None:
            self._progress(ev)
        return ev

    def _progress(self, ev: Evaluation) -> None:
        best = min(e.objective_J for e in self.history)
        start = self.history[0].objective_J
        elapsed = time.perf_counter() - self._t0
        n = len(self.history)
        eta = f", ETA {elapsed / n * (self.max_evals - n):.0f} s" if self.max_evals else ""
        p = " ".join(f"{k}={v:+.3f}" for k, v in ev.params.as_dict().items())
        bad = "" if ev.valid else "  [" + "; ".join(w["status"] for w in ev.walks if w["status"] != "ok") + "]"
        self.log(f"[{n}{'/' + str(self.max_evals) if self.max_evals else ''}] J={ev.objective_J:7.1f} "
                 f"best={best:7.1f} ({100 * (best - start) / start:+.2f} % vs start)  {p}{bad}  "
                 f"({ev.wall_s:.1f} s; elapsed {elapsed:.0f} s{eta})")

    def __call__(self, u: Sequence[float]) -> float:
        params = from_unit(u)
        key = tuple(np.round(params.as_array(), 9))
        if key not in self._cache:
            if self.max_evals is not None and len(self.history) >= self.max_evals:
                raise EvaluationBudgetSpent(self.max_evals)  # scipy's maxfev overshoots by up to a simplex
            self._cache[key] = self.evaluate(params).objective_J
        return self._cache[key]


class EvaluationBudgetSpent(Exception):
    """Raised by `ShapeObjective` when a new point would exceed its `max_evals`."""


@dataclass
class OptimizationResult:
    best: Evaluation
    start: Evaluation
    history: list[Evaluation]
    wall_s: float
    message: str

    @property
    def saving_pct(self) -> float:
        """Objective saving of the best shape against the start (the cycloid), %."""
        return 100.0 * (self.start.objective_J - self.best.objective_J) / self.start.objective_J


def optimize_shape(lift_height: float = 0.10, speeds: Sequence[float] = PAPER_SPEEDS, duration: float = 6.0,
                   measure_from: float = 2.0, max_evals: int = 100, workers: int = 2,
                   start: ShapeParams = CYCLOID_PARAMS, initial_step: float = 0.2, base: WalkConfig | None = None,
                   log: Callable[[str], None] | None = print, objective: str = "eq7",
                   hardware: HardwareConfig | None = None, gains: Sequence = DEFAULT_GAINS,
                   foot_inset: float = 0.0) -> OptimizationResult:
    """Bounded Nelder–Mead over the shape parameters (unit coordinates), started from `start`.

    initial_step: size of the initial simplex in unit coordinates (share of each parameter's range), each
    vertex stepping toward the interior from `start`. Walks of one evaluation run in `workers` spawned
    processes (1 = in this process). objective: what a walk's energy counts (OBJECTIVES); hardware: the robot
    walked (None: ideal; a HardwareConfig: its effects and its seeded mass draw, the same robot every walk);
    gains: the (kp, kd) factors of the joint PD each shape walks under at each speed (the objective their mean);
    foot_inset: m, every foot nearer the body's midline in every walk (a stance width the shape is searched at).
    """
    from scipy.optimize import minimize

    check_objective_args(lift_height, speeds, duration, measure_from, objective, hardware, gains)
    if not (isinstance(max_evals, (int, np.integer)) and max_evals >= 2):
        raise ValueError(f"max_evals must be an integer >= 2, got {max_evals!r}")
    if not (isinstance(workers, (int, np.integer)) and workers >= 1):
        raise ValueError(f"workers must be an integer >= 1, got {workers!r}")
    if not 0 < initial_step <= 0.5:
        raise ValueError(f"initial_step must be in (0, 0.5] (unit coordinates), got {initial_step!r}")
    t0 = time.perf_counter()
    x0 = to_unit(start)
    simplex = [x0]
    for i in range(len(x0)):  # one vertex per parameter, stepping into the box
        v = x0.copy()
        v[i] += initial_step if x0[i] + initial_step <= 1.0 else -initial_step
        simplex.append(v)
    with ProcessMap(workers) as pool:  # the workers live through every evaluation (they start once)
        cost = ShapeObjective(lift_height, speeds, duration, measure_from, base, pool, log, max_evals, objective,
                              hardware, gains, foot_inset)
        try:
            res = minimize(cost, x0, method="Nelder-Mead", bounds=[(0.0, 1.0)] * len(x0),
                           options={"maxfev": max_evals, "initial_simplex": np.array(simplex),
                                    "xatol": 0.01, "fatol": 0.5})  # 1 % of a range; 0.5 J ≈ 0.1 % of the objective
            message = str(res.message)
        except EvaluationBudgetSpent:
            message = f"stopped at the budget of {max_evals} evaluations"
    history = cost.history
    best = min(history, key=lambda e: e.objective_J)
    return OptimizationResult(best, history[0], history, time.perf_counter() - t0, message)
