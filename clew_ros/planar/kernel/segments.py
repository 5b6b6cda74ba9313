"""Plane geometry both the free intervals and the validity test use: a point's distance to a segment and an
object edge placed at a pose."""

from __future__ import annotations

import math

import numpy as np

from clew_ros.planar.kernel.jit import _leaf


@_leaf
def _point_segment_distance(px: float, py: float, ax: float, ay: float, bx: float, by: float) -> float:
    abx, aby = bx - ax, by - ay
    apx, apy = px - ax, py - ay
    length2 = abx * abx + aby * aby
    t = (apx * abx + apy * aby) / length2 if length2 > 0.0 else 0.0
    t = min(max(t, 0.0), 1.0)
    dx, dy = apx - t * abx, apy - t * aby
    return math.sqrt(dx * dx + dy * dy)


@_leaf
def _place(edges: np.ndarray, x: float, y: float, theta: float, px: float, py: float, out: np.ndarray) -> None:
    """``edges`` (object frame) at pose ``(x, y, theta)``, relative to the pivot ``p``, into ``out``."""
    c, s = math.cos(theta), math.sin(theta)
    for e in range(edges.shape[0]):
        for v in range(2):
            ex, ey = edges[e, v, 0], edges[e, v, 1]
            out[e, v, 0] = x + c * ex - s * ey - px
            out[e, v, 1] = y + s * ex + c * ey - py
