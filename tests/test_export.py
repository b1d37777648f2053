"""`evaluate.py export`: a policy as TorchScript and ONNX that act as the PyTorch actor does on a rollout's
observations, and a foot path as a joint table that keeps the robot's limits and walks when replayed."""
from __future__ import annotations

import dataclasses
import json
import math
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import yaml

import evaluate
from cyberdog import config as C
from cyberdog.analysis.gait_export import load_limits, replay_table
from cyberdog.control.gait_table import TablePlayer, gait_table
from cyberdog.core import kinematics as kin
from cyberdog.core.commanded_path import CommandedPath
from cyberdog.core.gait import GaitScheduler
from cyberdog.core.joint_table import (JOINTS, JointLimitError, JointLimits, JointTable, check_limits,
                                       limit_breaks)

ROOT = Path(__file__).resolve().parents[1]
ACTOR = ROOT / "results/battery/policy/seed0/stage2_actor.pt"
PATH_1MPS = ROOT / "results/battery/paths/seed0_1mps.json"
LIMITS_FILE = ROOT / "configs/robots/cyberdog_limits.yaml"
PARITY = 1e-5  # the largest |exported − PyTorch| allowed


@pytest.fixture(scope="module")
def exported(tmp_path_factory):
    """One export of the shipped battery seed 0: its actor and its 1.0 m/s path, through the command line."""
    pytest.importorskip("onnxruntime")
    out = tmp_path_factory.mktemp("export") / "out"
    rc = evaluate.main(["export", "--policy", str(ACTOR), "--gait", str(PATH_1MPS), "--speed", "1.0",
                        "--rate", "500", "--limits", str(LIMITS_FILE), "--out", str(out)])
    return out, rc


def rollout_observations(actor, steps: int = 36, speed: float = 1.0) -> np.ndarray:
    """The observations of a short deterministic walk of the actor in its env."""
    from cyberdog.envs.cyberdog_env import CyberDogEnv

    env = CyberDogEnv(config=dataclasses.replace(actor.config.env, target_speed_range=()), reward="stage2")
    obs, _ = env.reset(seed=3, options={"target_speed": speed})
    seen = [obs]
    for _ in range(steps - 1):
        obs, _, terminated, _, _ = env.step(actor(obs))
        seen.append(obs)
        assert not terminated
    env.close()
    return np.array(seen, dtype=np.float32)


# ---- the policy --------------------------------------------------------------------------------------------------

@pytest.mark.filterwarnings("ignore:`torch.jit.load` is deprecated:DeprecationWarning")
def test_torchscript_and_onnx_act_as_the_pytorch_actor_on_a_rollout(exported):
    import onnxruntime as ort
    import torch

    from cyberdog.rl.rollout import load_actor

    out, rc = exported
    assert rc == 0
    actor = load_actor(ACTOR)
    obs = rollout_observations(actor)
    assert obs.std(axis=0).max() > 0.1  # a walk: the observations change from step to step
    reference = np.array([actor(o) for o in obs])
    env = actor.config.env
    scale = np.tile([env.foot_offset_scale, env.foot_offset_scale,
                     env.foot_offset_scale_z or env.foot_offset_scale], 4)
    scripted = torch.jit.load(str(out / "policy_torchscript.pt"))
    with torch.no_grad():
        ts_action, ts_si = (t.numpy() for t in scripted(torch.as_tensor(obs)))
        one, _ = scripted(torch.as_tensor(obs[5]))  # one observation, unbatched
    session = ort.InferenceSession(str(out / "policy.onnx"), providers=["CPUExecutionProvider"])
    onnx_action, onnx_si = session.run(["action", "action_si"], {"observation": obs})
    for action, si in ((ts_action, ts_si), (onnx_action, onnx_si)):
        assert np.abs(action - reference).max() <= PARITY
        assert np.abs(si - reference * scale).max() <= PARITY * 0.03
    assert np.abs(one.numpy() - reference[5]).max() <= PARITY
    sidecar = json.loads((out / "policy.json").read_text())
    assert max(v for k, v in sidecar["parity"].items() if "action" in k) <= PARITY


