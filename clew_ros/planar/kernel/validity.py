"""The compiled first pass of the validity test: which configurations are valid beyond doubt (every
distance clear of its threshold by more than the world's rounding); the others go to the exact test."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from clew_ros.planar.kernel.jit import _inlined_leaf, _jit, _leaf
from clew_ros.planar.kernel.kinematics import _forward
from clew_ros.planar.kernel.packed import Model, PackedWorld, Placed, _arg, _named, _poses
from clew_ros.planar.kernel.segments import _place, _point_segment_distance


@_leaf
def _crosses(ax: float, ay: float, bx: float, by: float, cx: float, cy: float, dx: float, dy: float) -> bool:
    """Whether segments ``[a, b]`` and ``[c, d]`` cross at a point inside both (orientations differ)."""
    o1 = (bx - ax) * (cy - ay) - (by - ay) * (cx - ax)
    o2 = (bx - ax) * (dy - ay) - (by - ay) * (dx - ax)
    o3 = (dx - cx) * (ay - cy) - (dy - cy) * (ax - cx)
    o4 = (dx - cx) * (by - cy) - (dy - cy) * (bx - cx)
    return o1 * o2 < 0.0 and o3 * o4 < 0.0


@_leaf
def _segments_apart(
    ax: float, ay: float, bx: float, by: float, cx: float, cy: float, dx: float, dy: float, gap: float
) -> bool:
    """Whether segments ``[a, b]`` and ``[c, d]`` are farther apart than ``gap``."""
    if _crosses(ax, ay, bx, by, cx, cy, dx, dy):
        return False
    return (
        _point_segment_distance(ax, ay, cx, cy, dx, dy) > gap
        and _point_segment_distance(bx, by, cx, cy, dx, dy) > gap
        and _point_segment_distance(cx, cy, ax, ay, bx, by) > gap
        and _point_segment_distance(dx, dy, ax, ay, bx, by) > gap
    )


@_leaf
def _inside_ring(px: float, py: float, edges: np.ndarray, first: int, last: int) -> bool:
    """Point in the polygon bounded by ``edges[first:last]`` (crossing number; the point must not be
    on the boundary, which the callers have ruled out)."""
    inside = False
    for e in range(first, last):
        ax, ay, bx, by = edges[e, 0, 0], edges[e, 0, 1], edges[e, 1, 0], edges[e, 1, 1]
        if (ay > py) != (by > py) and px < ax + (py - ay) * (bx - ax) / (by - ay):
            inside = not inside
    return inside


@_leaf
def _segment_clear_of_ring(
    ax: float, ay: float, bx: float, by: float, edges: np.ndarray, first: int, last: int, gap: float
) -> bool:
    """Segment ``[a, b]`` farther than ``gap`` from the polygon ``edges[first:last]`` and not inside it."""
    for e in range(first, last):
        if not _segments_apart(ax, ay, bx, by, edges[e, 0, 0], edges[e, 0, 1], edges[e, 1, 0], edges[e, 1, 1], gap):
            return False
    return not _inside_ring(ax, ay, edges, first, last)


@_jit
def _clearly_valid(q: np.ndarray, poses: np.ndarray, out: np.ndarray, world: tuple[Any, ...]) -> None:
    """``out[b]``: configuration ``q[b]`` with the object at ``poses[b]`` passes the validity test of
    interface.md section 1 with every distance at least the world's rounding past its threshold. False means
    "not sure": the exact test decides (touching, within rounding, or invalid). ``world``:
    :attr:`~.packed.PackedWorld.plain`."""
    model = _named(world)
    n = model.chain.lengths.shape[0]
    placed = _placed(model)
    for b in range(q.shape[0]):
        out[b] = _valid_beyond(q[b], poses[b, 0], poses[b, 1], poses[b, 2], model.rounding, n, placed, model)


@_jit
def _placed(model: Model) -> Placed:
    """Scratch for :func:`_valid_beyond` in ``model``'s world."""
    shape = model.shape
    n = model.chain.lengths.shape[0]
    return Placed(
        np.empty((n, 2, 2)), np.empty((shape.edges.shape[0], 2, 2)), np.empty((shape.shrunk_edges.shape[0], 2, 2))
    )


