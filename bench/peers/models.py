"""The benchmark models as URDF (for Pinocchio) and MJCF (for MuJoCo).

Each model is a serial chain of revolute joints, written from the same
specification as eom's model:

* ``arm7``: ``models/arm7.ron`` (MODELS.md "arm7"): axes z, y, z, y, z, y, z;
  joint 1 at the world origin, joint k+1 at 0.3 m along +z of link k; every
  link 1.5 kg, centre of mass 0.15 m along local +z, inertia about the
  centre of mass diag(0.02, 0.02, 0.005) kg m^2.
* ``panda``: example-robot-data's ``panda_description/urdf/panda.urdf`` (the
  wheel pinned in requirements.txt, as ``bench/robots`` loads it): 7 arm
  joints and the two prismatic fingers, 9 DOF, fixed joints merged. The copy
  the three tools read (``peers_urdf``) has the ``<mimic>`` tag removed (as
  ``bench/robots/compare.py`` does: Pinocchio's parser ignores it by default;
  eom would add a holonomic constraint) and the ``<dynamics>`` tags (joint
  damping: eom applies it, Pinocchio's ABA does not), ``<visual>`` and
  ``<collision>`` removed, and its joint limits moved out of reach (±1e10, as
  the chains'; eom makes a URDF limit a unilateral contact): the rigid-body dynamics of its inertial data, the
  same in all three. Its MJCF is written from that URDF (``mjcf_from_urdf``).
* ``planar_chain{n}`` / ``spatial_chain{n}``:
  ``eom_gen::model::builder::n_link_chain(n, spatial)``: m = 1 kg,
  l = 0.5 m, r = 0.02 m; centre of mass (0, 0, l/2); inertia about the
  centre of mass diag(m(3r^2 + l^2)/12, m(3r^2 + l^2)/12, m r^2/2); joint 1
  at the origin, joint k at (0, 0, l) of link k-1; axes all y (planar) or
  z for odd k and y for even k (spatial).

Gravity is 9.81 m/s^2 along -z in all of them. Body frames sit at the joint,
with the inertia given about the centre of mass in body axes; joint angles
rotate the child relative to the parent about the axis, positive by the
right-hand rule, in all three tools. The script's acceleration check
(eom against both peers to 1e-10) is what proves the three descriptions
agree; this file only has to be right for that check to pass.
"""

import math
import os
import re
import sysconfig
import xml.etree.ElementTree as ET
from dataclasses import dataclass

GRAVITY = 9.81


@dataclass
class Link:
    """One link: its joint (axis, position in the parent frame) and inertia."""

    axis: tuple
    joint_pos: tuple
    mass: float
    com: tuple
    inertia: tuple  # (ixx, iyy, izz) about the centre of mass, body axes


def arm7():
    """models/arm7.ron."""
    m, l, c, ixx, izz = 1.5, 0.3, 0.15, 0.02, 0.005
    axes = [(0, 0, 1), (0, 1, 0)] * 3 + [(0, 0, 1)]
    return [
        Link(a, (0.0, 0.0, 0.0 if k == 0 else l), m, (0.0, 0.0, c), (ixx, ixx, izz))
        for k, a in enumerate(axes)
    ]


def chain(n, spatial):
    """eom_gen::model::builder::n_link_chain(n, spatial)."""
    m, l, r = 1.0, 0.5, 0.02
    it = m * (3 * r * r + l * l) / 12
    ia = m * r * r / 2
    links = []
    for k in range(1, n + 1):
        axis = (0, 0, 1) if spatial and k % 2 == 1 else (0, 1, 0)
        pos = (0.0, 0.0, 0.0 if k == 1 else l)
        links.append(Link(axis, pos, m, (0.0, 0.0, l / 2), (it, it, ia)))
    return links


@dataclass
class Robot:
    """A robot of example-robot-data, by its URDF inside the wheel."""

    urdf_path: str


def panda():
    prefix = os.path.join(sysconfig.get_paths()["purelib"], "cmeel.prefix")
    return Robot(
        os.path.join(prefix, "share", "example-robot-data", "robots", "panda_description", "urdf", "panda.urdf")
    )


