"""The second physics engine (MuJoCo, `cyberdog.sim.mujoco_robot`) against the first (PyBullet): the same robot
from the same URDF, the same state conventions and drivers' law, the same standing torques and cycloid walks; and
`SimConfig.engine` reaching it from the walker, the env and both command lines."""
from __future__ import annotations

import dataclasses
import subprocess
import sys
import warnings
import xml.etree.ElementTree as ET
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

import cyberdog  # noqa: F401  (registers CyberDog-v0)
from cyberdog import config as C
from cyberdog.analysis.engine_check import on_engine, stand
from cyberdog.analysis.walk import walk
from cyberdog.core.drivers import JointCommand, driver_torque
from cyberdog.core.kinematics import joint_limits, standing_joint_angles
from cyberdog.loop.walker import Walker
from cyberdog.sim import Robot, make_robot
from cyberdog.sim.engine import resolve_path
from cyberdog.sim.mujoco_robot import CONTACT, MujocoRobot

ROOT = Path(__file__).resolve().parents[1]
CFG = C.WalkConfig()
MUJOCO = on_engine(CFG, "mujoco")


@pytest.fixture(scope="module")
def engines():
    pb = make_robot(CFG.robot, CFG.actuator, CFG.sim)
    mj = make_robot(MUJOCO.robot, MUJOCO.actuator, MUJOCO.sim)
    yield pb, mj
    pb.close()
    mj.close()


def test_the_setting_chooses_the_engine_and_refuses_any_other(engines):
    pb, mj = engines
    assert type(pb) is Robot and type(mj) is MujocoRobot
    with pytest.raises(ValueError, match="SimConfig.engine must be one of pybullet, mujoco, got 'ode'"):
        C.SimConfig(engine="ode")
    assert C.override(C.WalkConfig(), ["sim.engine=mujoco"]).sim == MUJOCO.sim
    with Walker(MUJOCO) as walker:
        assert type(walker.robot) is MujocoRobot


def _random_poses(n: int, seed: int = 3):
    """n (joint angles within the limits, base position, yaw) drawn around the standing pose."""
    rng = np.random.default_rng(seed)
    lo, hi = joint_limits(CFG.robot)
    stand_q = standing_joint_angles(CFG.robot).ravel()
    for _ in range(n):
        q = np.clip(stand_q + rng.normal(0.0, 0.4, 12), lo + 0.01, hi - 0.01)
        yield q, rng.uniform((-2.0, -2.0, 0.3), (2.0, 2.0, 1.0)), float(rng.uniform(-np.pi, np.pi))


def test_forward_kinematics_and_base_pose_agree_after_a_reset(engines):
    pb, mj = engines
    feet = []
    for q, base, yaw in _random_poses(5):
        for robot in engines:
            robot.reset(q, base_position=base, base_yaw=yaw)
        np.testing.assert_allclose(mj.foot_positions_world(), pb.foot_positions_world(), rtol=0, atol=1e-6)
        (p_pb, quat_pb), (p_mj, quat_mj) = pb.base_pose(), mj.base_pose()
        np.testing.assert_allclose(p_mj, p_pb, rtol=0, atol=1e-6)
        np.testing.assert_allclose(quat_mj * np.sign(quat_mj @ quat_pb), quat_pb, rtol=0, atol=1e-6)
        np.testing.assert_allclose(mj.joint_angles(), q, rtol=0, atol=1e-12)
        feet.append(mj.foot_positions_world())
    assert np.ptp(np.array(feet), axis=0).min() > 0.01  # the poses differ: the comparison had something to check


def _urdf_links() -> dict:
    """{link: (mass, COM (3,), inertia tensor (3, 3))} as the URDF file writes them."""
    out = {}
    for link in ET.parse(resolve_path(CFG.robot.urdf)).getroot().iter("link"):
        i = link.find("inertial")
        t = {k: float(v) for k, v in i.find("inertia").attrib.items()}
        tensor = np.array([[t["ixx"], t["ixy"], t["ixz"]], [t["ixy"], t["iyy"], t["iyz"]],
                           [t["ixz"], t["iyz"], t["izz"]]])
        com = np.array([float(x) for x in i.find("origin").get("xyz").split()])
        out[link.get("name")] = (float(i.find("mass").get("value")), com, tensor)
    return out


