"""Forward kinematics of the planar chain (compiled, :func:`clew_ros.planar.kernel.chain`) and planar
pose algebra, over batches.

Configurations are ``(N, n)`` arrays of joint angles (rad); poses are ``(..., 3)``
arrays ``(x, y, theta)``.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from clew_ros.planar import kernel
from clew_ros.planar.world import Robot

__all__ = [
    "compose",
    "joint_positions",
    "relative",
    "tip_poses",
    "transform_points",
    "wrap_angle",
]


def joint_positions(robot: Robot, q: np.ndarray) -> np.ndarray:
    """Points ``p_0 .. p_n`` of the chain, shape ``(N, n + 1, 2)`` for ``q`` of shape ``(N, n)``.

    >>> from clew_ros.planar.world import Robot
    >>> import numpy as np
    >>> r = Robot(np.zeros(2), np.array([1.0, 1.0]), -np.ones(2) * 3, np.ones(2) * 3, np.zeros(2))
    >>> joint_positions(r, np.array([[np.pi / 2, -np.pi / 2]])).round(6).tolist()
    [[[0.0, 0.0], [0.0, 1.0], [1.0, 1.0]]]
    """
    return _chain(robot, q)[0]


def tip_poses(robot: Robot, q: np.ndarray) -> np.ndarray:
    """End-effector frames ``(x, y, phi_n)``, shape ``(N, 3)``."""
    return _chain(robot, q)[1]


def _chain(robot: Robot, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    q = np.atleast_2d(np.asarray(q, dtype=float))
    base, lengths = _arrays(robot)
    return kernel.chain(base, lengths, q)


@lru_cache(maxsize=256)
def _arrays(robot: Robot) -> tuple[np.ndarray, np.ndarray]:
    """The robot's base and link lengths as the kernel takes them (writable contiguous copies)."""
    return np.array(robot.base, dtype=float), np.array(robot.link_lengths, dtype=float)


def wrap_angle(angle: np.ndarray | float) -> np.ndarray:
    """Angles wrapped into ``[-pi, pi)``."""
    return (np.asarray(angle) + np.pi) % (2 * np.pi) - np.pi


def compose(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Pose ``a * b``: ``b`` expressed in ``a``'s frame, returned in ``a``'s parent frame."""
    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float)
    c, s = np.cos(a[..., 2]), np.sin(a[..., 2])
    shape = np.broadcast_shapes(a.shape, b.shape)
    out = np.empty(shape)
    out[..., 0] = a[..., 0] + c * b[..., 0] - s * b[..., 1]
    out[..., 1] = a[..., 1] + s * b[..., 0] + c * b[..., 1]
    out[..., 2] = a[..., 2] + b[..., 2]
    return out


def relative(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Pose of ``b`` in ``a``'s frame: ``inverse(a) * b``."""
    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float)
    c, s = np.cos(a[..., 2]), np.sin(a[..., 2])
    dx = b[..., 0] - a[..., 0]
    dy = b[..., 1] - a[..., 1]
    return np.stack([c * dx + s * dy, -s * dx + c * dy, b[..., 2] - a[..., 2]], axis=-1)


def transform_points(pose: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Points ``(V, 2)`` given in frame ``pose`` ``(..., 3)``, in world coordinates ``(..., V, 2)``."""
    pose = np.asarray(pose, dtype=float)
    c = np.cos(pose[..., 2])[..., None]
    s = np.sin(pose[..., 2])[..., None]
    out = np.empty(pose.shape[:-1] + points.shape)
    out[..., 0] = pose[..., 0, None] + c * points[:, 0] - s * points[:, 1]
    out[..., 1] = pose[..., 1, None] + s * points[:, 0] + c * points[:, 1]
    return out
