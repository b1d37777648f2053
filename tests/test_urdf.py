"""The generated URDF as PyBullet loads it: mass, inertia, joints, limits, kinematics, standing contacts."""
import importlib.util
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pybullet
import pytest
from pybullet_utils.bullet_client import BulletClient

from cyberdog.config import JOINT_NAMES, LEG_NAMES, ActuatorConfig, RobotConfig, SimConfig
from cyberdog.core.kinematics import foot_position_body, joint_limits, standing_joint_angles
from cyberdog.sim import Robot

ROOT = Path(__file__).resolve().parents[1]
URDF = ROOT / "urdf" / "cyberdog.urdf"
CFG = RobotConfig()
FEET = {f"{leg}_foot" for leg in LEG_NAMES}
REFLECTED = 8.9031e-05 * 9 ** 2


@pytest.fixture(scope="module")
def robot():
    r = Robot(CFG, ActuatorConfig(), SimConfig())
    yield r
    r.close()


def test_checked_in_urdf_matches_generator():
    spec = importlib.util.spec_from_file_location("make_urdf", ROOT / "tools" / "make_urdf.py")
    make_urdf = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(make_urdf)
    assert URDF.read_text() == make_urdf.urdf_text(), "run python tools/make_urdf.py"


def test_urdf_structure():
    root = ET.parse(URDF).getroot()
    links = root.findall("link")
    assert all(link.find("inertial") is not None for link in links), "a link without <inertial> gets 1 kg"
    assert len(links) == 1 + 4 * 4
    revolute = [j.get("name") for j in root.findall("joint") if j.get("type") == "revolute"]
    assert revolute == [f"{leg}_{j}_joint" for leg in LEG_NAMES for j in JOINT_NAMES]
    assert len(root.findall("joint[@type='fixed']")) == 4
    for shape in root.iter("geometry"):
        assert shape[0].tag in ("box", "cylinder", "sphere")


def test_total_mass_as_loaded_by_pybullet():
    client = BulletClient(connection_mode=pybullet.DIRECT)
    body = client.loadURDF(str(URDF), flags=pybullet.URDF_USE_INERTIA_FROM_FILE)
    mass = sum(client.getDynamicsInfo(body, link)[0] for link in range(-1, client.getNumJoints(body)))
    client.disconnect()
    assert mass == pytest.approx(13.573, abs=0.1)


def test_no_inertia_zeroed_and_rotor_inertia_added(robot):
    """Bullet silently zeroes an inertia that breaks the triangle inequality; the rotor term must survive."""
    c = robot.client
    for link, name in robot.link_names.items():
        mass, _, diag, _, orn = c.getDynamicsInfo(robot.body_id, link)[:5]
        assert mass > 0 and min(diag) > 0, f"{name}: mass {mass}, inertia {diag}"
        rot = np.array(c.getMatrixFromQuaternion(orn)).reshape(3, 3)
        inertia = rot @ np.diag(diag) @ rot.T  # about the COM, in the link frame
        axis = {"abad": 0, "thigh": 1, "calf": 1}.get(name.split("_")[-1])
        if axis is not None:  # child link of a joint: reflected rotor inertia about the joint axis
            assert inertia[axis, axis] > REFLECTED, name


def test_joint_order_and_limits(robot):
    lower, upper = joint_limits(CFG)
    assert robot.joint_names == [f"{leg}_{j}_joint" for leg in LEG_NAMES for j in JOINT_NAMES]
    for k, j in enumerate(robot.joint_ids):
        info = robot.client.getJointInfo(robot.body_id, j)
        assert info[1].decode() == robot.joint_names[k]
        assert info[2] == pybullet.JOINT_REVOLUTE
        # PyBullet reports the axis in the child's inertial (principal-axes) frame: rotate it to the link frame
        inertial_orn = robot.client.getDynamicsInfo(robot.body_id, j)[4]
        rot = np.array(robot.client.getMatrixFromQuaternion(inertial_orn)).reshape(3, 3)
        expected_axis = (1, 0, 0) if k % 3 == 0 else (0, 1, 0)
        np.testing.assert_allclose(rot @ np.array(info[13]), expected_axis, atol=1e-12)
        assert info[8] == pytest.approx(lower[k], abs=1e-8) and info[9] == pytest.approx(upper[k], abs=1e-8)
        assert info[10] == pytest.approx(25.0) and info[11] == pytest.approx(20.9136)
    assert [robot.link_names[i] for i in robot.foot_link_ids] == [f"{leg}_foot" for leg in LEG_NAMES]
    np.testing.assert_allclose(lower[:3], [-0.76096355387, -1.88495559215, -2.49582083035])
    np.testing.assert_allclose(upper[:3], [0.76096355387, 3.76991118431, -0.717155789644])