def test_the_model_keeps_the_urdfs_masses_inertias_limits_and_foot_spheres(engines):
    import mujoco
    pb, mj = engines
    m = mj.model
    links = _urdf_links()
    assert set(links) == set(mj.link_names.values())
    for name, (mass, com, tensor) in links.items():
        body = m.body(name)
        rotation = np.zeros(9)
        mujoco.mju_quat2Mat(rotation, body.iquat)
        rotation = rotation.reshape(3, 3)
        assert body.mass[0] == pytest.approx(mass, rel=1e-12), name
        np.testing.assert_allclose(body.ipos, com, rtol=0, atol=1e-12, err_msg=name)
        np.testing.assert_allclose(rotation @ np.diag(body.inertia) @ rotation.T, tensor, rtol=0,
                                   atol=1e-12 * np.abs(tensor).max(), err_msg=name)
    assert mj.total_mass() == pytest.approx(pb.total_mass(), abs=1e-9)
    assert mj.total_mass() == pytest.approx(sum(v[0] for v in links.values()), abs=1e-9)
    lo, hi = joint_limits(CFG.robot)
    np.testing.assert_allclose(m.jnt_range[1:], np.stack([lo, hi], axis=1), atol=1e-8)
    assert m.jnt_limited[1:].all() and m.jnt_type[0] == mujoco.mjtJoint.mjJNT_FREE
    feet = [g for g in range(m.ngeom) if m.geom_bodyid[g] in mj.foot_body_ids]
    assert [m.geom_type[g] for g in feet] == [mujoco.mjtGeom.mjGEOM_SPHERE] * 4
    np.testing.assert_array_equal(m.geom_size[feet, 0], CFG.robot.foot_radius)


def test_mass_scale_scales_every_link_and_friction_is_the_configured_pairs_coefficient(engines):
    pb, mj = engines
    nominal_mass, nominal_inertia = mj.model.body_mass.copy(), mj.model.body_inertia.copy()
    try:
        for robot in engines:
            robot.set_mass_scale(1.05)
        np.testing.assert_allclose(mj.model.body_mass, 1.05 * nominal_mass, rtol=1e-15)
        np.testing.assert_allclose(mj.model.body_inertia, 1.05 * nominal_inertia, rtol=1e-15)
        assert mj.total_mass() == pytest.approx(pb.total_mass(), abs=1e-9)
        assert mj.total_mass() == pytest.approx(1.05 * nominal_mass.sum(), rel=1e-12)
        mj.set_ground_friction(0.6)
        mj.reset()
        for _ in range(20):
            mj.step(np.zeros(12))
        d = mj.data
        assert d.ncon >= 4 and mj.foot_contacts().all()
        for i in range(d.ncon):
            assert d.contact.friction[i][0] == 0.6 and d.contact.dim[i] == CONTACT["condim"]
            np.testing.assert_array_equal(d.contact.solref[i], CONTACT["solref"])
            np.testing.assert_array_equal(d.contact.solimp[i], CONTACT["solimp"])
    finally:
        for robot in engines:
            robot.set_mass_scale(1.0)
        mj.set_ground_friction(CFG.sim.ground_friction)
    np.testing.assert_array_equal(mj.model.body_mass, nominal_mass)


def test_the_state_conventions_agree_in_free_flight(engines):
    """Lifted clear of the ground, yawed, the joints driven: the same state read by both engines, body values of
    the trunk's link frame (not its centre of mass), angular velocity in the world frame."""
    torque = [2.0, -1.5, 1.0, -2.0, 1.0, 0.5, 1.5, 1.0, -1.0, 0.5, -1.0, 2.0]
    for robot in engines:
        robot.reset(base_position=(0.3, -0.2, 1.5), base_yaw=0.6)
        for _ in range(20):  # 50 ms: the joints swing, no joint reaches its limit
            robot.step(torque)
    a, b = (robot.read() for robot in engines)
    tolerance = {"q": 1e-6, "dq": 1e-4, "base_position": 1e-5, "base_quaternion": 1e-6, "base_rpy": 1e-6,
                 "base_linear_velocity_world": 1e-4, "base_angular_velocity_world": 1e-4}
    for field, atol in tolerance.items():
        np.testing.assert_allclose(getattr(b, field), getattr(a, field), rtol=0, atol=atol, err_msg=field)
    assert a.time == b.time == pytest.approx(0.05)
    assert np.abs(a.dq).max() > 5 and np.abs(a.base_angular_velocity_world).max() > 1  # it moved


def test_the_drivers_law_acts_at_every_physics_step_on_the_state_then(engines):
    """`drive` on MuJoCo: the torque of each physics step is the drivers' law on the joint state after the step
    before, and the joints follow it exactly as a hand-held loop of `physics_step`."""
    _, mj = engines
    q0 = standing_joint_angles(CFG.robot).ravel().tolist()
    command = JointCommand([a + 0.1 for a in q0], [0.5] * 12, [1.0] * 12, [60.0] * 12, [2.0] * 12)
    mj.reset()
    driven = [mj.drive(command) for _ in range(4)]
    mj.reset()
    by_hand = []
    for _ in range(4 * mj.substeps):
        q, dq = mj.joint_lists()
        by_hand.append((mj.physics_step(driver_torque(command, q, dq, mj.actuator.torque_limit)),
                        mj.joint_lists()[0]))
    taus = [tau for period in driven for tau in period[0]]
    angles = [q for period in driven for q in period[1]]
    assert taus == [t for t, _ in by_hand] and angles == [q for _, q in by_hand]
    assert taus[0] != taus[1]  # the torque changed within a period


