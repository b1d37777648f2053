"""Write `urdf/cyberdog.urdf`, the first-generation Xiaomi CyberDog built from primitive shapes.

Usage:  python tools/make_urdf.py            (writes cyberdog/urdf/cyberdog.urdf, the package's copy that
                                              the top-level urdf/cyberdog.urdf links to)
        python tools/make_urdf.py --check    (exit 1 if the checked-in file differs from what is generated)

Every number below is the robot's parameter table, `docs/robot.md`, with its sources' tags: [X] Xiaomi's
open-source controller files (MiRoboticsLab/cyberdog_locomotion), [X-conv] the same values converted to URDF
link frames, [SPEC] the marketing spec, [G] a guess.

Frames (as `cyberdog/core/kinematics.py`): x forward, y left, z up; abad about +x, hip and knee about +y;
zero angles = leg straight down; hip > 0 swings the thigh backward; knee < 0.
"""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

LEGS = (("LF", +1, +1), ("RF", +1, -1), ("LH", -1, +1), ("RH", -1, -1))  # name, front(+1)/hind(-1), left(+1)/right(-1)

# --- geometry [X] -------------------------------------------------------------------------------------------
ABAD_ORIGIN = (0.23035, 0.05, 0.0)  # body centre → abad joint (signs per leg)
L1, L2, L3 = 0.105076, 0.200, 0.200  # abad → hip (along y), hip → knee, knee → foot-sphere centre
FOOT_RADIUS = 0.018

# --- masses [X], centres of mass and inertias about the COM for the left-front leg [X-conv] ------------------
BODY = dict(m=6.248410872, com=(0.018785003, 0.003291012, -0.000925646),
            I=(0.032143039, -0.000268204, -0.00241341, 0.13578316, 8.0244e-05, 0.14828095))  # ixx ixy ixz iyy iyz izz
ABAD = dict(m=0.537806728, com=(-0.001597914, 0.001680938, 2.253e-06),
            I=(0.000403612, 9.337e-06, 5.36e-07, 0.000600779, 6.3e-08, 0.000417249))
THIGH = dict(m=0.950266218, com=(-0.003205778, -0.027811623, -0.027767048),
             I=(0.004811898, 9.3647e-05, -0.000208709, 0.004752366, 0.000813258, 0.001079691))
CALF = dict(m=0.1135916, com=(0.007372358, 0.000122423, -0.10769301),
            I=(0.000667971, -1.0e-09, 5.356e-06, 0.000674399, -1.5e-08, 1.4181e-05))

# --- rotors [X]: one per joint, gear ratio 9 --------------------------------------------------------------
ROTOR_MASS = 0.076506382
ROTOR_I_SPIN, ROTOR_I_TRANSVERSE = 8.9031e-05, (4.5843e-05, 4.5871e-05)
ABAD_ROTOR_FROM_ABAD_JOINT = -0.0832504  # along x, toward the body centre (front legs −x, hind legs +x) [X]
HIP_ROTOR_FROM_HIP_JOINT = -0.107226  # along y for a left leg (placement pattern of Xiaomi's CD2 xacro) [X]+[G]
KNEE_ROTOR_FROM_HIP_JOINT = -0.0426259  # along y for a left leg [X]+[G]
# PyBullet has no joint armature: the rotor's reflected inertia J = 8.9031e-5 kg·m² × 9² = 0.00721 kg·m² is
# added to the CHILD link's inertia about the joint axis (to the COM tensor; the parallel-axis shift is
# unchanged, so the inertia about the joint axis grows by exactly J). Bullet zeroes any link inertia whose
# principal moments break the triangle inequality (BulletUrdfImporter.cpp), and J alone would break it
# for every leg link, so J is added as a flat disk on the joint axis: J about the axis and J/2 about the
# two perpendicular axes (the least a rigid body with axial inertia J can have). Unlike a true armature
# this also adds inertia to rotations about the other axes and couples to the base motion.
REFLECTED_INERTIA = ROTOR_I_SPIN * 9 ** 2

# --- joints -------------------------------------------------------------------------------------------------
LIMITS = {"abad": (-0.76096355387, 0.76096355387),  # rad [X-conv] limits_urdf
          "hip": (-1.88495559215, 3.76991118431),
          "knee": (-2.49582083035, -0.717155789644)}
EFFORT = 25.0  # N·m, the paper's torque command limit (Table 4); NOT enforced by PyBullet under torque control
VELOCITY = 20.9136  # rad/s, zero-torque speed of Xiaomi's torque-speed model [X]; not enforced either

