"""A foot path's joint torque (FootOffsetPath.feedforward), added by the trot to its feedforward, and
`stance_force_path`: a learned path written as its feet's motion and its stance legs' force."""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from cyberdog import config as C
from cyberdog.analysis.stance_force import (SPEED_TOLERANCE, SPEED_WALKS, STRETCH_BOUND, keep_harmonics,
                                            match_speed, phase_table, stance_force_path, stretch_sweep)
from cyberdog.analysis.walk import walk
from cyberdog.control.trot import BodyFeedback, TrotController
from cyberdog.core.commanded_path import CommandedPath
from cyberdog.core.foot_offsets import FootOffsetPath
from cyberdog.core.learned_set import read_path

GAIT = C.GaitConfig(lift_height=0.10)  # 0.4 s cycle, 0.2 s swing


def test_the_torque_table_interpolates_per_leg_and_survives_a_file(tmp_path):
    n = 8
    torque = np.zeros((4, n, 3))
    torque[1, :, 2] = np.arange(n)  # RF's knee: k N·m at phase k / 8
    torque[3, :, 0] = -1.5
    path = FootOffsetPath(np.zeros((4, n, 3)), 0.4, torque)
    at = path.feedforward_at([0.3, 2.5 / n + 1.0, 0.9, -0.25])
    assert at[0] == (0.0, 0.0, 0.0) and at[1][2] == pytest.approx(2.5) and at[3] == (-1.5, 0.0, -0.0)
    assert FootOffsetPath(np.zeros((4, n, 3)), 0.4).feedforward_at([0.1] * 4) == [(0.0, 0.0, 0.0)] * 4
    back = read_path(CommandedPath(1.0, GAIT, path).save(tmp_path / "p.json"))
    assert back.offsets == path and back.offsets != FootOffsetPath(np.zeros((4, n, 3)), 0.4)
    with pytest.raises(ValueError, match="offsets' shape"):
        FootOffsetPath(np.zeros((4, n, 3)), 0.4, np.zeros((4, n + 1, 3)))
    with pytest.raises(ValueError, match="finite"):
        FootOffsetPath(np.zeros((4, n, 3)), 0.4, np.full((4, n, 3), np.nan))


def test_the_trot_adds_the_paths_torque_to_its_feedforward_blended_in_as_its_shift():
    cfg = C.WalkConfig(gait=GAIT)
    torque = np.zeros((4, 8, 3))
    torque[0, :, 1] = 2.0  # LF's hip, every phase
    plain = TrotController(cfg, foot_offset_path=FootOffsetPath.zero(0.4, n=8))
    pushed = TrotController(cfg, foot_offset_path=FootOffsetPath(np.zeros((4, 8, 3)), 0.4, torque))
    q, body = np.tile([0.0, 0.8, -1.6], 4), BodyFeedback(forward_speed=1.0)
    ramp = cfg.controller.speed_ramp_time
    for t in (0.5 * ramp, ramp + 0.13):
        a, b = plain.command(t, q, body), pushed.command(t, q, body)
        extra = np.array(b.feedforward) - np.array(a.feedforward)
        assert extra[1] == pytest.approx(2.0 * min(1.0, t / ramp)) and np.count_nonzero(extra) == 1
        assert a.q_target == b.q_target and a.kp == b.kp  # the motion and the gains are the path's offsets'


def test_phase_table_averages_each_legs_steps_at_each_phase_and_keep_harmonics_drops_the_rest():
    rng = np.random.default_rng(0)
    phases = np.mod(np.arange(640)[:, None] / 64 + np.array([0.0, 0.5, 0.5, 0.0]), 1.0)
    values = np.sin(2 * np.pi * phases)[:, :, None] * np.array([1.0, 2.0, 3.0]) + rng.normal(0, 0.01, (640, 4, 3))
    table = phase_table(values, phases, 16)
    grid = np.arange(16) / 16
    assert np.allclose(table[2, :, 1], 2 * np.sin(2 * np.pi * grid), atol=0.1)  # half a bin off: 0.39 away
    rough = np.zeros((4, 16, 3))
    rough[:, 3] = 1.0  # one sample: every harmonic
    kept = keep_harmonics(rough, 2)
    assert np.allclose(kept.mean(axis=1), rough.mean(axis=1))  # the mean stays
    assert np.abs(np.fft.rfft(kept, axis=1)[:, 3:]).max() < 1e-12 and not np.allclose(kept, rough)
    with pytest.raises(ValueError, match="no step"):
        phase_table(values[:8], phases[:8], 16)
    with pytest.raises(ValueError, match="harmonics"):
        keep_harmonics(rough, 8)


def test_stretch_sweep_lengthens_the_fore_aft_motion_about_its_mean_and_nothing_else():
    phase = np.arange(16) / 16
    realised = np.zeros((4, 16, 3))
    realised[..., 0] = 0.2 + 0.1 * np.sin(2 * np.pi * phase)  # x about 0.2 m
    realised[..., 2] = -0.3
    offsets = np.full((4, 16, 3), 0.01)
    out = stretch_sweep(offsets, realised, 1.1)
    moved = realised + out - offsets  # the motion the stretched offsets make
    assert np.allclose(moved[..., 0] - 0.2, 1.1 * (realised[..., 0] - 0.2))
    assert np.array_equal(out[..., 1:], offsets[..., 1:]) and np.array_equal(stretch_sweep(offsets, realised, 1.0),
                                                                              offsets)
    with pytest.raises(ValueError, match="stretch"):
        stretch_sweep(offsets, realised, 0.0)


