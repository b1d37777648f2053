"""The learned trajectory as the policy commanded it: per-leg foot-target offsets over the phase, their
extraction from a rollout, and their replay through IK + PID."""
import dataclasses
from pathlib import Path

import numpy as np
import pytest

from cyberdog import config as C
from cyberdog.analysis.extract import ExtractionError, extract_commanded
from cyberdog.control.trot import BodyFeedback, TrotController
from cyberdog.core.commanded_path import CommandedPath
from cyberdog.core.learned_set import read_path
from cyberdog.core.foot_offsets import FootOffsetPath
from cyberdog.core.gait import GaitScheduler
from cyberdog.core.trajectories import SampledTrajectory

DT = 0.001  # s
GAIT = C.GaitConfig(lift_height=0.10)  # 0.4 s cycle, 0.2 s swing: the env's trot


def smooth_table(n: int = 40, seed: int = 0) -> np.ndarray:
    """(4, n, 3) m: a smooth periodic shift per leg (one harmonic of random amplitude and phase per axis)."""
    rng = np.random.default_rng(seed)
    phase = np.arange(n) / n
    amp, shift = rng.uniform(0.002, 0.02, (4, 1, 3)), rng.uniform(0, 1, (4, 1, 3))
    return amp * np.sin(2 * np.pi * (phase[None, :, None] + shift))


# ---- FootOffsetPath -------------------------------------------------------------------------------------

def test_offset_path_interpolates_its_table_and_its_rate_is_the_phase_derivative():
    table = smooth_table()
    path = FootOffsetPath(table, period=0.4)
    k = np.arange(path.n)
    for leg in range(4):  # at the samples: the table itself
        assert np.allclose(path.sample(leg, k / path.n), table[leg])
    phases = [0.13, 0.51, 0.77, 0.999]
    offsets, rates = path.at(phases)
    for leg, phase in enumerate(phases):  # `at` (the 1 kHz float path) equals the array evaluation
        assert np.allclose(offsets[leg], path.sample(leg, np.array([phase]))[0])
        h = 1e-6  # the rate is the derivative over time: d/dφ · 1/period, inside one linear piece
        num = (path.sample(leg, np.array([phase + h])) - path.sample(leg, np.array([phase]))) / h / 0.4
        assert np.allclose(rates[leg], num[0], atol=1e-6)
    assert path.at([1.25, -0.75, 0.25, 0.25])[0][0] == pytest.approx(path.at([0.25] * 4)[0][0])  # wraps



def test_offset_path_sample_is_the_array_interpolation():
    """`sample` and `at` share one interpolation (floats); it equals the plain array law of tests/oracles.py."""
    from oracles import foot_offsets
    table = smooth_table()
    path = FootOffsetPath(table, period=0.4)
    phases = np.concatenate([np.random.default_rng(0).uniform(-2.0, 2.0, 500), [0.0, -1e-17, 1.0, 0.999999]])
    for leg in range(4):
        np.testing.assert_allclose(path.sample(leg, phases), foot_offsets(table, leg, phases), rtol=0, atol=1e-15)
    assert path.sample(0, phases).shape == (len(phases), 3)

def test_offset_path_from_samples_recovers_a_table_sampled_at_each_legs_phase():
    table = smooth_table(n=100)
    path = FootOffsetPath(table, 0.4)
    t = np.arange(400) * DT  # one cycle at 1 kHz
    phases = GaitScheduler.from_config(GAIT).leg_phases(t)  # (400, 4), the diagonal pairs half a cycle apart
    samples = np.stack([path.sample(leg, phases[:, leg]) for leg in range(4)], axis=1)
    rebuilt = FootOffsetPath.from_samples(phases, samples, 0.4, 100)
    assert np.allclose(rebuilt.offsets, table, atol=1e-12)


@pytest.mark.parametrize("bad", [np.zeros((3, 10, 3)), np.zeros((4, 10, 2)), np.zeros((4, 2, 3)),
                                 np.full((4, 10, 3), np.nan)])
