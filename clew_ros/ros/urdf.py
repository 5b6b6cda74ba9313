"""The arm as a URDF (``~/robot_description``), generated from the world; pure, no rclpy.

The tree (all in the plane z = 0, joints about z, interface.md §1):

- ``world`` (root) --fixed ``base_joint`` at ``world.robot.base``--> ``base_link``;
- ``base_link`` --revolute ``joint_1``--> ``link_1`` --revolute ``joint_2``--> ``link_2`` ... ``link_n``:
  ``joint_i`` sits at the end of link i-1 (``(l_(i-1), 0, 0)`` in its frame; at the
  base for ``joint_1``), turns about z within ``[joint_lower_i, joint_upper_i]``,
  and link i runs along its x axis from 0 to ``l_i``;
- ``link_n`` --fixed ``tool_joint`` at ``(l_n, 0, 0)``--> ``tool``: the end
  effector frame of interface.md §1 (origin ``p_n``, x axis along ``phi_n``);
- ``tool`` --revolute ``gripper`` (limits [0, 1])--> ``gripper_left_jaw`` and,
  mimicking it, ``gripper_right``--> ``gripper_right_jaw``: two jaws at
  ``(0, +-h, 0)`` that stand open at +-:data:`JAW_OPEN_RAD` for ``gripper``
  0.0 and lie along x, closed, for 1.0, the values ``~/joint_states`` and
  ``~/trajectory`` give the ``gripper`` joint (1.0 while grasping).

Links are drawn (and collide) as the world says: a cylinder of diameter
``link_width`` along x with a sphere at each end (the capsule of §1). A world
of segments (``link_width`` 0) gets collision-free links drawn
:data:`SEGMENT_DRAW_WIDTH_M` wide. Joint frames and their transforms at a
joint state are in :mod:`clew_ros.ros.frames`.
"""

from __future__ import annotations

import math
from xml.sax.saxutils import quoteattr

from clew_ros.planar.world import Robot, World

__all__ = [
    "BASE_LINK",
    "JAW_LINKS",
    "JAW_OPEN_RAD",
    "ROOT_FRAME",
    "SEGMENT_DRAW_WIDTH_M",
    "TOOL_FRAME",
    "jaw_offset_m",
    "link_name",
    "robot_urdf",
    "visual_width_m",
]

#: The URDF's root link: the fixed frame of every message (``messages.FRAME_ID``).
ROOT_FRAME = "world"
#: The arm's base, at ``world.robot.base``.
BASE_LINK = "base_link"
#: The end-effector frame at the tip.
TOOL_FRAME = "tool"
#: The two jaw links; the first is moved by the ``gripper`` joint, the second by ``gripper_right`` (its mimic).
JAW_LINKS = ("gripper_left_jaw", "gripper_right_jaw")
#: Angle (rad) of each jaw off the tool's x axis with the gripper open (``gripper`` 0.0); 0 when closed (1.0).
JAW_OPEN_RAD = 1.0
#: Width (m) a link is drawn with in a world of segments (``link_width`` 0).
SEGMENT_DRAW_WIDTH_M = 0.02

_ROBOT_NAME = "clew_arm"
_MATERIALS = {"link": (0.45, 0.47, 0.52), "joint": (0.15, 0.15, 0.18), "gripper": (0.95, 0.55, 0.1)}


def link_name(index: int) -> str:
    """The link moved by ``joint_<index>`` (1-based): ``link_<index>``."""
    return f"link_{index}"


def visual_width_m(robot: Robot) -> float:
    """Width (m) the links are drawn with: ``link_width``, or :data:`SEGMENT_DRAW_WIDTH_M` for segments."""
    return float(robot.link_width) if robot.link_width > 0 else SEGMENT_DRAW_WIDTH_M


def jaw_offset_m(robot: Robot) -> float:
    """Distance (m) of each jaw's hinge from the tool's x axis."""
    return 0.5 * visual_width_m(robot)


def _number(value: float) -> str:
    return repr(float(value))  # shortest text that reads back as the same double


def _xyz(x: float, y: float, z: float = 0.0) -> str:
    return f"{_number(x)} {_number(y)} {_number(z)}"


def _origin(x: float = 0.0, y: float = 0.0, yaw: float = 0.0, *, pitch: float = 0.0) -> str:
    return f'<origin xyz="{_xyz(x, y)}" rpy="{_xyz(0.0, pitch, yaw)}"/>'


def _shape(tag: str, origin: str, geometry: str, material: str | None = None) -> str:
    """One ``<visual>`` or ``<collision>`` element."""
    paint = f'<material name="{material}"/>' if material else ""
    return f"<{tag}>{origin}<geometry>{geometry}</geometry>{paint}</{tag}>"


