"""`evaluate.py extract`: the learned foot path from trained policies, its replay check and candidates, in turn or
over worker processes (the extraction itself from recorded traces: tests/test_extract.py)."""
import dataclasses
import json
from types import SimpleNamespace

import numpy as np
import pytest

from cyberdog import config as C
from cyberdog.core.trajectories import SampledTrajectory
from cyberdog.provenance import portable_path


def _zero_actor_file(path, **env_changes):
    """An actor file in the trainer's format whose policy outputs 0: the env's trot controller (residual mode
    by default; `env_changes` e.g. action_mode="foot", target_speed_range=(1.0, 1.4))."""
    torch = pytest.importorskip("torch")
    from cyberdog.envs.cyberdog_env import observation_typical_magnitude
    from cyberdog.rl.networks import TanhActor

    cfg = C.ExperimentConfig()
    env_changes = {"action_mode": "residual", "observe_last_action": False, "target_speed_range": (), **env_changes}
    cfg = C.replace(cfg, env=C.replace(cfg.env, **env_changes))
    scale = observation_typical_magnitude(cfg.env)
    actor = TanhActor(len(scale), 12, (8,), scale)
    with torch.no_grad():
        actor.net[-1].weight.zero_()
        actor.net[-1].bias.zero_()
    cfg = C.replace(cfg, agent=C.replace(cfg.agent, hidden_sizes=(8,)))
    state = {"actor": {f"module.{k}": v for k, v in actor.state_dict().items()}, "config": C.to_dict(cfg),
             "stage": 2, "episode": 1}
    torch.save(state, path)
    return path


def test_evaluate_extract_from_a_policy(tmp_path, capsys):
    import evaluate

    actor = _zero_actor_file(tmp_path / "stage2_actor.pt")
    out = tmp_path / "ex"
    # 2.6 s: a few cycles after the 1 s speed ramp, while the speed integral still overshoots by 10-20 %
    assert evaluate.main(["extract", "--policy", str(tmp_path), "--rollout-duration", "2.6",
                          "--speed-tolerance", "0.3", "--out", str(out)]) == 0
    traj = SampledTrajectory.load(out / "learned" / "seed0.json")
    p = traj.provenance
    assert p["policy"] == portable_path(actor) and not p["policy"].startswith("/")  # provenance that travels
    assert p["seed"] == 0 and p["speed_command_mps"] == 1.0
    assert abs(p["cycle_speed_mps"] - 1.0) <= 0.3 and p["speed_tolerance"] == 0.3
    assert p["replay_check"]["status"] == "ok" and p["replay_check"]["speeds_mps"] == [1.0]  # it walks open loop
    assert 0.07 < traj.lift_height < 0.13  # the env's trot lifts 0.10 m
    rows = json.loads((out / "learned" / "seed0_cycles.json").read_text())
    chosen = [r for r in rows if r["chosen"]]
    assert len(chosen) == 1 and chosen[0]["energy_J"] == pytest.approx(p["cycle_energy_J"])
    assert min(r["energy_J"] for r in rows if r["valid"] and r["speed_ok"]) == pytest.approx(p["cycle_energy_J"])
    assert (out / "figure7_learned_trajectory.png").exists()
    assert "cycle" in capsys.readouterr().out


def test_evaluate_extracts_the_commanded_path_of_a_speed_range_policy_at_each_speed(tmp_path, capsys):
    import evaluate
    from cyberdog.core.commanded_path import CommandedPath

    _zero_actor_file(tmp_path / "stage2_actor.pt", action_mode="foot", target_speed_range=(1.0, 1.4))
    out = tmp_path / "ex"
    # without the replay check (its 100 m walks take a minute here; the tests below cover it)
    assert evaluate.main(["extract", "--policy", str(tmp_path), "--speeds", "1.0", "1.2", "--rollout-duration",
                          "3.0", "--speed-tolerance", "0.3", "--no-replay-check", "--out", str(out)]) == 0
    for v in (1.0, 1.2):
        path = CommandedPath.load(out / "learned" / f"seed0_{v:g}mps.json")
        assert path.speed == v and path.provenance["path"] == "commanded" and path.provenance["cycle"] == "mean"
        assert np.all(path.offsets.offsets == 0)  # a zero policy commands the plain trot
        assert path.own_lift_height() == pytest.approx(0.10, abs=1e-3)  # the env's trot lifts 0.10 m
    assert evaluate.main(["extract", "--policy", str(tmp_path), "--speeds", "1.6", "--out", str(tmp_path / "x")]) == 2
    assert "outside the policy's training range" in capsys.readouterr().err


