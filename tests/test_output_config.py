"""Every `evaluate.py` sub-command's config.yaml holds the whole robot it walked: the walk config and the hardware
model of its hardware-like walks (null: the ideal robot only), read back by the project's loader
(`cyberdog.config.load_walked`) and by --config. Hardware settings reach the walks that use one (the video's among
them) and are refused in one line where no hardware-like robot walks, where a --config file's hardware section is
not used (a note says so). Tiny budgets: walks of 0.3 m or 0.3 s."""
from __future__ import annotations

from pathlib import Path

import pytest

from cyberdog import config as C
from cyberdog.analysis import video
from cyberdog.analysis.robot_words import robot_words
from cyberdog.evaluation import commands, walked_robot
from cyberdog.evaluation.cli import parse_args
from cyberdog.loop.walker import Walker

ASKED = ["--set", "hardware.latency_s=0.005", "pid.kd=[3,3,3]"]
WALK = C.override(C.WalkConfig(), ["pid.kd=[3,3,3]"])  # the walk config ASKED asks for
HARDWARE = C.replace(C.HARDWARE_LIKE, latency_s=0.005)  # the hardware model ASKED asks for
ASKED_ROBOT = C.WalkedRobot(WALK, HARDWARE)
IDEAL_ROBOT = C.WalkedRobot(WALK, None)  # ASKED's walk config on the ideal robot
TINY_VIDEO = ["video", "--video-trajectory", "cycloid", "--video-duration", "0.1"]
TINY_PROTOTYPE = ["--speeds", "1.0", "--prototype-distance", "0.3", "--prototype-run-up", "0", "--prototype-draws", "1",
                  "--no-prototype-reference", "--workers", "1"]
TINY_COMPARE = ["--speeds", "1.0", "--duration", "0.3", "--no-same-lift", "--no-reference", "--workers", "1"]
TINY_BASELINES = ["baselines", "--speeds", "1.0", "--duration", "0.3", "--trajectories", "cycloid"]
PRESET = Path(__file__).resolve().parents[1] / "configs" / "battery.yaml"  # a training preset (base: table5.yaml)


@pytest.fixture
def path_file(tmp_path):
    """A commanded path at 1 m/s, recorded under the default trot."""
    from conftest import commanded
    from cyberdog.core.learned_set import LearnedPath

    return str(LearnedPath("seed0", commanded(1.0, 0.0, 0)).save(tmp_path / "paths"))


@pytest.fixture
def walkers(monkeypatch):
    """The video's walkers, as built: each one's hardware model and actuation delay in controller periods."""
    built = []

    class Recorded(Walker):
        def __init__(self, cfg, *args, **kwargs):
            super().__init__(cfg, *args, **kwargs)
            built.append((self.hardware, self.latency_steps, self.cfg.pid))

    monkeypatch.setattr(video, "Walker", Recorded)
    return built


def evaluate(argv: list) -> int:
    """`evaluate.py ARGV` without the figures (the package run on its own)."""
    argv = [str(a) for a in argv]
    return commands.run(parse_args(argv), argv)


def robot(out) -> C.WalkedRobot:
    return C.load_walked(out / "config.yaml")


def test_the_video_walks_the_hardware_asked_names_it_and_its_config_walks_it_again(tmp_path, walkers, capsys):
    out, again = tmp_path / "video", tmp_path / "again"
    assert evaluate([*TINY_VIDEO, *ASKED, "--out", out]) == 0
    assert walkers == [(HARDWARE, 2, WALK.pid)]  # 5 ms: two 2.5 ms controller periods
    assert "on the hardware-like robot (latency 5 ms)  kp 60/60/60  kd 3/3/3" in capsys.readouterr().out
    assert robot(out) == ASKED_ROBOT
    assert evaluate([*TINY_VIDEO, "--config", out / "config.yaml", "--out", again]) == 0
    assert walkers[1] == walkers[0] and robot(again) == ASKED_ROBOT
    assert (again / "config.yaml").read_text() == (out / "config.yaml").read_text()


