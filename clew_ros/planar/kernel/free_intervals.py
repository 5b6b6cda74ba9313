"""The free interval of one joint over a batch of configurations (compiled), and bouncing.

Free interval of joint ``j`` at configuration ``q``. When ``j`` turns, links
``j..n-1`` (and in transfer the carried object) turn rigidly about
``p_j``. Two segments kept ``offset`` apart first touch where an end point of
one, moving on its circle about the pivot, meets the *stadium* (the segment
inflated by ``offset``) of the other: circle-line and circle-circle
intersections. The pairs, each checked both ways round:

* moving link vs obstacle edge: link radius ``r``;
* moving link vs static link (two or more apart, ``self_collision``): ``2 r``;
* transit: moving link vs the resting object shrunk by ``grasp_tolerance``: 0;
* transfer: object edge vs obstacle edge: 0; shrunk object vs static link: 0.

An end point closer than ``offset + 1.5 margin`` is kept only ``offset``
away (it starts there), otherwise ``offset + margin``; the same for a point
and a bound. Moving joints and,
in transfer, the object's vertices stay inside the bounds (inset ``r`` and
0, plus the margin). The nearest contact each way, the joint limits and
``2 pi`` bound the interval, backed off by :data:`BACKOFF_RAD`.

Only the nearest contact each way matters: a contact that a cheap pseudo-angle
places between the nearest ones found so far is skipped before its ``atan2``
(:func:`~.contacts._cannot_improve`), which leaves every interval bit for bit the same.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from clew_ros.planar.kernel.contacts import _annulus, _annulus_of, _bound_crossings, _pieces, _reset
from clew_ros.planar.kernel.jit import _inlined_leaf, _jit, _leaf
from clew_ros.planar.kernel.kinematics import _forward
from clew_ros.planar.kernel.packed import IntervalWork, Model, PackedWorld, _arg, _named, _poses
from clew_ros.planar.kernel.segments import _place

#: Largest move of one joint in one Manhattan move (rad), as in the paper.
MAX_MOVE_RAD = 2.0 * math.pi
#: Free intervals stop this far (rad) short of the first contact.
BACKOFF_RAD = 1e-6
_TWO_PI = 2.0 * math.pi


#: The broad phase of :func:`_interval` keeps an obstacle whose bounding circle is within this (m) of the
#: moving pieces' reach: far more than the rounding of the distances it compares.
_BROAD_PHASE_SLACK = 1e-6


@_leaf
def _bounce(x: float, low: float, high: float) -> float:
    """Fold ``x`` into ``[low, high]`` with a triangular wave of period ``2 (high - low)``."""
    width = high - low
    if not width > 0.0:
        return low
    period = 2.0 * width
    u = (x - low) - period * math.floor((x - low) / period)
    folded = low + (u if u <= width else period - u)
    return min(max(folded, low), high)


@_leaf
def _place_obstacles(
    obstacles: np.ndarray,
    groups: np.ndarray,
    px: float,
    py: float,
    horizon: float,
    obstacle_rel: np.ndarray,
    obstacle_radii: np.ndarray,
) -> None:
    """The obstacles' edges relative to the pivot ``p``, with their annuli (:func:`_annulus_of`), for the
    obstacles (``groups`` of :attr:`PackedWorld.obstacle_groups`) whose bounding circle comes within
    ``horizon`` of the pivot; the edges of the others are marked out of reach (nearest distance
    infinite, farthest minus infinite: :func:`_pieces` skips them) without being placed."""
    for g in range(groups.shape[0]):
        first, last = int(groups[g, 0]), int(groups[g, 1])
        cx, cy = groups[g, 2] - px, groups[g, 3] - py
        if math.sqrt(cx * cx + cy * cy) - groups[g, 4] > horizon:
            for e in range(first, last):
                obstacle_radii[e, 0] = math.inf
                obstacle_radii[e, 1] = -math.inf
            continue
        for e in range(first, last):
            for v in range(2):
                obstacle_rel[e, v, 0] = obstacles[e, v, 0] - px
                obstacle_rel[e, v, 1] = obstacles[e, v, 1] - py
            _annulus_of(obstacle_rel, obstacle_radii, e)


@_inlined_leaf
def _interval(  # noqa: C901, PLR0912 - one compiled loop nest over every pair kind, commented step by step
    q: np.ndarray, joint: int, transfer: bool, pose: np.ndarray, margin: float, model: Model, work: IntervalWork
) -> tuple[float, float]:
    """Free interval ``(low <= 0, high >= 0)`` of ``joint`` at configuration ``q`` ``(n,)``.

    ``pose``: the resting object's pose (transit) or its pose in the end-effector frame
    (transfer). ``work``: scratch (:func:`_scratch`).
    """
    links, link_radii, obstacle_rel, obstacle_radii, object_rel, object_radii, shrunk_rel, shrunk_radii, best = work
    base, lengths, lower, upper = model.chain
    r, self_collision, bounds = model.link_radius, model.self_collision, model.scene.bounds
    obstacles, groups = model.scene.edges, model.scene.groups
    object_edges, shrunk_edges = model.shape.edges, model.shape.shrunk_edges
    n = lengths.shape[0]
    tip_x, tip_y, tip_theta = _forward(q, base, lengths, links)
    px, py = links[joint, 0, 0], links[joint, 0, 1]  # the pivot p_joint: everything relative to it
    for i in range(n):
        for v in range(2):
            links[i, v, 0] -= px
            links[i, v, 1] -= py
    _annulus(links, link_radii)
    if transfer:  # the object's pose: the tip's frame composed with the grasp
        c, s = math.cos(tip_theta), math.sin(tip_theta)
        ox, oy, otheta = tip_x + c * pose[0] - s * pose[1], tip_y + s * pose[0] + c * pose[1], tip_theta + pose[2]
        _place(object_edges, ox, oy, otheta, px, py, object_rel)
        _annulus(object_rel, object_radii)
    else:
        ox, oy, otheta = pose[0], pose[1], pose[2]
    # broad phase: an obstacle whose bounding circle lies beyond every moving piece's reach (its farthest
    # point from the pivot, plus what :func:`_pieces` grows it by) has no edge :func:`_pieces` would test
    horizon = -math.inf
    for i in range(joint, n):
        horizon = max(horizon, link_radii[i, 1] + r + margin)
    if transfer:
        for e in range(object_rel.shape[0]):
            horizon = max(horizon, object_radii[e, 1] + margin)
    _place_obstacles(obstacles, groups, px, py, horizon + _BROAD_PHASE_SLACK, obstacle_rel, obstacle_radii)
    _place(shrunk_edges, ox, oy, otheta, px, py, shrunk_rel)
    _annulus(shrunk_rel, shrunk_radii)
    _reset(best)
    n_obstacles = obstacles.shape[0]
    _pieces(links, link_radii, joint, n, obstacle_rel, obstacle_radii, 0, n_obstacles, r, margin, best)
    if self_collision:
        for i in range(joint, n):
            if i - 2 >= 0:
                _pieces(links, link_radii, i, i + 1, links, link_radii, 0, min(joint, i - 1), 2.0 * r, margin, best)
    if transfer:
        n_object = object_rel.shape[0]
        _pieces(object_rel, object_radii, 0, n_object, obstacle_rel, obstacle_radii, 0, n_obstacles, 0.0, margin, best)
        _pieces(shrunk_rel, shrunk_radii, 0, shrunk_rel.shape[0], links, link_radii, 0, joint, 0.0, margin, best)
    else:
        n_shrunk = shrunk_rel.shape[0]
        _pieces(links, link_radii, joint, n, shrunk_rel, shrunk_radii, 0, n_shrunk, 0.0, margin, best)
    # the moving joints (inset r) and the carried object's vertices (inset 0) stay inside the bounds
    for i in range(joint, n):
        _bound_crossings(px, py, links[i, 1, 0], links[i, 1, 1], r, margin, bounds, best)
    if transfer:
        for e in range(object_rel.shape[0]):
            _bound_crossings(px, py, object_rel[e, 0, 0], object_rel[e, 0, 1], 0.0, margin, bounds, best)
    hi = best[0]
    lo = best[1] - _TWO_PI  # -inf when nothing was met
    up = min(max(upper[joint] - q[joint], 0.0), MAX_MOVE_RAD)
    down = min(max(lower[joint] - q[joint], -MAX_MOVE_RAD), 0.0)
    return max(down, min(lo + BACKOFF_RAD, 0.0)), min(up, max(hi - BACKOFF_RAD, 0.0))


@_jit
def _scratch(model: Model) -> IntervalWork:
    """Scratch for :func:`_interval` in ``model``'s world."""
    n, n_obstacles = model.chain.lengths.shape[0], model.scene.edges.shape[0]
    n_object, n_shrunk = model.shape.edges.shape[0], model.shape.shrunk_edges.shape[0]
    return IntervalWork(
        np.empty((n, 2, 2)),
        np.empty((n, 4)),
        np.empty((n_obstacles, 2, 2)),
        np.empty((n_obstacles, 4)),
        np.empty((n_object, 2, 2)),
        np.empty((n_object, 4)),
        np.empty((n_shrunk, 2, 2)),
        np.empty((n_shrunk, 4)),
        np.empty(4),
    )