def test_a_commanded_path_that_does_not_replay_is_rejected_for_the_next_candidate(tmp_path, capsys, monkeypatch):
    """Extraction keeps the first candidate whose replay walks (here a stand-in check rejects the first), records
    the rejected ones, and refuses to keep any path when none walks."""
    import evaluate
    from cyberdog.analysis.replay_check import ReplayCheck
    from cyberdog.core.commanded_path import CommandedPath
    from cyberdog.evaluation import extraction

    _zero_actor_file(tmp_path / "stage2_actor.pt", action_mode="foot", target_speed_range=(1.0, 1.4))
    checks = iter([ReplayCheck("speed miss (0.911 m/s)"), ReplayCheck("ok", 30.0)])
    monkeypatch.setattr(extraction, "replay_check", lambda *a, **k: next(checks))
    args = ["extract", "--policy", str(tmp_path), "--speeds", "1.0", "--rollout-duration", "3.0",
            "--speed-tolerance", "0.3"]
    assert evaluate.main([*args, "--candidates", "1", "--out", str(tmp_path / "ex")]) == 0
    prov = CommandedPath.load(tmp_path / "ex" / "learned" / "seed0_1mps.json").provenance
    assert prov["cycle"] == "cheapest" and prov["rollout_seed"] == 0  # the other cycle choice of the same rollout
    assert prov["replay_check"]["rejected"] == [{"rollout_seed": 0, "cycle": "mean",
                                                 "status": "speed miss (0.911 m/s)"}]
    from cyberdog.analysis import replay_check as rc
    assert prov["replay_check"]["spread_seeds"] == list(rc.SPREAD_CHECK_SEEDS)  # what the check walked, recorded
    assert prov["replay_check"]["hardware_like_pd_scales"] == list(rc.HARDWARE_CHECK_PD_SCALES)
    assert "rejected: the mean path of env seed 0 does not replay" in capsys.readouterr().out
    monkeypatch.setattr(extraction, "replay_check", lambda *a, **k: ReplayCheck("fell at 2.50 s"))
    assert evaluate.main([*args, "--replay-attempts", "2", "--out", str(tmp_path / "none")]) == 2
    err = capsys.readouterr().err
    assert "no candidate path passes the replay check" in err and "cheapest of env seed 1: fell at 2.50 s" in err
    assert not (tmp_path / "none" / "learned" / "seed0_1mps.json").exists()


