"""What the robot of either physics engine shares: the robot's files, the checks of its settings, and the motor
drivers' loop in floats. No physics engine is imported here.

`EngineRobot` is the interface the simulation loop (`cyberdog.loop.walker.Walker`), the env and the scripted walks
use; `cyberdog.sim.robot.Robot` (PyBullet) and `cyberdog.sim.mujoco_robot.MujocoRobot` (MuJoCo) implement its
engine calls (`_advance`, `joint_lists`, `read`, the contacts, the mass and ground settings, `render`, `close`).
The drivers' law at every physics step (`drive`), the torque held over a controller period (`step`) and the
actuator law (`cyberdog.core.actuator.ActuatorModel`) are written once, here. All arrays are numpy, SI units;
joint arrays are (12,) in the order LF, RF, LH, RH × abad, hip, knee.
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from cyberdog.config import JOINT_NAMES, LEG_NAMES, ActuatorConfig, RobotConfig, SimConfig
from cyberdog.core.actuator import ActuatorModel
from cyberdog.core.drivers import JointCommand, driver_torque
from cyberdog.core.kinematics import foot_position_body, standing_joint_angles
from cyberdog.sim.state import RobotState, StateReading

# The robot's files ship inside the package (cyberdog/urdf/, package data in setup.cfg) so that an installed
# wheel can walk; the repository's top-level urdf/ links to them. The package folder rather than
# importlib.resources: the engines need a real file path, and pip installs packages unzipped.
PACKAGE_DIR = Path(__file__).resolve().parents[1]
REPO_ROOT = PACKAGE_DIR.parent  # a checkout's root; in an installed package, site-packages (never a match)
SPAWN_CLEARANCE = 0.002  # m, default base height above robot.body_height so the feet start just off the ground
N_JOINTS = len(LEG_NAMES) * len(JOINT_NAMES)
JOINT_ORDER = [f"{leg}_{j}_joint" for leg in LEG_NAMES for j in JOINT_NAMES]  # names of tools/make_urdf.py
FOOT_LINKS = [f"{leg}_foot" for leg in LEG_NAMES]


def resolve_path(path: str) -> Path:
    """An absolute path as given. A relative one (the default "urdf/cyberdog.urdf") is the package's shipped
    file of that name if there is one, else relative to the repository root (a checkout's own files)."""
    p = Path(path)
    if p.is_absolute():
        return p
    shipped = PACKAGE_DIR / p
    return shipped if shipped.is_file() else REPO_ROOT / p


def rest_pose(robot: RobotConfig, joint_angles=None, base_position=None, base_yaw: float = 0.0) -> tuple:
    """(12 joint angles, body origin (3 floats), body quaternion x y z w) of a robot put at rest: the standing
    pose at robot.body_height (+ 2 mm) unless given; ValueError for angles or a position that are not finite."""
    if joint_angles is None:
        q = standing_joint_angles(robot).reshape(N_JOINTS)
    else:
        q = np.asarray(joint_angles, dtype=float).reshape(-1)
        if q.shape != (N_JOINTS,) or not np.all(np.isfinite(q)):
            raise ValueError(f"joint_angles must be {N_JOINTS} finite angles (rad), got {joint_angles!r}")
    if base_position is None:
        base_position = (0.0, 0.0, robot.body_height + SPAWN_CLEARANCE)
    pos = np.asarray(base_position, dtype=float)
    if pos.shape != (3,) or not np.all(np.isfinite(pos)) or not math.isfinite(base_yaw):
        raise ValueError(f"base_position must be 3 finite numbers (m) and base_yaw finite, "
                         f"got {base_position!r}, {base_yaw!r}")
    quat = (0.0, 0.0, math.sin(base_yaw / 2.0), math.cos(base_yaw / 2.0))
    return q.tolist(), pos.tolist(), quat


GEOMETRY_TOLERANCE_M = 1e-3  # a foot's position, or its radius, by the URDF and by RobotConfig
MODEL_MASS_TOLERANCE = 1e-3  # RobotConfig.total_mass within 0.1 % of the URDF's links (13.573 of 13.577 kg)


class EngineRobot:
    """The CyberDog on a flat plane in one physics engine, driven by joint torques set at every physics step.

    A subclass calls `super().__init__` first, builds its world and implements the methods below that raise
    NotImplementedError: reset, one physics step (`_advance`), the reads, the contacts, the settings' engine
    calls, `render` and `_release`."""

    def __init__(self, robot: RobotConfig, actuator: ActuatorConfig, sim: SimConfig):
        for name, value, cls in (("robot", robot, RobotConfig), ("actuator", actuator, ActuatorConfig),
                                 ("sim", sim, SimConfig)):
            if not isinstance(value, cls):
                raise TypeError(f"{type(self).__name__}({name}=...) must be a {cls.__name__}, "
                                f"got {type(value).__name__}")
        self.urdf = resolve_path(robot.urdf)
        if not self.urdf.is_file():
            raise FileNotFoundError(f"RobotConfig.urdf = {robot.urdf!r}: no file {self.urdf} (a relative path is "
                                    f"looked up in {PACKAGE_DIR}, then {REPO_ROOT}; the shipped robot is "
                                    f"urdf/cyberdog.urdf, regenerated by python tools/make_urdf.py)")
        self.robot_config, self.actuator_config, self.sim_config = robot, actuator, sim
        self.actuator = ActuatorModel(actuator)
        self.dt = sim.controller_dt  # s, one `step`
        self.physics_dt = sim.physics_dt  # s, one `physics_step`
        self.substeps = sim.physics_substeps  # physics steps per `step`
        self.joint_names = list(JOINT_ORDER)
        self.ground_friction = sim.ground_friction  # foot–ground coefficient now (set_ground_friction)
        self.mass_scale = 1.0  # every link's mass and inertia × this (set_mass_scale)
        self.physics_steps = 0  # since the last reset
        self._closed = False

    # ---- the engine's part ----------------------------------------------------------------------------------
    def reset(self, joint_angles: np.ndarray | None = None, base_position=None, base_yaw: float = 0.0) -> None:
        """Put the robot at rest: joint angles (12,) (default: standing pose at robot.body_height), body origin
        at base_position (default (0, 0, body_height + 2 mm)) with yaw base_yaw (rad); all velocities zero
        (`rest_pose`); `time` restarts at 0."""
        raise NotImplementedError

    def _advance(self, joint_torque: list) -> None:
        """One physics step with these 12 joint torques (N·m) acting over it."""
        raise NotImplementedError

    def _set_step(self, physics_dt: float) -> None:
        raise NotImplementedError

    def _set_friction(self, coefficient: float) -> None:
        raise NotImplementedError

    def _scale_masses(self, scale: float) -> None:
        """Every link's mass and inertia × `scale` of the URDF's."""
        raise NotImplementedError

    def _foot_radius(self) -> float:
        """m, the foot sphere's radius as the engine holds it (every foot's: the URDF's)."""
        raise NotImplementedError

    def _carry_payload(self, body_ratio: float) -> None:
        """The trunk's mass and inertia × `body_ratio` of the URDF's (its nominal ones, which mass scales scale)."""
        raise NotImplementedError

    def _settle_model(self) -> None:
        """Refuse a `RobotConfig` that is not the URDF's model (`model_mismatch`; the engine closed first), then
        put `RobotConfig.payload` on the body: at its centre of mass, spread as the body's own mass is (the
        trunk's inertia × the trunk's mass ratio)."""
        problem = self.model_mismatch()
        if problem:
            self.close()
            raise ValueError(problem)
        payload = self.robot_config.payload
        if payload > 0:
            self._carry_payload((self._trunk_mass() + payload) / self._trunk_mass())

    def _trunk_mass(self) -> float:
        """kg, the trunk link's mass in the URDF."""
        raise NotImplementedError

    def model_mismatch(self) -> str:
        """"" where `RobotConfig` states this URDF's model, else one line on what differs: total_mass (the links'
        sum, within 0.1 %), the leg geometry (abad offsets, l1, l2, l3: in two poses, the body at the origin, each
        foot where `cyberdog.core.kinematics` puts it, within 1 mm) and foot_radius. These settings are what the
        trot's weight feed-forward, kinematics and stand height read; they do not change the body."""
        cfg, name = self.robot_config, self.urdf.name
        links_mass = self.total_mass()
        if abs(links_mass - cfg.total_mass) > MODEL_MASS_TOLERANCE * cfg.total_mass:
            return (f"RobotConfig.total_mass = {cfg.total_mass} kg, but {name}'s links weigh {links_mass:.3f} kg: "
                    "total_mass states the URDF's mass; to walk a heavier robot set robot.payload (kg on the body)")
        stand = standing_joint_angles(cfg).reshape(4, 3)
        for q in (stand, stand + np.array([0.2, 0.3, -0.3])):
            self.reset(q, base_position=(0.0, 0.0, 0.0))
            error = float(np.abs(self.foot_positions_world() - foot_position_body(q, cfg)).max())
            if error > GEOMETRY_TOLERANCE_M:
                return (f"RobotConfig's leg geometry (abad_offset_x/y, l1, l2, l3) is not {name}'s: a foot sits "
                        f"{1e3 * error:.1f} mm from where it puts it; these settings state the URDF's legs: for "
                        "another robot point robot.urdf at its URDF and set them to its geometry")
        if abs(self._foot_radius() - cfg.foot_radius) > GEOMETRY_TOLERANCE_M:
            return (f"RobotConfig.foot_radius = {cfg.foot_radius} m, but {name}'s foot spheres are "
                    f"{self._foot_radius():.4f} m: foot_radius states the URDF's feet")
        return ""

    def joint_lists(self) -> tuple[list, list]:
        """(q, dq) as 12 floats each, read now and cached until the next step or reset (do not modify)."""
        raise NotImplementedError

    def read(self) -> StateReading:
        """Joint and body state in plain floats (the controller's per-period read). Body values are of the trunk's
        URDF link frame (the body frame of `cyberdog.core.kinematics`): its origin's position and velocity in
        the world, its quaternion (x y z w), roll/pitch/yaw (R = Rz Ry Rx), its angular velocity in the world."""
        raise NotImplementedError

    def base_pose(self) -> tuple[np.ndarray, np.ndarray]:
        """Position (3,) and quaternion (x y z w) of the trunk's link frame (the body frame) in the world."""
        raise NotImplementedError

    def foot_contacts(self) -> np.ndarray:
        """(4,) bool: each foot (LF, RF, LH, RH) touched the ground over the last physics step."""
        raise NotImplementedError

    def foot_contact_forces(self) -> np.ndarray:
        """(4,) normal force of the ground on each foot over the last physics step, N (0 in the air)."""
        raise NotImplementedError

    def ground_contact_links(self) -> set[str]:
        """Names of the robot's links touching the ground (in a healthy gait: feet only)."""
        raise NotImplementedError

    def foot_positions_world(self) -> np.ndarray:
        """(4, 3) foot-sphere centres in the world, m."""
        raise NotImplementedError

    def total_mass(self) -> float:
        """Sum of the link masses as the engine holds them, kg."""
        raise NotImplementedError

    def render(self, width: int = 320, height: int = 240, distance: float = 1.2, yaw_deg: float = 45.0,
               pitch_deg: float = -20.0) -> np.ndarray:
        """(height, width, 3) uint8 RGB image from a camera `distance` m from the body, looking at it from
        `yaw_deg` about the vertical and `pitch_deg` (< 0: from above)."""
        raise NotImplementedError

    def _release(self) -> None:
        """The engine's world let go (`close`, once)."""
        raise NotImplementedError

    @property
    def foot_link_names(self) -> list[str]:
        """Names of the four foot links, LF, RF, LH, RH."""
        return list(FOOT_LINKS)

    def close(self) -> None:
        if not self._closed:
            self._closed = True
            self._release()

    # ---- stepping -------------------------------------------------------------------------------------------
    def physics_step(self, torque_command: list) -> list:
        """Apply joint torque commands (12 numbers, N·m, a list) for one physics step (`physics_dt`) and return
        the motor torque applied, as 12 floats: what the joints received over the step (with joint friction,
        if on, added to what reaches them but not to the returned torque).

        The actuator model clips the command and applies the torque–speed envelope at the joint velocities
        now. The law runs in Python floats: 12 values are too few for numpy's call overhead."""
        if type(torque_command) is not list or len(torque_command) != N_JOINTS:
            raise ValueError(f"torque_command must be a list of {N_JOINTS} numbers, got {torque_command!r}")
        if not math.isfinite(sum(torque_command)) and not all(map(math.isfinite, torque_command)):
            raise ValueError(f"torque_command must be finite, got {torque_command!r}")
        motor, joint = self.actuator.joint_torque(torque_command, self.joint_lists()[1])
        self._advance(joint)
        self.physics_steps += 1
        return motor

    def drive(self, command: JointCommand | None, added: list | None = None, damping: float = 0.0) -> tuple:
        """One controller period under the motor drivers: at each of its `substeps` physics steps, their torque on
        the joint state then (`cyberdog.core.drivers.driver_torque` of `command`, None: no command yet, zero;
        plus `added`, 12 floats N·m held over the period; minus `damping` N·m·s/rad × q̇), then `physics_step`'s
        actuator law and one engine step. Returns (the motor torque applied over each physics step, the
        joint angles after each): `substeps` lists of 12 floats each. The per-step path, in floats."""
        limit, act, advance, read = self.actuator.torque_limit, self.actuator.joint_torque, self._advance, \
            self.joint_lists
        isfinite = math.isfinite
        q, dq = read()
        taus, angles = [], []
        for _ in range(self.substeps):
            tau = driver_torque(command, q, dq, limit) if command is not None else [0.0] * N_JOINTS
            if added is not None:
                tau = [a + b for a, b in zip(tau, added)]
            if damping:
                tau = [t - damping * w for t, w in zip(tau, dq)]
            if not isfinite(sum(tau)):
                raise ValueError(f"torque_command must be finite, got {tau!r}")
            motor, joint = act(tau, dq)
            advance(joint)
            taus.append(motor)
            q, dq = read()
            angles.append(q)
        self.physics_steps += self.substeps
        return taus, angles

    def step(self, torque_command: np.ndarray | list) -> list:
        """Hold joint torque commands (12,) N·m (an array, or a list of 12 numbers) over one controller period
        (`dt`: `substeps` physics steps, the actuator law at each); return the motor torque applied, the
        period's mean, as 12 floats. For callers that hold a torque; the walker's drivers use `drive`."""
        if type(torque_command) is list and len(torque_command) != N_JOINTS:
            raise ValueError(f"torque_command must hold {N_JOINTS} numbers, got {len(torque_command)}")
        tau = np.asarray(torque_command, dtype=float)
        if tau.shape != (N_JOINTS,):
            raise ValueError(f"torque_command must have shape ({N_JOINTS},), got {tau.shape}")
        applied = [self.physics_step(tau.tolist()) for _ in range(self.substeps)]
        return [sum(column) / self.substeps for column in zip(*applied)]

    @property
    def time(self) -> float:
        """Simulated time since the last reset, s."""
        return self.physics_steps * self.physics_dt

    # ---- settings -------------------------------------------------------------------------------------------
    def set_physics_dt(self, physics_dt: float) -> None:
        """Step the physics at `physics_dt` s from the next step on, a whole fraction of the controller period
        (a walk's robot drawn with other gains than the configured one: `Walker.reset`)."""
        n = int(round(self.dt / physics_dt))
        if not (n >= 1 and abs(n * physics_dt - self.dt) <= 1e-9 * self.dt):
            raise ValueError(f"physics_dt must divide the controller period {self.dt} s, got {physics_dt!r}")
        self._set_step(float(physics_dt))
        self.physics_dt, self.substeps = float(physics_dt), n

    def set_ground_friction(self, coefficient: float) -> None:
        """The foot–ground Coulomb coefficient: exactly `coefficient` (each engine's combination rule set so)."""
        if not (math.isfinite(coefficient) and 0.0 < coefficient <= 5.0):
            raise ValueError(f"ground friction must be in (0, 5], got {coefficient!r}")
        self._set_friction(float(coefficient))
        self.ground_friction = float(coefficient)

    def set_mass_scale(self, scale: float) -> None:
        """Scale every link's mass and inertia by `scale` relative to the URDF (e.g. 0.95..1.05)."""
        if not (math.isfinite(scale) and 0.5 <= scale <= 2.0):
            raise ValueError(f"mass scale must be in [0.5, 2.0], got {scale!r}")
        if scale != self.mass_scale:  # (unchanged: nothing to do)
            self._scale_masses(float(scale))
        self.mass_scale = float(scale)

    # ---- reads ----------------------------------------------------------------------------------------------
    def joint_angles(self) -> np.ndarray:
        return np.array(self.joint_lists()[0])

    def joint_velocities(self) -> np.ndarray:
        return np.array(self.joint_lists()[1])

    def read_state(self) -> RobotState:
        """Joint and body state as arrays (a `RobotState`); body values are of the trunk's link frame."""
        return RobotState.from_reading(self.read())

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        self.close()