def dof(links):
    """Speeds of a model (revolute and prismatic joints)."""
    if isinstance(links, Robot):
        root = ET.fromstring(peers_urdf(links))
        return sum(j.get("type") in ("revolute", "continuous", "prismatic") for j in root.iter("joint"))
    return len(links)


def peers_urdf(robot):
    """The URDF the three tools read: mimic, dynamics, visual and collision
    tags removed (see the module documentation)."""
    with open(robot.urdf_path) as src:
        text = src.read()
    for tag in ("mimic", "dynamics", "visual", "collision"):
        text = re.sub(rf"<{tag}\b[^>]*/>|<{tag}\b[^>]*>.*?</{tag}>", "", text, flags=re.S)
    # Joint limits far out of reach, as the chains' (eom makes a URDF limit a
    # unilateral contact, which `linearize` refuses to linearise when closed).
    text = re.sub(r'(<limit\b[^>]*?)\blower="[^"]*"', r'\1lower="-1e10"', text)
    text = re.sub(r'(<limit\b[^>]*?)\bupper="[^"]*"', r'\1upper="1e10"', text)
    return text


def quat_rpy(rpy):
    """URDF roll-pitch-yaw (fixed axes x, y, z) as a quaternion (w, x, y, z):
    qz(yaw) qy(pitch) qx(roll)."""
    r, p, y = (0.5 * x for x in rpy)
    cr, sr, cp, sp, cy, sy = math.cos(r), math.sin(r), math.cos(p), math.sin(p), math.cos(y), math.sin(y)
    return (
        cy * cp * cr + sy * sp * sr,
        cy * cp * sr - sy * sp * cr,
        cy * sp * cr + sy * cp * sr,
        sy * cp * cr - cy * sp * sr,
    )