# --- collision / visual shapes: primitives only ---------------------------------------------------------------
TRUNK_BOX = (0.47, 0.20, 0.12)  # [G] shell guess; Xiaomi's contact box is 0.4607 x 0.10 x 0.10 [X]
ABAD_CYLINDER = (0.045, 0.05)  # radius, length along y, centred between abad and hip joint [G]
THIGH_BOX = (0.035, 0.03, 0.20)  # x, y, z; hip joint → knee [G]
CALF_CYLINDER = (0.011, 0.15)  # radius, length; spans 0.015..0.165 m below the knee, ending 0.035 m above the
#                                 foot centre (0.053 m above the sphere's bottom), so only the feet touch [G]
CALF_CYLINDER_TOP = 0.015
FOOT_MASS, FOOT_INERTIA = 1e-3, 1e-7  # kg, kg·m²: tiny explicit inertial for the foot helper link (+4 g total)


def mirrored(part: dict, sx: int, sy: int, mirror_x: bool) -> tuple[float, np.ndarray, np.ndarray]:
    """(mass, com, 3x3 inertia) of a left-front part mirrored to another leg (the [X-conv] rule of docs/robot.md).

    Right legs mirror y (com_y, Ixy, Iyz negated); hind legs mirror x only for the abad link (com_x, Ixy, Ixz).
    """
    fx = sx if mirror_x else 1
    com = np.array(part["com"]) * (fx, sy, 1)
    ixx, ixy, ixz, iyy, iyz, izz = part["I"]
    ixy, ixz, iyz = ixy * fx * sy, ixz * fx, iyz * sy
    return part["m"], com, np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]])


def rotor(position, spin_axis: int) -> tuple[float, np.ndarray, np.ndarray]:
    """A rotor as (mass, position, inertia about its centre) spinning about body axis `spin_axis` (0=x, 1=y)."""
    diag = list(ROTOR_I_TRANSVERSE)
    diag.insert(spin_axis, ROTOR_I_SPIN)
    return ROTOR_MASS, np.array(position, dtype=float), np.diag(diag)


def combine(*parts) -> tuple[float, np.ndarray, np.ndarray]:
    """Merge rigid parts (mass, com, inertia about com) into one: total mass, COM, inertia about the new COM."""
    m = sum(p[0] for p in parts)
    com = sum(p[0] * p[1] for p in parts) / m
    inertia = np.zeros((3, 3))
    for mi, ci, Ii in parts:
        d = ci - com
        inertia += Ii + mi * (d @ d * np.eye(3) - np.outer(d, d))  # parallel-axis theorem
    return m, com, inertia


def f(*values: float) -> str:
    return " ".join(f"{v + 0.0:.9g}" for v in values)  # + 0.0 turns -0.0 into 0.0


def inertial(m: float, com, inertia) -> str:
    I = inertia
    return (f'    <inertial>\n      <origin xyz="{f(*com)}" rpy="0 0 0"/>\n      <mass value="{f(m)}"/>\n'
            f'      <inertia ixx="{f(I[0][0])}" ixy="{f(I[0][1])}" ixz="{f(I[0][2])}" iyy="{f(I[1][1])}" '
            f'iyz="{f(I[1][2])}" izz="{f(I[2][2])}"/>\n    </inertial>\n')


def shape(geometry: str, xyz=(0, 0, 0), rpy=(0, 0, 0), colour: str = "grey") -> str:
    """The same primitive as visual and collision."""
    origin = f'<origin xyz="{f(*xyz)}" rpy="{f(*rpy)}"/>'
    return (f'    <visual>\n      {origin}\n      <geometry>{geometry}</geometry>\n'
            f'      <material name="{colour}"/>\n    </visual>\n'
            f'    <collision>\n      {origin}\n      <geometry>{geometry}</geometry>\n    </collision>\n')


def link(name: str, body: str) -> str:
    return f'  <link name="{name}">\n{body}  </link>\n'


def joint(name: str, kind: str, parent: str, child: str, xyz, axis=None, limit=None) -> str:
    text = (f'  <joint name="{name}" type="{kind}">\n    <parent link="{parent}"/>\n    <child link="{child}"/>\n'
            f'    <origin xyz="{f(*xyz)}" rpy="0 0 0"/>\n')
    if axis is not None:
        text += (f'    <axis xyz="{f(*axis)}"/>\n    <limit lower="{f(limit[0])}" upper="{f(limit[1])}" '
                 f'effort="{f(EFFORT)}" velocity="{f(VELOCITY)}"/>\n    <dynamics damping="0" friction="0"/>\n')
    return text + "  </joint>\n"