def test_the_video_walks_the_ideal_robot_unless_a_hardware_one_is_asked(tmp_path, walkers, capsys):
    assert evaluate([*TINY_VIDEO, "--set", "pid.kd=[3,3,3]", "--out", tmp_path / "ideal"]) == 0
    assert walkers[-1][:2] == (None, 0) and robot(tmp_path / "ideal") == IDEAL_ROBOT
    assert "on the ideal robot  kp 60/60/60  kd 3/3/3" in capsys.readouterr().out
    assert evaluate([*TINY_VIDEO, "--video-robot", "hardware", "--out", tmp_path / "plain"]) == 0
    assert walkers[-1][:2] == (C.HARDWARE_LIKE, 1)
    assert robot(tmp_path / "plain") == C.WalkedRobot(C.WalkConfig(), C.HARDWARE_LIKE)
    assert "on the hardware-like robot  kp" in capsys.readouterr().out  # HARDWARE_LIKE itself: no setting named


def test_the_robot_is_named_by_what_differs_from_the_hardware_like_one():
    assert robot_words(None, C.PIDConfig()) == "ideal robot  kp 60/60/60  kd 2/2/2"
    hw = C.replace(C.HARDWARE_LIKE, latency_s=0.005, mass_uncertainty=0.1, friction=False, seed=3)
    assert robot_words(hw, C.PIDConfig(kp=(84, 84, 84))) == ("hardware-like robot (friction off, latency 5 ms, "
                                                               "mass ±10 %, seed 3)  kp 84/84/84  kd 2/2/2")


@pytest.mark.parametrize("command", ["prototype", "stiffness"])
def test_the_prototype_and_stiffness_record_their_hardware_like_robot(command, path_file, tmp_path):
    scales = ["--pd-scales", "1.0"] if command == "stiffness" else []
    out = tmp_path / command
    assert evaluate([command, "--learned", path_file, *TINY_PROTOTYPE, *scales, *ASKED, "--out", out]) == 0
    assert robot(out) == ASKED_ROBOT
    ideal = tmp_path / f"{command}_ideal"
    assert evaluate([command, "--learned", path_file, *TINY_PROTOTYPE, *scales, "--prototype-modes", "ideal",
                     "--set", "pid.kd=[3,3,3]", "--out", ideal]) == 0
    assert robot(ideal) == IDEAL_ROBOT


def test_the_check_walks_and_records_the_hardware_asked(path_file, tmp_path, monkeypatch):
    from types import SimpleNamespace

    from cyberdog.analysis import replay_check

    walked = []

    def stand_in(path, speed, cfg=None, duration=10.0, hardware=None, distance=None, progress=None, run_up=0.0):
        walked.append(hardware)  # the 100 m walks: minutes each
        return SimpleNamespace(fell=False, speed_ok=True, mean_speed=1.0, distance=100.0, electrical_energy=4e4,
                               dropped_shifts=0)

    monkeypatch.setattr(replay_check, "replay_walk", stand_in)
    out = tmp_path / "check"
    assert evaluate(["check", path_file, "--parts", "hardware", "--workers", "1", *ASKED, "hardware.seed=5",
                     "--out", out]) == 0
    assert walked == [C.replace(HARDWARE, seed=5 + s) for s in replay_check.HARDWARE_CHECK_SEEDS]
    assert robot(out) == C.WalkedRobot(WALK, C.replace(HARDWARE, seed=5))
    assert evaluate(["check", path_file, "--parts", "hardware", "--workers", "1", "--out", tmp_path / "plain"]) == 0
    assert walked[-1] == C.replace(C.HARDWARE_LIKE, seed=replay_check.HARDWARE_CHECK_SEEDS[-1])  # as extraction's
    assert robot(tmp_path / "plain").hardware == C.HARDWARE_LIKE


def test_all_records_the_hardware_its_prototype_and_video_walk(path_file, tmp_path, walkers):
    out = tmp_path / "all"
    assert evaluate(["all", "--learned", path_file, *TINY_COMPARE, *TINY_PROTOTYPE[2:], "--video",
                     "--video-duration", "0.1", *ASKED, "--out", out]) == 0
    assert robot(out) == ASKED_ROBOT and walkers == [(HARDWARE, 2, WALK.pid)]