@_inlined_leaf
def _valid_beyond(  # noqa: C901, PLR0911, PLR0912 - one compiled pass per configuration, leaving at the first doubt
    q: np.ndarray, px: float, py: float, pt: float, eps: float, shrunk_links: int, placed: Placed, model: Model
) -> bool:
    """One configuration ``q (n,)`` of :func:`_clearly_valid`, the object at ``(px, py, pt)``; only the
    first ``shrunk_links`` links are tested against the shrunk object. ``placed``: scratch (:func:`_placed`)."""
    links, shape, shrunk = placed
    base, lengths = model.chain.base, model.chain.lengths
    r, self_collision = model.link_radius, model.self_collision
    bounds, obstacles, obstacle_starts, boxes = (
        model.scene.bounds,
        model.scene.edges,
        model.scene.starts,
        model.scene.boxes,
    )
    object_edges, shrunk_edges, shrunk_starts = model.shape
    n = lengths.shape[0]
    xmin, ymin, xmax, ymax = bounds[0], bounds[1], bounds[2], bounds[3]
    _forward(q, base, lengths, links)
    for i in range(n):
        for v in range(2):
            x, y = links[i, v, 0], links[i, v, 1]
            if not (xmin + r + eps < x < xmax - r - eps and ymin + r + eps < y < ymax - r - eps):
                return False
    _place(object_edges, px, py, pt, 0.0, 0.0, shape)
    _place(shrunk_edges, px, py, pt, 0.0, 0.0, shrunk)
    sx0, sy0, sx1, sy1 = math.inf, math.inf, -math.inf, -math.inf  # the object's bounding box
    for e in range(shape.shape[0]):  # the object inside the bounds
        vx, vy = shape[e, 0, 0], shape[e, 0, 1]
        if not (xmin + eps < vx < xmax - eps and ymin + eps < vy < ymax - eps):
            return False
        sx0, sy0, sx1, sy1 = min(sx0, vx), min(sy0, vy), max(sx1, vx), max(sy1, vy)
    for o in range(boxes.shape[0]):
        first, last = obstacle_starts[o], obstacle_starts[o + 1]
        lx, ly, hx, hy = boxes[o, 0] - r - eps, boxes[o, 1] - r - eps, boxes[o, 2] + r + eps, boxes[o, 3] + r + eps
        for i in range(n):  # links kept r away from the obstacle
            ax, ay, bx, by = links[i, 0, 0], links[i, 0, 1], links[i, 1, 0], links[i, 1, 1]
            if max(ax, bx) < lx or min(ax, bx) > hx or max(ay, by) < ly or min(ay, by) > hy:
                continue
            if not _segment_clear_of_ring(ax, ay, bx, by, obstacles, first, last, r + eps):
                return False
        if sx1 < boxes[o, 0] - eps or sx0 > boxes[o, 2] + eps or sy1 < boxes[o, 1] - eps or sy0 > boxes[o, 3] + eps:
            continue  # boxes more than eps apart: so are the object and the obstacle, neither inside the other
        for e in range(shape.shape[0]):  # the object off the obstacle: boundaries apart, neither inside
            if not _segment_clear_of_ring(
                shape[e, 0, 0], shape[e, 0, 1], shape[e, 1, 0], shape[e, 1, 1], obstacles, first, last, eps
            ):
                return False
        if _inside_ring(obstacles[first, 0, 0], obstacles[first, 0, 1], shape, 0, shape.shape[0]):
            return False
    for part in range(shrunk_starts.shape[0] - 1):  # links out of the object shrunk by the tolerance
        for i in range(shrunk_links):
            if not _segment_clear_of_ring(
                links[i, 0, 0],
                links[i, 0, 1],
                links[i, 1, 0],
                links[i, 1, 1],
                shrunk,
                shrunk_starts[part],
                shrunk_starts[part + 1],
                eps,
            ):
                return False
    if self_collision:
        for a in range(n):
            for c in range(a + 2, n):
                if not _segments_apart(
                    links[a, 0, 0],
                    links[a, 0, 1],
                    links[a, 1, 0],
                    links[a, 1, 1],
                    links[c, 0, 0],
                    links[c, 0, 1],
                    links[c, 1, 0],
                    links[c, 1, 1],
                    2.0 * r + eps,
                ):
                    return False
    return True


def clearly_valid(world: PackedWorld, q: np.ndarray, poses: np.ndarray) -> np.ndarray:
    """Compiled: which configurations ``q (B, n)`` (object at ``poses``) are valid beyond doubt; the
    others (invalid, touching, or within rounding of a threshold) need the exact test."""
    q = _arg(np.atleast_2d(q))
    out = np.empty(len(q), dtype=np.bool_)
    _clearly_valid(q, _poses(poses, len(q)), out, world.plain)
    return out
