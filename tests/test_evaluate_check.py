"""`evaluate.py check`: every walk of the replay check, not only up to the first that fails, and a verdict per
path; the policy check's inputs refused before any walk."""
from __future__ import annotations

import json
from pathlib import Path
from types import SimpleNamespace

import pytest

import evaluate


@pytest.fixture
def two_paths(tmp_path):
    from conftest import commanded
    from cyberdog.core.learned_set import LearnedPath

    files = [LearnedPath(f"seed{seed}", commanded(1.2, 0.0, seed)).save(tmp_path / "learned") for seed in (0, 1)]
    return files


def test_every_spread_walk_is_walked_and_a_path_that_fails_one_is_named_with_it(two_paths, tmp_path, monkeypatch,
                                                                                capsys):
    from cyberdog.analysis import replay_check

    walked = []

    def stand_in(path, speed, cfg=None, duration=10.0, hardware=None, distance=None, progress=None, run_up=0.0):
        walked.append((path.label, hardware.seed, cfg.pid.kp[0]))
        slow = path.label == "seed1" and hardware.seed == replay_check.SPREAD_CHECK_SEEDS[0] and cfg.pid.kp[0] > 60
        return SimpleNamespace(fell=False, speed_ok=not slow, mean_speed=1.1 if slow else 1.2, distance=20.0,
                               electrical_energy=4000.0, dropped_shifts=0)

    monkeypatch.setattr(replay_check, "replay_walk", stand_in)
    out = tmp_path / "spread"
    code = evaluate.main(["check", *map(str, two_paths), "--parts", "spread", "--workers", "1", "--out", str(out)])
    n = len(replay_check.SPREAD_CHECK_SEEDS) * len(replay_check.SPREAD_CHECK_PD_SCALES)
    assert code == 1  # one path failed
    assert len(walked) == 2 * n  # seed1's failing first walk did not stop its other walks
    assert sorted({round(kp, 6) for _, _, kp in walked}) == sorted(round(60.0 * s, 6)
                                                                 for s in replay_check.SPREAD_CHECK_PD_SCALES)
    result = json.loads((out / "replay_check.json").read_text())
    verdicts = {Path(f).name: v for f, v in result["verdicts"].items()}
    first = replay_check.SPREAD_CHECK_SEEDS[0]
    assert verdicts[two_paths[0].name] == "ok"
    assert verdicts[two_paths[1].name] == f"hardware-like robot (seed {first}, PD 1.4x), 20 m: speed miss (1.100 m/s)"
    slow = [r for r in result["rows"] if r["status"] != "ok"]
    assert len(slow) == 1 and slow[0]["speed_share"] == pytest.approx(1.1 / 1.2)
    assert all(r["electrical_J_per_m"] == pytest.approx(200.0) for r in result["rows"])
    # the output is never overwritten
    capsys.readouterr()
    assert evaluate.main(["check", str(two_paths[0]), "--out", str(out)]) == 2
    assert "already holds" in capsys.readouterr().err


