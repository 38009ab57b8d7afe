"""The benchmark models as URDF (for Pinocchio) and MJCF (for MuJoCo).

Each model is a serial chain of revolute joints, written from the same
specification as eom's model:

* ``arm7``: ``models/arm7.ron`` (MODELS.md "arm7"): axes z, y, z, y, z, y, z;
  joint 1 at the world origin, joint k+1 at 0.3 m along +z of link k; every
  link 1.5 kg, centre of mass 0.15 m along local +z, inertia about the
  centre of mass diag(0.02, 0.02, 0.005) kg m^2.
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

import re
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


def f(x):
    """A float as text, exactly (repr round-trips)."""
    return repr(float(x))


def vec(v):
    return " ".join(f(x) for x in v)


def urdf(name, links):
    """URDF: a fixed `base` link, then `link1..n` on revolute joints with
    limits far out of reach (`continuous` would give Pinocchio a cos/sin
    joint with nq = 2)."""
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


def mjcf(name, links):
    """MJCF: nested bodies, one hinge each, explicit inertials, no geoms.
    Contacts, all constraints (limits, equality, friction loss) and
    actuation are disabled; armature, damping and friction loss are zero
    (the defaults, also set explicitly)."""
    out = [
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
    table = {"arm7": arm7()}
    for n in (5, 10, 50):
        table[f"planar_chain{n}"] = chain(n, False)
        table[f"spatial_chain{n}"] = chain(n, True)
    # The long chain of issue 28 (emitted as loops over its bodies).
    table["spatial_chain200"] = chain(200, True)
    return table


# Three real robots of example-robot-data (issue 28), by the path of their
# URDF under the package's `robots` directory: a 7-DOF arm with its two
# fingers (mimic removed: 9 DOF), a 6-DOF arm, and a 32-DOF humanoid (a tree).
ROBOTS = {
    "panda": "panda_description/urdf/panda.urdf",
    "ur5": "ur_description/urdf/ur5_robot.urdf",
    "talos_reduced": "talos_data/robots/talos_reduced.urdf",
}


def robot_urdf(text):
    """A robot's URDF as all three tools read it here: as bench/robots loads
    it (the `<mimic>` tags removed: Pinocchio's parser and MuJoCo ignore
    them, eom would add a constraint for each), and without `<visual>` and
    `<collision>` (meshes none of the dynamics reads, which MuJoCo would try
    to open). Inertias, frames, axes and `<dynamics damping>` as shipped."""
    text = re.sub(r"<mimic\b[^>]*/>|<mimic\b[^>]*>.*?</mimic>", "", text, flags=re.S)
    return re.sub(r"<visual\b.*?</visual>|<collision\b.*?</collision>", "", text, flags=re.S)


def robot_mujoco(urdf_text):
    """The robot's URDF (`robot_urdf`) for MuJoCo's own URDF import (which
    keeps every number at full precision; MJCF written back by MuJoCo has
    six digits): a `<mujoco>` block with the options of `mjcf` — contacts,
    all constraints (limits, equality, friction loss), actuation and springs
    disabled, gravity 9.81 m/s^2 along -z. The base is fixed, the inertias
    are the file's, armature zero, and `<dynamics damping>` becomes joint
    damping with the damper left on: eom applies the URDF damping as a joint
    damper, Pinocchio's ABA is given tau - D v."""
    block = (
        "<mujoco>\n"
        '    <compiler angle="radian"/>\n'
        f'    <option gravity="0 0 {f(-GRAVITY)}" timestep="0.001">\n'
        '      <flag contact="disable" constraint="disable" limit="disable" equality="disable" '
        'frictionloss="disable" actuation="disable" spring="disable"/>\n'
        "    </option>\n"
        "  </mujoco>"
    )
    return re.sub(r"(<robot\b[^>]*>)", lambda m: m.group(1) + "\n  " + block, urdf_text, count=1)
