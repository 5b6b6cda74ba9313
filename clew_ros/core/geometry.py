"""Vectorised planar primitives: segment distances and edge lists.

Segments are arrays ``(..., 2, 2)`` (start, end); every function broadcasts.
"""

from __future__ import annotations

import numpy as np

__all__ = ["point_segment_distance", "polygon_edges", "segment_distance"]


def polygon_edges(vertices: np.ndarray) -> np.ndarray:
    """Closed ring ``(..., V, 2)`` as edges ``(..., V, 2, 2)``."""
    edges: np.ndarray = np.stack([vertices, np.roll(vertices, -1, axis=-2)], axis=-2)
    return edges


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    cross: np.ndarray = a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]
    return cross


def point_segment_distance(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Distance from points ``p`` to segments ``[a, b]`` (all ``(..., 2)``)."""
    abx, aby = b[..., 0] - a[..., 0], b[..., 1] - a[..., 1]
    apx, apy = p[..., 0] - a[..., 0], p[..., 1] - a[..., 1]
    denominator = abx * abx + aby * aby
    t = (apx * abx + apy * aby) / np.where(denominator > 0, denominator, 1.0)
    t = np.minimum(np.maximum(t, 0.0), 1.0)  # np.clip costs more on the small arrays of the planner
    dx, dy = apx - t * abx, apy - t * aby
    distance: np.ndarray = np.sqrt(dx * dx + dy * dy)
    return distance


def segment_distance(p1: np.ndarray, p2: np.ndarray, q1: np.ndarray, q2: np.ndarray) -> np.ndarray:
    """Distance between segments ``[p1, p2]`` and ``[q1, q2]``; 0 where they cross."""
    d = np.minimum(
        np.minimum(point_segment_distance(p1, q1, q2), point_segment_distance(p2, q1, q2)),
        np.minimum(point_segment_distance(q1, p1, p2), point_segment_distance(q2, p1, p2)),
    )
    r = p2 - p1
    s = q2 - q1
    o1 = _cross(r, q1 - p1)
    o2 = _cross(r, q2 - p1)
    o3 = _cross(s, p1 - q1)
    o4 = _cross(s, p2 - q1)
    crossing = (o1 * o2 < 0) & (o3 * o4 < 0)
    return np.where(crossing, 0.0, d)
