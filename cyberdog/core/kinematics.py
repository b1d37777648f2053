"""Leg kinematics of the CyberDog: the paper's Eq. (1)–(6), in the URDF's frames. Pure numpy.

Frames and signs (as the URDF): x forward, y left, z up. Each leg has an abad joint about +x, a hip joint
about +y and a knee joint about +y; legs LF, RF, LH, RH. Zero angles: leg straight down. hip > 0 swings the
thigh backward, knee < 0 folds the calf forward (the knee points backward).

A foot position is given in the **leg frame**: origin at the abad joint, axes parallel to the body. In that
frame the hip joint sits at (0, s·l1, 0) with s = +1 for left legs and −1 for right legs.

Relation to the paper. Eq. (1)–(3) (swing phase, Table 1) are the full 3-joint forward and inverse
kinematics; Eq. (4)–(6) (support phase, Table 2) are the same leg with the lateral joint fixed at θ1 = 0,
i.e. the planar two-link problem in the sagittal plane. As printed they contain typos that make them
inconsistent with their own D–H tables, so they are re-derived here rather than transcribed:
- Eq. (1)/(2) put θ1 about the vertical axis (p_x ∝ c1) while the robot's θ1 is a roll about x; the rotation
  matrix's (1,2) entry "−c3 s23" should be "−c1 s23"; and a/2, b/2, h place the foot in the body frame, here
  done by adding the abad offset (`foot_position_body`).
- Eq. (3): D1 = sqrt((h − p_z)² + (p_y + b/2)² − l1) subtracts a length from a squared length; the correct
  term is sqrt(r² − l1²) with r the distance from the abad axis (`_sagittal_height`). D2 lacks its
  denominator 2·l2 (Eq. (6) has it). θ3 = arccos((p_x − a/2 − l2 s2)/l3) − θ2 only holds for one knee branch.
- Eq. (5) gives (p_x, p_y) where the planar support-phase problem is in (x, z).
The derivation below is the textbook two-link solution; it is checked against PyBullet's own forward
kinematics of the URDF in the tests (agreement within 1 mm).
"""
from __future__ import annotations

import math

import numpy as np

from cyberdog.config import RobotConfig

LEFT_RIGHT = np.array([1.0, -1.0, 1.0, -1.0])  # s per leg (LF, RF, LH, RH): +1 left, −1 right
_SIDES = tuple(float(v) for v in LEFT_RIGHT)  # the same, as floats for the per-period paths
FRONT_REAR = np.array([1.0, 1.0, -1.0, -1.0])  # +1 front legs, −1 hind legs


def abad_offsets(robot: RobotConfig) -> np.ndarray:
    """(4, 3) position of each abad joint in the body frame, m."""
    return np.stack([FRONT_REAR * robot.abad_offset_x, LEFT_RIGHT * robot.abad_offset_y, np.zeros(4)], axis=-1)


def _side(side: np.ndarray | float | None, shape: tuple) -> np.ndarray:
    """Broadcast the left/right sign to the batch shape of the joint or foot arrays (default: 4 legs)."""
    if side is None:
        side = LEFT_RIGHT
    return np.broadcast_to(np.asarray(side, dtype=float), shape)


# ---------------------------------------------------------------------------------------------------------
# Support phase (Eq. 4–6): planar two-link leg in the sagittal plane, θ1 = 0
# ---------------------------------------------------------------------------------------------------------

def sagittal_foot_position(hip: np.ndarray, knee: np.ndarray, l2: float, l3: float) -> tuple[np.ndarray, np.ndarray]:
    """Eq. (5), corrected: foot (x, z) relative to the hip joint for thigh angle `hip` and knee angle `knee`."""
    x = -l2 * np.sin(hip) - l3 * np.sin(hip + knee)
    z = -l2 * np.cos(hip) - l3 * np.cos(hip + knee)
    return x, z


class UnreachableFootTarget(ValueError):
    """A foot target outside the leg's reach (a ValueError): raised by the inverse kinematics; a walk whose trot
    asks for one ends there (`cyberdog.analysis.walk`)."""


