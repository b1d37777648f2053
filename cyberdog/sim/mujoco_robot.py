"""The CyberDog in its own MuJoCo world: the second engine, behind the interface of `cyberdog.sim.engine.EngineRobot`
(the same drivers' loop, actuator law and state conventions as the PyBullet `cyberdog.sim.robot.Robot`).

The model is built from the same URDF (`RobotConfig.urdf`) with `mujoco.MjSpec`:

- MuJoCo's URDF import welds the root link to the world and fuses fixed-joint links into their parents: the
  trunk gets a free joint and `fusestatic` is off, so that the foot links (and their 18 mm spheres) stay bodies;
- `inertiafromgeom` and `balanceinertia` are off: every link keeps the URDF's mass, centre of mass and full
  inertia tensor exactly (MuJoCo diagonalises it into the body's inertial frame, as PyBullet does); the rotors'
  reflected inertia is in the URDF's link inertias, as for PyBullet;
- the URDF's joint limits are kept (MuJoCo's soft limits, default solref/solimp); no joint damping or friction in
  the model: the actuator law adds friction when it is on, as for PyBullet;
- only robot–ground contacts exist (PyBullet loads the URDF without self-collision): robot geoms contype 1,
  conaffinity 0; the ground plane contype 0, conaffinity 1;
- the ground plane has the higher priority, so that a robot–ground contact takes the ground's friction, solref,
  solimp and condim as they are (MuJoCo combines equal-priority geoms by max): the foot–ground Coulomb coefficient
  is exactly `SimConfig.ground_friction` (`set_ground_friction`).

The contact values (CONTACT below) are physical ones, fixed by a calibration without any learned gait
(docs/design.md, "The second engine"). One physics step is one mj_step with the joint torques in qfrc_applied.
After mj_step, MuJoCo's positions and velocities are the new state and its contacts and forces are those that
acted over the step (computed at its start): `foot_contacts`, `foot_contact_forces` and `ground_contact_links`
report that step's contacts, as PyBullet's do. The base pose is the trunk's URDF link frame (MuJoCo's body
frame); the free joint's angular velocity (body frame) is turned into the world frame.
"""
from __future__ import annotations

import math
import warnings

import mujoco
import numpy as np

from cyberdog.config import ActuatorConfig, RobotConfig, SimConfig
from cyberdog.sim.engine import FOOT_LINKS, JOINT_ORDER, EngineRobot, rest_pose
from cyberdog.sim.mujoco_view import MujocoView
from cyberdog.sim.state import StateReading

# The ground contact (every robot geom against the plane), from physical values and a calibration with no learned
# gait (docs/design.md, "The second engine"; python -m cyberdog.analysis.engine_check):
CONTACT = dict(
    # s, –: 4 physics steps at 800 Hz (MuJoCo needs >= 2); a standing foot sinks 0.29 mm under its 33 N, about
    # 1e5 N/m, the order of a hard rubber foot [G]; critically damped: a landing foot does not bounce
    solref=(0.005, 1.0),
    solimp=(0.9, 0.95, 0.001, 0.5, 2.0),  # MuJoCo's default: impedance 0.9 → 0.95 over the first 1 mm
    condim=3,  # normal + sliding friction; a sphere on a plane: no torsional or rolling friction (PyBullet's: 0)
)
CONE = mujoco.mjtCone.mjCONE_ELLIPTIC  # Coulomb's friction cone, |f_t| <= mu·f_n
# friction-to-normal impedance ratio: at 1 a standing robot's feet creep outward (2.5 mm in 4 s under 1 N of
# a 27 N friction limit) and its abad torques fall 14 % below PyBullet's; at 100 they hold (MuJoCo Menagerie's
# quadrupeds use elliptic cones with 100)
IMPRATIO = 100.0
ROBOT_COLOURS = {"trunk": (0.55, 0.55, 0.6, 1), "foot": (0.95, 0.45, 0.1, 1)}  # others (0.15, 0.15, 0.18, 1)


