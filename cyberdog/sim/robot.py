"""The CyberDog in its own PyBullet world: loading, joint map, torque stepping, state reads.

One `Robot` owns one `BulletClient` (never the global connection), the ground (`urdf/ground.urdf`) and the
robot: with its state types (`cyberdog.sim.state`), the only place in the project where pybullet is called. The
drivers' loop, the torque hold and the actuator law are the engines' shared part (`cyberdog.sim.engine.EngineRobot`,
also under `cyberdog.sim.mujoco_robot.MujocoRobot`). Facts it relies on (measured, `docs/robot.md`):

- TORQUE_CONTROL lasts for ONE stepSimulation, and repeated calls within a step add up: `physics_step`
  applies the torque exactly once and steps once. The default velocity motors are disabled at load.
- One stepSimulation is one physics step (`SimConfig.physics_dt`, fixedTimeStep with numSubSteps = 1), so
  that the motor drivers can set a new torque at every physics step from the joint state then
  (`cyberdog.loop.walker.Walker`, `cyberdog.core.drivers`): the torque `physics_step` returns is the one the
  joints received over that step. `step` holds one torque over a controller period (`SimConfig.controller_dt`,
  `physics_substeps` physics steps; the same joint states, bit for bit, as PyBullet's numSubSteps over the
  period: tests/test_control_rate.py), for callers without drivers.
- PyBullet enforces neither the URDF effort nor velocity limits under torque control: the clip and the
  torque–speed envelope are applied by `cyberdog.core.actuator.ActuatorModel`.
- getJointStates reports no applied torque under TORQUE_CONTROL: `physics_step` and `drive` return the motor torque
  they applied.
- The URDF is loaded with URDF_USE_INERTIA_FROM_FILE (otherwise inertia is recomputed from the collision
  shapes) and reset by setting state, not by reloading (0.5 s).
- PyBullet's "base pose" (get/resetBasePositionAndOrientation, getBaseVelocity) is the pose of the trunk's
  INERTIAL frame: its centre of mass, rotated onto the principal axes of inertia (about 1.1 deg of pitch for
  this trunk). Every base pose and velocity in this class is converted to the trunk's URDF link frame (the
  body frame of `cyberdog.core.kinematics`), both when read and when reset.

- PyBullet's GUI connection calls the C `exit()` when it cannot open an X display (no exception, the
  interpreter just ends): `gui=True` is checked first (`display_problem`) and falls back to a DIRECT
  connection, without a window, with a warning.

Friction: Bullet multiplies the two bodies' friction coefficients, so every robot link gets lateral friction
1.0 and the plane gets `SimConfig.ground_friction`; the foot–ground coefficient is then exactly that value.
All arrays are numpy, SI units; joint arrays are (12,) in the order LF, RF, LH, RH × abad, hip, knee.
"""
from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np

from cyberdog.config import ActuatorConfig, RobotConfig, SimConfig
from cyberdog.sim.display import display_problem
from cyberdog.sim.engine import (FOOT_LINKS, JOINT_ORDER, N_JOINTS, PACKAGE_DIR, REPO_ROOT,  # noqa: F401
                                 SPAWN_CLEARANCE, EngineRobot, resolve_path, rest_pose)
from cyberdog.sim.quiet import quiet_pybullet
from cyberdog.sim.state import RobotState, StateReading  # noqa: F401  (the state types, re-exported here)

with quiet_pybullet():  # without pybullet's build banner
    import pybullet
    import pybullet_data
    from pybullet_utils.bullet_client import BulletClient

GROUND_URDF = "ground.urdf"  # in PACKAGE_DIR / "urdf": pybullet_data's plane, extended ahead (see the file)