@_jit
def _intervals(
    q: np.ndarray,
    joint: int,
    transfer: bool,
    poses: np.ndarray,
    margin: float,
    out: np.ndarray,
    world: tuple[Any, ...],
) -> None:
    """Free intervals ``out[0]`` (low) and ``out[1]`` (high), ``(2, B)``, of ``joint`` for configurations
    ``q (B, n)``; ``poses`` is ``(B, 3)`` or one pose ``(1, 3)`` for all. ``world``:
    :attr:`~.packed.PackedWorld.plain`."""
    model = _named(world)
    _interval_rows(q, joint, transfer, poses, margin, out, model, _scratch(model))


@_leaf
def _interval_rows(
    q: np.ndarray,
    joint: int,
    transfer: bool,
    poses: np.ndarray,
    margin: float,
    out: np.ndarray,
    model: Model,
    work: IntervalWork,
) -> None:
    """The loop of :func:`_intervals`, in a function that allocates nothing and so counts no references (written
    in the entry point, which allocates, the loop took a twentieth longer)."""
    shared = poses.shape[0] == 1
    for b in range(q.shape[0]):
        out[0, b], out[1, b] = _interval(q[b], joint, transfer, poses[0] if shared else poses[b], margin, model, work)


@_leaf
def _bounce_all(x: np.ndarray, low: np.ndarray, high: np.ndarray, out: np.ndarray) -> None:
    for i in range(x.shape[0]):
        out[i] = _bounce(x[i], low[i], high[i])


def intervals(
    world: PackedWorld, q: np.ndarray, joint: int, transfer: bool, poses: np.ndarray, margin: float
) -> tuple[np.ndarray, np.ndarray]:
    """Compiled: free intervals ``(low, high)`` of ``joint`` for configurations ``q (B, n)``."""
    # the planner asks for a few dozen intervals at a time: this wrapper is kept to the checks it needs
    q = _arg(q)
    if q.ndim == 1:
        q = q[None]
    out = np.empty((2, len(q)))
    poses = _arg(poses)
    rows = poses if poses.shape == (1, 3) else _poses(poses, len(q))  # one pose for all: no copies
    _intervals(q, int(joint), transfer, rows, float(margin), out, world.plain)
    return out[0], out[1]


def bounce_array(x: np.ndarray, low: np.ndarray, high: np.ndarray) -> np.ndarray:
    """Compiled :func:`_bounce` over arrays of one shape."""
    x, low, high = np.broadcast_arrays(*(np.asarray(a, dtype=np.float64) for a in (x, low, high)))
    out = np.empty(x.shape)
    _bounce_all(_arg(x).reshape(-1), _arg(low).reshape(-1), _arg(high).reshape(-1), out.reshape(-1))
    return out