def test_the_sidecar_documents_the_observation_and_action_the_graph_takes_and_gives(exported):
    from cyberdog.envs.cyberdog_env import CyberDogEnv
    from cyberdog.rl.rollout import load_actor

    out, _ = exported
    d = json.loads((out / "policy.json").read_text())
    actor = load_actor(ACTOR)
    n = actor.module.observation_scale.numel()
    assert d["source_actor"] == "results/battery/policy/seed0/stage2_actor.pt"
    assert d["control_period_s"] == pytest.approx(0.025)
    assert d["observation"]["shape"][1] == n
    groups = d["observation"]["groups"]
    assert [g["slice"][0] for g in groups[1:]] == [g["slice"][1] for g in groups[:-1]]  # contiguous
    assert groups[0]["slice"][0] == 0 and groups[-1]["slice"][1] == n
    for g in groups:
        assert len(g["entries"]) == len(g["scale"]) == g["slice"][1] - g["slice"][0]
        assert g["unit"]
    scale = np.concatenate([g["scale"] for g in groups]).astype(float)
    np.testing.assert_allclose(scale, actor.module.observation_scale.numpy())
    joints = next(g for g in groups if g["name"] == "joint_angles")
    assert joints["entries"][4] == "joint_angles.RF_hip" and joints["unit"] == "rad"
    # the action: 12 entries LF, RF, LH, RH x (dx, dy, dz), m, and the scale the env applies to it
    layout = d["action"]["layout"]
    assert [a["leg"] for a in layout] == [leg for leg in C.LEG_NAMES for _ in range(3)]
    env = CyberDogEnv(config=dataclasses.replace(actor.config.env, target_speed_range=()), reward="stage2")
    env.reset(seed=0)
    action = np.linspace(-0.9, 0.8, 12)
    env.step(action)
    applied = np.array(env.walker.controller.last_foot_offsets)  # the shift the trot ran at the step's end, m
    env.close()
    np.testing.assert_allclose(applied.reshape(-1), action * [a["scale"] for a in layout], atol=1e-12)
    assert all(a["unit"] == "m" for a in layout)


def test_the_package_imports_without_onnx_and_the_export_names_the_extra(tmp_path):
    code = ("import sys\nfor m in ('onnx', 'onnxruntime', 'onnxscript'): sys.modules[m] = None\n"
            "import cyberdog.rl.policy_export, evaluate\n"
            f"sys.exit(evaluate.main(['export', '--policy', {str(ACTOR)!r}, '--out', {str(tmp_path / 'o')!r}]))\n")
    done = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert done.returncode == 2, done.stderr
    assert 'pip install -e ".[export]"' in done.stderr and "--policy" in done.stderr
    assert not (tmp_path / "o").exists()


# ---- the gait ----------------------------------------------------------------------------------------------------

def test_the_exported_gait_keeps_the_limits_and_its_replay_walks(exported):
    out, rc = exported
    assert rc == 0
    table = JointTable.read(out / "gait.csv")
    assert table.rate == 500 and table.frames == 200 and table.period == pytest.approx(0.4)
    assert table.header["source"] == "results/battery/paths/seed0_1mps.json"
    assert limit_breaks(table, load_limits(LIMITS_FILE)) == []
    replay = json.loads((out / "gait_replay.json").read_text())
    assert not replay["fell"] and replay["duration_s"] == pytest.approx(10.0)
    assert abs(replay["mean_speed_mps"] - 1.0) <= 0.05 and replay["in_band"]
    assert replay["ground_speed_mps"] >= replay["mean_speed_mps"] - 1e-3  # |v_xy| >= v_x


def test_the_replay_plays_the_table_it_is_given():
    """A table that holds the standing pose stands; the player sends frame k at the walker's period k."""
    cfg = C.WalkConfig()
    stand = kin.standing_joint_angles(cfg.robot).reshape(1, 12)
    n = 20
    table = JointTable(500.0, np.repeat(stand, n, 0), np.zeros((n, 12)), np.full((n, 12), 60.0),
                       np.full((n, 12), 2.0), np.zeros((n, 12)))
    replay = replay_table(table, cfg, speed=1.0, duration=1.0)
    assert not replay.result.fell and abs(replay.result.mean_speed) < 0.02 and replay.result.distance < 0.05
    player = TablePlayer(dataclasses.replace(table, q=table.q + np.arange(n)[:, None]))
    assert [player.command(k * 0.002, None).q_target[0] - stand[0, 0] for k in (0, 7, 19, 20, 27)] == \
        pytest.approx([0, 7, 19, 0, 7])


def _plain_table(speed=1.0, rate=500.0):
    path = CommandedPath.load(PATH_1MPS)
    cfg = dataclasses.replace(C.WalkConfig(), gait=path.gait)
    return gait_table(cfg, speed, rate, foot_offsets=path.offsets), path, cfg