def test_a_measured_path_that_does_not_replay_at_every_speed_gives_way_to_the_next_cheapest_cycle(
        tmp_path, capsys, monkeypatch):
    """The paper's measured path is one cycle rescaled to every speed: the cheapest in-band cycle whose replay
    walks the band at each speed is kept (here a stand-in walk misses at 1.2 m/s for the first cycle tried), the
    rejected cycle is recorded, and when no cycle replays no path is kept."""
    import evaluate
    from cyberdog.evaluation import extraction

    _zero_actor_file(tmp_path / "stage2_actor.pt", target_speed_range=(1.0, 1.4))
    walked = []

    def stand_in(path, speed, cfg):  # the first cycle tried misses at 1.2 m/s, every later one walks
        first = path.path.provenance["cycle_index"] if not walked else walked[0][0]
        walked.append((path.path.provenance["cycle_index"], speed))
        miss = speed == 1.2 and path.path.provenance["cycle_index"] == first
        return SimpleNamespace(fell=False, duration=10.0, speed_ok=not miss, mean_speed=1.03 if miss else speed)

    monkeypatch.setattr(extraction, "replay_walk", stand_in)
    args = ["extract", "--policy", str(tmp_path), "--speeds", "1.0", "1.2", "--rollout-duration", "2.6",
            "--speed-tolerance", "0.3"]
    assert evaluate.main([*args, "--out", str(tmp_path / "ex")]) == 0
    first, second = walked[0][0], walked[-1][0]
    assert first != second and walked == [(first, 1.0), (first, 1.2), (second, 1.0), (second, 1.2)]
    p = SampledTrajectory.load(tmp_path / "ex" / "learned" / "seed0.json").provenance
    assert p["cycle_index"] == second and p["cycles_skipped"] == [first]
    assert p["replay_check"]["rejected"] == [{"leg": "LF", "rollout_seed": 0, "cycle_index": first,
                                              "status": "1.2 m/s: speed miss (1.030 m/s)"}]
    assert p["replay_check"]["speeds_mps"] == [1.0, 1.2]
    rows = json.loads((tmp_path / "ex" / "learned" / "seed0_cycles.json").read_text())
    by_index = {r["cycle"]: r for r in rows}
    assert by_index[first]["energy_J"] <= by_index[second]["energy_J"]  # the cheapest was tried first
    assert f"rejected: cycle {first} of LF in env seed 0 does not replay" in capsys.readouterr().out
    monkeypatch.setattr(extraction, "replay_walk", lambda path, speed, cfg: SimpleNamespace(
        fell=True, duration=2.5, speed_ok=False, mean_speed=0.4))
    assert evaluate.main([*args, "--replay-attempts", "1", "--out", str(tmp_path / "none")]) == 2
    assert "no measured path of any foot replays in the band" in capsys.readouterr().err
    assert not (tmp_path / "none" / "learned" / "seed0.json").exists()


def test_when_no_cycle_of_the_reference_foot_replays_the_other_feet_are_tried_in_turn(tmp_path, capsys, monkeypatch):
    """A policy's feet need not move alike: when none of LF's cycles replays in any rollout, RF's come next (from
    the same rollouts), and the path records the foot it is of and every LF cycle rejected; a foot chosen with
    --leg is tried first."""
    import evaluate
    from cyberdog.evaluation import extraction

    _zero_actor_file(tmp_path / "stage2_actor.pt", target_speed_range=(1.0, 1.4))
    walked, rollouts = [], []

    def stand_in(path, speed, cfg):  # LF's path misses at 1.0 m/s, every other foot's walks
        leg = path.path.provenance["leg"]
        walked.append(leg)
        return SimpleNamespace(fell=False, duration=10.0, speed_ok=leg != "LF",
                               mean_speed=0.9 if leg == "LF" else speed)

    monkeypatch.setattr(extraction, "replay_walk", stand_in)
    rollout = extraction._rollout
    monkeypatch.setattr(extraction, "_rollout", lambda *a: rollouts.append(a[4]) or rollout(*a))
    args = ["extract", "--policy", str(tmp_path), "--speeds", "1.0", "--rollout-duration", "2.6",
            "--speed-tolerance", "0.3", "--replay-attempts", "2"]
    assert evaluate.main([*args, "--out", str(tmp_path / "ex")]) == 0
    p = SampledTrajectory.load(tmp_path / "ex" / "learned" / "seed0.json").provenance
    lf = walked.count("LF")
    assert p["leg"] == "RF" and walked == ["LF"] * lf + ["RF"] and lf >= 2
    rejected = p["replay_check"]["rejected"]
    assert {r["leg"] for r in rejected} == {"LF"} and sum("cycle_index" in r for r in rejected) == lf
    assert {r["rollout_seed"] for r in rejected} == {0, 1}  # both rollouts' LF cycles first
    assert rollouts == [0, 1]  # each rollout run once, for every foot
    out = capsys.readouterr().out
    assert "no cycle of LF replays in the band: the RF foot's cycles next" in out
    walked.clear()
    assert evaluate.main([*args, "--leg", "LH", "--out", str(tmp_path / "lh")]) == 0
    assert walked == ["LH"]
    assert SampledTrajectory.load(tmp_path / "lh" / "learned" / "seed0.json").provenance["leg"] == "LH"


