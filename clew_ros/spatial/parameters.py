"""The specification of a spatial world's parameters (interface.md section 1b), one :class:`ParameterSpec` each.

- :data:`SPATIAL_WORLD_PARAMETERS`: every ``world.*`` key of a ``world.kind: spatial`` world (the robot, the
  obstacles' names and the scene file, the supports, the object, the tolerances);
- :data:`SPATIAL_OBSTACLE_PARAMETERS`: the keys of each obstacle, ``world.obstacles.<name>.shape / .size /
  .pose`` (one set per name in ``world.obstacle_names``).

The spatial world parser takes from them its defaults, its required keys (:func:`world_value`) and its checks
of scalar values (:func:`checked_value`, the one checker of :mod:`clew_ros.core.parameters`); the node its
ROS descriptors (``clew_ros.ros.parameters.descriptor_for``); docs/parameters.md its spatial tables
(``clew_ros.cli.parameter_tables``). The lists, poses and the rules that tie keys together (one of urdf and
description, a stable placement, a grasp on the object) are checked by the parser itself, naming the key.
Pure data and checks: no ROS, no numpy.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Iterable, Mapping
from typing import Any

from clew_ros.core.errors import ParameterError, WorldError
from clew_ros.core.parameters import LIMITS, REQUIRED, ParameterSpec, ParameterTable, ParameterType, check_value
from clew_ros.spatial import WORLD_KIND

__all__ = [
    "OBSTACLE_PREFIX",
    "SPATIAL_OBSTACLE_PARAMETERS",
    "SPATIAL_WORLD_PARAMETERS",
    "checked_value",
    "spatial_spec",
    "unknown_keys",
    "world_value",
]

_S, _D = ParameterType.STRING, ParameterType.DOUBLE
_DA, _SA = ParameterType.DOUBLE_ARRAY, ParameterType.STRING_ARRAY

#: A pose, as every spatial pose parameter reads it.
_POSE = "[x, y, z, roll, pitch, yaw] (m, rad; rotation Rz(yaw) Ry(pitch) Rx(roll), URDF's rpy)"


def _locked(specs: Iterable[ParameterSpec]) -> list[ParameterSpec]:
    """``world.*`` parameters are fixed at start, as the planar world's (``LOCKED_PREFIXES``)."""
    return [dataclasses.replace(spec, locked=True) for spec in specs]