def with_reflected_inertia(part, axis: int):
    """Add the rotor's reflected inertia J to a part about body axis `axis` as a flat disk: diag J/2, J on axis."""
    m, com, inertia = part
    disk = np.full(3, REFLECTED_INERTIA / 2)
    disk[axis] = REFLECTED_INERTIA
    return m, com, inertia + np.diag(disk)


def urdf_text() -> str:
    box = lambda s: f'<box size="{f(*s)}"/>'
    cylinder = lambda r, l: f'<cylinder radius="{f(r)}" length="{f(l)}"/>'
    # Trunk: the body plus the four abad rotors, which sit in the body and drive the abad joints.
    trunk_parts = [(BODY["m"], np.array(BODY["com"]), mirrored(BODY, 1, 1, False)[2])]
    for _, sx, sy in LEGS:
        trunk_parts.append(rotor((sx * (ABAD_ORIGIN[0] + ABAD_ROTOR_FROM_ABAD_JOINT), sy * ABAD_ORIGIN[1], 0), 0))
    out = ['<?xml version="1.0"?>\n',
           "<!-- GENERATED by tools/make_urdf.py from the project's CyberDog parameter set; do not edit. -->\n",
           '<robot name="cyberdog">\n',
           '  <material name="grey"><color rgba="0.55 0.55 0.6 1"/></material>\n',
           '  <material name="dark"><color rgba="0.15 0.15 0.18 1"/></material>\n',
           '  <material name="orange"><color rgba="0.95 0.45 0.1 1"/></material>\n',
           link("trunk", inertial(*combine(*trunk_parts)) + shape(box(TRUNK_BOX)))]
    for leg, sx, sy in LEGS:
        # Abad link: abad housing + the hip rotor, which rides on it (its stator is fixed to the abad link).
        hip_rotor = rotor((0, sy * (L1 + HIP_ROTOR_FROM_HIP_JOINT), 0), 1)
        abad = with_reflected_inertia(combine(mirrored(ABAD, sx, sy, True), hip_rotor), 0)
        # Thigh link: thigh + the knee rotor, which rides on the thigh (drives the calf through a linkage).
        knee_rotor = rotor((0, sy * KNEE_ROTOR_FROM_HIP_JOINT, 0), 1)
        thigh = with_reflected_inertia(combine(mirrored(THIGH, sx, sy, False), knee_rotor), 1)
        calf = with_reflected_inertia(mirrored(CALF, sx, sy, False), 1)
        rad, length = ABAD_CYLINDER
        out += [
            link(f"{leg}_abad", inertial(*abad) + shape(cylinder(rad, length), (0, sy * L1 / 2, 0),
                                                        (np.pi / 2, 0, 0), "dark")),
            link(f"{leg}_thigh", inertial(*thigh) + shape(box(THIGH_BOX), (0, 0, -L2 / 2))),
            link(f"{leg}_calf", inertial(*calf) + shape(cylinder(*CALF_CYLINDER),
                                                        (0, 0, -CALF_CYLINDER_TOP - CALF_CYLINDER[1] / 2),
                                                        colour="dark")),
            link(f"{leg}_foot", inertial(FOOT_MASS, (0, 0, 0), np.eye(3) * FOOT_INERTIA)
                 + shape(f'<sphere radius="{f(FOOT_RADIUS)}"/>', colour="orange")),
            joint(f"{leg}_abad_joint", "revolute", "trunk", f"{leg}_abad",
                  (sx * ABAD_ORIGIN[0], sy * ABAD_ORIGIN[1], 0), (1, 0, 0), LIMITS["abad"]),
            joint(f"{leg}_hip_joint", "revolute", f"{leg}_abad", f"{leg}_thigh", (0, sy * L1, 0), (0, 1, 0),
                  LIMITS["hip"]),
            joint(f"{leg}_knee_joint", "revolute", f"{leg}_thigh", f"{leg}_calf", (0, 0, -L2), (0, 1, 0),
                  LIMITS["knee"]),
            joint(f"{leg}_foot_joint", "fixed", f"{leg}_calf", f"{leg}_foot", (0, 0, -L3)),
        ]
    return "".join(out) + "</robot>\n"


def main(argv: list[str]) -> int:
    target = Path(__file__).resolve().parent.parent / "cyberdog" / "urdf" / "cyberdog.urdf"  # package data
    text = urdf_text()
    if "--check" in argv:
        if not target.exists() or target.read_text() != text:
            print(f"{target} is out of date: run python tools/make_urdf.py", file=sys.stderr)
            return 1
        print(f"{target} is up to date")
        return 0
    target.parent.mkdir(parents=True, exist_ok=True)
    target.write_text(text)
    print(f"wrote {target}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