def test_forward_kinematics_matches_pybullet(robot):
    rng = np.random.default_rng(0)
    lower, upper = joint_limits(CFG)
    errors = []
    for _ in range(150):
        q = rng.uniform(lower, upper)
        robot.reset(q, base_position=(0.0, 0.0, 0.0))
        errors.append(np.abs(robot.foot_positions_world() - foot_position_body(q.reshape(4, 3), CFG)).max())
    assert max(errors) < 1e-3, f"max FK error {max(errors):.2e} m"


def test_reset_and_state_are_in_the_trunk_link_frame(robot):
    robot.reset(base_position=(0.3, -0.2, 0.5), base_yaw=0.7)
    state = robot.read_state()
    np.testing.assert_allclose(state.base_position, [0.3, -0.2, 0.5], atol=1e-9)
    np.testing.assert_allclose(state.base_rpy, [0.0, 0.0, 0.7], atol=1e-6)
    np.testing.assert_allclose(state.q, standing_joint_angles(CFG).reshape(12), atol=1e-12)
    assert np.all(state.dq == 0) and np.all(state.base_linear_velocity_world == 0)


def test_base_velocity_matches_finite_difference():
    # one physics step per `step` (controller period = physics step), so that Bullet's own integration rule holds
    with Robot(CFG, ActuatorConfig(), SimConfig(physics_dt=0.001, controller_dt=0.001)) as robot:
        _check_base_velocity(robot)


def _check_base_velocity(robot):
    robot.reset(base_position=(0.0, 0.0, 0.6))
    rng = np.random.default_rng(1)
    for _ in range(50):
        robot.step(rng.uniform(-5, 5, 12))  # tumble in the air to get angular velocity
    before = robot.read_state()
    robot.step(np.zeros(12))
    after = robot.read_state()
    # Bullet integrates semi-implicitly: x(t + dt) = x(t) + dt · v(t + dt)
    finite_difference = (after.base_position - before.base_position) / robot.dt
    assert np.linalg.norm(before.base_angular_velocity_world) > 0.1
    np.testing.assert_allclose(finite_difference, after.base_linear_velocity_world, atol=3e-4)
    rot = np.array(robot.client.getMatrixFromQuaternion(after.base_quaternion)).reshape(3, 3)
    np.testing.assert_allclose(rot @ after.base_linear_velocity_body, after.base_linear_velocity_world, atol=1e-12)
    np.testing.assert_allclose(rot @ after.base_angular_velocity_body, after.base_angular_velocity_world,
                               atol=1e-12)


def test_standing_touches_ground_with_feet_only(robot):
    """Joint PD hold of the standing pose for 1 s: only the four foot spheres carry the body."""
    robot.reset()
    q_stand = standing_joint_angles(CFG).reshape(12)
    for k in range(1000):
        state = robot.read_state()
        robot.step(60.0 * (q_stand - state.q) - 2.0 * state.dq)
        if k % 50 == 49:
            assert robot.ground_contact_links() <= FEET, robot.ground_contact_links()
    state = robot.read_state()
    assert robot.ground_contact_links() == FEET
    assert robot.foot_contacts().all()
    assert robot.foot_contact_forces().sum() == pytest.approx(robot.total_mass() * 9.81, rel=0.02)
    assert state.base_position[2] == pytest.approx(CFG.body_height, abs=0.025)
    assert np.abs(state.base_rpy[:2]).max() < 0.05


@pytest.mark.parametrize("x", [99.95, 150.0, 2000.0])
def test_the_ground_carries_the_robot_far_beyond_100_m(robot, x):
    """pybullet_data's plane ends at x = 100 m, where walks longer than 100 m fell off; the ground goes on to
    x = 2.1 km: standing there (and astride the seam at 100 m) the feet touch it and carry the body."""
    robot.reset(base_position=(x, 0.0, CFG.body_height + 0.02))
    q_stand = standing_joint_angles(CFG).reshape(12)
    for _ in range(400):  # 1 s
        state = robot.read_state()
        robot.step(60.0 * (q_stand - state.q) - 2.0 * state.dq)
    assert robot.foot_contacts().all()
    assert robot.read_state().base_position[2] == pytest.approx(CFG.body_height, abs=0.025)


def test_mass_scale(robot):
    nominal = robot.total_mass()
    robot.set_mass_scale(1.05)
    assert robot.total_mass() == pytest.approx(1.05 * nominal)
    robot.set_mass_scale(1.0)
    assert robot.total_mass() == pytest.approx(nominal)
    with pytest.raises(ValueError, match="mass scale"):
        robot.set_mass_scale(float("nan"))


def test_render_shape(robot):
    robot.reset()
    image = robot.render(64, 48)
    assert image.shape == (48, 64, 3) and image.dtype == np.uint8 and image.std() > 0