def mjcf_from_urdf(name, robot):
    """MJCF of a URDF tree (revolute, continuous, prismatic and fixed joints):
    nested bodies at the joint origins, a hinge or slide each (none for a
    fixed joint), explicit full inertials at the URDF inertial frames, no
    geoms; the URDF's root link is the world (its inertia moves nothing).
    Options as in `mjcf`."""
    root = ET.fromstring(peers_urdf(robot))
    links = {ln.get("name"): ln for ln in root.iter("link")}
    below = {}
    for j in root.iter("joint"):
        below.setdefault(j.find("parent").get("link"), []).append(j)
    children = {j.find("child").get("link") for j in root.iter("joint")}
    (base,) = [n for n in links if n not in children]

    def origin(el):
        o = el.find("origin") if el is not None else None
        xyz = [float(x) for x in (o.get("xyz", "0 0 0") if o is not None else "0 0 0").split()]
        rpy = [float(x) for x in (o.get("rpy", "0 0 0") if o is not None else "0 0 0").split()]
        return xyz, quat_rpy(rpy)

    out = header(name)
    def body(joint, indent):
        child = joint.find("child").get("link")
        xyz, q = origin(joint)
        out.append(f'{indent}<body name="{child}" pos="{vec(xyz)}" quat="{vec(q)}">')
        kind = joint.get("type")
        if kind != "fixed":
            axis = [float(x) for x in joint.find("axis").get("xyz").split()]
            hinge = "slide" if kind == "prismatic" else "hinge"
            out.append(f'{indent}  <joint name="{joint.get("name")}" type="{hinge}" pos="0 0 0" axis="{vec(axis)}"/>')
        inertial = links[child].find("inertial")
        if inertial is not None and float(inertial.find("mass").get("value")) > 0:
            ixyz, (w, x, y, z) = origin(inertial)
            i = inertial.find("inertia")
            g = lambda k: float(i.get(k, "0"))  # noqa: E731
            tensor = [
                [g("ixx"), g("ixy"), g("ixz")],
                [g("ixy"), g("iyy"), g("iyz")],
                [g("ixz"), g("iyz"), g("izz")],
            ]
            # In the body frame: R I Rᵀ, R of the inertial frame's quaternion.
            rot = [
                [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
            ]
            body_i = [
                [sum(rot[r][a] * tensor[a][b] * rot[c][b] for a in range(3) for b in range(3)) for c in range(3)]
                for r in range(3)
            ]
            full = [body_i[0][0], body_i[1][1], body_i[2][2], body_i[0][1], body_i[0][2], body_i[1][2]]
            out.append(
                f'{indent}  <inertial pos="{vec(ixyz)}" '
                f'mass="{f(inertial.find("mass").get("value"))}" fullinertia="{vec(full)}"/>'
            )
        for j in below.get(child, []):
            body(j, indent + "  ")
        out.append(f"{indent}</body>")

    for j in below.get(base, []):
        body(j, "    ")
    out += ["  </worldbody>", "</mujoco>"]
    return "\n".join(out) + "\n"


def f(x):
    """A float as text, exactly (repr round-trips)."""
    return repr(float(x))


def vec(v):
    return " ".join(f(x) for x in v)


def urdf(name, links):
    """URDF: a fixed `base` link, then `link1..n` on revolute joints with
    limits far out of reach (`continuous` would give Pinocchio a cos/sin
    joint with nq = 2); a robot's `peers_urdf`."""
    if isinstance(links, Robot):
        return peers_urdf(links)
    out = [f'<?xml version="1.0"?>', f'<robot name="{name}">', '  <link name="base"/>']
    for k, ln in enumerate(links, start=1):
        parent = "base" if k == 1 else f"link{k - 1}"
        ixx, iyy, izz = ln.inertia
        out += [
            f'  <link name="link{k}">',
            "    <inertial>",
            f'      <origin xyz="{vec(ln.com)}" rpy="0 0 0"/>',
            f'      <mass value="{f(ln.mass)}"/>',
            f'      <inertia ixx="{f(ixx)}" ixy="0" ixz="0" iyy="{f(iyy)}" iyz="0" izz="{f(izz)}"/>',
            "    </inertial>",
            "  </link>",
            f'  <joint name="j{k}" type="revolute">',
            f'    <parent link="{parent}"/>',
            f'    <child link="link{k}"/>',
            f'    <origin xyz="{vec(ln.joint_pos)}" rpy="0 0 0"/>',
            f'    <axis xyz="{vec(ln.axis)}"/>',
            '    <limit lower="-1e10" upper="1e10" effort="1e10" velocity="1e10"/>',
            "  </joint>",
        ]
    out.append("</robot>")
    return "\n".join(out) + "\n"


def header(name):
    """The head of every MJCF here, up to the opening <worldbody>."""
    return [
        f'<mujoco model="{name}">',
        '  <compiler angle="radian" autolimits="false" inertiafromgeom="false"/>',
        f'  <option gravity="0 0 {f(-GRAVITY)}" timestep="0.001">',
        '    <flag contact="disable" constraint="disable" limit="disable" '
        'equality="disable" frictionloss="disable" actuation="disable" '
        'spring="disable" damper="disable"/>',
        "  </option>",
        "  <default>",
        '    <joint armature="0" damping="0" frictionloss="0" stiffness="0" limited="false"/>',
        "  </default>",
        "  <worldbody>",
    ]


def mjcf(name, links):
    """MJCF: nested bodies, one hinge each, explicit inertials, no geoms.
    Contacts, all constraints (limits, equality, friction loss) and
    actuation are disabled; armature, damping and friction loss are zero
    (the defaults, also set explicitly)."""
    if isinstance(links, Robot):
        return mjcf_from_urdf(name, links)
    out = header(name)
    indent = "    "
    for k, ln in enumerate(links, start=1):
        ixx, iyy, izz = ln.inertia
        out += [
            f'{indent}<body name="link{k}" pos="{vec(ln.joint_pos)}">',
            f'{indent}  <joint name="j{k}" type="hinge" pos="0 0 0" axis="{vec(ln.axis)}"/>',
            f'{indent}  <inertial pos="{vec(ln.com)}" mass="{f(ln.mass)}" '
            f'diaginertia="{f(ixx)} {f(iyy)} {f(izz)}"/>',
        ]
        indent += "  "
    for _ in links:
        indent = indent[:-2]
        out.append(f"{indent}</body>")
    out += ["  </worldbody>", "</mujoco>"]
    return "\n".join(out) + "\n"


def models():
    """name -> links, in table order."""
    table = {"arm7": arm7(), "panda": panda()}
    for n in (5, 10, 50):
        table[f"planar_chain{n}"] = chain(n, False)
        table[f"spatial_chain{n}"] = chain(n, True)
    # The long chain of issue 28 (emitted as loops over its bodies).
    table["spatial_chain200"] = chain(200, True)
    return table
