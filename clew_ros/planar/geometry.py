"""Vectorised planar primitives: segment distances and edge lists.

Segments are arrays ``(..., 2, 2)`` (start, end); every function broadcasts.
"""

from __future__ import annotations

import numpy as np

__all__ = ["point_segment_distance", "polygon_edges"]


def polygon_edges(vertices: np.ndarray) -> np.ndarray:
    """Closed ring ``(..., V, 2)`` as edges ``(..., V, 2, 2)``."""
    edges: np.ndarray = np.stack([vertices, np.roll(vertices, -1, axis=-2)], axis=-2)
    return edges


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