def test_a_speed_that_fails_keeps_the_paths_extracted_before_it(tmp_path, capsys, monkeypatch):
    """Each path is saved as it is extracted: an extraction that fails at its second speed (minutes of replay
    checks later) leaves the first speed's path, with its recorded trot controller, on disk; a replay check
    walked under another trot than the policy's is said and recorded."""
    import evaluate
    from cyberdog.analysis.replay_check import ReplayCheck
    from cyberdog.core.commanded_path import CommandedPath
    from cyberdog.evaluation import extraction

    _zero_actor_file(tmp_path / "stage2_actor.pt", action_mode="foot", target_speed_range=(1.0, 1.4))
    checks = iter([ReplayCheck("ok", 30.0), ReplayCheck("fell at 2.00 s"), ReplayCheck("fell at 2.00 s")])
    monkeypatch.setattr(extraction, "replay_check", lambda *a, **k: next(checks))
    assert evaluate.main(["extract", "--policy", str(tmp_path), "--speeds", "1.0", "1.2", "--rollout-duration",
                          "3.0", "--speed-tolerance", "0.3", "--replay-attempts", "1", "--candidates", "1",
                          "--out", str(tmp_path / "ex")]) == 2
    assert "no candidate path passes the replay check" in capsys.readouterr().err
    kept = CommandedPath.load(tmp_path / "ex" / "learned" / "seed0_1mps.json")
    assert kept.provenance["controller"] == dataclasses.asdict(C.EnvConfig().walk.controller)
    assert not (tmp_path / "ex" / "learned" / "seed0_1.2mps.json").exists()
    # a replay check under another trot than the policy's is said, and recorded
    checks = iter([ReplayCheck("ok", 30.0)])
    assert evaluate.main(["extract", "--policy", str(tmp_path), "--speeds", "1.0", "--rollout-duration", "3.0",
                          "--speed-tolerance", "0.3", "--replay-attempts", "1", "--candidates", "1",
                          "--set", "controller.sagittal_placement_gain=0.1", "--out", str(tmp_path / "placed")]) == 0
    out = capsys.readouterr().out
    assert "recorded under another trot controller" in out
    assert "sagittal_placement_gain 0 recorded, 0.1 here" in out
    prov = CommandedPath.load(tmp_path / "placed" / "learned" / "seed0_1mps.json").provenance
    assert prov["controller"]["sagittal_placement_gain"] == 0.0
    assert prov["replay_check"]["controller"]["sagittal_placement_gain"] == 0.1
    assert prov["replay_check"]["walk_settings"] == {}  # the trot is recorded apart; nothing else was set
    # a policy trained under foot placement: without a --set its replay check walks the policy's own trot
    placed_walk = C.replace(C.EnvConfig().walk, controller=C.replace(C.ControllerConfig(),
                                                                     sagittal_placement_gain=0.2))
    (tmp_path / "placed_policy").mkdir()
    _zero_actor_file(tmp_path / "placed_policy" / "stage2_actor.pt", action_mode="foot",
                     target_speed_range=(1.0, 1.4), walk=placed_walk)
    checks = iter([ReplayCheck("ok", 30.0)])
    assert evaluate.main(["extract", "--policy", str(tmp_path / "placed_policy"), "--speeds", "1.0",
                          "--rollout-duration", "3.0", "--speed-tolerance", "0.3", "--replay-attempts", "1",
                          "--candidates", "1", "--out", str(tmp_path / "own")]) == 0
    assert "recorded under the trot controller controller.sagittal_placement_gain=0.2" in capsys.readouterr().out
    prov = CommandedPath.load(tmp_path / "own" / "learned" / "seed0_1mps.json").provenance
    assert prov["controller"]["sagittal_placement_gain"] == 0.2
    assert prov["replay_check"]["controller"]["sagittal_placement_gain"] == 0.2