@pytest.mark.parametrize("argv", [
    ["compare", "--learned", "PATH", *TINY_COMPARE],
    TINY_BASELINES,
    ["pd-match", "PATH", "--pd-scale", "1.4"],
], ids=lambda argv: argv[0])
def test_a_sub_command_on_the_ideal_robot_records_its_walk_and_no_hardware(argv, path_file, tmp_path):
    out = tmp_path / "out"
    assert evaluate([path_file if a == "PATH" else a for a in argv] + ["--set", "pid.kd=[3,3,3]", "--out", out]) == 0
    assert robot(out) == IDEAL_ROBOT
    assert "hardware: null" in (out / "config.yaml").read_text()


def test_export_records_the_walk_its_table_is_made_from_and_no_hardware(path_file, tmp_path):
    from cyberdog.core.learned_set import LearnedSet

    out = tmp_path / "export"
    assert evaluate(["export", "--gait", path_file, "--no-replay", "--set", "pid.kd=[3,3,3]", "--out", out]) == 0
    made_from = LearnedSet.load([path_file]).paths()[0].walk_args(WALK, 1.0)[0]  # the gait at the path's speed
    assert robot(out) == C.WalkedRobot(made_from, None) and made_from.pid == WALK.pid


def test_extract_records_its_walk_and_no_hardware(tmp_path, monkeypatch):
    """The extraction itself (policy rollouts, replay checks: tests/test_extract_command.py) stood in for."""
    from cyberdog.core.learned_set import LearnedSet
    from cyberdog.evaluation import learned

    seen = {}

    def extraction(args, out, speeds, cfg=None, **kwargs):
        seen["cfg"] = cfg
        return LearnedSet([])

    monkeypatch.setattr(learned, "check_learned_inputs", lambda args: None)
    monkeypatch.setattr(commands, "learned_trajectories", extraction)
    out = tmp_path / "extract"
    assert evaluate(["extract", "--policy", tmp_path, "--set", "pid.kd=[3,3,3]", "--out", out]) == 0
    assert seen["cfg"] == WALK and robot(out) == IDEAL_ROBOT