def test_offset_path_rejects_bad_tables(bad):
    with pytest.raises(ValueError, match="offsets"):
        FootOffsetPath(bad, 0.4)
    with pytest.raises(ValueError, match="period"):
        FootOffsetPath(np.zeros((4, 10, 3)), 0.0)


def test_a_zero_offset_path_leaves_the_trot_torque_unchanged_and_a_shift_moves_the_targets_once_blended_in():
    cfg = C.WalkConfig(gait=GAIT)
    plain, zero = TrotController(cfg), TrotController(cfg, foot_offset_path=FootOffsetPath.zero(0.4))
    shifted = TrotController(cfg, foot_offset_path=FootOffsetPath(np.full((4, 8, 3), 0.01), 0.4))
    q = np.tile([0.0, 0.8, -1.6], 4)
    dq = np.zeros(12)
    ramp = cfg.controller.speed_ramp_time  # s: over the start-up ramp the shift grows with the commanded speed
    for t in (0.25 * ramp, ramp + 0.05, ramp + 0.23, ramp + 0.31):
        body = BodyFeedback(forward_speed=1.0)
        assert np.array_equal(plain.torque(t, q, dq, body), zero.torque(t, q, dq, body))
        shifted.torque(t, q, dq, body)
        share = min(1.0, t / ramp)
        assert np.allclose(np.array(shifted.last_foot_targets) - np.array(plain.last_foot_targets), 0.01 * share)
        assert np.allclose(shifted.last_foot_offsets, 0.01 * share)


# ---- CommandedPath --------------------------------------------------------------------------------------

def test_commanded_path_lift_height_and_file_round_trip(tmp_path):
    zero = CommandedPath(1.0, GAIT, FootOffsetPath.zero(0.4, n=400))
    assert zero.own_lift_height() == pytest.approx(GAIT.lift_height, abs=1e-4)  # the cycloid's own H
    # lower every swing by 2 cm (phase < 0.5 of each leg), stance untouched: the path's own H drops by 2 cm
    table = np.zeros((4, 400, 3))
    table[:, :200, 2] = -0.02 * np.sin(np.pi * np.arange(200) / 200)
    lowered = CommandedPath(1.2, GAIT, FootOffsetPath(table, 0.4), {"seed": 3})
    assert lowered.own_lift_height() == pytest.approx(GAIT.lift_height - 0.02, abs=2e-4)
    assert lowered.step_length == pytest.approx(1.2 * GAIT.stance_time)
    back = read_path(lowered.save(tmp_path / "p.json"))
    assert isinstance(back, CommandedPath) and back.speed == 1.2
    assert np.allclose(back.offsets.offsets, lowered.offsets.offsets, atol=1e-6)  # stored in 1 µm steps
    assert back.provenance == {"seed": 3} and back.gait == lowered.gait
    ref = lowered.as_sampled("LF")  # the paper's single reference foot, for figures
    assert isinstance(ref, SampledTrajectory) and ref.lift_height == pytest.approx(lowered.leg_lift_heights()[0])
    sampled = SampledTrajectory(ref.phase, ref.x, ref.z, ref.step_length, ref.lift_height)
    assert isinstance(read_path(sampled.save(tmp_path / "s.json")), SampledTrajectory)


def test_commanded_path_rejects_a_period_mismatch_and_a_sampled_base_without_its_file():
    with pytest.raises(ValueError, match="period"):
        CommandedPath(1.0, GAIT, FootOffsetPath.zero(0.5))
    with pytest.raises(ValueError, match="sampled_file"):
        CommandedPath(1.0, dataclasses.replace(GAIT, trajectory="sampled"), FootOffsetPath.zero(0.4))