def build_model(urdf: str, sim: SimConfig) -> mujoco.MjModel:
    """The MuJoCo model of the robot in `urdf` on a ground plane, with the settings of the module docstring."""
    spec = mujoco.MjSpec.from_file(urdf)
    spec.compiler.fusestatic = False
    spec.compiler.inertiafromgeom = mujoco.mjtInertiaFromGeom.mjINERTIAFROMGEOM_FALSE
    spec.compiler.balanceinertia = False
    spec.compiler.discardvisual = False  # (the URDF's visuals are gone already; the ground's look stays)
    o = spec.option
    o.timestep, o.gravity = sim.physics_dt, (0.0, 0.0, -sim.gravity)
    o.integrator, o.cone, o.impratio = mujoco.mjtIntegrator.mjINT_EULER, CONE, IMPRATIO
    spec.body("trunk").add_freejoint(name="trunk_free")
    for geom in spec.geoms:
        geom.contype, geom.conaffinity = 1, 0
        kind = "trunk" if geom.parent.name == "trunk" else "foot" if geom.parent.name.endswith("_foot") else ""
        geom.rgba = ROBOT_COLOURS.get(kind, (0.15, 0.15, 0.18, 1))
    spec.add_texture(name="grid", type=mujoco.mjtTexture.mjTEXTURE_2D, builtin=mujoco.mjtBuiltin.mjBUILTIN_CHECKER,
                     rgb1=(0.2, 0.3, 0.4), rgb2=(0.1, 0.2, 0.3), width=256, height=256)
    ground_look = spec.add_material(name="ground", texrepeat=(1.0, 1.0), texuniform=True)
    ground_look.textures[mujoco.mjtTextureRole.mjTEXROLE_RGB] = "grid"
    spec.worldbody.add_geom(name="ground", type=mujoco.mjtGeom.mjGEOM_PLANE, size=(0.0, 0.0, 1.0), contype=0,
                            conaffinity=1, priority=1, friction=(sim.ground_friction, 0.0, 0.0),
                            material="ground", **CONTACT)
    spec.worldbody.add_light(pos=(0.0, 0.0, 4.0), dir=(0.0, 0.0, -1.0), type=mujoco.mjtLightType.mjLIGHT_DIRECTIONAL)
    spec.visual.global_.offwidth, spec.visual.global_.offheight = 1920, 1080
    return spec.compile()


def _rotate(quat_wxyz, v) -> tuple:
    """v (3 floats) rotated by the unit quaternion (w, x, y, z): R v, in floats."""
    w, x, y, z = quat_wxyz
    vx, vy, vz = v
    tx, ty, tz = 2.0 * (y * vz - z * vy), 2.0 * (z * vx - x * vz), 2.0 * (x * vy - y * vx)  # t = 2 q × v
    return (vx + w * tx + y * tz - z * ty, vy + w * ty + z * tx - x * tz, vz + w * tz + x * ty - y * tx)


def euler_from_quaternion(x: float, y: float, z: float, w: float) -> tuple:
    """(roll, pitch, yaw), rad, of the quaternion x y z w: R = Rz(yaw) Ry(pitch) Rx(roll), PyBullet's convention."""
    sin_pitch = 2.0 * (w * y - z * x)
    pitch = math.asin(1.0 if sin_pitch > 1.0 else -1.0 if sin_pitch < -1.0 else sin_pitch)
    return (math.atan2(2.0 * (w * x + y * z), 1.0 - 2.0 * (x * x + y * y)), pitch,
            math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z)))