@pytest.mark.parametrize("argv, why", [
    (["compare"], "Table 5"), (["baselines"], "ideal robot"), (["extract", "--policy", "P"], "validation robots"),
    (["pd-match", "P", "--pd-scale", "1.4"], "ideal robot"), (["export", "--gait", "P"], "ideal robot"),
    (["prototype", "--prototype-modes", "ideal"], "--prototype-modes ideal"),
    (["stiffness", "--prototype-modes", "ideal"], "--prototype-modes ideal"),
    (["video", "--video-robot", "ideal"], "--video-robot ideal"), (["check", "P", "--parts", "ideal"], "--parts ideal"),
    (["all", "--no-prototype"], "--no-prototype"),
], ids=lambda v: v[0] if isinstance(v, list) else "")
def test_hardware_settings_where_no_hardware_like_robot_walks_are_refused_in_one_line(argv, why, tmp_path, capsys):
    out = tmp_path / "out"
    assert evaluate([*argv, *ASKED, "--out", out]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--set hardware.latency_s" in err[0] and why in err[0], err
    assert not out.exists()
    # a --config file's hardware section there is not walked: one note says so, and the run goes on
    file = tmp_path / "robot.yaml"
    C.save_walked(ASKED_ROBOT, file)
    args = parse_args([*argv, "--config", str(file)])
    assert commands.walk_config(args) == WALK and walked_robot.walked_hardware(args, WALK) is None
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and f"--config {file}'s hardware section is not used" in err[0] and why in err[0], err


def test_every_sub_command_says_whether_it_walks_a_hardware_like_robot():
    assert set(walked_robot.IDEAL_ONLY) | walked_robot.ALWAYS_HARDWARE == set(commands.COMMAND_FUNCTIONS)
    assert not set(walked_robot.IDEAL_ONLY) & walked_robot.ALWAYS_HARDWARE


def test_a_config_files_hardware_section_is_read_back_as_training_reads_env_hardware(tmp_path):
    file = tmp_path / "robot.yaml"
    C.save_walked(ASKED_ROBOT, file)
    assert C.load_walked(file) == ASKED_ROBOT
    assert all(f"{name}:" in file.read_text() for name in C.to_dict(HARDWARE))  # every field written
    args = parse_args(["prototype", "--config", str(file), "--set", "hardware.seed=2"])
    assert commands.walk_config(args) == WALK and args.hardware == C.replace(HARDWARE, seed=2)
    # a partial section: its fields over HardwareConfig()'s (every effect off), as training's env.hardware reads it
    file.write_text("pid: {kd: [3, 3, 3]}\nhardware: {latency_s: 0.005, friction: true}\n")
    in_training = C.from_dict(C.EnvConfig, {"hardware": {"latency_s": 0.005, "friction": True}}).hardware
    assert C.load_walked(file) == C.WalkedRobot(WALK, in_training)
    assert in_training == C.HardwareConfig(latency_s=0.005, friction=True)
    args = parse_args(["prototype", "--config", str(file), "--set", "hardware.seed=2"])  # --set over the section
    assert commands.walk_config(args) == WALK and args.hardware == C.replace(in_training, seed=2)
    C.save(WALK, file)  # a plain walk config: the ideal robot
    assert C.load_walked(file) == IDEAL_ROBOT
    file.write_text("hardware: {latency_s: 0.003}\n")
    with pytest.raises(ValueError, match="hardware.latency_s.*whole multiple of sim.controller_dt"):
        C.load_walked(file)


def test_a_config_files_hardware_section_is_not_walked_where_no_hardware_like_robot_walks(tmp_path, capsys):
    file, out = tmp_path / "robot.yaml", tmp_path / "out"
    C.save_walked(ASKED_ROBOT, file)
    assert evaluate([*TINY_BASELINES, "--config", file, "--out", out]) == 0
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "hardware section is not used" in err[0], err
    assert robot(out) == IDEAL_ROBOT  # the walk config as given, no hardware walked
    assert evaluate([*TINY_BASELINES, "--config", file, "--set", "hardware.seed=2", "--out", tmp_path / "set"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--set hardware.seed" in err[0] and "hardware section" not in err[0], err


def test_a_training_preset_given_as_a_walk_config_is_named_as_one(tmp_path, capsys):
    with pytest.raises(ValueError, match="is a training preset \\(train.py --config\\), not a WalkConfig file"):
        C.load_walked(PRESET)
    assert evaluate(["compare", "--config", PRESET, "--out", tmp_path / "out"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "is a training preset (train.py --config), not a WalkConfig file" in err[0], err
    assert "hardware" in err[0] and not (tmp_path / "out").exists()  # the sections a walk config file may have
    with pytest.raises(ValueError, match="is a training preset"):
        C.load(C.WalkConfig, PRESET)
    assert C.load(C.ExperimentConfig, PRESET) == C.load_preset(PRESET).config


def test_a_latency_of_no_whole_controller_period_is_refused_before_the_video(tmp_path, capsys):
    assert evaluate([*TINY_VIDEO, "--set", "hardware.latency_s=0.003", "--out", tmp_path / "out"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "hardware.latency_s" in err[0] and "whole multiple" in err[0], err
    assert not (tmp_path / "out").exists()


def test_figures_refuses_walk_settings_it_would_not_use(tmp_path, capsys):
    """`evaluate.py figures` draws saved results: a --set or --config there is refused in one line."""
    source = Path(__file__).resolve().parents[1] / "results" / "figures_input"
    for extra in (["--set", "gait.lift_height=0.1"], ["--config", str(source / "config.yaml")]):
        out = tmp_path / extra[0].strip("-")
        assert evaluate(["figures", "--from", source, *extra, "--out", out]) == 2
        err = capsys.readouterr().err
        assert "walks nothing" in err and len(err.strip().splitlines()) == 1 and not out.exists()
