"""The walk strip (plots/walk_strip.py): the same frames of the last whole gait period of each `evaluate.py video`
run, the robot each walked, each path drawn with its own gait; drawn from saved inputs only."""
import dataclasses
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import plots
from conftest import commanded
from cyberdog import config as C
from plots import walk_strip

ROOT = Path(__file__).resolve().parents[1]


def fake_video_run(folder: Path, name: str, frames: int, lift: float = 0.11, swing_time: float = 0.2,
                   hardware: C.HardwareConfig | None = None) -> Path:
    """An `evaluate.py video` run folder: its config (walk config and robot), record and a GIF whose frame i is a
    uniform grey of 4·i."""
    from PIL import Image

    folder.mkdir(parents=True)
    gait = dataclasses.replace(C.WalkConfig().gait, lift_height=lift, swing_time=swing_time)
    C.save_walked(C.WalkedRobot(dataclasses.replace(C.WalkConfig(), gait=gait), hardware), folder / "config.yaml")
    argv = ["video", "--learned", "results/battery/paths"] if name.startswith("learned") else ["video"]
    (folder / "outputs.json").write_text(json.dumps({"runs": [{"argv": argv}]}))
    if name.startswith("learned"):
        commanded(1.0, -0.005, 0).save(folder / "learned" / "seed0_1mps.json")
    images = [Image.new("RGB", (480, 360), (4 * i,) * 3) for i in range(frames)]
    images[0].save(folder / f"trot_{name}_1mps.gif", save_all=True, append_images=images[1:], duration=40)
    return folder


def test_walk_strip_takes_the_same_frames_of_the_last_whole_gait_period_from_each_video(tmp_path):
    learned = fake_video_run(tmp_path / "learned", "learned_seed0", 30)  # 1.2 s at 25 frames/s
    cycloid = fake_video_run(tmp_path / "cycloid", "cycloid", 40, lift=0.095)  # 1.6 s: the shorter video decides
    strip = walk_strip.extract([learned, cycloid])
    assert np.allclose(strip.times_s, [0.40, 0.48, 0.56, 0.64, 0.72])  # the period [0.4, 0.8) s, T = 0.4 s
    assert len(strip.frames) == 2  # a row a video
    for row in strip.frames:  # frame i is grey 4·i: frames 10, 12, ..., 18 in both rows
        assert [int(np.median(f)) for f in row] == [40, 48, 56, 64, 72]
    # the learned row at its path's own lift (the feet's mean peak, 0.095 m), the cycloid at the same: its seed's
    assert strip.labels == ["learned (RL), battery recipe, seed 0, H = 0.095 m", "composite cycloid, H = 0.095 m"]
    assert strip.trajectories == ["learned", "cycloid"] and strip.seeds == ["seed0", "seed0"]
    assert strip.robots == ["ideal robot", "ideal robot"]
    assert strip.feet_xz.shape == (2, 4, walk_strip.PATH_POINTS, 2)
    assert np.allclose(strip.feet_xz[:, :, :, 1].max(axis=2), 0.095, atol=1e-3)  # every foot's peak: the H walked
    saved = strip.save(tmp_path / "in")
    back = walk_strip.StripInput.load(saved)
    assert np.array_equal(back.frames, strip.frames) and back.labels == strip.labels
    assert back.seeds == strip.seeds and np.array_equal(back.feet_xz, strip.feet_xz) and back.robots == strip.robots
    # the battery beside each row: the prototype run's walks of the same trajectory, seed, speed and lift that count
    walk = dict(seed="seed0", speed_mps=1.0, robot="hardware", pd_scale=1.0, pd_matched=False, lift_height_m=0.095,
                reached=True, fell=False, mean_speed_mps=1.0, distance_m=20.0)
    walks = [dict(walk, trajectory="learned", battery_used_pct=0.7),
             dict(walk, trajectory="learned", battery_used_pct=0.8),
             dict(walk, trajectory="learned", battery_used_pct=0.1, fell=True),  # does not count
             dict(walk, trajectory="cycloid", battery_used_pct=1.0),
             dict(walk, trajectory="cycloid", battery_used_pct=2.0, lift_height_m=0.15)]  # the paper's lift
    assert walk_strip.prototype_battery(back, walks) == pytest.approx([3.75, 5.0])
    (tmp_path / "in" / "prototype.json").write_text(json.dumps(walks))
    (png,) = plots.draw_all(tmp_path / "in", tmp_path / "out", only=["walk_strip"], pdf=False)
    assert png.name == "walk_strip.png"
    with pytest.raises(ValueError, match="one GIF"):
        walk_strip.extract([tmp_path / "in"])


def test_the_walk_strip_names_the_robot_each_run_walked(tmp_path):
    ideal = fake_video_run(tmp_path / "ideal", "learned_seed0", 30)
    hardware = fake_video_run(tmp_path / "hardware", "cycloid", 30, hardware=C.replace(C.HARDWARE_LIKE,
                                                                                        latency_s=0.005))
    strip = walk_strip.extract([ideal, hardware])
    assert strip.robots == ["ideal robot", "hardware-like robot (latency 5 ms)"]
    fig = walk_strip.draw(strip)
    texts = [t.get_text() for t in fig.texts]
    assert texts[0].endswith("simulated in PyBullet")  # the rows differ: each row's label names its robot
    assert any(t.endswith(", hardware-like robot (latency 5 ms)") for t in texts)
    alike = walk_strip.extract([hardware, hardware])
    assert walk_strip.draw(alike).texts[0].get_text().endswith("(hardware-like robot (latency 5 ms))")


def test_a_commanded_path_is_drawn_with_its_own_gait_not_the_run_configs(tmp_path):
    from cyberdog.core.learned_set import LearnedSet
    from plots.figure4 import cycle_path

    folder = fake_video_run(tmp_path / "learned", "learned_seed0", 30, swing_time=0.15)  # config.yaml: 0.15 s swing
    run = walk_strip.video_run(folder)
    path = LearnedSet.load([folder / "learned"]).at(1.0)["seed0"].path
    g = path.gait  # the path's own trot: 0.2 s swing
    expected = [cycle_path(f, f.step_length, f.lift_height, g.swing_time, g.stance_time, walk_strip.PATH_POINTS)[1]
                for f in (path.as_sampled(leg) for leg in C.LEG_NAMES)]
    assert g.swing_time == 0.2 and np.allclose(run.feet_xz, np.stack(expected)) and run.period_s == g.period


def test_a_strip_input_of_another_format_is_one_line_naming_the_command_that_remakes_it(tmp_path):
    strip = walk_strip.extract([fake_video_run(tmp_path / "run", "cycloid", 30)])
    fields = {f.name: getattr(strip, f.name) for f in dataclasses.fields(strip) if f.name != "robots"}
    (tmp_path / "in").mkdir()
    np.savez_compressed(tmp_path / "in" / walk_strip.INPUT_NAME, **fields)
    with pytest.raises(ValueError, match="has no robots .*python -m plots.walk_strip RUN... --save-inputs"):
        walk_strip.StripInput.load(tmp_path / "in" / walk_strip.INPUT_NAME)
    proc = subprocess.run([sys.executable, "-m", "plots", "--from", tmp_path / "in", "--out", tmp_path / "out",
                           "--only", "walk_strip"], cwd=ROOT, capture_output=True, text=True, timeout=120)
    err = proc.stderr.strip().splitlines()
    assert proc.returncode == 2 and len(err) == 1 and "python -m plots.walk_strip" in err[0], proc.stderr
