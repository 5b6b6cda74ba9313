"""Spatial plans timed and played back: every joint of the URDF, every link's frame, the trajectory's limits.

Pure NumPy and the standard library (no rclpy, no URDF parser package), so it is tested without a ROS
graph:

- :class:`UrdfTree` reads the URDF's joints (type, parent and child link, origin, axis, limits with the
  velocity limit, mimic) and gives every link's pose relative to its parent at joint values
  (:meth:`UrdfTree.joint_transforms`, what ``robot_state_publisher`` puts on ``/tf``) and in ``world``
  (:meth:`UrdfTree.link_poses`), independently of the planner's packed chain.
- :func:`spatial_track` times a spatial plan as the node times a planar one (the rest-to-rest quintic of
  :mod:`~clew_ros.motion.timing` per straight piece, a grasp or an ungrasp lasting ``grasp_dwell_s``),
  each planned joint within the lower of its URDF velocity limit and ``trajectory.max_velocity``, and
  within ``trajectory.max_acceleration`` (URDF has no acceleration limit). The track's ``joint_names`` are
  the planned joints' URDF names only (no ``gripper`` joint: interface.md section 3, spatial paragraph).
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from clew_ros.motion.playback import MIN_STEP_NS, Track, TrackTiming
from clew_ros.motion.timing import rest_to_rest_duration_s
from clew_ros.spatial.transforms import axis_motion, matrix_pose, pose_matrix

if TYPE_CHECKING:
    from clew_ros.core.plan import Plan
    from clew_ros.spatial.world import SpatialWorld

__all__ = ["UrdfJoint", "UrdfTree", "spatial_track", "velocity_limits"]

Matrix = NDArray[np.float64]
_MOVABLE = ("revolute", "continuous", "prismatic")


@dataclass(frozen=True)
class UrdfJoint:
    """One ``<joint>`` of a URDF: ``origin`` its 4x4 pose in the parent link's frame; ``velocity`` its
    ``<limit velocity>`` (rad/s or m/s; ``inf`` when absent); ``mimic`` ``(joint, multiplier, offset)``."""

    name: str
    type: str
    parent: str
    child: str
    origin: Matrix
    axis: tuple[float, float, float]
    lower: float
    upper: float
    velocity: float
    mimic: tuple[str, float, float] | None

    @property
    def movable(self) -> bool:
        return self.type in _MOVABLE


def _floats(text: str | None, count: int, default: float) -> list[float]:
    if not text:
        return [default] * count
    values = [float(v) for v in text.split()]
    if len(values) != count:
        raise ValueError(f"expected {count} numbers, got {text!r}")
    return values


class UrdfTree:
    """The joints and links of a URDF text (every link, not only the planned chain)."""

    def __init__(self, urdf_text: str) -> None:
        root = ET.fromstring(urdf_text)
        self.links: tuple[str, ...] = tuple(str(link.get("name")) for link in root.findall("link"))
        joints = []
        for element in root.findall("joint"):
            origin = element.find("origin")
            xyz = _floats(origin.get("xyz") if origin is not None else None, 3, 0.0)
            rpy = _floats(origin.get("rpy") if origin is not None else None, 3, 0.0)
            axis_element = element.find("axis")
            axis = _floats(axis_element.get("xyz") if axis_element is not None else None, 3, 0.0)
            if element.get("type") in _MOVABLE and axis_element is None:
                axis = [1.0, 0.0, 0.0]  # URDF's default axis
            limit = element.find("limit")
            lower = float(limit.get("lower", "0")) if limit is not None else 0.0
            upper = float(limit.get("upper", "0")) if limit is not None else 0.0
            if element.get("type") == "continuous":
                lower, upper = -math.inf, math.inf
            velocity = float(limit.get("velocity", "inf")) if limit is not None else math.inf
            mimic_element = element.find("mimic")
            mimic = None
            if mimic_element is not None:
                mimic = (
                    str(mimic_element.get("joint")),
                    float(mimic_element.get("multiplier", "1")),
                    float(mimic_element.get("offset", "0")),
                )
            parent, child = element.find("parent"), element.find("child")
            if parent is None or child is None:
                raise ValueError(f"joint {element.get('name')!r}: expected <parent> and <child>")
            joints.append(
                UrdfJoint(
                    name=str(element.get("name")),
                    type=str(element.get("type")),
                    parent=str(parent.get("link")),
                    child=str(child.get("link")),
                    origin=pose_matrix([*xyz, *rpy]),
                    axis=(axis[0], axis[1], axis[2]),
                    lower=lower,
                    upper=upper,
                    velocity=velocity,
                    mimic=mimic,
                )
            )
        self.joints: tuple[UrdfJoint, ...] = tuple(joints)
        children = {joint.child for joint in joints}
        roots = [link for link in self.links if link not in children]
        if len(roots) != 1:
            raise ValueError(f"expected one root link, got {roots}")
        self.root = roots[0]
        self._by_child = {joint.child: joint for joint in joints}
        self._order = self._topological()

    def _topological(self) -> list[UrdfJoint]:
        """The joints, each after the joint of its parent link."""
        by_parent: dict[str, list[UrdfJoint]] = {}
        for joint in self.joints:
            by_parent.setdefault(joint.parent, []).append(joint)
        order: list[UrdfJoint] = []
        stack = [self.root]
        while stack:
            link = stack.pop()
            for joint in by_parent.get(link, []):
                order.append(joint)
                stack.append(joint.child)
        return order

    @property
    def movable_joint_names(self) -> list[str]:
        """Every movable joint (revolute, continuous, prismatic), in the URDF's order."""
        return [joint.name for joint in self.joints if joint.movable]

    def joint_values(self, planned: Sequence[str], q: Sequence[float], fixed: Mapping[str, float]) -> dict[str, float]:
        """The value of every movable joint: the planned ones from ``q``, the others from ``fixed``
        (``RobotModel.fixed_positions``), mimic joints following theirs, any other 0 clamped to its limits."""
        values = {name: float(v) for name, v in zip(planned, q, strict=True)}
        for joint in self.joints:
            if joint.movable and joint.name not in values and joint.name in fixed:
                values[joint.name] = float(fixed[joint.name])
        for joint in self.joints:
            if joint.movable and joint.name not in values:
                if joint.mimic is not None and joint.mimic[0] in values:
                    values[joint.name] = joint.mimic[1] * values[joint.mimic[0]] + joint.mimic[2]
                else:
                    values[joint.name] = min(max(0.0, joint.lower), joint.upper)
        return values

    def joint_transforms(
        self, values: Mapping[str, float], movable: bool | None = None
    ) -> list[tuple[str, str, Matrix]]:
        """``(parent link, child link, 4x4 pose of the child in the parent)`` of every joint at ``values``
        (``movable``: only the movable joints, or only the others)."""
        out = []
        for joint in self._order:
            if movable is not None and joint.movable != movable:
                continue
            transform = joint.origin
            if joint.movable:
                axis = np.asarray(joint.axis) / np.linalg.norm(joint.axis)
                motion = axis_motion(axis, values.get(joint.name, 0.0), prismatic=joint.type == "prismatic")
                transform = transform @ motion
            out.append((joint.parent, joint.child, transform))
        return out

    def root_pose(self, base_link: str, base: Matrix, values: Mapping[str, float]) -> Matrix:
        """The root link's pose in ``world`` that puts ``base_link`` at ``base`` (``world.robot.base_pose``)."""
        relative = self.link_poses(np.eye(4), values)[base_link]
        pose: Matrix = base @ np.linalg.inv(relative)
        return pose

    def link_poses(self, root: Matrix, values: Mapping[str, float]) -> dict[str, Matrix]:
        """Every link's 4x4 pose, the root at ``root``."""
        poses = {self.root: np.asarray(root, dtype=float)}
        for parent, child, transform in self.joint_transforms(values):
            poses[child] = poses[parent] @ transform
        return poses

    def velocity_of(self, name: str) -> float:
        return next(joint.velocity for joint in self.joints if joint.name == name)


