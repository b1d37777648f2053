"""The robot's state as one read gives it: `StateReading` (plain floats, the controller's per-period path) and
`RobotState` (arrays). Body values are of the trunk's link frame (`cyberdog.sim.robot`)."""
from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import NamedTuple

import numpy as np

from cyberdog.core.kinematics import lateral_velocity_body
from cyberdog.sim.quiet import quiet_pybullet

with quiet_pybullet():  # without pybullet's build banner
    import pybullet


class StateReading(NamedTuple):
    """One read of the robot's state as PyBullet reports it, in plain floats (`Robot.read`): what the
    controller's per-period path uses, without building arrays. `RobotState.from_reading` makes the arrays."""

    time: float  # s, simulated time since the last reset
    q: list  # 12 joint angles, rad
    dq: list  # 12 joint velocities, rad/s
    base_position: tuple  # body origin in the world, m
    base_quaternion: tuple  # x y z w
    base_rpy: tuple  # roll, pitch, yaw, rad
    base_linear_velocity_world: tuple  # m/s
    base_angular_velocity_world: tuple  # rad/s


@dataclass(frozen=True)
class RobotState:
    """One snapshot of the robot, read after the last controller period.

    The rotation matrix and the body-frame velocities are computed on first access (then kept): most
    users need at most one of them. The controller's per-period path reads a `StateReading` instead.
    """

    time: float  # s, simulated time since the last reset
    q: np.ndarray  # (12,) joint angles, rad
    dq: np.ndarray  # (12,) joint velocities, rad/s
    base_position: np.ndarray  # (3,) body origin in the world, m
    base_quaternion: np.ndarray  # (4,) body orientation, x y z w
    base_rpy: np.ndarray  # (3,) roll, pitch, yaw, rad (PyBullet's convention)
    base_linear_velocity_world: np.ndarray  # (3,) m/s
    base_angular_velocity_world: np.ndarray  # (3,) rad/s

    @cached_property
    def rotation_matrix(self) -> np.ndarray:
        """(3, 3) body → world (v_world = R v_body), PyBullet's matrix of `base_quaternion`."""
        return np.array(pybullet.getMatrixFromQuaternion(self.base_quaternion.tolist())).reshape(3, 3)

    @cached_property
    def base_linear_velocity_body(self) -> np.ndarray:
        """(3,) m/s, in the body frame (Rᵀ v)."""
        return self.base_linear_velocity_world @ self.rotation_matrix

    @property
    def lateral_velocity_body(self) -> float:
        """m/s, the body-frame y velocity (= base_linear_velocity_body[1]), in floats (`lateral_velocity_body`)."""
        return lateral_velocity_body(self.base_quaternion.tolist(), self.base_linear_velocity_world.tolist())

    @classmethod
    def from_reading(cls, r: StateReading) -> "RobotState":
        """The snapshot of a `StateReading`, as arrays."""
        return cls(r.time, np.array(r.q), np.array(r.dq), np.array(r.base_position), np.array(r.base_quaternion),
                   np.array(r.base_rpy), np.array(r.base_linear_velocity_world),
                   np.array(r.base_angular_velocity_world))

    @cached_property
    def base_angular_velocity_body(self) -> np.ndarray:
        """(3,) rad/s, in the body frame (Rᵀ ω)."""
        return self.base_angular_velocity_world @ self.rotation_matrix