def test_extraction_keeps_the_candidate_cheapest_on_the_check_robots(tmp_path, capsys, monkeypatch):
    """With --candidates N the first N rollouts whose path replays each give one candidate, and the path kept is
    the one with the least electrical energy per metre on the check's robots; with fewer rollouts that replay
    than N, the cheapest of those. Every candidate and its energy is in the provenance."""
    import evaluate
    from cyberdog.analysis.replay_check import ReplayCheck
    from cyberdog.core.commanded_path import CommandedPath
    from cyberdog.evaluation import extraction

    _zero_actor_file(tmp_path / "stage2_actor.pt", action_mode="foot", target_speed_range=(1.0, 1.4))
    # rollout 0: mean replays (31 J/m); rollout 1: mean falls, cheapest replays (27 J/m); rollout 2: mean 29 J/m
    checks = iter([ReplayCheck("ok", 31.0), ReplayCheck("fell at 3.00 s"), ReplayCheck("ok", 27.0),
                   ReplayCheck("ok", 29.0), ReplayCheck("ok", 20.0)])
    monkeypatch.setattr(extraction, "replay_check", lambda *a, **k: next(checks))
    args = ["extract", "--policy", str(tmp_path), "--speeds", "1.0", "--rollout-duration", "3.0",
            "--speed-tolerance", "0.3", "--replay-attempts", "5"]
    assert evaluate.main([*args, "--candidates", "3", "--out", str(tmp_path / "ex")]) == 0
    check = CommandedPath.load(tmp_path / "ex" / "learned" / "seed0_1mps.json").provenance["replay_check"]
    assert [(c["rollout_seed"], c["cycle"], c["electrical_J_per_m"]) for c in check["candidates"]] == [
        (0, "mean", 31.0), (1, "cheapest", 27.0), (2, "mean", 29.0)]  # three found: the fourth rollout not run
    prov = CommandedPath.load(tmp_path / "ex" / "learned" / "seed0_1mps.json").provenance
    assert (prov["rollout_seed"], prov["cycle"]) == (1, "cheapest")
    assert "the cheapest of 3 candidates" in capsys.readouterr().out
    checks = iter([ReplayCheck("fell at 1.00 s"), ReplayCheck("ok", 33.0), ReplayCheck("fell at 1.00 s"),
                   ReplayCheck("fell at 1.00 s")])
    monkeypatch.setattr(extraction, "replay_check", lambda *a, **k: next(checks))
    assert evaluate.main([*args, "--replay-attempts", "2", "--candidates", "3", "--out", str(tmp_path / "few")]) == 0
    prov = CommandedPath.load(tmp_path / "few" / "learned" / "seed0_1mps.json").provenance
    assert (prov["rollout_seed"], prov["cycle"]) == (0, "cheapest")  # the only candidate of two rollouts
    assert len(prov["replay_check"]["candidates"]) == 1


def test_replay_status_is_ok_for_the_plain_trot_and_names_a_path_that_stumbles():
    from conftest import commanded
    from cyberdog.analysis.replay_check import replay_status
    from cyberdog.core.learned_set import LearnedPath

    assert replay_status(LearnedPath("seed0", commanded(1.0, 0.0, 0)), 1.0) == "ok"  # the comparison's 10 s walk
    # swing feet lowered by 9 cm at mid-swing (a 1 cm lift): the feet scuff and the trot loses its speed
    status = replay_status(LearnedPath("seed0", commanded(1.0, -0.09, 0)), 1.0)
    assert status.startswith(("speed miss", "fell at")), status


def test_a_speed_miss_says_when_the_trots_speed_loop_sat_at_its_bound():
    """A walk off the band whose speed loop ran at its bound for LOOP_NOTE_PCT % of it or more says how long (the
    path needs more of the loop than the bound gives); a shorter stay, or a walk without the record, does not."""
    from cyberdog.analysis.replay_check import walk_status
    from cyberdog.loop.result import LOOP_NOTE_PCT

    def result(speed, at_limit, fell=False):
        return SimpleNamespace(fell=fell, duration=4.0, speed_ok=abs(speed - 1.0) <= 0.05, mean_speed=speed,
                               speed_loop_at_limit=at_limit)

    assert walk_status(result(1.077, 0.74)) == "speed miss (1.077 m/s; speed loop at its bound 74 % of the walk)"
    assert walk_status(result(1.077, (LOOP_NOTE_PCT - 1) / 100)) == "speed miss (1.077 m/s)"
    assert walk_status(result(1.077, float("nan"))) == "speed miss (1.077 m/s)"
    assert walk_status(result(1.02, 0.9)) == "ok"  # in the band, however hard the loop worked
    assert walk_status(result(0.5, 0.9, fell=True)) == "fell at 4.00 s"