SPATIAL_WORLD_PARAMETERS = ParameterTable(
    "world.",
    _locked(
        [
            ParameterSpec("world.kind", _S, REQUIRED, f"The kind of world: {WORLD_KIND} for the worlds of this table."),
            ParameterSpec(
                "world.name",
                _S,
                WORLD_KIND,
                f"Name of the world; plans and recordings carry it. At most {LIMITS.max_name_chars} characters.",
            ),
            ParameterSpec(
                "world.bounds",
                _DA,
                None,
                "The workspace box [xmin, ymin, zmin, xmax, ymax, zmax] (m) the robot and the object stay in; "
                "absent: no box.",
                "m",
            ),
            ParameterSpec(
                "world.robot.urdf",
                _S,
                None,
                "The URDF file: a path (relative to the parameter file's folder) or package://PKG/path; exactly "
                f"one of it and world.robot.description; at most {LIMITS.max_urdf_bytes} bytes.",
            ),
            ParameterSpec(
                "world.robot.description",
                _S,
                None,
                "The URDF text itself (what a robot_description parameter holds), instead of world.robot.urdf.",
            ),
            ParameterSpec(
                "world.robot.package_paths",
                _SA,
                None,
                "Folders (relative to the parameter file's) that hold the packages of package:// URIs, looked in "
                "before the ament index and ROS_PACKAGE_PATH; absent: none.",
            ),
            ParameterSpec(
                "world.robot.srdf",
                _S,
                None,
                "An SRDF file (path or package:// URI): its disable_collisions pairs are not checked for "
                "self-collision; absent: only a link and its parent are exempt.",
            ),
            ParameterSpec(
                "world.robot.base_link",
                _S,
                REQUIRED,
                "The URDF link the planned chain starts from; the planned joints are the movable ones from it "
                "to world.robot.tip_link.",
            ),
            ParameterSpec(
                "world.robot.tip_link", _S, REQUIRED, "The URDF link the planned chain ends at (the tcp's link)."
            ),
            ParameterSpec(
                "world.robot.tcp",
                _DA,
                [0.0] * 6,
                f"The tool centre point as a pose {_POSE} in tip_link's frame; grasps are poses of this frame.",
                "m, rad",
            ),
            ParameterSpec("world.robot.base_pose", _DA, [0.0] * 6, f"base_link's pose {_POSE} in world.", "m, rad"),
            ParameterSpec(
                "world.robot.joint_lower",
                _DA,
                None,
                "Lower limits of the planned joints (rad; m for a prismatic joint), one per joint; they may only "
                "narrow the URDF's; absent: the URDF's.",
                "rad",
            ),
            ParameterSpec(
                "world.robot.joint_upper",
                _DA,
                None,
                "Upper limits of the planned joints (rad; m for a prismatic joint), one per joint; they may only "
                "narrow the URDF's; absent: the URDF's.",
                "rad",
            ),
            ParameterSpec(
                "world.robot.initial",
                _DA,
                REQUIRED,
                "The planned joints at the start (rad; m for a prismatic joint), in chain order, within their limits.",
                "rad",
            ),
            ParameterSpec(
                "world.robot.goal",
                _DA,
                None,
                "A motion-only query's goal (no world.object): the planned joints' goal values (rad; m for a "
                "prismatic joint).",
                "rad",
            ),
            ParameterSpec(
                "world.robot.goal_pose",
                _DA,
                None,
                f"A motion-only query's goal instead of world.robot.goal: the tcp's pose {_POSE} in world, any "
                "inverse-kinematics solution.",
                "m, rad",
            ),
            ParameterSpec(
                "world.robot.fixed_joint_names",
                _SA,
                None,
                "Movable URDF joints outside the planned chain (fingers) given a position in "
                "world.robot.fixed_joint_positions; the others stay at 0 clamped to their limits.",
            ),
            ParameterSpec(
                "world.robot.fixed_joint_positions",
                _DA,
                None,
                "The positions (rad; m for a prismatic joint) of world.robot.fixed_joint_names, one per name.",
                "rad",
            ),
            ParameterSpec(
                "world.robot.gripper_links",
                _SA,
                None,
                "The links that may touch the object (fingers, hand); absent: none.",
            ),
            ParameterSpec(
                "world.robot.padding",
                _D,
                0.0,
                "How far (m) every link's collision geometry is grown (MoveIt's link padding).",
                "m",
                (0.0, 1.0),
            ),
            ParameterSpec(
                "world.obstacle_names",
                _SA,
                None,
                "Names of the obstacles; each needs world.obstacles.<name>.shape, .size and .pose. Omit it for a "
                f"world without obstacles. At most {LIMITS.max_obstacles} obstacles with the scene file's.",
            ),
            ParameterSpec(
                "world.scene_file",
                _S,
                None,
                "A MoveIt planning scene as YAML (relative to the parameter file's folder): each collision "
                "object's primitives become obstacles named <id> (<id>_<k> when there are several); at most "
                f"{LIMITS.max_scene_file_bytes} bytes.",
            ),
            ParameterSpec(
                "world.supports",
                _SA,
                None,
                "Names of obstacles (boxes, or cylinders standing upright) whose top face carries the object.",
            ),
            ParameterSpec(
                "world.object.shape",
                _S,
                REQUIRED,
                "The object's shape, box or cylinder (with world.object; without it, a motion-only query).",
            ),
            ParameterSpec(
                "world.object.size",
                _DA,
                REQUIRED,
                "The object's size as shape_msgs/SolidPrimitive dimensions (m): box [x, y, z] full extents, "
                "cylinder [height, radius].",
                "m",
            ),
            ParameterSpec(
                "world.object.initial",
                _DA,
                REQUIRED,
                f"The object's start pose {_POSE}: a stable placement on a support.",
                "m, rad",
            ),
            ParameterSpec(
                "world.object.goal",
                _DA,
                REQUIRED,
                f"The object's goal pose {_POSE}: a stable placement on a support; ~/plan plans to it.",
                "m, rad",
            ),
            ParameterSpec(
                "world.object.grasps",
                _DA,
                REQUIRED,
                "Grasps: a flat list of tcp poses in the object's frame, 6 numbers each (m, rad), each tcp on or "
                f"inside the object within world.grasp_tolerance; at most {LIMITS.max_grasps}.",
                "m, rad",
            ),
            ParameterSpec(
                "world.placement_tolerance",
                _D,
                0.001,
                "A stable placement's face lies within this distance (m) of its support's top face.",
                "m",
                (0.0, 1.0),
            ),
            ParameterSpec(
                "world.grasp_tolerance",
                _D,
                0.005,
                "The tcp holds a grasp when it is within this distance (m) of the grasp's pose.",
                "m",
                (0.0, 1.0),
            ),
            ParameterSpec(
                "world.grasp_angle_tolerance",
                _D,
                0.01,
                "The tcp holds a grasp when its orientation is within this angle (rad) of the grasp's.",
                "rad",
                (0.0, math.pi),
            ),
            ParameterSpec(
                "world.goal_tolerance",
                _D,
                0.02,
                "Largest distance (m) of the object's final centre from the goal's.",
                "m",
                (0.0, 10.0),
            ),
            ParameterSpec(
                "world.goal_angle_tolerance",
                _D,
                math.pi,
                "Largest yaw error (rad) about z of the object at the goal; pi (or more): any yaw.",
                "rad",
                (0.0, 2.0 * math.pi),
            ),
        ]
    ),
)

