"""Forward kinematics of a URDF parsed by urdf_parser_py: every link's 4x4 pose in the root link.

Written from the URDF specification alone (joint origin ``xyz`` / ``rpy``, then the motion about
``axis``; ``mimic`` joints follow theirs), so the tests check the generated URDF against it.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np


def _rotation(rpy: list[float]) -> np.ndarray:
    roll, pitch, yaw = rpy
    rx = np.array([[1, 0, 0], [0, math.cos(roll), -math.sin(roll)], [0, math.sin(roll), math.cos(roll)]])
    ry = np.array([[math.cos(pitch), 0, math.sin(pitch)], [0, 1, 0], [-math.sin(pitch), 0, math.cos(pitch)]])
    rz = np.array([[math.cos(yaw), -math.sin(yaw), 0], [math.sin(yaw), math.cos(yaw), 0], [0, 0, 1]])
    return rz @ ry @ rx  # URDF: fixed axes roll, pitch, yaw


def _axis_angle(axis: np.ndarray, angle: float) -> np.ndarray:
    axis = axis / np.linalg.norm(axis)
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + math.sin(angle) * k + (1 - math.cos(angle)) * k @ k


def matrix(rotation: np.ndarray, translation: np.ndarray) -> np.ndarray:
    out = np.eye(4)
    out[:3, :3] = rotation
    out[:3, 3] = translation
    return out


def urdf_fk(robot: Any, positions: dict[str, float]) -> dict[str, np.ndarray]:
    """Every link's 4x4 pose in the root link, from the parsed URDF's joints (revolute, fixed, mimic)."""
    poses = {robot.get_root(): np.eye(4)}
    pending = list(robot.joints)
    while pending:
        joint = next(j for j in pending if j.parent in poses)
        pending.remove(joint)
        origin = joint.origin
        placed = poses[joint.parent] @ matrix(_rotation(list(origin.rpy)), np.array(origin.xyz))
        if joint.type == "fixed":
            motion = np.eye(4)
        else:
            assert joint.type == "revolute", joint.type
            if joint.mimic is not None:
                value = positions[joint.mimic.joint] * joint.mimic.multiplier + joint.mimic.offset
            else:
                value = positions[joint.name]
            motion = matrix(_axis_angle(np.array(joint.axis, dtype=float), value), np.zeros(3))
        poses[joint.child] = placed @ motion
    return poses