def test_replay_verdict_walks_both_robots_over_the_papers_distance_and_names_the_walk_that_fails(monkeypatch):
    """The check walks the ideal robot (Table 5's 10 s), many hardware-like robots over the prototype's walk at
    both ends of the PD's stiffness, the ideal robot over the paper's 100 m, then hardware-like robots over 100 m,
    none of them a prototype draw, and names the first walk that fails; one of those walks, shortened to 20 m,
    passes for the plain trot. The energy per metre is the 100 m hardware-like walks'."""
    from conftest import commanded
    from cyberdog.analysis import replay_check
    from cyberdog.config import HARDWARE_LIKE
    from cyberdog.config.paper import PAPER_DISTANCE_M, PROTOTYPE_DISTANCE_M, PROTOTYPE_RUN_UP_S
    from cyberdog.core.learned_set import LearnedPath
    from cyberdog.evaluation.cli import DEFAULT_PROTOTYPE_DRAWS

    path = LearnedPath("seed0", commanded(1.2, 0.0, 0))
    seeds, spread = replay_check.HARDWARE_CHECK_SEEDS, replay_check.SPREAD_CHECK_SEEDS
    assert replay_check.CHECK_DISTANCE_M == PAPER_DISTANCE_M == 100.0
    assert replay_check.SPREAD_CHECK_DISTANCE_M == PROTOTYPE_DISTANCE_M
    assert len(seeds) >= 2 and len(spread) >= 8  # two robots at an end cannot tell a path that fails on half
    assert min(seeds + spread) >= 100 * DEFAULT_PROTOTYPE_DRAWS and not set(seeds) & set(spread)
    hardware = dataclasses.replace(HARDWARE_LIKE, seed=seeds[0])
    assert replay_check.replay_status(path, 1.2, None, 30.0, hardware, 20.0) == "ok"
    calls = []

    def stand_in(path, speed, cfg=None, duration=10.0, hardware=None, distance=None, progress=None, run_up=0.0):
        calls.append((None if hardware is None else hardware.seed, distance, (cfg or C.WalkConfig()).pid.kp[0],
                      run_up))
        fell = hardware is not None and hardware.seed == seeds[-1]
        return SimpleNamespace(fell=fell, duration=14.0, speed_ok=True, mean_speed=1.2, distance=distance or 12.0,
                               electrical_energy=(2000.0 + (0.0 if hardware is None else hardware.seed)) * (
                                   (distance or 12.0) / 100.0), dropped_shifts=1 if distance else 0)

    monkeypatch.setattr(replay_check, "replay_walk", stand_in)
    verdict = replay_check.replay_verdict(path, 1.2)
    pd, spread_pd = replay_check.HARDWARE_CHECK_PD_SCALES, replay_check.SPREAD_CHECK_PD_SCALES
    stiffness = f", PD {pd[-1]:g}x" if pd[-1] != 1 else ""  # the PD named where it is not as configured
    assert verdict == f"hardware-like robot (seed {seeds[-1]}{stiffness}), 100 m: fell at 14.00 s"
    # each hardware-like robot with its own PD stiffness (kp 60 N·m/rad × the scale): 1.0, 0.7 and 1.4 among them;
    # the spread walks after the prototype's run-up, the stiff end first
    assert calls == ([(None, None, 60.0, 0.0)]
                     + [(seed, PROTOTYPE_DISTANCE_M, pytest.approx(60.0 * s), PROTOTYPE_RUN_UP_S)
                        for s in spread_pd for seed in spread]
                     + [(None, 100.0, 60.0, 0.0)]
                     + [(seed, 100.0, pytest.approx(60.0 * s), 0.0) for seed, s in zip(seeds, pd)])
    assert {1.0, 0.7, 1.4} <= set(pd) and set(spread_pd) == {0.7, 1.4} and spread_pd[0] == 1.4
    # all walk: the energy per metre is the mean over the 100 m hardware-like walks only
    monkeypatch.setattr(replay_check, "HARDWARE_CHECK_SEEDS", seeds[:-1])
    lines = []
    check = replay_check.replay_check(path, 1.2, log=lines.append)
    assert check.status == "ok"
    assert len(lines) == 2 + 2 * len(spread) + len(seeds) - 1  # a line a walk
    assert lines[0] == "replay check, ideal robot, 10 s: ok"
    assert lines[1] == f"replay check, hardware-like robot (seed {spread[0]}, PD 1.4x), 20 m: ok"
    assert check.electrical_J_per_m == pytest.approx((2000.0 + sum(seeds[:-1]) / len(seeds[:-1])) / 100.0)
    assert check.dropped_shifts == 2 * len(spread) + len(seeds)  # the walks' dropped shifts (one per distance walk)
    monkeypatch.setattr(replay_check, "replay_walk",
                        lambda *a, **k: SimpleNamespace(fell=False, speed_ok=False, mean_speed=0.9, dropped_shifts=0))
    assert replay_check.replay_verdict(path, 1.2) == "ideal robot, 10 s: speed miss (0.900 m/s)"


