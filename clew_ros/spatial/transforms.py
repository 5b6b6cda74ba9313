"""Rigid transforms as 4x4 matrices: URDF ``rpy`` poses, quaternions, axis-angle motions.

A pose is ``[x, y, z, roll, pitch, yaw]`` with rotation ``Rz(yaw) Ry(pitch) Rx(roll)`` (URDF's ``rpy``,
interface.md section 1b).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

__all__ = [
    "axis_motion",
    "matrix_pose",
    "matrix_quaternion",
    "pose_matrix",
    "quaternion_matrix",
    "rpy_matrix",
    "translation_matrix",
]

Matrix = NDArray[np.float64]


def rpy_matrix(roll: float, pitch: float, yaw: float) -> Matrix:
    """The 3x3 rotation ``Rz(yaw) Ry(pitch) Rx(roll)``."""
    cr, sr = math.cos(roll), math.sin(roll)
    cp, sp = math.cos(pitch), math.sin(pitch)
    cy, sy = math.cos(yaw), math.sin(yaw)
    return np.array(
        [
            [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
            [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
            [-sp, cp * sr, cp * cr],
        ]
    )


def translation_matrix(xyz: Sequence[float]) -> Matrix:
    """The 4x4 transform that moves by ``xyz`` (m)."""
    out = np.eye(4)
    out[:3, 3] = xyz
    return out


def pose_matrix(pose: Sequence[float]) -> Matrix:
    """The 4x4 transform of a pose ``[x, y, z, roll, pitch, yaw]`` (m, rad)."""
    out = np.eye(4)
    out[:3, :3] = rpy_matrix(pose[3], pose[4], pose[5])
    out[:3, 3] = pose[:3]
    return out


def quaternion_matrix(position: Sequence[float], quaternion: Sequence[float]) -> Matrix:
    """The 4x4 transform of ``position`` (m) and a unit quaternion ``[x, y, z, w]`` (normalised here)."""
    x, y, z, w = (float(v) for v in quaternion)
    norm = math.sqrt(x * x + y * y + z * z + w * w)
    x, y, z, w = x / norm, y / norm, z / norm, w / norm
    out = np.eye(4)
    out[:3, :3] = [
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ]
    out[:3, 3] = position
    return out


def axis_motion(axis: NDArray[np.float64], value: float, *, prismatic: bool) -> Matrix:
    """The 4x4 motion of a joint about (revolute, rad) or along (prismatic, m) the unit ``axis``."""
    out = np.eye(4)
    if prismatic:
        out[:3, 3] = axis * value
        return out
    k = np.array([[0.0, -axis[2], axis[1]], [axis[2], 0.0, -axis[0]], [-axis[1], axis[0], 0.0]])
    out[:3, :3] = np.eye(3) + math.sin(value) * k + (1.0 - math.cos(value)) * (k @ k)
    return out


def matrix_pose(matrix: NDArray[np.float64]) -> list[float]:
    """The pose ``[x, y, z, roll, pitch, yaw]`` (m, rad) of a 4x4 transform (inverse of :func:`pose_matrix`;
    at pitch +-pi/2, roll is 0)."""
    r = matrix[:3, :3]
    pitch = math.asin(max(-1.0, min(1.0, -float(r[2, 0]))))
    if abs(math.cos(pitch)) < 1e-9:
        roll, yaw = 0.0, math.atan2(-float(r[0, 1]), float(r[1, 1]))
    else:
        roll, yaw = math.atan2(float(r[2, 1]), float(r[2, 2])), math.atan2(float(r[1, 0]), float(r[0, 0]))
    return [float(matrix[0, 3]), float(matrix[1, 3]), float(matrix[2, 3]), roll, pitch, yaw]


def matrix_quaternion(r: Matrix) -> tuple[float, float, float, float]:
    """A unit quaternion ``(x, y, z, w)`` of a rotation matrix (3x3)."""
    trace = float(r[0, 0] + r[1, 1] + r[2, 2])
    if trace > 0:
        s = 2.0 * math.sqrt(trace + 1.0)
        q = ((r[2, 1] - r[1, 2]) / s, (r[0, 2] - r[2, 0]) / s, (r[1, 0] - r[0, 1]) / s, 0.25 * s)
    elif r[0, 0] > r[1, 1] and r[0, 0] > r[2, 2]:
        s = 2.0 * math.sqrt(1.0 + r[0, 0] - r[1, 1] - r[2, 2])
        q = (0.25 * s, (r[0, 1] + r[1, 0]) / s, (r[0, 2] + r[2, 0]) / s, (r[2, 1] - r[1, 2]) / s)
    elif r[1, 1] > r[2, 2]:
        s = 2.0 * math.sqrt(1.0 + r[1, 1] - r[0, 0] - r[2, 2])
        q = ((r[0, 1] + r[1, 0]) / s, 0.25 * s, (r[1, 2] + r[2, 1]) / s, (r[0, 2] - r[2, 0]) / s)
    else:
        s = 2.0 * math.sqrt(1.0 + r[2, 2] - r[0, 0] - r[1, 1])
        q = ((r[0, 2] + r[2, 0]) / s, (r[1, 2] + r[2, 1]) / s, 0.25 * s, (r[1, 0] - r[0, 1]) / s)
    x, y, z, w = (float(v) for v in q)
    return x, y, z, w