#: The prefix of an obstacle's keys in :data:`SPATIAL_OBSTACLE_PARAMETERS` (``<name>``: any listed name).
OBSTACLE_PREFIX = "world.obstacles.<name>."

SPATIAL_OBSTACLE_PARAMETERS = ParameterTable(
    OBSTACLE_PREFIX,
    _locked(
        [
            ParameterSpec(
                "world.obstacles.<name>.shape", _S, REQUIRED, "The obstacle's shape: box, cylinder or sphere."
            ),
            ParameterSpec(
                "world.obstacles.<name>.size",
                _DA,
                REQUIRED,
                "The obstacle's size as shape_msgs/SolidPrimitive dimensions (m): box [x, y, z] full extents, "
                "cylinder [height, radius] along its z, sphere [radius].",
                "m",
            ),
            ParameterSpec(
                "world.obstacles.<name>.pose", _DA, REQUIRED, f"The obstacle's pose {_POSE} in world.", "m, rad"
            ),
        ]
    ),
)


def spatial_spec(name: str) -> ParameterSpec | None:
    """The spec of a spatial world's parameter by its full name (``world.obstacles.<name>.<key>`` for any
    obstacle name); ``None`` when a spatial world has no such parameter."""
    if name.startswith("world.obstacles."):
        obstacle, _, key = name[len("world.obstacles.") :].rpartition(".")
        return SPATIAL_OBSTACLE_PARAMETERS.get(key) if obstacle else None
    return SPATIAL_WORLD_PARAMETERS.get(name.removeprefix("world.")) if name.startswith("world.") else None


def unknown_keys(names: Iterable[str]) -> list[str]:
    """The full names among ``names`` (``world.*`` parameters) that no spatial spec covers."""
    return [name for name in names if spatial_spec(name) is None]


def world_value(part: Mapping[str, Any], name: str) -> Any:
    """The value of parameter ``name`` (a full name, ``world.robot.padding``) in ``part``, the mapping that
    holds its last key (``world.robot``'s tree), else its default; a required one that is absent raises
    :class:`~clew_ros.core.errors.WorldError` naming it."""
    spec = spatial_spec(name)
    if spec is None:
        raise KeyError(f"{name} is not a spatial world parameter")
    key = name.rpartition(".")[2]
    if key in part:
        return part[key]
    if spec.required:
        raise WorldError(name, f"missing (required): {spec.description}")
    return spec.default


def checked_value(part: Mapping[str, Any], name: str) -> Any:
    """:func:`world_value` checked and converted by :func:`~clew_ros.core.parameters.check_value` (a scalar:
    a string, a number within the spec's limits); :class:`~clew_ros.core.errors.WorldError` names ``name``
    and what was expected. ``None`` when the parameter is absent and has no default."""
    value = world_value(part, name)
    if value is None:
        return None
    spec = spatial_spec(name)
    assert spec is not None
    try:
        return check_value(dataclasses.replace(spec, name=name), value)
    except ParameterError as error:
        raise WorldError(error.parameter, error.expected) from None