def velocity_limits(tree: UrdfTree, joint_names: Sequence[str], limit: float | Sequence[float]) -> np.ndarray:
    """Each planned joint's velocity limit: the lower of its URDF ``<limit velocity>`` and ``limit`` (the
    ``trajectory.max_velocity`` parameter: one for all joints, or one per joint)."""
    given = np.broadcast_to(np.asarray(limit, dtype=float), (len(joint_names),))
    urdf = np.array([tree.velocity_of(name) for name in joint_names])
    urdf = np.where(np.isfinite(urdf) & (urdf > 0), urdf, np.inf)  # 0 or absent: no limit given
    out: np.ndarray = np.minimum(given, urdf)
    return out


def spatial_track(world: SpatialWorld, plan: Plan, tree: UrdfTree, settings: TrackTiming) -> Track:
    """A successful spatial plan timed for a controller (the module docstring); object poses of 6 numbers."""
    from clew_ros.spatial.plan import replay  # the spatial extra
    from clew_ros.spatial.turns import unwrapped

    if not plan.segments:
        raise ValueError("a plan without segments has no trajectory")
    robot = world.robot
    names = list(robot.joint_names)
    max_velocity = velocity_limits(tree, names, settings.velocity_limit_rad_s)
    max_acceleration = np.broadcast_to(np.asarray(settings.max_acceleration_rad_s2, dtype=float), (len(names),))
    positions: list[np.ndarray] = []
    poses: list[np.ndarray] = []
    gripper: list[float] = []
    segment_of: list[int] = []
    grasps: list[int | None] = []
    grasp_rel: list[np.ndarray | None] = []
    for motion in replay(world, plan, waypoints_only=True):
        transfer = motion.kind == "transfer"
        grasps.append(motion.grasp if transfer else None)
        grasp_rel.append(None if motion.grasp_rel is None else np.linalg.inv(motion.grasp_rel))
        count = len(motion.configurations)
        positions.extend(np.asarray(motion.configurations))
        gripper.extend([1.0 if transfer else 0.0] * count)
        segment_of.extend([motion.index] * count)
        object_poses = motion.object_poses
        poses.extend(np.zeros((count, 6)) if object_poses is None else object_poses)
    # a continuous joint's points within pi of the one before: the controller's straight line is the short way
    positions_a = unwrapped(np.array(positions), robot.continuous)
    gripper_a = np.array(gripper)
    times = np.zeros(len(positions_a), dtype=np.int64)
    for k in range(1, len(positions_a)):
        if gripper_a[k] != gripper_a[k - 1]:
            step_ns = round(settings.grasp_dwell_s * 1e9)
        else:
            step_s = rest_to_rest_duration_s(positions_a[k] - positions_a[k - 1], max_velocity, max_acceleration)
            step_ns = math.ceil(step_s * 1e9)
        times[k] = times[k - 1] + max(MIN_STEP_NS, step_ns)

    def held_pose(q: np.ndarray, object_in_tcp: np.ndarray) -> np.ndarray:
        return np.array(matrix_pose(robot.tcp_pose(q.tolist()) @ object_in_tcp), dtype=float)

    def tcp_positions(qs: np.ndarray) -> np.ndarray:
        return np.array([robot.tcp_pose(q.tolist())[:3, 3] for q in np.atleast_2d(qs)])

    return Track(
        joint_names=names,
        times_ns=times,
        positions=positions_a,
        velocities=np.zeros_like(positions_a),
        accelerations=np.zeros_like(positions_a),
        gripper=gripper_a,
        object_poses=np.array(poses),
        segment=np.array(segment_of),
        grasps=grasps,
        grasp_rel=grasp_rel,
        tip_pose_fn=tcp_positions,
        max_velocity=np.asarray(max_velocity, dtype=float).copy(),
        max_acceleration=np.asarray(max_acceleration, dtype=float).copy(),
        held_pose_fn=held_pose,
        gripper_joint=False,
    )
