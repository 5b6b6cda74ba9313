"""How far apart: the landmark distance EXPLORE maximises (:func:`landmark_features`), the object's distance to
the goal SEARCH_TRANSFER minimises (:func:`goal_distance`), and whether it rests at the goal (:func:`at_goal`)."""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from clew_ros.spatial.settle import rests
from clew_ros.spatial.space_parts import SpaceParts
from clew_ros.spatial.transforms import matrices
from clew_ros.spatial.turns import joint_features

__all__ = ["at_goal", "goal_distance", "goal_parts", "landmark_features"]

Array = NDArray[np.float64]


def landmark_features(parts: SpaceParts, joints: Array, object_poses: Array, joint_weight: float) -> Array:
    """Object position (m); orientation as its rotation matrix times the object's radius over sqrt 2
    (distances are then chords, m, of a circle of that radius: the face down and the yaw both count);
    joints times ``joint_weight`` (m/rad) times ``sqrt(2 / n)``, as the planar space weighs them (a
    continuous joint on the unit circle: :func:`~clew_ros.spatial.turns.joint_features`)."""
    rot = matrices(object_poses)[:, :3, :3].reshape(len(object_poses), 9)
    weight = joint_weight * float(np.sqrt(2.0 / joints.shape[1]))
    turned = joint_features(joints, parts.world.robot.continuous)  # continuous joints modulo 2 pi
    return np.concatenate(
        [np.asarray(object_poses)[:, :3], parts.object_radius / math.sqrt(2.0) * rot, weight * turned], axis=1
    )


def goal_parts(parts: SpaceParts, object_poses: Array, goal: Array) -> tuple[Array, Array, Array]:
    """Per pose: the centre's distance to the goal's (m), the angle (rad) between the world's up seen
    from the object and from the goal (0: the same face down), and the yaw error beyond
    ``world.goal_angle_tolerance`` (rad)."""
    mats = matrices(object_poses)
    target = matrices(goal)[0]
    distance = np.linalg.norm(mats[:, :3, 3] - target[:3, 3], axis=1)
    up_here = mats[:, 2, :3]  # world z in the object's frame: row 2 of R
    up_goal = target[2, :3]
    tilt = np.arccos(np.clip(up_here @ up_goal, -1.0, 1.0))
    relative = mats[:, :3, :3] @ target[:3, :3].T  # about world z when the faces agree
    yaw = np.abs(np.arctan2(relative[:, 1, 0], relative[:, 0, 0]))
    excess = np.maximum(yaw - parts.world.tolerances["goal_angle_tolerance"], 0.0)
    return distance, tilt, excess


def goal_distance(parts: SpaceParts, object_poses: Array, goal: Array) -> Array:
    """The centre's distance (m) plus ``SpatialTuning.angle_weight_m`` x (the face's tilt + the yaw beyond
    its tolerance): 0 at the goal."""
    distance, tilt, excess = goal_parts(parts, object_poses, goal)
    out: Array = distance + parts.tuning.angle_weight_m * (tilt + excess)
    return out


def at_goal(parts: SpaceParts, object_pose: Array, goal: Array) -> bool:
    """Whether the object rests at ``object_pose`` within the goal's tolerances (section 1b)."""
    distance, tilt, excess = goal_parts(parts, object_pose[None], goal)
    tol = parts.world.tolerances
    return bool(
        distance[0] <= tol["goal_tolerance"]
        and tilt[0] <= parts.tuning.face_tolerance_rad
        and excess[0] <= 0.0
        and rests(parts.world, object_pose)
    )