def test_match_speed_stretches_in_proportion_to_the_speed_missed_and_keeps_the_nearest():
    walked = []

    def walk_speed(stretch):  # a robot 5 % slow whose speed grows 0.9x as fast as its stride
        walked.append(stretch)
        return 1.4 * 0.95 * (1 + 0.9 * (stretch - 1))

    stretch, walks = match_speed(lambda s: s, 1.4, walk_speed)
    assert walked[0] == 1.0 and len(walks) <= SPEED_WALKS and stretch > 1.05
    assert abs(walks[-1]["speed_mps"] / 1.4 - 1) <= SPEED_TOLERANCE and stretch == walks[-1]["stretch"]
    stretch, walks = match_speed(lambda s: s, 1.4, lambda s: 1.0 + 0.01 * s)  # a stride that hardly moves it
    assert len(walks) == SPEED_WALKS and stretch == max(w["stretch"] for w in walks) == 1 + STRETCH_BOUND
    stretch, walks = match_speed(lambda s: s, 1.0, lambda s: 1.001)  # already matched: one walk
    assert (stretch, len(walks)) == (1.0, 1)


def test_a_path_written_as_motion_and_force_walks_as_it_did_and_halving_kp_changes_it_less():
    """A path that pushes its stance feet 2 cm below where they can go (the ideal robot, short walks): as motion +
    force it draws the battery as it did at the default gains, and at kp 0.5x its draw moves less than the path's
    as offsets does (the force no longer scales with kp)."""
    cfg = C.WalkConfig(gait=dataclasses.replace(GAIT, speed=1.0))
    table = np.zeros((4, 32, 3))
    table[:, 16:, 2] = -0.02 * np.sin(np.pi * np.arange(16) / 16)  # stance: phase >= 0.5
    path = CommandedPath(1.0, GAIT, FootOffsetPath(table, 0.4))
    written, record = stance_force_path(path, cfg, hardware=None, duration=4.0, run_up=2.0)
    assert record["stance_error_rms_mm"] > 5 and written.offsets.n == 64
    assert written.provenance["stance_force"] == record
    assert 1 <= len(record["speed_walks"]) <= SPEED_WALKS and record["sweep_stretch"] > 0
    force = written.offsets.feedforward
    assert np.all(force[:, :32] == 0) and np.abs(force[:, 32:]).max() > 0.5  # stance only, and a real push
    soft = dataclasses.replace(cfg, pid=dataclasses.replace(cfg.pid, kp=tuple(0.5 * k for k in cfg.pid.kp)))
    draw = {}
    for gains, c in (("default", cfg), ("kp 0.5x", soft)):
        for form, offsets in (("offsets", path.offsets), ("force", written.offsets)):
            r = walk(c, 6.0, None, foot_offsets=offsets, run_up=2.0)
            assert not r.fell and r.mean_speed == pytest.approx(1.0, abs=0.02)
            draw[gains, form] = r.electrical_energy / r.distance  # J/m
    assert draw["default", "force"] == pytest.approx(draw["default", "offsets"], rel=0.05)
    change = {form: abs(draw["kp 0.5x", form] / draw["default", form] - 1) for form in ("offsets", "force")}
    assert change["force"] < 0.5 * change["offsets"]
    with pytest.raises(ValueError, match="already carries"):
        stance_force_path(written, cfg, hardware=None)


def test_stance_force_writes_beside_never_over_and_refuses_what_it_cannot_rewrite(tmp_path, capsys):
    import evaluate
    from pathlib import Path

    shipped = Path(__file__).resolve().parents[1] / "results/battery_searched_pick/paths/seed40_1.2mps.json"
    out = tmp_path / "out"
    assert evaluate.main(["stance-force", str(shipped), "--harmonics", "4", "--out", str(out),
                          "--set", "controller.sagittal_placement_gain=0.0"]) == 0
    written = read_path(out / "learned" / shipped.name)
    record = written.provenance["stance_force"]
    assert record["harmonics"] == 4 and record["robot"] == "hardware-like, seed 1000"
    # made under the trot the command line set, the form records that trot, and the path's own beside it
    assert written.provenance["controller"]["sagittal_placement_gain"] == 0.0
    assert written.provenance["source_controller"]["sagittal_placement_gain"] == 0.2
    assert written.provenance["controller"]["max_speed_correction"] == 0.3  # the config's own trot, as --set makes it
    assert written.offsets.feedforward is not None and written.speed == 1.2
    assert "hardware: null" not in (out / "config.yaml").read_text()  # the model it walked is recorded
    assert evaluate.main(["stance-force", str(shipped), "--out", str(out)]) == 2  # never over a run
    assert evaluate.main(["stance-force", str(out / "learned"), "--out", str(tmp_path / "again")]) == 2
    assert "already written with a stance torque" in capsys.readouterr().err
    assert evaluate.main(["stance-force", str(shipped), "--harmonics", "40", "--out", str(tmp_path / "h")]) == 2
