"""What the trot's speed loop added: `WalkResult.speed_loop_share` and `speed_loop_at_limit`, and the prototype
rows that carry them. A commanded path can lean on the loop (its stance shift shortens the stride and the
integral lengthens it back); these numbers say how far, and whether the loop ran out."""
import dataclasses

import numpy as np
import pytest

from cyberdog import config as C
from cyberdog.analysis.walk import walk
from cyberdog.core.foot_offsets import FootOffsetPath
from cyberdog.core.trajectories import swing_fraction


def cfg_with(speed: float = 1.0, **controller) -> C.WalkConfig:
    cfg = C.WalkConfig()
    return dataclasses.replace(cfg, gait=dataclasses.replace(cfg.gait, speed=speed),
                               controller=dataclasses.replace(cfg.controller, **controller))


def stance_creep(cfg: C.WalkConfig, d: float, n: int = 40) -> FootOffsetPath:
    """Every foot target moved forward by 2·d over its stance (−d at touchdown to +d at lift-off) and back in the
    swing: the stance stroke the trot commands is 2·d shorter than S = v·stance time."""
    beta = swing_fraction(cfg.gait.swing_time, cfg.gait.stance_time)
    phase = np.arange(n) / n
    x = np.where(phase < beta, d - 2 * d * phase / beta, -d + 2 * d * (phase - beta) / (1 - beta))
    table = np.zeros((4, n, 3))
    table[:, :, 0] = x
    return FootOffsetPath(table, cfg.gait.period)


def test_the_loop_adds_back_the_stride_a_stance_shift_takes():
    cfg, d = cfg_with(1.0), 0.01  # m: a 20 mm shorter stance stroke
    plain = walk(cfg, 8.0, run_up=3.0)
    creep = walk(cfg, 8.0, run_up=3.0, foot_offsets=stance_creep(cfg, d))
    assert not plain.fell and not creep.fell
    assert -0.15 < plain.speed_loop_share < 0 and plain.speed_loop_at_limit < 0.05  # the plain trot overshoots
    expected = 2 * d / cfg.gait.stance_time / cfg.gait.speed  # +0.1: the stride lengthened by what was taken
    assert creep.speed_loop_share - plain.speed_loop_share == pytest.approx(expected, abs=0.04)
    assert abs(creep.mean_speed - 1.0) < 0.05  # the loop kept the speed


def test_a_loop_at_its_bound_says_so_and_a_loop_off_adds_nothing():
    """The plain trot overshoots its command (measured: 1.09 m/s at S = v·stance time on the ideal robot) and
    its loop takes about a tenth off the stride; bound at 1 % of the command it runs out and the walk is fast."""
    bound = 0.01  # share of the command
    tight = walk(cfg_with(1.0, max_speed_correction=bound), 6.0, run_up=3.0)
    assert tight.speed_loop_at_limit > 0.9
    assert tight.speed_loop_share == pytest.approx(-bound, abs=1e-6)
    assert tight.mean_speed > 1.05
    off = walk(cfg_with(1.0, speed_gain=0.0), 4.0)
    assert off.speed_loop_share == 0.0 and off.speed_loop_at_limit == 0.0


def test_prototype_rows_carry_the_speed_loop():
    from cyberdog.analysis.prototype import run_prototype
    (row,) = run_prototype({"cycloid": None}, speeds=(1.0,), distance_m=2.0, modes=("ideal",), workers=1,
                           run_up_s=1.5, log=lambda _: None)
    r = walk(cfg_with(1.0), 30.0, distance=2.0, run_up=1.5)
    assert row["speed_loop_pct"] == pytest.approx(100 * r.speed_loop_share)
    assert row["speed_loop_at_limit_pct"] == pytest.approx(100 * r.speed_loop_at_limit)