def sagittal_inverse(x: np.ndarray, z: np.ndarray, l2: float, l3: float) -> tuple[np.ndarray, np.ndarray]:
    """Eq. (6), corrected: hip and knee angles (knee ≤ 0 branch) placing the foot at (x, z) from the hip.

    Law of cosines for the knee, then the hip as the direction to the foot plus the calf's offset angle.
    Raises ValueError if a target is outside the annulus |l2 − l3| ≤ d ≤ l2 + l3.
    """
    x = np.asarray(x, dtype=float)
    z = np.asarray(z, dtype=float)
    d2 = x * x + z * z
    cos_knee = (d2 - l2 * l2 - l3 * l3) / (2.0 * l2 * l3)
    bad = (cos_knee > 1.0 + 1e-12) | (cos_knee < -1.0 - 1e-12)
    if np.any(bad):
        d = np.sqrt(d2)[bad].ravel()[0]
        raise UnreachableFootTarget(
            f"unreachable foot target: distance {d:.4f} m from the hip; the leg reaches "
            f"{abs(l2 - l3):.4f} m to {l2 + l3:.4f} m (x={np.ravel(x[bad] if x.shape else x)[0]:.4f}, "
            f"z={np.ravel(z[bad] if z.shape else z)[0]:.4f})")
    knee = -np.arccos(np.clip(cos_knee, -1.0, 1.0))
    # u = (−x, −z) points from the hip to the foot measured from straight down; its angle from −z is
    # alpha = hip + atan2(l3 sin knee, l2 + l3 cos knee).
    alpha = np.arctan2(-x, -z)
    hip = alpha - np.arctan2(l3 * np.sin(knee), l2 + l3 * np.cos(knee))
    return hip, knee


# ---------------------------------------------------------------------------------------------------------
# Swing phase (Eq. 1–3): the full 3-joint leg
# ---------------------------------------------------------------------------------------------------------

def foot_position(q: np.ndarray, robot: RobotConfig, side: np.ndarray | None = None) -> np.ndarray:
    """Eq. (1)–(2), corrected: foot-sphere centre in the leg frame, for joint angles q (..., 3).

    Default batch: q of shape (4, 3), one row per leg (LF, RF, LH, RH). `side` (+1 left, −1 right) may be
    given for any other batch shape.
    """
    q = np.asarray(q, dtype=float)
    s = _side(side, q.shape[:-1])
    abad, hip, knee = q[..., 0], q[..., 1], q[..., 2]
    x, z_leg = sagittal_foot_position(hip, knee, robot.l2, robot.l3)
    y_leg = s * robot.l1
    c1, s1 = np.cos(abad), np.sin(abad)
    # rotation about x by the abad angle
    return np.stack([x, c1 * y_leg - s1 * z_leg, s1 * y_leg + c1 * z_leg], axis=-1)


def foot_position_body(q: np.ndarray, robot: RobotConfig) -> np.ndarray:
    """(4, 3) foot-sphere centres in the body frame (adds the abad offsets: the paper's a/2, b/2)."""
    return abad_offsets(robot) + foot_position(q, robot)


def _sagittal_height(y: np.ndarray, z: np.ndarray, l1: float) -> np.ndarray:
    """Signed length of the leg's projection in its own sagittal plane: −sqrt(y² + z² − l1²) (below the hip)."""
    r2 = y * y + z * z - l1 * l1
    return -np.sqrt(np.maximum(r2, 0.0))