def test_the_table_is_the_paths_feet_through_ik_with_the_stance_feedforward_at_the_targets():
    table, path, cfg = _plain_table()
    n, r = table.frames, cfg.robot
    feet = kin.foot_position(table.q.reshape(n, 4, 3), r)  # (n, 4, 3), leg frame
    for leg in range(4):
        shift = int(round(cfg.gait.phase_offsets[leg] * n))
        _, x, z = path.leg_path(leg, n)  # the commanded path at phases k / n
        order = (np.arange(n) + shift) % n  # frame k: the leg's phase (k / n + offset) mod 1
        y = kin.LEFT_RIGHT[leg] * r.l1 + path.offsets.sample(leg, order / n)[:, 1]
        np.testing.assert_allclose(feet[:, leg, 0], x[order], atol=1e-9)
        np.testing.assert_allclose(feet[:, leg, 1], y, atol=1e-9)
        np.testing.assert_allclose(feet[:, leg, 2], z[order] - (r.body_height - r.foot_radius), atol=1e-9)
    # τ_ff: Jᵀ f of each stance foot carrying its share of the weight, at the targets; none in swing
    swing = GaitScheduler.from_config(cfg.gait).in_swing(np.arange(n) / table.rate)
    jac = kin.jacobian(table.q.reshape(n, 4, 3), r)  # (n, 4, 3, 3)
    weight = r.total_mass * cfg.sim.gravity
    force = np.where(swing, 0.0, -weight / (4 - swing.sum(axis=1, keepdims=True)))  # (n, 4), N
    expected = np.einsum("nlij,nli->nlj", jac, np.stack([0 * force, 0 * force, force], axis=-1))
    np.testing.assert_allclose(table.tau_ff.reshape(n, 4, 3), expected, atol=1e-9)
    assert np.all(table.kp == C.PIDConfig().kp[0]) and np.all(table.kd == C.PIDConfig().kd[0])


def test_the_tables_joint_speed_is_the_derivative_of_its_joint_angle():
    """The central difference over the repeating period, away from the trot's speed jumps (lift-off, touch-down)."""
    cfg = dataclasses.replace(C.WalkConfig(), gait=dataclasses.replace(C.GaitConfig(), lift_height=0.1))
    table = gait_table(cfg, 1.0, 1000.0)  # the plain cycloid: smooth between its phase boundaries
    dq_fd = (np.roll(table.q, -1, 0) - np.roll(table.q, 1, 0)) * table.rate / 2
    smooth = np.abs(np.roll(table.dq, -1, 0) - np.roll(table.dq, 1, 0)) < 0.5  # rad/s between the neighbours
    assert smooth.mean() > 0.8 and np.abs(table.dq).max() > 5.0
    assert np.abs(dq_fd - table.dq)[smooth].max() < 0.02


def test_the_csv_and_its_sidecar_read_back_as_written(tmp_path):
    table, _, _ = _plain_table()
    table.header["speed_mps"] = 1.0
    csv_path, json_path = table.write(tmp_path / "gait.csv")
    assert csv_path.read_text().splitlines()[0].split(",")[2:7] == [
        "LF_abad_q_rad", "LF_abad_dq_radps", "LF_abad_kp_Nm_per_rad", "LF_abad_kd_Nms_per_rad", "LF_abad_tau_ff_Nm"]
    back = JointTable.read(csv_path)
    for name in ("q", "dq", "kp", "kd", "tau_ff"):
        np.testing.assert_allclose(getattr(back, name), getattr(table, name), rtol=1e-9, atol=1e-12)
    assert back.header == {"speed_mps": 1.0} and json.loads(json_path.read_text())["joint_order"] == list(JOINTS)


def test_the_limits_file_is_the_robots_config():
    limits = load_limits(LIMITS_FILE)
    r, a = C.RobotConfig(), C.ActuatorConfig()
    assert limits.torque == a.torque_limit and limits.joint_speed == a.zero_torque_speed
    assert limits.position == ((-r.abad_limit, r.abad_limit), r.hip_limit, r.knee_limit)
    assert limits.kp == (0.0, 200.0) and limits.kd == (0.0, 10.0)
    np.testing.assert_allclose(limits.position_jump, np.radians([8.0, 10.0, 12.0]))
    assert dataclasses.replace(limits, source="") == dataclasses.replace(JointLimits.cyberdog(), source="")
    assert "cyberdog_limits.yaml" in limits.source


BREAKS = {  # kind: (frame, joint, the change, words the error names)
    "position": (37, 5, lambda t, k, j: t.q.__setitem__((k, j), -3.0), "position_range_rad"),
    "speed": (120, 2, lambda t, k, j: t.dq.__setitem__((k, j), 25.0), "joint_speed_limit_radps"),
    "torque": (61, 10, lambda t, k, j: t.tau_ff.__setitem__((k, j), -30.0), "torque_limit_Nm"),
    "kp": (0, 0, lambda t, k, j: t.kp.__setitem__((k, j), 250.0), "kp_range_Nm_per_rad"),
    "kd": (199, 11, lambda t, k, j: t.kd.__setitem__((k, j), -0.5), "kd_range_Nms_per_rad"),
    "jump": (90, 4, lambda t, k, j: t.q.__setitem__((slice(k + 1, None), j), t.q[k + 1:, j] + math.radians(15)),
             "position_jump_deg.hip"),
}


