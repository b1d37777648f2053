"""Reward of the paper's Eq. (10)–(11): one small named function per term, weights in `RewardConfig`. Pure Python.

    r_t = A·r_v + B·r_yoffset + C·r_Fuselage stable + D·r_Keep moving + E·r_E        (10)
    r_t = −2·r_v − 20·r_yoffset − 50·r_Fuselage stable + 25·r_Keep moving − 0.2·r_E   (11)

The functions here return the **unweighted** terms (all ≥ 0); `weighted_terms` multiplies them by the weights
of a `RewardConfig`, and `total_reward` is the sum of exactly those weighted terms, so an environment can
report them in `info` and a test can check that they add up to the reward. A weight of 0 turns a term off
(the paper's stage 1 sets the energy weight E = 0).
"""
from __future__ import annotations

import math

from cyberdog.config import REWARD_TERM_NAMES, RewardConfig

_TERM_NAME_SET = frozenset(REWARD_TERM_NAMES)


def speed_term(v_x: float, v_target: float, deadband: float = 0.0, per_speed: float | None = None,
               cap: float = 0.0) -> float:
    """r_v = (v_target − v_x)², (m/s)²: squared error of the forward body speed.

    The paper writes r_v = (v0 − v_x)² but calls v0 the measured and v_x the target speed; here v_x is the
    measured forward speed and v_target the commanded one (the square makes the order irrelevant).
    With `deadband` > 0 (a share of the command, `RewardConfig.speed_deadband`) only the error beyond
    deadband·|v_target| counts: r_v = max(0, |v_target − v_x| − deadband·|v_target|)². 0 is the paper's term.
    With `per_speed` (m/s, `RewardConfig.speed_relative`: the episode's set speed) the error is a share of it and
    r_v is unitless: r_v = (max(0, |v_target − v_x| − deadband·|v_target|) / per_speed)². None is the paper's.
    With `cap` > 0 (a share of the command, `RewardConfig.speed_cap`) the error counts up to cap·|v_target|: r_v
    stops growing there, so that a walk far off the command still scores above a fall. 0 is the paper's (no cap).
    """
    if not (0.0 <= deadband < 1.0):
        raise ValueError(f"deadband must be in [0, 1) (a share of the command), got {deadband!r}")
    if per_speed is not None and not (per_speed > 0 and math.isfinite(per_speed)):
        raise ValueError(f"per_speed must be > 0 m/s and finite (None: the error in m/s), got {per_speed!r}")
    if not (0.0 <= cap and math.isfinite(cap)):
        raise ValueError(f"cap must be >= 0 and finite (a share of the command; 0: no cap), got {cap!r}")
    error = max(0.0, abs(v_target - v_x) - deadband * abs(v_target))
    if cap > 0:
        error = min(error, cap * abs(v_target))
    return (error if per_speed is None else error / per_speed) ** 2


class SpeedWindow:
    """The speeds r_v compares when it is taken over a window (`RewardConfig.speed_window`): the means of the
    measured speed and of the command over the last `steps` agent steps (fewer since a `reset`). A trot's body
    surges and slows within each stride; over one gait period the mean is the speed the robot walks."""

    def __init__(self, steps: int):
        if not (isinstance(steps, int) and steps >= 1):
            raise ValueError(f"steps must be an integer >= 1, got {steps!r}")
        self.steps = steps
        self._history: list[tuple[float, float]] = []

    def reset(self) -> None:
        self._history.clear()

    def add(self, v_x: float, v_target: float) -> tuple[float, float]:
        """Take one step's (v_x, v_target), m/s; return their means over the window, (v̄_x, v̄_target)."""
        history = self._history
        history.append((float(v_x), float(v_target)))
        del history[:-self.steps]
        n = len(history)
        return sum(h[0] for h in history) / n, sum(h[1] for h in history) / n


def y_offset_term(y: float) -> float:
    """r_yoffset = y², m²: sideways drift of the body from the straight line it should walk along."""
    return y ** 2


def fuselage_term(z: float, z_nominal: float) -> float:
    """r_Fuselage stable = ẑ² = (z − z_nominal)², m²: the body's height deviation (trunk vibration)."""
    return (z - z_nominal) ** 2


def keep_moving_term(sample_time: float, episode_time: float) -> float:
    """r_Keep moving = Ts / Tf: agent sample time over episode length; summed over a full episode it is 1.

    A constant bonus per step survived, which rewards not falling (the episode ends when the robot falls).
    """
    if not (episode_time > 0 and math.isfinite(episode_time)):
        raise ValueError(f"episode_time (Tf) must be > 0 and finite, got {episode_time!r}")
    if not (sample_time >= 0 and math.isfinite(sample_time)):
        raise ValueError(f"sample_time (Ts) must be >= 0 and finite, got {sample_time!r}")
    return sample_time / episode_time


def energy_term(step_energy_J: float) -> float:
    """r_E, J: mechanical energy spent over the agent step, Σ_ij ∫|τ_ij · θ̇_ij| dt (Eq. 7 over one step).

    The paper's text writes ∫τ·θ̇ dt over the 10 s episode; the absolute value of Eq. (7) is used so that
    negative (braking) work is not counted as a gain. The integral itself is computed by the caller over
    the controller periods of the agent step (the energy layer), and passed in here.
    """
    if not (step_energy_J >= 0 and math.isfinite(step_energy_J)):
        raise ValueError(f"step_energy_J must be >= 0 and finite, got {step_energy_J!r}")
    return float(step_energy_J)


def reward_terms(*, v_x: float, v_target: float, y: float, z: float, z_nominal: float,
                 sample_time: float, episode_time: float, step_energy_J: float,
                 speed_deadband: float = 0.0, speed_per: float | None = None,
                 speed_cap: float = 0.0) -> dict[str, float]:
    """The five unweighted terms of Eq. (10), keyed by `REWARD_TERM_NAMES` (speed, y_offset, fuselage,
    keep_moving, energy), in that order. `speed_deadband`, `speed_per`, `speed_cap`: see `speed_term`'s deadband,
    per_speed, cap."""
    return {  # in the order of REWARD_TERM_NAMES
        "speed": float(speed_term(v_x, v_target, speed_deadband, speed_per, speed_cap)),
        "y_offset": float(y_offset_term(y)),
        "fuselage": float(fuselage_term(z, z_nominal)),
        "keep_moving": float(keep_moving_term(sample_time, episode_time)),
        "energy": energy_term(step_energy_J),
    }


def weighted_terms(terms: dict[str, float], cfg: RewardConfig) -> dict[str, float]:
    """Each term times its weight (A…E of Eq. 10); the values sum to the reward (`total_reward`)."""
    if terms.keys() != _TERM_NAME_SET:
        missing = [n for n in REWARD_TERM_NAMES if n not in terms]
        unknown = sorted(set(terms) - _TERM_NAME_SET)
        raise ValueError(f"reward terms must be exactly {list(REWARD_TERM_NAMES)}; "
                         f"missing {missing}, unknown {unknown}")
    weights = cfg.weights
    return {n: weights[n] * terms[n] for n in REWARD_TERM_NAMES}


def total_reward(terms: dict[str, float], cfg: RewardConfig) -> float:
    """r_t of Eq. (10): the sum, in the order of Eq. (10), of `weighted_terms(terms, cfg)`."""
    return float(sum(weighted_terms(terms, cfg).values()))