def _capsule(length: float, width: float, material: str | None, tag: str) -> list[str]:
    """A capsule along x from 0 to ``length``: a cylinder (its axis z turned onto x) and two spheres."""
    radius = _number(0.5 * width)
    cylinder = f'<cylinder radius="{radius}" length="{_number(length)}"/>'
    parts = [_shape(tag, _origin(0.5 * length, pitch=math.pi / 2), cylinder, material)]
    parts.extend(_shape(tag, _origin(x), f'<sphere radius="{radius}"/>', material) for x in (0.0, length))
    return parts


def _link(name: str, body: list[str]) -> str:
    return f"  <link name={quoteattr(name)}>\n" + "".join(f"    {line}\n" for line in body) + "  </link>\n"


def _joint(
    name: str, kind: str, parent: str, child: str, *, origin: str, axis: str | None = None, extra: str = ""
) -> str:
    lines = [f"<parent link={quoteattr(parent)}/>", f"<child link={quoteattr(child)}/>", origin]
    if axis is not None:
        lines.append(f'<axis xyz="{axis}"/>')
    if extra:
        lines.append(extra)
    return (
        f"  <joint name={quoteattr(name)} type={quoteattr(kind)}>\n"
        + "".join(f"    {line}\n" for line in lines)
        + "  </joint>\n"
    )


def robot_urdf(world: World) -> str:
    """The URDF of ``world``'s arm (see the module docstring), as the text ``~/robot_description`` carries.

    >>> from clew_ros.planar.world import load_world  # doctest: +SKIP
    >>> "joint_2" in robot_urdf(load_world("config/figure1.yaml"))  # doctest: +SKIP
    True
    """
    robot = world.robot
    width = visual_width_m(robot)
    solid = robot.link_width > 0
    jaw_length = max(2.0 * width, 0.04)
    jaw_width = 0.5 * width
    out = [f'<?xml version="1.0"?>\n<robot name="{_ROBOT_NAME}">\n']
    out.extend(
        f'  <material name="{name}"><color rgba="{r} {g} {b} 1.0"/></material>\n'
        for name, (r, g, b) in _MATERIALS.items()
    )
    out.append(f"  <link name={quoteattr(ROOT_FRAME)}/>\n")
    base_radius = 1.5 * width
    base_disk = f'<cylinder radius="{_number(base_radius)}" length="{_number(width)}"/>'
    out.append(_link(BASE_LINK, [_shape("visual", _origin(), base_disk, "joint")]))
    base_x, base_y = (float(v) for v in robot.base)
    out.append(_joint("base_joint", "fixed", ROOT_FRAME, BASE_LINK, origin=_origin(base_x, base_y)))
    parent, offset = BASE_LINK, 0.0
    for i, (length, lower, upper) in enumerate(
        zip(robot.link_lengths, robot.joint_lower, robot.joint_upper, strict=True), start=1
    ):
        body = _capsule(float(length), width, "link", "visual")
        if solid:
            body += _capsule(float(length), width, None, "collision")
        out.append(_link(link_name(i), body))
        limit = f'<limit lower="{_number(lower)}" upper="{_number(upper)}" effort="0.0" velocity="0.0"/>'
        out.append(
            _joint(
                f"joint_{i}", "revolute", parent, link_name(i), origin=_origin(offset), axis=_xyz(0, 0, 1), extra=limit
            )
        )
        parent, offset = link_name(i), float(length)
    out.append(_link(TOOL_FRAME, []))
    out.append(_joint("tool_joint", "fixed", parent, TOOL_FRAME, origin=_origin(offset)))
    jaw_box = f'<box size="{_xyz(jaw_length, jaw_width, jaw_width)}"/>'
    jaw = [_shape("visual", _origin(0.5 * jaw_length), jaw_box, "gripper")]
    hinge = jaw_offset_m(robot)
    gripper_limit = '<limit lower="0.0" upper="1.0" effort="0.0" velocity="0.0"/>'
    left, right = JAW_LINKS
    out.append(_link(left, jaw))
    out.append(
        _joint(
            "gripper",
            "revolute",
            TOOL_FRAME,
            left,
            origin=_origin(0.0, hinge, JAW_OPEN_RAD),
            axis=_xyz(0, 0, -1),
            extra=gripper_limit,
        )
    )
    out.append(_link(right, jaw))
    out.append(
        _joint(
            "gripper_right",
            "revolute",
            TOOL_FRAME,
            right,
            origin=_origin(0.0, -hinge, -JAW_OPEN_RAD),
            axis=_xyz(0, 0, 1),
            extra=gripper_limit + '<mimic joint="gripper" multiplier="1.0" offset="0.0"/>',
        )
    )
    out.append("</robot>\n")
    return "".join(out)