def test_extraction_over_worker_processes_saves_what_extraction_in_turn_saves(tmp_path, capsys):
    """`extract --workers 2` runs one job per policy and speed in worker processes: the same paths, byte for
    byte, as in turn; a job that fails hands back its error instead of stopping the others."""
    import evaluate
    from cyberdog.evaluation import extraction

    import torch

    for seed in (0, 1):
        (tmp_path / f"s{seed}").mkdir()
        actor = _zero_actor_file(tmp_path / f"s{seed}" / "stage2_actor.pt", action_mode="foot",
                                 target_speed_range=(1.0, 1.4))
        state = torch.load(actor, weights_only=False)
        state["config"]["train"]["seed"] = seed
        torch.save(state, actor)
    common = ["extract", "--policies", str(tmp_path / "s0"), str(tmp_path / "s1"), "--speeds", "1.0", "1.2",
              "--rollout-duration", "3.0", "--speed-tolerance", "0.3", "--no-replay-check"]
    assert evaluate.main(common + ["--out", str(tmp_path / "serial")]) == 0
    assert evaluate.main(common + ["--workers", "2", "--out", str(tmp_path / "parallel")]) == 0
    assert "4 jobs (policy and speed) over 2 worker processes" in capsys.readouterr().out
    names = sorted(f.name for f in (tmp_path / "serial" / "learned").glob("*mps.json"))
    assert names == ["seed0_1.2mps.json", "seed0_1mps.json", "seed1_1.2mps.json", "seed1_1mps.json"]
    for name in names:
        assert ((tmp_path / "parallel" / "learned" / name).read_text()
                == (tmp_path / "serial" / "learned" / name).read_text())
    # a job whose extraction fails returns its error: the worker pool goes on with the others
    from cyberdog.evaluation.cli import build_parser
    args = build_parser().parse_args(["extract", "--policy", str(tmp_path / "s0"), "--rollout-duration", "3.0",
                                      "--speed-tolerance", "0.0001", "--no-replay-check"])
    result = extraction._extraction_job((tmp_path / "s0" / "stage2_actor.pt", "commanded", "seed0", 1.0, (1.0,)), args,
                                            tmp_path / "failing", None)
    assert isinstance(result, str) and "1 m/s" in result
    assert not list((tmp_path / "failing").glob("learned/*.json"))


def test_the_checks_other_settings_are_what_differs_from_the_defaults_but_the_trot_and_gait():
    from cyberdog.analysis.replay_check import walk_settings

    cfg = C.override(C.WalkConfig(), ["pid.kd=[3,3,3]", "controller.heading_gain=0.4", "gait.lift_height=0.09"])
    assert walk_settings(cfg) == {"pid.kd": [3.0, 3.0, 3.0]} and walk_settings(C.WalkConfig()) == {}