def inverse_kinematics(p: np.ndarray, robot: RobotConfig, side: np.ndarray | None = None) -> np.ndarray:
    """Eq. (3), corrected: joint angles (..., 3) that put the foot at p (..., 3) in the leg frame.

    Chooses the knee ≤ 0 branch and the abad solution with the foot below the hip. Raises ValueError naming
    the target and the reach when a target cannot be reached.
    """
    p = np.asarray(p, dtype=float)
    s = _side(side, p.shape[:-1])
    x, y, z = p[..., 0], p[..., 1], p[..., 2]
    l1 = robot.l1
    r2 = y * y + z * z
    if np.any(r2 < l1 * l1 - 1e-12):
        i = np.argmin(np.ravel(r2 - l1 * l1))
        raise UnreachableFootTarget(
            f"unreachable foot target {np.reshape(p, (-1, 3))[i].round(4).tolist()} m: it lies "
            f"{np.sqrt(np.ravel(r2)[i]):.4f} m from the abad axis, closer than the abad offset l1 = {l1:.4f} m")
    z_leg = _sagittal_height(y, z, l1)
    # rotate (s·l1, z_leg) about x onto (y, z)
    abad = np.arctan2(z, y) - np.arctan2(z_leg, s * l1)
    abad = (abad + np.pi) % (2.0 * np.pi) - np.pi
    try:
        hip, knee = sagittal_inverse(x, z_leg, robot.l2, robot.l3)
    except ValueError as err:
        raise UnreachableFootTarget(
            f"unreachable foot target (leg frame) {np.round(p, 4).tolist()}: {err}") from None
    return np.stack([abad, hip, knee], axis=-1)


def jacobian(q: np.ndarray, robot: RobotConfig, side: np.ndarray | None = None) -> np.ndarray:
    """Foot-position Jacobian ∂p/∂q (..., 3, 3) in the leg frame, rows x, y, z and columns abad, hip, knee."""
    q = np.asarray(q, dtype=float)
    s = _side(side, q.shape[:-1])
    abad, hip, knee = q[..., 0], q[..., 1], q[..., 2]
    l1, l2, l3 = robot.l1, robot.l2, robot.l3
    c1, s1 = np.cos(abad), np.sin(abad)
    x, z_leg = sagittal_foot_position(hip, knee, l2, l3)
    # derivatives of the sagittal (x, z_leg) with respect to hip and knee
    dx_dhip = -l2 * np.cos(hip) - l3 * np.cos(hip + knee)
    dx_dknee = -l3 * np.cos(hip + knee)
    dz_dhip = l2 * np.sin(hip) + l3 * np.sin(hip + knee)
    dz_dknee = l3 * np.sin(hip + knee)
    y_leg = s * l1
    J = np.zeros(q.shape[:-1] + (3, 3))
    J[..., 0, 1] = dx_dhip
    J[..., 0, 2] = dx_dknee
    # y = c1·y_leg − s1·z_leg ; z = s1·y_leg + c1·z_leg
    J[..., 1, 0] = -s1 * y_leg - c1 * z_leg
    J[..., 2, 0] = c1 * y_leg - s1 * z_leg
    J[..., 1, 1] = -s1 * dz_dhip
    J[..., 1, 2] = -s1 * dz_dknee
    J[..., 2, 1] = c1 * dz_dhip
    J[..., 2, 2] = c1 * dz_dknee
    return J


# ---------------------------------------------------------------------------------------------------------
# One leg in plain Python floats: the same formulas as above, for the controller's per-period inner loop, where
# numpy's per-call overhead on (4, 3) arrays cost more than the arithmetic (about 10x). Tested against the
# array functions in tests/test_fast_paths.py.
# ---------------------------------------------------------------------------------------------------------
_sqrt, _atan2, _acos, _sin, _cos = math.sqrt, math.atan2, math.acos, math.sin, math.cos  # no attribute lookups
_PI, _TWO_PI = math.pi, 2.0 * math.pi


def leg_inverse_kinematics(x: float, y: float, z: float, side: float, l1: float, l2: float, l3: float
                           ) -> tuple[float, float, float]:
    """`inverse_kinematics` of one leg: (abad, hip, knee), rad, putting the foot at (x, y, z), m, leg frame.

    side: +1 left, −1 right; l1, l2, l3 the link lengths (m). Raises ValueError for an unreachable target
    (the array function's message names the reach; call it for the message).
    """
    return leg_inverse_kinematics_velocity(x, y, z, None, None, None, side, l1, l2, l3)