def test_a_sampled_path_is_refused_before_any_walk(tmp_path, capsys):
    from test_fast_paths import sampled_trajectory

    from cyberdog.core.learned_set import LearnedPath

    file = LearnedPath("seed0", sampled_trajectory()).save(tmp_path / "in")
    assert evaluate.main(["check", str(file), "--out", str(tmp_path / "out")]) == 2
    assert "not commanded paths" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("argv, words", [
    ([], ["PATH", "--runs"]),  # neither
    (["PATHS", "--runs", "RUN"], ["PATH", "--runs"]),  # both
    (["PATHS", "--speeds", "1.0"], ["--speeds", "check --runs"]),  # a policy option with paths
    (["--runs", "RUN", "--parts", "ideal"], ["--parts", "not for --runs"]),  # a path option with policies
    (["--runs", "RUN", "--set", "pid.kp=[80,80,80]"], ["--set", "not for --runs"]),
    (["--runs", "RUN"], ["no stage1_final_actor.pt"]),  # a run folder without actors
])
def test_check_refuses_what_it_cannot_serve_before_any_walk(argv, words, two_paths, tmp_path, capsys):
    run = tmp_path / "run"
    run.mkdir()
    argv = [str(two_paths[0]) if a == "PATHS" else str(run) if a == "RUN" else a for a in argv]
    assert evaluate.main(["check", *argv, "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert all(w in err for w in words), err
    assert not (tmp_path / "out").exists()


def test_check_and_pd_match_are_listed_and_refuse_each_others_options(capsys):
    with pytest.raises(SystemExit):
        evaluate.main(["--help"])
    top = capsys.readouterr().out
    assert "    check " in top and "    pd-match " in top
    with pytest.raises(SystemExit) as exit_:
        evaluate.main(["pd-match", "PATH.json", "--pd-scale", "1.4", "--runs", "runs/x"])
    assert exit_.value.code == 2
    last = capsys.readouterr().err.strip().splitlines()[-1]
    assert "unrecognized arguments: --runs" in last and "is an option of: check" in last


def test_a_shipped_policy_folder_is_checked_by_its_final_actors(tmp_path):
    from cyberdog.evaluation.check import run_actors
    from cyberdog.evaluation.cli import UsageError

    root = Path(__file__).resolve().parents[1]
    shipped, run = root / "results/table5/policy/seed0", tmp_path / "seed0"  # run: a training run's folder
    run.mkdir()
    for stage in (1, 2):
        (run / f"stage{stage}_final_actor.pt").write_bytes(b"")
    assert run_actors([shipped], "final")["seed0"] == {1: shipped / "stage1_actor.pt", 2: shipped / "stage2_actor.pt"}
    assert run_actors([run], "final")["seed0"][2] == run / "stage2_final_actor.pt"
    with pytest.raises(UsageError, match="stage1_best_actor.pt"):
        run_actors([shipped], "best")  # a shipped folder holds the final actors only
    with pytest.raises(UsageError, match="two runs named seed0"):
        run_actors([shipped, run], "final")  # the label is the folder's name


def test_a_recipes_seed_folder_gives_its_last_stage1_and_stage2_phases_actors(tmp_path):
    """configs/torque.yaml's seed folder: main, speed, band (stage 1), energy to energy4 (stage 2): the
    check walks band's stage-1 actor and energy4's stage-2 actor, labelled by the seed folder; one whose last
    stage-2 phase has not finished is refused (not walked as stage 1 alone); a phase of both stages gives both."""
    from cyberdog import config as C
    from cyberdog.evaluation.check import run_actors
    from cyberdog.evaluation.cli import UsageError

    seed = tmp_path / "seed3"
    C.write_phases(seed, C.load_preset(Path(evaluate.__file__).parent / "configs" / "torque.yaml"), 3)
    for phase in C.read_phases(seed)[0]:  # every phase finished: its final actor written
        (seed / phase.name).mkdir()
        (seed / phase.name / f"stage{phase.last_stage}_final_actor.pt").write_bytes(b"")
    assert run_actors([seed], "final") == {"seed3": {1: seed / "band" / "stage1_final_actor.pt",
                                                     2: seed / "energy4" / "stage2_final_actor.pt"}}
    # its last stage-2 phase interrupted: refused, not walked as stage 1 alone
    (seed / "energy4" / "stage2_final_actor.pt").unlink()
    with pytest.raises(UsageError, match="phase energy4 .stage 2. has no stage2_final_actor.pt"):
        run_actors([seed], "final")
    one = tmp_path / "seed4"  # configs/table5.yaml: one phase that trains both stages
    C.write_phases(one, C.load_preset(Path(evaluate.__file__).parent / "configs" / "table5.yaml"), 4)
    (one / "train").mkdir()
    for stage in (1, 2):
        (one / "train" / f"stage{stage}_final_actor.pt").write_bytes(b"")
    assert run_actors([one], "final") == {"seed4": {s: one / "train" / f"stage{s}_final_actor.pt" for s in (1, 2)}}
