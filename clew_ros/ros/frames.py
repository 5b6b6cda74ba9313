"""The TF frames of the arm and the object at a joint state; pure, no rclpy.

Each :class:`FrameTransform` is one edge of the TF tree, the pose of ``child``
in ``parent`` (planar: a translation in z = 0 and a rotation about z), exactly
the transform of the URDF joint between the two links
(:mod:`clew_ros.ros.urdf`):

- :func:`static_transforms` (``/tf_static``): ``world`` -> ``base_link`` (at
  ``world.robot.base``) and ``link_n`` -> ``tool`` (at ``(l_n, 0)``);
- :func:`arm_transforms` (``/tf``, at each sample): ``base_link`` -> ``link_1``
  (rotation ``q_1``), ``link_(i-1)`` -> ``link_i`` (at ``(l_(i-1), 0)``,
  rotation ``q_i``), and ``tool`` -> each gripper jaw (its angle from the
  ``gripper`` value);
- :func:`object_transform` (``/tf``): ``world`` -> ``object`` at the object's
  pose ``(x, y, theta)``;
- :func:`state_transforms`: both, what ``/tf`` carries at one played-back state.

Composed from ``world``, ``link_i`` has origin ``p_(i-1)`` and x axis along
``phi_i``, and ``tool`` is the end-effector frame of interface.md §1.
``clew_ros.recording.cdr.tf_message`` makes them a ``tf2_msgs/msg/TFMessage``, recorded and published.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from clew_ros.planar.world import Robot
from clew_ros.ros.urdf import BASE_LINK, JAW_LINKS, JAW_OPEN_RAD, ROOT_FRAME, TOOL_FRAME, jaw_offset_m, link_name

__all__ = [
    "OBJECT_FRAME",
    "FrameTransform",
    "arm_transforms",
    "object_transform",
    "state_transforms",
    "static_transforms",
]

#: The object's frame: origin at its pose's position, x axis along its angle.
OBJECT_FRAME = "object"


@dataclass(frozen=True)
class FrameTransform:
    """The pose of frame ``child`` in frame ``parent``: translation ``(x, y, 0)`` m, rotation ``yaw`` rad about z."""

    parent: str
    child: str
    x: float
    y: float
    yaw: float

    @property
    def translation(self) -> tuple[float, float, float]:
        return (self.x, self.y, 0.0)

    @property
    def rotation(self) -> tuple[float, float, float, float]:
        """The rotation as a unit quaternion ``(x, y, z, w)``."""
        return (0.0, 0.0, math.sin(0.5 * self.yaw), math.cos(0.5 * self.yaw))


def static_transforms(robot: Robot) -> list[FrameTransform]:
    """The fixed joints: ``world`` -> ``base_link`` and ``link_n`` -> ``tool``."""
    return [
        FrameTransform(ROOT_FRAME, BASE_LINK, float(robot.base[0]), float(robot.base[1]), 0.0),
        FrameTransform(link_name(robot.dof), TOOL_FRAME, float(robot.link_lengths[-1]), 0.0, 0.0),
    ]


def arm_transforms(robot: Robot, joints: Sequence[float] | np.ndarray, gripper: float) -> list[FrameTransform]:
    """The moving joints at ``joints`` ``(n,)`` rad and ``gripper`` (0.0 open ... 1.0 closed)."""
    q = [float(v) for v in joints]
    if len(q) != robot.dof:
        raise ValueError(f"expected {robot.dof} joint angles, got {len(q)}")
    out = [FrameTransform(BASE_LINK, link_name(1), 0.0, 0.0, q[0])]
    out.extend(
        FrameTransform(link_name(i), link_name(i + 1), float(robot.link_lengths[i - 1]), 0.0, q[i])
        for i in range(1, robot.dof)
    )
    hinge = jaw_offset_m(robot)
    closing = min(max(float(gripper), 0.0), 1.0)  # the URDF's gripper limits
    left, right = JAW_LINKS
    out.append(FrameTransform(TOOL_FRAME, left, 0.0, hinge, JAW_OPEN_RAD - closing))
    out.append(FrameTransform(TOOL_FRAME, right, 0.0, -hinge, -JAW_OPEN_RAD + closing))
    return out


def object_transform(pose: Sequence[float] | np.ndarray) -> FrameTransform:
    """``world`` -> ``object`` at ``pose`` ``(x, y, theta)``."""
    return FrameTransform(ROOT_FRAME, OBJECT_FRAME, float(pose[0]), float(pose[1]), float(pose[2]))


def state_transforms(
    robot: Robot, joints: Sequence[float] | np.ndarray, gripper: float, object_pose: Sequence[float] | np.ndarray
) -> list[FrameTransform]:
    """``/tf`` at one state: :func:`arm_transforms` at ``joints`` and ``gripper``, then :func:`object_transform`."""
    return [*arm_transforms(robot, joints, gripper), object_transform(object_pose)]
