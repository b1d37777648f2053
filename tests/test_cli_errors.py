"""Mistakes a new user makes end in one line naming the problem and what to do, exit 2, before any work."""
import re
from pathlib import Path

import pytest

import evaluate
from cyberdog import train_cli as train


@pytest.mark.parametrize("out", ["/proc/x", "README.md/sub"])
def test_an_unwritable_output_folder_is_one_line(out, capsys):
    assert evaluate.main(["baselines", "--speeds", "1", "--duration", "0.1", "--out", out]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "cannot write the output folder --out" in err[0]


def test_a_policy_that_is_not_an_actor_file_is_one_line(tmp_path, capsys):
    assert evaluate.main(["extract", "--policies", "results/table5/policy/seed0/metrics.csv",
                          "--out", str(tmp_path / "e")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "not a file written by train.py" in err[0]
    assert not (tmp_path / "e").exists()  # refused before the output folder was made


@pytest.mark.parametrize("command", ["prototype", "all"])
def test_a_missing_prototype_reference_is_one_line_before_any_walk(command, tmp_path, capsys):
    assert evaluate.main([command, "--prototype-reference", str(tmp_path / "none.json"),
                          "--out", str(tmp_path / "p")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--prototype-reference" in err[0] and "does not exist" in err[0]
    assert not (tmp_path / "p").exists()


def test_mp4_without_a_writer_fails_before_rendering(tmp_path, capsys, monkeypatch):
    import cyberdog.analysis.video as video
    monkeypatch.setattr(video, "mp4_writer_problem", lambda: "MP4 needs imageio[ffmpeg] or ffmpeg")
    rendered = []
    monkeypatch.setattr(video, "render_walk", lambda *a, **k: rendered.append(1) or [])
    assert evaluate.main(["video", "--video-trajectory", "cycloid", "--video-format", "mp4",
                          "--out", str(tmp_path / "v")]) == 2
    assert "MP4 needs" in capsys.readouterr().err and not rendered


def test_a_garbage_init_from_file_is_one_clear_line(tmp_path, capsys):
    garbage = tmp_path / "garbage.pt"
    garbage.write_text("not a checkpoint")
    with pytest.raises(SystemExit) as exit_:
        train.main(["--config", "configs/tiny.yaml", "--init-from", str(garbage), "--run-dir", str(tmp_path / "run")])
    message = str(exit_.value.code)
    assert "not a file written by train.py" in message and len(message.splitlines()) == 1
    assert "weights_only" not in message and "file an issue" not in message.lower()


@pytest.mark.parametrize("command, option", [("video", "--video-trajectory"), ("video", "--video-format"),
                                             ("prototype", "--prototype-modes"), ("video", "--video-speed"),
                                             ("video", "--video-duration"), ("extract", "--rollout-duration")])
def test_every_option_says_what_it_does_and_its_default(command, option, capsys):
    with pytest.raises(SystemExit):
        evaluate.main([command, "--help"])
    text = " ".join(capsys.readouterr().out.split())
    start = text.rindex(option + " ")  # its entry in the options list, after the usage line
    entry = text[start:start + 400]
    assert "default" in entry, entry


def test_an_interrupted_run_can_be_run_again_into_the_same_folder(tmp_path, monkeypatch, capsys):
    """Ctrl-C after the output folder was made: the folder records the run as interrupted with its files, and
    the same command then runs again without --force."""
    import cyberdog.analysis.baselines as baselines
    out = tmp_path / "out"
    argv = ["baselines", "--speeds", "1", "--duration", "0.2", "--out", str(out)]

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    with monkeypatch.context() as m:
        m.setattr(baselines, "baseline_rows", interrupted)
        assert evaluate.main(argv) == 130
    assert (out / "config.yaml").is_file()
    from cyberdog.output_folder import read_manifest
    assert [r["status"] for r in read_manifest(out)["runs"]] == ["interrupted"]
    assert evaluate.main(argv) == 0  # no --force needed: only the interrupted run's files were there
    runs = read_manifest(out)["runs"]
    assert [r["status"] for r in runs] == ["finished"] and "config.yaml" in runs[0]["files"]


def test_a_killed_run_leaves_a_folder_the_next_run_can_use(tmp_path):
    """A run killed outright stays "running" in outputs.json; what it wrote is taken as its own."""
    from cyberdog.output_folder import OutputFolder, OutputFolderError
    out = tmp_path / "out"
    OutputFolder(out, command="compare")  # entered as running, then killed: no finish, no abandon
    (out / "config.yaml").write_text("sim: {}\n")
    again = OutputFolder(out, command="compare")
    assert not (out / "config.yaml").exists() and any("did not finish" in n for n in again.notes)
    (out / "someone_elses.txt").write_text("x")  # a file no run wrote: still refused without --force
    again.finish()
    with pytest.raises(OutputFolderError, match="already holds"):
        OutputFolder(out, command="compare")


@pytest.mark.slow
def test_the_main_job_prints_a_short_summary_ending_with_the_headline_and_the_folder(tmp_path, capfd):
    """`python evaluate.py` (here at reduced budgets, the shipped paths): a summary of at most ~30 lines besides
    the progress lines (`[k/N] ...`: a quarter of the walks, or 15 s without a line, so their number follows the
    machine's speed), the headline table named, the output folder last; the long tables stay in the files."""
    out = tmp_path / "out"
    assert evaluate.main(["--duration", "1", "--prototype-distance", "1", "--out", str(out)]) == 0
    lines = capfd.readouterr().out.strip().splitlines()
    summary = [line for line in lines if not re.match(r"\s*\[\d+/\d+\] ", line)]
    assert len(summary) <= 30 and len(lines) > len(summary), "\n".join(lines)
    assert any(line.strip() == f"the headline table:  {out / 'table5.md'}" for line in lines)
    assert lines[-1] == f"output folder: {out}/"
    assert (out / "comparison.md").is_file() and (out / "prototype.md").is_file()


def test_the_video_of_a_learned_path_names_its_seed_and_walks_it_as_the_tables_do(tmp_path, monkeypatch, capsys):
    import cyberdog.analysis.video as video
    recorded = {}

    def record(cfg, trajectory, path, duration, label="", hardware=None, foot_offsets=None, lift_height=None):
        recorded.update(path=Path(path), label=label, hardware=hardware, offsets=foot_offsets, lift=lift_height)
        return Path(path)

    monkeypatch.setattr(video, "record_video", record)
    assert evaluate.main(["video", "--video-duration", "0.1", "--out", str(tmp_path / "v")]) == 0
    assert recorded["label"] == "learned, seed0" and recorded["path"].name == "trot_learned_seed0_1mps.gif"
    assert recorded["hardware"] is None  # the ideal robot: no hardware setting given
    # the commanded path as the tables walk it: each foot its own shift, at the path's own lift (its feet's mean)
    from cyberdog.core.learned_set import LearnedSet
    path = LearnedSet.load([Path(evaluate.__file__).parent / "results/table5/paths"]).at(1.0)["seed0"]
    assert recorded["offsets"].to_dict() == path.path.offsets.to_dict() and recorded["lift"] == path.lift_height
    assert "the learned, seed0 trajectory" in capsys.readouterr().out


def test_a_mistyped_sub_command_is_one_line_naming_the_closest(capsys):
    from cyberdog.evaluation.cli import parse_args
    with pytest.raises(SystemExit) as exit_:
        parse_args(["comapre", "--learned", "x"])
    err = capsys.readouterr().err.strip()
    assert exit_.value.code == 2 and len(err.splitlines()) == 1
    assert "unknown sub-command 'comapre'" in err and "did you mean 'compare'" in err


@pytest.mark.parametrize("command", ["prototype", "stiffness"])
def test_a_closed_loop_actor_that_is_no_actor_or_has_no_path_is_one_line_before_any_walk(command, tmp_path, capsys):
    assert evaluate.main([command, "--closed-loop", "results/table5/policy/seed0/metrics.csv",
                          "--out", str(tmp_path / "p")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--closed-loop" in err[0] and not (tmp_path / "p").exists()
    # seed 0's actor with a learned set that holds seed 1's path only: refused
    assert evaluate.main([command, "--learned", "results/battery/paths/seed1_1mps.json", "--speeds", "1.0",
                          "--closed-loop", "results/battery/policy/seed0/stage2_actor.pt",
                          "--out", str(tmp_path / "q")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "no learned path of the same seed" in err[0] and "seed0" in err[0]
    assert not (tmp_path / "q").exists()


def test_a_bad_pd_scale_is_one_line(tmp_path, capsys):
    with pytest.raises(SystemExit) as stop:
        evaluate.main(["stiffness", "--pd-scales", "0", "--out", str(tmp_path / "s")])
    assert stop.value.code == 2 and "--pd-scales" in capsys.readouterr().err
    assert evaluate.main(["stiffness", "--pd-scales", "1", "1", "--out", str(tmp_path / "s")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--pd-scales" in err[0] and "distinct" in err[0]


def test_the_hardware_like_robot_is_set_on_the_command_line_as_in_training():
    """`evaluate.py ... --set hardware.FIELD=V` changes the prototype's hardware-like robot (HARDWARE_LIKE by
    default) and nothing else; a wrong field is one clear error naming the allowed ones."""
    from cyberdog import config as C
    from cyberdog.evaluation.cli import parse_args
    from cyberdog.evaluation.commands import UsageError, walk_config

    args = parse_args(["prototype", "--set", "hardware.latency_s=0.005", "hardware.mass_uncertainty=0.1",
                       "gait.lift_height=0.12"])
    cfg = walk_config(args)
    assert args.hardware == C.replace(C.HARDWARE_LIKE, latency_s=0.005, mass_uncertainty=0.1)
    assert cfg.gait.lift_height == 0.12 and cfg == C.override(C.WalkConfig(), ["gait.lift_height=0.12"])
    plain = parse_args(["prototype"])
    walk_config(plain)
    assert plain.hardware == C.HARDWARE_LIKE
    with pytest.raises(UsageError, match="no field 'latency'.*latency_s"):
        walk_config(parse_args(["prototype", "--set", "hardware.latency=0.005"]))


def test_the_command_line_robot_reaches_the_prototype_walks(monkeypatch, tmp_path):
    """cmd_prototype hands `--set hardware.*`'s robot to run_prototype (which builds each draw from it)."""
    from cyberdog import config as C
    from cyberdog.analysis import prototype
    from cyberdog.evaluation import commands
    from cyberdog.evaluation.cli import parse_args

    seen = {}

    def fake_run_prototype(trajectories, **kwargs):
        seen.update(kwargs)
        raise KeyboardInterrupt  # stop before any walk: the arguments are what is checked

    monkeypatch.setattr(prototype, "run_prototype", fake_run_prototype)
    args = parse_args(["prototype", "--speeds", "1.0", "--set", "hardware.latency_s=0.005", "--out",
                       str(tmp_path / "out")])
    assert commands.run(args, []) == 130
    assert seen["hardware"] == C.replace(C.HARDWARE_LIKE, latency_s=0.005)