def test_a_commanded_path_on_a_sampled_base_keeps_its_file_and_draws_that_base(tmp_path):
    """A policy trained around a sampled path (a searched shape) records the file its base path was read from;
    with zero offsets its foot path is that shape at the path's step length and lift."""
    phase = np.linspace(0.0, 1.0, 80, endpoint=False)
    swing = phase < 0.5
    x = np.where(swing, -0.5 + phase * 2, 0.5 - (phase - 0.5) * 2)  # normalised: one step length, back and forth
    z = np.where(swing, np.sin(np.pi * phase * 2) ** 2, 0.0)
    shape = SampledTrajectory(phase, x * 0.24, z * 0.08, 0.24, 0.08).save(tmp_path / "shape.json")
    gait = dataclasses.replace(GAIT, trajectory="sampled", sampled_file=str(shape), lift_height=0.08)
    path = CommandedPath(1.2, gait, FootOffsetPath.zero(0.4, n=200))
    back = read_path(path.save(tmp_path / "p.json"))
    assert back.gait.sampled_file == str(shape) and back.gait == path.gait
    _, xs, zs = back.leg_path("LF")
    assert zs.max() == pytest.approx(0.08, abs=2e-3) and xs.max() - xs.min() == pytest.approx(1.2 * GAIT.stance_time,
                                                                                              abs=2e-3)


# ---- extraction -----------------------------------------------------------------------------------------

def synthetic_rollout(table: np.ndarray, levels, speed: float = 1.0) -> dict:
    """Traces of a rollout whose commanded offsets follow `table` in every cycle; cycle k has joint power
    12·levels[k] W and body speed `speed` (except where levels[k] < 0: that cycle walks at half speed)."""
    n = 400 * len(levels)
    t = np.arange(n) * DT
    path = FootOffsetPath(table, 0.4)
    phases = GaitScheduler.from_config(GAIT).leg_phases(t)
    offsets = np.stack([path.sample(leg, phases[:, leg]) for leg in range(4)], axis=1)
    level = np.repeat(np.abs(levels), 400)
    v = np.repeat([speed if lv >= 0 else speed / 2 for lv in levels], 400)
    x = np.concatenate([[0.0], np.cumsum(v * DT)])[:n]
    return {"t": t, "tau": np.sqrt(level)[:, None] * np.ones((n, 12)), "dq": np.sqrt(level)[:, None] * np.ones((n, 12)),
            "base_position": np.stack([x, np.zeros(n), np.full(n, 0.3)], axis=1), "foot_offsets": offsets}


def test_extract_commanded_mean_and_cheapest_cycles():
    table = smooth_table(n=400)
    levels = [5.0, 5.0, 5.0, 6.0, 4.0, -3.0, 7.0]  # cycles 0-4 before the 2 s settle time; 5 walks too slowly
    traces = synthetic_rollout(table, levels)
    ex = extract_commanded(traces, DT, 1.0, GAIT, cycle="mean")
    assert ex.used == [6]  # cycles 0-4 start before 2 s; cycle 5 is out of the speed band
    traces = synthetic_rollout(table, [5.0] * 5 + [6.0, 4.0, 5.0])
    mean = extract_commanded(traces, DT, 1.0, GAIT, cycle="mean")
    cheap = extract_commanded(traces, DT, 1.0, GAIT, cycle="cheapest")
    assert mean.used == [5, 6, 7] and cheap.used == [6]
    assert mean.energy == pytest.approx(12 * 5.0 * 0.4, rel=1e-9)  # Eq. (7) of the used cycles, averaged
    assert cheap.energy == pytest.approx(12 * 4.0 * 0.4, rel=1e-9)
    assert np.allclose(mean.path.offsets.offsets, table, atol=1e-12)  # every cycle commanded the same shift
    assert mean.path.speed == 1.0 and mean.path.provenance["cycles_used"] == [5, 6, 7]