class Robot(EngineRobot):
    """CyberDog on a flat plane, driven by joint torques set at every physics step (see the module docstring)."""

    def __init__(self, robot: RobotConfig, actuator: ActuatorConfig, sim: SimConfig, gui: bool = False):
        super().__init__(robot, actuator, sim)
        urdf = self.urdf
        if gui:
            problem = display_problem()
            if problem:
                warnings.warn(f"no window for the simulation: {problem}; running without one (PyBullet DIRECT). "
                              f"Set DISPLAY to a reachable X server to watch it", RuntimeWarning, stacklevel=3)
                gui = False
        self.gui = gui  # whether a PyBullet window is open
        with quiet_pybullet():  # without the "argv[0]=" line of every connection
            self.client = BulletClient(connection_mode=pybullet.GUI if gui else pybullet.DIRECT)
        c = self.client
        c.setGravity(0.0, 0.0, -sim.gravity)
        c.setPhysicsEngineParameter(fixedTimeStep=sim.physics_dt, numSubSteps=1,
                                    numSolverIterations=sim.solver_iterations, deterministicOverlappingPairs=1)
        self.plane_id = c.loadURDF(str(PACKAGE_DIR / "urdf" / GROUND_URDF), useFixedBase=True)
        # what the camera sees of the ground: pybullet_data's plane.urdf, its checkered look, colliding with nothing
        ground_look = c.loadURDF(str(Path(pybullet_data.getDataPath()) / "plane.urdf"), useFixedBase=True)
        c.setCollisionFilterGroupMask(ground_look, -1, 0, 0)
        c.changeDynamics(self.plane_id, -1, lateralFriction=sim.ground_friction)
        self.body_id = c.loadURDF(str(urdf), [0.0, 0.0, robot.body_height], flags=pybullet.URDF_USE_INERTIA_FROM_FILE)

        self._map_links(urdf)
        self._prepare_dynamics()

        # bound functions for the per-step path (BulletClient's __getattr__ costs a lookup per call)
        self._set_motors = c.setJointMotorControlArray
        self._step_simulation = c.stepSimulation
        self._get_joint_states = c.getJointStates
        self._get_base_pose = c.getBasePositionAndOrientation
        self._get_base_velocity = c.getBaseVelocity
        self._get_euler = c.getEulerFromQuaternion
        self._multiply_transforms = c.multiplyTransforms
        self._joint_cache: tuple[list, list] | None = None  # (q, dq) as floats, until the next step or reset
        self._settle_model()
        self.reset()

    def _map_links(self, urdf: Path) -> None:
        """Link names by index, the twelve joints and the four feet in leg-major order (names of make_urdf)."""
        c = self.client
        self.link_names = {-1: c.getBodyInfo(self.body_id)[0].decode()}
        joint_by_name = {}
        for i in range(c.getNumJoints(self.body_id)):
            info = c.getJointInfo(self.body_id, i)
            joint_by_name[info[1].decode()] = i
            self.link_names[i] = info[12].decode()
        link_by_name = {name: i for i, name in self.link_names.items()}
        try:
            self.joint_ids = [joint_by_name[name] for name in JOINT_ORDER]
            self.foot_link_ids = [link_by_name[name] for name in FOOT_LINKS]
        except KeyError as err:
            raise ValueError(f"{urdf}: missing joint or link {err}; expected the names of tools/make_urdf.py") from None

    def _prepare_dynamics(self) -> None:
        """No default velocity motors, no damping, unit link friction (see the module docstring); the nominal
        masses and the body's inertial frame."""
        c = self.client
        c.setJointMotorControlArray(self.body_id, self.joint_ids, pybullet.VELOCITY_CONTROL, forces=[0.0] * N_JOINTS)
        for link in self.link_names:
            c.changeDynamics(self.body_id, link, linearDamping=0.0, angularDamping=0.0, jointDamping=0.0,
                             lateralFriction=1.0)
        self._nominal_dynamics = {}  # link → (mass, principal inertia diagonal) as loaded
        for link in self.link_names:
            info = c.getDynamicsInfo(self.body_id, link)
            self._nominal_dynamics[link] = (info[0], info[2])
        inertial_pos, inertial_orn = c.getDynamicsInfo(self.body_id, -1)[3:5]  # inertial frame in the link frame
        self._link_to_inertial = (inertial_pos, inertial_orn)
        self._inertial_to_link = c.invertTransform(inertial_pos, inertial_orn)

    # ------------------------------------------------------------------------------------------------------
    # reset and step
    # ------------------------------------------------------------------------------------------------------

    def reset(self, joint_angles: np.ndarray | None = None, base_position=None, base_yaw: float = 0.0) -> None:
        """`EngineRobot.reset`: the link-frame pose moved to the inertial frame PyBullet's base pose is."""
        q, pos, quat = rest_pose(self.robot_config, joint_angles, base_position, base_yaw)
        c = self.client
        com_pos, com_quat = c.multiplyTransforms(pos, quat, *self._link_to_inertial)
        c.resetBasePositionAndOrientation(self.body_id, com_pos, com_quat)
        c.resetBaseVelocity(self.body_id, [0.0, 0.0, 0.0], [0.0, 0.0, 0.0])
        for j, angle in zip(self.joint_ids, q):
            c.resetJointState(self.body_id, j, angle, 0.0)
        self._joint_cache = None
        self.physics_steps = 0

    def _set_step(self, physics_dt: float) -> None:
        self.client.setPhysicsEngineParameter(fixedTimeStep=physics_dt)

    def _advance(self, joint_torque: list) -> None:
        """One stepSimulation with the joint torques applied once (TORQUE_CONTROL lasts for one step)."""
        self._set_motors(self.body_id, self.joint_ids, pybullet.TORQUE_CONTROL, forces=joint_torque)
        self._step_simulation()
        self._joint_cache = None

    # ------------------------------------------------------------------------------------------------------
    # state reads
    # ------------------------------------------------------------------------------------------------------

    def joint_lists(self) -> tuple[list, list]:
        """(q, dq) as 12 floats each from one getJointStates call, cached until the next step or reset (do not
        modify)."""
        if self._joint_cache is None:
            states = self._get_joint_states(self.body_id, self.joint_ids)
            self._joint_cache = ([s[0] for s in states], [s[1] for s in states])
        return self._joint_cache

    def base_pose(self) -> tuple[np.ndarray, np.ndarray]:
        pos, quat = self._multiply_transforms(*self._get_base_pose(self.body_id), *self._inertial_to_link)
        return np.array(pos), np.array(quat)

    def read(self) -> StateReading:
        """`EngineRobot.read`: PyBullet's base pose and velocity moved from the inertial to the link frame."""
        q, dq = self.joint_lists()
        com_pos, com_quat = self._get_base_pose(self.body_id)
        pos, quat = self._multiply_transforms(com_pos, com_quat, *self._inertial_to_link)
        lin_com, ang = self._get_base_velocity(self.body_id)
        # velocity of the link-frame origin: v_com + ω × (p_link − p_com) (np.cross is slow on 3-vectors)
        rx, ry, rz = pos[0] - com_pos[0], pos[1] - com_pos[1], pos[2] - com_pos[2]
        wx, wy, wz = ang
        lin = (lin_com[0] + wy * rz - wz * ry, lin_com[1] + wz * rx - wx * rz, lin_com[2] + wx * ry - wy * rx)
        return StateReading(self.physics_steps * self.physics_dt, q, dq, pos, quat, self._get_euler(quat), lin, ang)

    def _ground_contacts(self) -> list:
        return self.client.getContactPoints(bodyA=self.body_id, bodyB=self.plane_id)

    def foot_contacts(self) -> np.ndarray:
        touching = {pt[3] for pt in self._ground_contacts()}
        return np.array([link in touching for link in self.foot_link_ids])

    def foot_contact_forces(self) -> np.ndarray:
        """`EngineRobot.foot_contact_forces`: PyBullet's contact impulse divided by fixedTimeStep, the physics
        step (measured: a standing robot's feet carry m·g)."""
        force = dict.fromkeys(self.foot_link_ids, 0.0)
        for pt in self._ground_contacts():
            if pt[3] in force:
                force[pt[3]] += pt[9]
        return np.array([force[link] for link in self.foot_link_ids])

    def ground_contact_links(self) -> set[str]:
        return {self.link_names[pt[3]] for pt in self._ground_contacts()}

    def foot_positions_world(self) -> np.ndarray:
        states = self.client.getLinkStates(self.body_id, self.foot_link_ids, computeForwardKinematics=1)
        return np.array([s[4] for s in states])

    def total_mass(self) -> float:
        """Sum of the link masses as PyBullet holds them, kg."""
        return float(sum(self.client.getDynamicsInfo(self.body_id, link)[0] for link in self.link_names))

    def _set_friction(self, coefficient: float) -> None:
        """The plane's lateral friction: every robot link has 1.0, and Bullet multiplies the two."""
        self.client.changeDynamics(self.plane_id, -1, lateralFriction=coefficient)

    def _foot_radius(self) -> float:
        return float(self.client.getCollisionShapeData(self.body_id, self.foot_link_ids[0])[0][3][0])

    def _trunk_mass(self) -> float:
        return float(self._nominal_dynamics[-1][0])

    def _carry_payload(self, body_ratio: float) -> None:
        mass, inertia = self._nominal_dynamics[-1]
        self._nominal_dynamics[-1] = (mass * body_ratio, tuple(i * body_ratio for i in inertia))
        self._scale_masses(self.mass_scale)

    def _scale_masses(self, scale: float) -> None:
        for link, (mass, inertia) in self._nominal_dynamics.items():
            self.client.changeDynamics(self.body_id, link, mass=mass * scale,
                                       localInertiaDiagonal=[i * scale for i in inertia])

    # ------------------------------------------------------------------------------------------------------
    # rendering and teardown
    # ------------------------------------------------------------------------------------------------------

    def render(self, width: int = 320, height: int = 240, distance: float = 1.2, yaw_deg: float = 45.0,
               pitch_deg: float = -20.0) -> np.ndarray:
        """`EngineRobot.render` with PyBullet's TinyRenderer (no GPU)."""
        c = self.client
        target = self.base_pose()[0].tolist()
        view = c.computeViewMatrixFromYawPitchRoll(target, distance, yaw_deg, pitch_deg, 0.0, 2)
        proj = c.computeProjectionMatrixFOV(60.0, width / height, 0.01, 20.0)
        _, _, rgba, _, _ = c.getCameraImage(width, height, view, proj, renderer=pybullet.ER_TINY_RENDERER)
        return np.asarray(rgba, dtype=np.uint8).reshape(height, width, 4)[:, :, :3].copy()

    def _release(self) -> None:
        self.client.disconnect()