def leg_joint_velocity(abad: float, hip: float, knee: float, side: float, vx: float, vy: float, vz: float,
                       l1: float, l2: float, l3: float) -> tuple[float, float, float]:
    """J(q)⁻¹ v of one leg: joint speeds (rad/s) that move the foot at v = (vx, vy, vz), m/s, leg frame.

    Closed form of `np.linalg.solve(jacobian(q), v)`: the abad row pair is a rotation of the sagittal
    (x, z_leg) velocity, so the 3×3 system splits into the abad speed and a 2×2 sagittal system.
    Raises numpy.linalg.LinAlgError where J is singular (straight knee, or foot level with the abad axis).
    """
    return _leg_velocity(math.cos(abad), math.sin(abad), math.cos(hip), math.sin(hip), math.cos(hip + knee),
                         math.sin(hip + knee), side, vx, vy, vz, l1, l2, l3)


def _leg_velocity(c1: float, s1: float, c_h: float, s_h: float, c_hk: float, s_hk: float, side: float,
                  vx: float, vy: float, vz: float, l1: float, l2: float, l3: float) -> tuple[float, float, float]:
    """`leg_joint_velocity` from the cosines and sines of abad, hip and hip + knee."""
    z_leg = -l2 * c_h - l3 * c_hk
    dx_dhip, dx_dknee = -l2 * c_h - l3 * c_hk, -l3 * c_hk
    dz_dhip, dz_dknee = l2 * s_h + l3 * s_hk, l3 * s_hk
    det = dx_dhip * dz_dknee - dx_dknee * dz_dhip  # = −l2·l3·sin(knee)
    if z_leg == 0.0 or det == 0.0:
        raise np.linalg.LinAlgError("Singular matrix")
    # rows y, z of J: (J10, −s1·dz_dhip, −s1·dz_dknee), (J20, c1·dz_dhip, c1·dz_dknee);
    # c1·vy + s1·vz = −z_leg·dabad and −s1·vy + c1·vz = y_leg·dabad + (sagittal z_leg velocity)
    dabad = -(c1 * vy + s1 * vz) / z_leg
    vz_leg = -s1 * vy + c1 * vz - dabad * side * l1
    dhip = (vx * dz_dknee - dx_dknee * vz_leg) / det
    dknee = (dx_dhip * vz_leg - dz_dhip * vx) / det
    return dabad, dhip, dknee


def leg_inverse_kinematics_velocity(x: float, y: float, z: float, vx: float | None, vy: float | None,
                                    vz: float | None, side: float, l1: float, l2: float, l3: float
                                    ) -> tuple[float, ...]:
    """`leg_inverse_kinematics` and `leg_joint_velocity` in one call (the trot controller's per-period path, one
    function call per leg): (abad, hip, knee, dabad, dhip, dknee), rad and rad/s, for the foot at (x, y, z), m,
    moving at (vx, vy, vz), m/s, leg frame; with vx None the angles alone. Raises ValueError for an unreachable
    target."""
    r2 = y * y + z * z
    l1_sq = l1 * l1
    if r2 < l1_sq - 1e-12:
        raise UnreachableFootTarget(
            f"unreachable foot target {[x, y, z]}: closer to the abad axis than l1 = {l1} m")
    # min/max as conditional expressions (with the builtins' choice on ties and NaN): this runs 1,600 times a
    # simulated second, where a builtin call costs more than the comparison
    h2 = r2 - l1_sq
    z_leg = -_sqrt(0.0 if 0.0 > h2 else h2)  # _sagittal_height
    abad = _atan2(z, y) - _atan2(z_leg, side * l1)
    abad = (abad + _PI) % _TWO_PI - _PI
    # sagittal_inverse
    cos_knee = (x * x + z_leg * z_leg - l2 * l2 - l3 * l3) / (2.0 * l2 * l3)
    if cos_knee > 1.0 + 1e-12 or cos_knee < -1.0 - 1e-12:
        raise UnreachableFootTarget(f"unreachable foot target {[x, y, z]}: outside the leg's reach")
    cos_knee = -1.0 if -1.0 > cos_knee else cos_knee
    knee = -_acos(1.0 if 1.0 < cos_knee else cos_knee)
    hip = _atan2(-x, -z_leg) - _atan2(l3 * _sin(knee), l2 + l3 * _cos(knee))
    if vx is None:
        return abad, hip, knee
    hip_knee = hip + knee
    da, dh, dk = _leg_velocity(_cos(abad), _sin(abad), _cos(hip), _sin(hip), _cos(hip_knee), _sin(hip_knee), side,
                               vx, vy, vz, l1, l2, l3)
    return abad, hip, knee, da, dh, dk