def test_extract_commanded_errors_are_clear():
    table = smooth_table(n=400)
    with pytest.raises(ExtractionError, match="no settled gait cycle"):
        extract_commanded(synthetic_rollout(table, [5.0] * 8), DT, 1.4, GAIT)  # walks 1.0, asked 1.4
    traces = synthetic_rollout(table, [5.0] * 8)
    traces["foot_offsets"] = np.full_like(traces["foot_offsets"], np.nan)
    with pytest.raises(ExtractionError, match="not finite"):
        extract_commanded(traces, DT, 1.0, GAIT)
    del traces["foot_offsets"]
    with pytest.raises(ExtractionError, match="foot targets"):
        extract_commanded(traces, DT, 1.0, GAIT)
    with pytest.raises(ValueError, match="cycle must be"):
        extract_commanded(synthetic_rollout(table, [5.0] * 8), DT, 1.0, GAIT, cycle="best")


# ---- the saving survives extraction: closed loop vs replay ----------------------------------------------

SHIPPED = Path(__file__).resolve().parents[1] / "results" / "table5" / "policy" / "seed0" / "stage2_actor.pt"


@pytest.mark.slow
def test_replaying_the_commanded_path_reproduces_the_closed_loop_energy():
    """A short real rollout of the shipped foot-mode policy: the commanded path of its settled cycles,
    replayed by IK + PID with no policy in the loop, costs what those cycles cost in closed loop (within 5 %),
    and clearly less than the plain trot at the same base lift height; the measured-path extraction (the
    paper's) still works on the same rollout."""
    from cyberdog.analysis.extract import commanded_from_rollout
    from cyberdog.analysis.extract_measured import extract_from_rollout
    from cyberdog.analysis.walk import walk
    from cyberdog.rl.rollout import load_actor, rollout

    actor = load_actor(SHIPPED)
    env = actor.config.env
    speed = env.target_speed_range[0] if env.target_speed_range else env.target_speed
    r = rollout(actor, speed=speed, duration=5.0, env_config=env)
    assert not r.fell
    ex = commanded_from_rollout(r, env, cycle="mean", settle_time=2.0)
    assert len(ex.used) >= 5
    cfg = dataclasses.replace(env.walk, gait=dataclasses.replace(ex.path.gait, speed=speed))
    dt = cfg.sim.controller_dt  # s, one traced period
    per = int(round(cfg.gait.period / dt))  # traced periods per gait cycle

    def settled_cycle_energy(result) -> float:
        p = result.traces["power"].sum(axis=1)
        return float(np.mean([p[k * per:(k + 1) * per].sum() * dt for k in range(5, len(p) // per)]))

    replay = walk(cfg, 5.0, record=True, foot_offsets=ex.path.offsets)
    plain = walk(cfg, 5.0, record=True)
    assert not replay.fell and replay.speed_ok
    assert settled_cycle_energy(replay) == pytest.approx(ex.energy, rel=0.05)
    assert settled_cycle_energy(replay) < 0.95 * settled_cycle_energy(plain)
    measured = extract_from_rollout(r, env, settle_time=2.0)
    assert measured.trajectory.lift_height > 0.05


def test_the_shipped_learned_paths_cover_five_seeds_at_the_papers_speeds():
    """results/table5/paths/ (Table 5's input): one commanded path per seed and speed, each from a rollout at that
    speed that did not fall, built from settled in-band cycles."""
    import evaluate

    learned = evaluate.load_learned([evaluate.DEFAULT_LEARNED])
    assert learned.labels == [f"seed{s}" for s in range(5)] and learned.speeds() == [1.0, 1.2, 1.4]
    for v in learned.speeds():
        for label, learned_path in learned.at(v).items():
            path, p = learned_path.path, learned_path.provenance
            assert isinstance(path, CommandedPath) and path.speed == v == p["speed_command_mps"]
            assert p["path"] == "commanded" and p["cycle"] == "mean" and not p["rollout_fell"]
            assert len(p["cycles_used"]) >= 10 and abs(p["cycle_speed_mps"] - v) <= 0.05 * v
            per_cycle = round(path.gait.period / p["controller_dt_s"])  # one offset per controller period
            assert 0.08 < path.own_lift_height() < 0.11 and path.offsets.n == per_cycle