@pytest.mark.parametrize("kind", sorted(BREAKS))
def test_a_table_that_breaks_a_limit_is_refused_naming_the_frame_the_joint_and_the_limit(kind):
    table, _, _ = _plain_table()
    limits = load_limits(LIMITS_FILE)
    check_limits(table, limits)  # the table as made keeps them all
    frame, joint, change, words = BREAKS[kind]
    change(table, frame, joint)
    with pytest.raises(JointLimitError) as err:
        check_limits(table, limits)
    line = str(err.value)
    assert "\n" not in line and f"frame {frame} " in line and f"joint {JOINTS[joint]}:" in line and words in line


def test_the_jump_across_the_periods_seam_is_checked():
    table, _, _ = _plain_table()
    table.q[:, 7] += np.linspace(0.0, math.radians(11), table.frames)  # a drift of 11 deg over the period
    breaks = limit_breaks(table, load_limits(LIMITS_FILE))
    assert len(breaks) == 1 and "frame 199" in breaks[0] and "to frame 0" in breaks[0] and "LH_hip" in breaks[0]


@pytest.mark.parametrize("edit, words", [
    (lambda d: d.pop("kd_range_Nms_per_rad"), "missing key(s) ['kd_range_Nms_per_rad']"),
    (lambda d: d.__setitem__("kp_range_Nm_per_rad", [200, 0]), "kp_range_Nm_per_rad must be [low, high]"),
    (lambda d: d.__setitem__("torque_limit_Nm", -1), "torque_limit_Nm must be a finite number > 0"),
    (lambda d: d["position_jump_deg"].pop("knee"), "position_jump_deg must map each of abad, hip, knee"),
])
def test_a_bad_limits_file_is_refused_naming_the_key(tmp_path, edit, words):
    data = yaml.safe_load(LIMITS_FILE.read_text())
    edit(data)
    bad = tmp_path / "limits.yaml"
    bad.write_text(yaml.safe_dump(data))
    with pytest.raises(JointLimitError, match=re.escape(words)):
        load_limits(bad)


# ---- the command line's refusals ---------------------------------------------------------------------------------

def _export(args, tmp_path):
    return evaluate.main(["export", *args, "--out", str(tmp_path / "out")])


@pytest.mark.parametrize("args, words", [
    ([], "export needs --policy"),
    (["--gait", "results/battery/paths/nothing.json"], "--gait results/battery/paths/nothing.json: no such file"),
    (["--gait", str(PATH_1MPS), "--speed", "1.2"], "no learned path at 1.2 m/s"),
    (["--gait", str(PATH_1MPS), "--rate", "333"], "--rate: rate 333 Hz does not divide the gait period 0.4 s"),
])
def test_bad_input_ends_with_one_line_and_status_2(tmp_path, capsys, args, words):
    assert _export(args, tmp_path) == 2
    err = capsys.readouterr().err
    assert words in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "out" / "gait.csv").exists()


@pytest.mark.parametrize("args, words", [(["--rate", "50"], "--rate: must be a rate in [100, 2000] Hz"),
                                         (["--speed", "-1"], "--speed: must be a number > 0")])
def test_out_of_range_options_are_refused_by_the_parser(tmp_path, capsys, args, words):
    with pytest.raises(SystemExit) as end:
        _export(["--gait", str(PATH_1MPS), *args], tmp_path)
    assert end.value.code == 2 and words in capsys.readouterr().err


def test_a_table_beyond_the_limits_file_is_refused_and_nothing_written(tmp_path, capsys):
    data = yaml.safe_load(LIMITS_FILE.read_text())
    data["kp_range_Nm_per_rad"] = [0, 50]
    limits = tmp_path / "soft.yaml"
    limits.write_text(yaml.safe_dump(data))
    assert _export(["--gait", str(PATH_1MPS), "--limits", str(limits), "--no-settle"], tmp_path) == 2
    err = capsys.readouterr().err
    assert "frame 0 " in err and "joint LF_abad: kp 60" in err and "kp_range_Nm_per_rad" in err
    assert not (tmp_path / "out").exists()


def test_an_output_never_lands_on_an_input(tmp_path, capsys):
    source = tmp_path / "out" / "gait.json"
    source.parent.mkdir()
    source.write_text(PATH_1MPS.read_text())
    assert _export(["--gait", str(source), "--force"], tmp_path) == 2
    assert "its gait.json is an input" in capsys.readouterr().err
    assert source.read_text() == PATH_1MPS.read_text()