def leg_jacobian_z_row(abad: float, hip: float, knee: float, side: float, l1: float, l2: float, l3: float
                       ) -> tuple[float, float, float]:
    """Row z of `jacobian` for one leg: ∂p_z/∂(abad, hip, knee), m/rad (Jᵀ(0, 0, f_z) = f_z · this row)."""
    c1, s1 = math.cos(abad), math.sin(abad)
    s_hk, c_hk = math.sin(hip + knee), math.cos(hip + knee)
    z_leg = -l2 * math.cos(hip) - l3 * c_hk
    return (c1 * (side * l1) - s1 * z_leg, c1 * (l2 * math.sin(hip) + l3 * s_hk), c1 * (l3 * s_hk))


def add_stance_weight_torque(tau: list[float], q: list[float], in_swing: list[bool], robot: RobotConfig,
                             weight: float) -> None:
    """The stance legs carry the body: τ += Jᵀ f per stance leg, f = (0, 0, −weight / n_stance) (N; virtual work:
    τ·q̇ = f·ṗ, f the force the foot exerts), added to tau (12 floats, N·m) in place; q as 12 floats, the legs'
    swing flags (4 bools). Only the stance legs' Jacobian rows are computed (the swing legs' terms are zeros;
    tests/oracles.py holds the array form)."""
    n = 4 - sum(in_swing)
    if n == 0:
        return
    f_z = -weight / n  # N, each stance foot's share of the weight, pushing down
    l1, l2, l3 = robot.l1, robot.l2, robot.l3
    for leg, swing in enumerate(in_swing):
        if not swing:
            i = 3 * leg
            row = leg_jacobian_z_row(q[i], q[i + 1], q[i + 2], _SIDES[leg], l1, l2, l3)
            for j in range(3):
                tau[i + j] += row[j] * f_z


def lateral_velocity_body(quaternion, linear_velocity_world) -> float:
    """m/s, the body-frame y velocity (row y of Rᵀ times v) in floats, without the matrix: row y of Rᵀ is
    column y of R, (s(xy − zw), 1 − s(x² + z²), s(yz + xw)) with s = 2 / |q|² for the quaternion q = (x, y, z, w)
    (as PyBullet's getMatrixFromQuaternion, which does not assume |q| = 1)."""
    x, y, z, w = quaternion
    vx, vy, vz = linear_velocity_world
    s = 2.0 / (x * x + y * y + z * z + w * w)
    return s * (x * y - z * w) * vx + (1.0 - s * (x * x + z * z)) * vy + s * (y * z + x * w) * vz


def joint_limits(robot: RobotConfig) -> tuple[np.ndarray, np.ndarray]:
    """(12,) lower and upper joint limits, rad, in joint order leg-major (LF abad, hip, knee, RF ...)."""
    lo = np.array([-robot.abad_limit, robot.hip_limit[0], robot.knee_limit[0]] * 4)
    hi = np.array([robot.abad_limit, robot.hip_limit[1], robot.knee_limit[1]] * 4)
    return lo, hi


def standing_joint_angles(robot: RobotConfig, height: float | None = None) -> np.ndarray:
    """(4, 3) joint angles with each foot straight below its hip joint at the body height above ground."""
    h = robot.body_height if height is None else height
    z = -(h - robot.foot_radius)
    feet = np.stack([np.zeros(4), LEFT_RIGHT * robot.l1, np.full(4, z)], axis=-1)
    return inverse_kinematics(feet, robot)