def test_standing_joint_torques_agree_within_5_percent():
    """The trot controller's stance held still on each engine: the same joint torques (the abad torques hold the
    feet's lateral forces: MuJoCo's friction must not let them creep), the weight on the feet, a shallow sink."""
    pb, mj = stand(on_engine(CFG, "pybullet")), stand(MUJOCO)
    rel = np.abs(mj.joint_torque - pb.joint_torque) / np.abs(pb.joint_torque)
    assert rel.max() <= 0.05, np.round(rel, 3)
    weight = CFG.robot.total_mass * CFG.sim.gravity
    for s in (pb, mj):
        assert s.foot_force.sum() == pytest.approx(weight, rel=0.02)
    assert (0.0 < mj.penetration).all() and (mj.penetration < 0.001).all()  # m: sunk, under a millimetre


@pytest.mark.parametrize("speed", [1.0, 1.2, 1.4])
def test_a_cycloid_walk_keeps_the_band_on_both_engines_at_close_energies(speed):
    """3 s of composite-cycloid trot after the 1 s start-up ramp, on each engine: within ±5 % of the command, no
    fall, only feet on the ground; Eq. 7 J/m of the two engines within 10 %."""
    results = {}
    for engine in ("pybullet", "mujoco"):
        cfg = on_engine(dataclasses.replace(CFG, gait=dataclasses.replace(CFG.gait, speed=speed)), engine)
        results[engine] = r = walk(cfg, duration=4.0, run_up=1.0)
        assert not r.fell and r.speed_ok and not r.non_foot_contacts, (engine, r.mean_speed)
    pb, mj = results["pybullet"], results["mujoco"]
    assert mj.energy_per_metre == pytest.approx(pb.energy_per_metre, rel=0.10)


def test_gymnasium_check_env_passes_on_mujoco():
    from gymnasium.utils.env_checker import check_env
    config = C.EnvConfig(walk=MUJOCO, episode_time=0.25)
    env = gym.make("CyberDog-v0", config=config, reward="stage2")
    assert type(env.unwrapped.walker.robot) is MujocoRobot
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        check_env(env.unwrapped, skip_render_check=True)
    env.close()


def test_render_draws_the_robot_offscreen(engines):
    _, mj = engines
    mj.reset()
    try:
        image = mj.render(64, 48)
    except RuntimeError as err:  # no OpenGL here: the error names the setting
        assert "MUJOCO_GL" in str(err)
        pytest.skip(str(err))
    assert image.shape == (48, 64, 3) and image.dtype == np.uint8
    assert image.std() > 5  # a picture, not a blank


def _run(args: list[str], timeout: float) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, *args], cwd=ROOT, capture_output=True, text=True, timeout=timeout)


def test_train_py_trains_on_mujoco(tmp_path):
    run = tmp_path / "run"
    done = _run(["train.py", "--config", "configs/tiny.yaml", "--no-progress", "--set", "env.walk.sim.engine=mujoco",
                 "--run-dir", str(run)], timeout=300)
    assert done.returncode == 0, done.stderr[-2000:]
    assert C.load(C.ExperimentConfig, run / "config.yaml").env.walk.sim.engine == "mujoco"
    assert (run / "stage2_final_actor.pt").is_file() and len((run / "metrics.csv").read_text().splitlines()) > 2


def test_evaluate_py_walks_on_mujoco(tmp_path):
    done = _run(["evaluate.py", "baselines", "--speeds", "1.0", "--trajectories", "cycloid", "--duration", "2",
                 "--set", "sim.engine=mujoco", "--out", str(tmp_path / "out")], timeout=300)
    assert done.returncode == 0, done.stderr[-2000:]
    assert C.load_walked(tmp_path / "out" / "config.yaml").walk.sim.engine == "mujoco"


def test_the_two_engines_share_no_run_of_six_identical_lines():
    """What both robots need is in cyberdog/sim/engine.py, not copied into each."""
    def lines(name: str) -> list[str]:
        return [s for line in (ROOT / "cyberdog" / "sim" / name).read_text().splitlines() if (s := line.strip())]
    a, b = lines("robot.py"), lines("mujoco_robot.py")
    runs = {tuple(a[i:i + 6]) for i in range(len(a) - 5)}
    shared = [b[j:j + 6] for j in range(len(b) - 5) if tuple(b[j:j + 6]) in runs]
    assert not shared, shared[0]
