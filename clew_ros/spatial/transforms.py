"""Rigid transforms as 4x4 matrices: URDF ``rpy`` poses, quaternions, axis-angle motions, and their batches.

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
    "inverse_matrix",
    "matrices",
    "matrix_pose",
    "matrix_quaternion",
    "pose_matrix",
    "poses",
    "quaternion_matrix",
    "rotation_vectors",
    "rpy_matrix",
    "translation_matrix",
    "turned_about_z",
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


def matrices(poses: Matrix) -> Matrix:
    """4x4 transforms (B, 4, 4) of poses (B, 6) ``[x, y, z, roll, pitch, yaw]`` (vectorised :func:`pose_matrix`)."""
    poses = np.asarray(poses, dtype=float).reshape(-1, 6)
    cr, sr = np.cos(poses[:, 3]), np.sin(poses[:, 3])
    cp, sp = np.cos(poses[:, 4]), np.sin(poses[:, 4])
    cy, sy = np.cos(poses[:, 5]), np.sin(poses[:, 5])
    out = np.zeros((len(poses), 4, 4))
    out[:, 0, 0], out[:, 0, 1], out[:, 0, 2] = cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr
    out[:, 1, 0], out[:, 1, 1], out[:, 1, 2] = sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr
    out[:, 2, 0], out[:, 2, 1], out[:, 2, 2] = -sp, cp * sr, cp * cr
    out[:, :3, 3] = poses[:, :3]
    out[:, 3, 3] = 1.0
    return out


def poses(transforms: Matrix) -> Matrix:
    """Poses (B, 6) of 4x4 transforms (B, 4, 4) (vectorised :func:`matrix_pose`)."""
    r = np.asarray(transforms, dtype=float).reshape(-1, 4, 4)
    pitch = np.arcsin(np.clip(-r[:, 2, 0], -1.0, 1.0))
    flat = np.abs(np.cos(pitch)) < 1e-9
    roll = np.where(flat, 0.0, np.arctan2(r[:, 2, 1], r[:, 2, 2]))
    yaw = np.where(flat, np.arctan2(-r[:, 0, 1], r[:, 1, 1]), np.arctan2(r[:, 1, 0], r[:, 0, 0]))
    return np.column_stack([r[:, 0, 3], r[:, 1, 3], r[:, 2, 3], roll, pitch, yaw])


def rotation_vectors(rotations: Matrix) -> Matrix:
    """Rotation vectors (B, 3) (axis times angle, rad) of rotations (B, 3, 3)."""
    vec = 0.5 * np.stack(
        [
            rotations[:, 2, 1] - rotations[:, 1, 2],
            rotations[:, 0, 2] - rotations[:, 2, 0],
            rotations[:, 1, 0] - rotations[:, 0, 1],
        ],
        axis=1,
    )
    sine = np.linalg.norm(vec, axis=1)
    cosine = np.clip((np.trace(rotations, axis1=1, axis2=2) - 1.0) / 2.0, -1.0, 1.0)
    angle = np.arctan2(sine, cosine)
    scale = np.where(sine > 1e-12, angle / np.maximum(sine, 1e-300), 1.0)
    out: Matrix = vec * scale[:, None]
    return out


def inverse_matrix(transform: Matrix) -> Matrix:
    """The inverse of a rigid 4x4 transform."""
    out = np.eye(4)
    out[:3, :3] = transform[:3, :3].T
    out[:3, 3] = -transform[:3, :3].T @ transform[:3, 3]
    return out


def turned_about_z(base: Matrix, yaws: Sequence[float], tolerance: float) -> list[Matrix]:
    """``base`` (4x4) turned about world z through its own centre by each of ``yaws`` (rad) within
    ``tolerance`` (rad, either way), in their order."""
    out = []
    for yaw in yaws:
        if abs(yaw) <= tolerance + 1e-12:
            turned = base.copy()
            turned[:3, :3] = rpy_matrix(0.0, 0.0, yaw) @ base[:3, :3]
            out.append(turned)
    return out
