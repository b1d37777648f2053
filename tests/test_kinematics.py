"""Leg kinematics (paper Eq. 1-6): round trips, Jacobian, support-phase special case, error paths."""
import numpy as np
import pytest

from cyberdog.config import RobotConfig
from cyberdog.core import kinematics as kin

ROBOT = RobotConfig()


def random_joint_angles(rng, n):
    """n × 4 legs of joint angles inside the joint limits (knee away from the straight-leg singularity)."""
    abad = rng.uniform(-ROBOT.abad_limit, ROBOT.abad_limit, (n, 4))
    hip = rng.uniform(-1.5, 2.5, (n, 4))
    knee = rng.uniform(ROBOT.knee_limit[0], ROBOT.knee_limit[1], (n, 4))
    return np.stack([abad, hip, knee], axis=-1)


def test_ik_of_fk_round_trips():
    q = random_joint_angles(np.random.default_rng(0), 500)
    # the IK returns the branch with the foot below the hip (walking poses); keep those samples
    _, z_leg = kin.sagittal_foot_position(q[..., 1], q[..., 2], ROBOT.l2, ROBOT.l3)
    q = q[np.all(z_leg < -0.02, axis=1)]
    assert len(q) > 100
    p = kin.foot_position(q, ROBOT, side=np.broadcast_to(kin.LEFT_RIGHT, q.shape[:-1]))
    q_back = kin.inverse_kinematics(p, ROBOT, side=np.broadcast_to(kin.LEFT_RIGHT, q.shape[:-1]))
    assert np.max(np.abs(q_back - q)) < 1e-6


def test_fk_of_ik_reaches_target():
    rng = np.random.default_rng(1)
    feet = np.stack([rng.uniform(-0.15, 0.15, 4), kin.LEFT_RIGHT * ROBOT.l1 + rng.uniform(-0.03, 0.03, 4),
                     rng.uniform(-0.33, -0.15, 4)], axis=-1)
    q = kin.inverse_kinematics(feet, ROBOT)
    assert np.allclose(kin.foot_position(q, ROBOT), feet, atol=1e-9)
    assert np.all(q[:, 2] <= 0), "knee must stay on the knee-backward branch"


def test_jacobian_matches_finite_differences():
    q = random_joint_angles(np.random.default_rng(2), 50)
    side = np.broadcast_to(kin.LEFT_RIGHT, q.shape[:-1])
    J = kin.jacobian(q, ROBOT, side=side)
    eps = 1e-6
    for j in range(3):
        dq = np.zeros(3)
        dq[j] = eps
        numeric = (kin.foot_position(q + dq, ROBOT, side) - kin.foot_position(q - dq, ROBOT, side)) / (2 * eps)
        assert np.allclose(J[..., :, j], numeric, atol=1e-8)


def test_support_phase_is_the_planar_leg():
    """Eq. (4)-(6): with theta1 = 0 the full kinematics reduces to the sagittal two-link leg."""
    rng = np.random.default_rng(3)
    hip, knee = rng.uniform(-1, 2, 20), rng.uniform(-2.4, -0.8, 20)
    q = np.stack([np.zeros(20), hip, knee], axis=-1)
    p = kin.foot_position(q, ROBOT, side=np.ones(20))
    x, z = kin.sagittal_foot_position(hip, knee, ROBOT.l2, ROBOT.l3)
    assert np.allclose(p[:, 0], x) and np.allclose(p[:, 2], z) and np.allclose(p[:, 1], ROBOT.l1)
    hip2, knee2 = kin.sagittal_inverse(x, z, ROBOT.l2, ROBOT.l3)
    assert np.allclose(hip2, hip) and np.allclose(knee2, knee)


def test_standing_pose_puts_feet_under_hips_at_body_height():
    q = kin.standing_joint_angles(ROBOT)
    feet = kin.foot_position_body(q, ROBOT)
    assert np.allclose(feet[:, 2], -(ROBOT.body_height - ROBOT.foot_radius))
    assert np.allclose(feet[:, 0], kin.abad_offsets(ROBOT)[:, 0])
    lo, hi = kin.joint_limits(ROBOT)
    assert np.all(q.ravel() >= lo) and np.all(q.ravel() <= hi)


@pytest.mark.parametrize("target", [[0.0, 0.105, -0.45], [0.3, 0.105, -0.3], [0.0, 0.105, -0.001]])
def test_unreachable_target_raises_naming_reach(target):
    feet = np.tile(np.array(target), (4, 1)) * np.array([1, 1, 1])
    feet[:, 1] = kin.LEFT_RIGHT * abs(target[1])
    with pytest.raises(ValueError, match="unreachable foot target"):
        kin.inverse_kinematics(feet, ROBOT)