class MujocoRobot(EngineRobot):
    """CyberDog on a flat plane in MuJoCo, driven by joint torques set at every physics step (see the module
    docstring). `gui` is refused with a warning (no window): the robot runs headless, `render` draws offscreen."""

    def __init__(self, robot: RobotConfig, actuator: ActuatorConfig, sim: SimConfig, gui: bool = False):
        super().__init__(robot, actuator, sim)
        if gui:
            warnings.warn("the MuJoCo robot opens no window; running without one (render() draws images)",
                          RuntimeWarning, stacklevel=3)
        self.gui = False
        self.model = m = build_model(str(self.urdf), sim)
        self.data = mujoco.MjData(m)
        try:
            joints = [m.joint(name) for name in JOINT_ORDER]
            self.foot_body_ids = [m.body(name).id for name in FOOT_LINKS]
        except KeyError as err:
            raise ValueError(f"{self.urdf}: missing joint or link {err}; expected the names of tools/make_urdf.py") \
                from None
        self._qpos = [int(j.qposadr[0]) for j in joints]
        self._dof = [int(j.dofadr[0]) for j in joints]
        if self._qpos != list(range(7, 19)) or self._dof != list(range(6, 18)):
            raise ValueError(f"{self.urdf}: the joints are not in the order {JOINT_ORDER} after the trunk")
        self.ground_id = m.geom("ground").id
        self.link_names = {b: m.body(b).name for b in range(1, m.nbody)}  # body id → URDF link name
        self._geom_body = m.geom_bodyid.tolist()
        self._nominal_dynamics = (m.body_mass.copy(), m.body_inertia.copy())
        self._trunk = m.body("trunk").id
        self._joint_cache: tuple[list, list] | None = None  # (q, dq) as floats, until the next step or reset
        self._view: MujocoView | None = None
        self._settle_model()
        self.reset()

    # ---- reset and step -------------------------------------------------------------------------------------
    def reset(self, joint_angles: np.ndarray | None = None, base_position=None, base_yaw: float = 0.0) -> None:
        """`EngineRobot.reset`: MuJoCo's data cleared (warm start included), the pose set, the model forwarded."""
        q, pos, (x, y, z, w) = rest_pose(self.robot_config, joint_angles, base_position, base_yaw)
        m, d = self.model, self.data
        mujoco.mj_resetData(m, d)
        d.qpos[:7] = pos + [w, x, y, z]
        d.qpos[7:19] = q
        mujoco.mj_forward(m, d)
        self._joint_cache = None
        self.physics_steps = 0

    def _set_step(self, physics_dt: float) -> None:
        self.model.opt.timestep = physics_dt

    def _advance(self, joint_torque: list) -> None:
        """One mj_step with the joint torques as applied generalised forces over it."""
        self.data.qfrc_applied[6:18] = joint_torque
        mujoco.mj_step(self.model, self.data)
        self._joint_cache = None

    # ---- state reads ----------------------------------------------------------------------------------------
    def joint_lists(self) -> tuple[list, list]:
        if self._joint_cache is None:
            self._joint_cache = (self.data.qpos[7:19].tolist(), self.data.qvel[6:18].tolist())
        return self._joint_cache

    def base_pose(self) -> tuple[np.ndarray, np.ndarray]:
        x, y, z, w, qx, qy, qz = self.data.qpos[:7].tolist()
        return np.array([x, y, z]), np.array([qx, qy, qz, w])

    def read(self) -> StateReading:
        """`EngineRobot.read`: the free joint's pose and linear velocity are the link frame's; its angular velocity,
        in the body frame, turned into the world frame."""
        q, dq = self.joint_lists()
        px, py, pz, w, x, y, z = self.data.qpos[:7].tolist()
        vx, vy, vz, *omega_body = self.data.qvel[:6].tolist()
        quat = (x, y, z, w)
        return StateReading(self.physics_steps * self.physics_dt, q, dq, (px, py, pz), quat,
                            euler_from_quaternion(*quat), (vx, vy, vz), _rotate((w, x, y, z), omega_body))

    def _ground_contacts(self) -> list[tuple[int, int]]:
        """(contact index, robot body id) of every robot–ground contact of the last step."""
        d, ground, body = self.data, self.ground_id, self._geom_body
        out = []
        for i, (g1, g2) in enumerate(d.contact.geom[:d.ncon].tolist()):
            if g1 == ground or g2 == ground:
                out.append((i, body[g2 if g1 == ground else g1]))
        return out

    def foot_contacts(self) -> np.ndarray:
        touching = {b for _, b in self._ground_contacts()}
        return np.array([b in touching for b in self.foot_body_ids])

    def foot_contact_forces(self) -> np.ndarray:
        """`EngineRobot.foot_contact_forces`: the normal part of mj_contactForce, summed per foot."""
        force = dict.fromkeys(self.foot_body_ids, 0.0)
        wrench = np.zeros(6)
        for i, b in self._ground_contacts():
            if b in force:
                mujoco.mj_contactForce(self.model, self.data, i, wrench)
                force[b] += float(wrench[0])
        return np.array([force[b] for b in self.foot_body_ids])

    def ground_contact_links(self) -> set[str]:
        return {self.link_names[b] for _, b in self._ground_contacts()}

    def foot_positions_world(self) -> np.ndarray:
        """`EngineRobot.foot_positions_world`, from the kinematics of the state now."""
        mujoco.mj_kinematics(self.model, self.data)
        return self.data.xpos[self.foot_body_ids].copy()

    def total_mass(self) -> float:
        return float(self.model.body_mass[1:].sum())

    # ---- settings -------------------------------------------------------------------------------------------
    def _set_friction(self, coefficient: float) -> None:
        """The ground's sliding friction: the higher-priority geom's friction is the contact's."""
        self.model.geom_friction[self.ground_id, 0] = coefficient

    def _foot_radius(self) -> float:
        foot_geoms = [g for g in range(self.model.ngeom) if self._geom_body[g] == self.foot_body_ids[0]]
        return float(self.model.geom_size[foot_geoms[0], 0])

    def _trunk_mass(self) -> float:
        return float(self._nominal_dynamics[0][self._trunk])

    def _carry_payload(self, body_ratio: float) -> None:
        mass, inertia = self._nominal_dynamics
        mass[self._trunk] *= body_ratio
        inertia[self._trunk] *= body_ratio
        self._scale_masses(self.mass_scale)

    def _scale_masses(self, scale: float) -> None:
        """Every body's mass and inertia × scale; MuJoCo's constants that depend on them recomputed, the state
        kept."""
        m, d = self.model, self.data
        mass, inertia = self._nominal_dynamics
        m.body_mass[:] = mass * scale
        m.body_inertia[:] = inertia * scale
        qpos, qvel = d.qpos.copy(), d.qvel.copy()
        mujoco.mj_setConst(m, d)
        d.qpos[:], d.qvel[:] = qpos, qvel
        mujoco.mj_forward(m, d)

    # ---- rendering and teardown -----------------------------------------------------------------------------
    def render(self, width: int = 320, height: int = 240, distance: float = 1.2, yaw_deg: float = 45.0,
               pitch_deg: float = -20.0) -> np.ndarray:
        """`EngineRobot.render` with MuJoCo's offscreen renderer (yaw and pitch as PyBullet's camera's)."""
        if self._view is None or self._view.size != (width, height):
            self._release()
            self._view = MujocoView(self.model, width, height)
        camera = mujoco.MjvCamera()
        camera.lookat[:] = self.data.qpos[:3]
        camera.distance, camera.azimuth, camera.elevation = distance, yaw_deg + 90.0, pitch_deg
        mujoco.mj_kinematics(self.model, self.data)
        return self._view.draw(self.data, camera)

    def _release(self) -> None:
        if self._view is not None:
            self._view.close()
            self._view = None
