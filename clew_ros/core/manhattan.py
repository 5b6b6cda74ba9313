"""Manhattan paths and the bouncing technique (paper 1.3.1 and 1.3.3).

A Manhattan path of order ``k`` for an ``n``-joint arm is coded as a real vector
``(k, n)``: "move joint 1 by x_1, then joint 2 by x_2, ..." repeated ``k``
times. Before each move the free interval ``[dmin, dmax]`` of the moving joint
is computed given the moves before it (:func:`free_intervals`), and the gene is
folded into that interval by a triangular wave (:func:`bounce`). Every real
vector therefore codes a collision-free path.

Free intervals in closed form
-----------------------------
When joint ``j`` turns, links ``j..n`` (and, in transfer, the carried object)
turn rigidly about ``p_(j-1)``. Two segments first touch where an end point of
one, moving on a circle about the pivot, meets the other; keeping a clearance
``margin`` apart, the end point meets the *stadium* (the segment inflated by the
margin). Those meetings are circle-line and circle-circle intersections in
closed form (the construction Lozano-Perez 1987 uses, which the paper cites),
computed in numpy for a whole batch at once. The nearest contact on each side,
the joint limits and ``2 pi`` bound the interval. Every angle inside it keeps
the clearance, continuously, so plans are valid at any checking resolution,
which is what the plan validator checks at 0.002 rad.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from typing import Callable

import numpy as np

from clew_ros.core.collision import scene_of
from clew_ros.core.geometry import point_segment_distance
from clew_ros.core.kinematics import compose, joint_positions, tip_poses, transform_points
from clew_ros.core.world import World

__all__ = ["Counters", "free_intervals", "bounce", "ManhattanPaths", "run_manhattan"]

#: Largest move of one joint in one Manhattan move (rad), as in the paper.
MAX_MOVE_RAD = 2 * np.pi
#: Free intervals stop this far (rad) short of the first contact.
BACKOFF_RAD = 1e-6


@dataclass
class Counters:
    """Work done, for stats and benchmarks."""

    clearance_checks: int = 0  # free intervals computed (one per configuration and joint move)
    evaluations: int = 0  # genetic-algorithm individuals evaluated


@dataclass
class _Body:
    """The pieces that turn about the pivot and the pieces they may hit."""

    pivot: np.ndarray  # (B, 2)
    moving: np.ndarray  # (B, M, 2, 2) segments turning with the joint
    static: np.ndarray  # (B, S, 2, 2) segments they may hit
    pairs: tuple  # the pairs checked, from _checked_pairs
    points: np.ndarray  # (B, P, 2) moving points that must stay in bounds
    insets: np.ndarray  # (P,) how far inside the bounds (m)


@lru_cache(maxsize=256)
def _pair_offsets(world: World, joint: int, transfer: bool) -> tuple[np.ndarray, np.ndarray]:
    """Offsets (M, S) between moving and static pieces for one joint, and point insets (P,).

    Moving: links ``joint..n-1`` [, object edges, shrunk-object edges]; static:
    obstacle edges, links ``0..joint-1`` [, shrunk-object edges in transit].
    """
    scene = scene_of(world)
    n = world.robot.dof
    r = scene.link_radius
    n_obstacle, n_object, n_shrunk = len(scene.obstacle_edges), len(scene.object_edges), len(scene.shrunk_edges)
    moving_links = np.arange(joint, n)
    static_links = np.arange(joint)
    links_vs_links = np.where(np.abs(moving_links[:, None] - static_links[None]) >= 2, 2 * r, np.nan)
    if not world.robot.self_collision:
        links_vs_links[:] = np.nan
    rows = [np.hstack([np.full((len(moving_links), n_obstacle), r), links_vs_links,
                       np.full((len(moving_links), 0 if transfer else n_shrunk), 0.0)])]
    insets = [np.full(len(moving_links), r)]
    if transfer:
        rows.append(np.hstack([np.zeros((n_object, n_obstacle)), np.full((n_object, joint), np.nan)]))
        rows.append(np.hstack([np.full((n_shrunk, n_obstacle), np.nan), np.zeros((n_shrunk, joint))]))
        insets.append(np.zeros(n_object))
    return np.vstack(rows), np.concatenate(insets)


def _body(world: World, q: np.ndarray, joint: int, object_poses: np.ndarray | None,
          grasp_rel: np.ndarray | None) -> _Body:
    scene = scene_of(world)
    pts = joint_positions(world.robot, q)
    batch = len(q)
    links = np.empty((batch, pts.shape[1] - 1, 2, 2))  # (B, n, 2, 2)
    links[:, :, 0] = pts[:, :-1]
    links[:, :, 1] = pts[:, 1:]
    obstacles = np.broadcast_to(scene.obstacle_edges[None], (batch,) + scene.obstacle_edges.shape)
    transfer = grasp_rel is not None
    insets = _pair_offsets(world, joint, transfer)[1]
    moving = [links[:, joint:]]
    static = [obstacles, links[:, :joint]]
    points = [pts[:, joint + 1:]]
    if transfer:
        tips = np.empty((batch, 3))  # tip_poses without computing the chain again
        tips[:, :2] = pts[:, -1]
        tips[:, 2] = q.sum(axis=1)
        object_pose = compose(tips, grasp_rel)
        object_edges = _edges_at(object_pose, scene.object_edges)
        moving += [object_edges, _edges_at(object_pose, scene.shrunk_edges)]
        points.append(object_edges[:, :, 0])
    else:
        static.append(_edges_at(np.broadcast_to(object_poses, (batch, 3)), scene.shrunk_edges))
    return _Body(pts[:, joint], np.concatenate(moving, axis=1), np.concatenate(static, axis=1),
                 _checked_pairs(world, joint, transfer),
                 np.concatenate(points, axis=1), insets)


def _edges_at(poses: np.ndarray, local_edges: np.ndarray) -> np.ndarray:
    flat = local_edges.reshape(-1, 2)
    return transform_points(poses, flat).reshape(len(poses), -1, 2, 2)


_TWO_PI = 2.0 * np.pi
_SIGNS = np.array([1.0, -1.0])  # the two roots of a pair


def _angle(v: np.ndarray) -> np.ndarray:
    return np.arctan2(v[..., 1], v[..., 0])


def _dot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return a[..., 0] * b[..., 0] + a[..., 1] * b[..., 1]  # einsum's call costs more on small arrays


def _circle_stadium(rho: np.ndarray, e1: np.ndarray, e2: np.ndarray, offset: np.ndarray) -> np.ndarray:
    """Polar angles where the circle of radius ``rho`` about the origin meets the boundary of the
    stadium of radius ``offset`` around segment ``[e1, e2]`` (points relative to the pivot).

    Returns ``(8, ...)`` angles, NaN where there is no crossing: two offset lines (two roots
    each) and two end circles (two roots each). Extra roots inside the stadium are harmless:
    starting outside it, the first crossing met is always on its boundary.
    """
    d = e2 - e1
    length2 = _dot(d, d)
    has_length = length2 > 0
    safe_length2 = np.where(has_length, length2, 1.0)
    normal = np.empty_like(d)
    scale = 1.0 / np.sqrt(safe_length2)
    normal[..., 0] = -d[..., 1] * scale
    normal[..., 1] = d[..., 0] * scale
    rho2 = rho * rho
    # both offset lines and both roots at once: axes (side, sign, ...), few numpy calls on small arrays
    shift = offset[..., None] * normal
    a = np.stack([e1 + shift, e1 - shift])  # (2, ..., 2)
    ad = _dot(a, d)
    disc = ad * ad - length2 * (_dot(a, a) - rho2)
    root = np.sqrt(np.maximum(disc, 0.0))
    signs = _SIGNS.reshape((2,) + (1,) * rho.ndim)
    t = (-ad[:, None] + signs * root[:, None]) / safe_length2  # (2, 2, ...)
    ok = (disc >= 0)[:, None] & (t >= 0) & (t <= 1) & has_length
    lines = np.where(ok, _angle(a[:, None] + t[..., None] * d), np.nan)
    ends = np.stack([e1, e2])  # (2, ..., 2)
    e = np.sqrt(_dot(ends, ends))
    denominator = 2.0 * rho * e
    cos_beta = (rho2 + e * e - offset * offset) / np.where(denominator > 0, denominator, 1.0)
    ok = (np.abs(cos_beta) <= 1.0) & (denominator > 0) & (offset > 0)
    beta = np.arccos(np.minimum(np.maximum(cos_beta, -1.0), 1.0))
    base = _angle(ends)
    circles = np.where(ok[:, None], base[:, None] + signs * beta[:, None], np.nan)  # (2, 2, ...)
    return np.concatenate([lines.reshape((4,) + lines.shape[2:]), circles.reshape((4,) + circles.shape[2:])])


@lru_cache(maxsize=256)
def _checked_pairs(world: World, joint: int, transfer: bool) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The pairs a free interval checks, both ways round.

    Pieces are indexed moving first, then static (as :func:`_contact_angles`
    stacks them). Returns ``ends (Q,)``, the piece whose end points meet the
    stadium of piece ``other (Q,)``, ``turn (Q,)``, +1 when the end points
    turn with the joint (a moving piece's) and -1 when the stadium does, and
    ``offsets (Q,)`` (distance to keep, m). Every pair of
    :func:`_pair_offsets` appears twice: end points of the moving piece
    against the static one's stadium, and the other way round.
    """
    offsets, _insets = _pair_offsets(world, joint, transfer)
    moving, static = np.nonzero(~np.isnan(offsets))
    keep = offsets[moving, static]
    static = static + offsets.shape[0]
    ends = np.concatenate([moving, static])
    other = np.concatenate([static, moving])
    turn = np.concatenate([np.ones(len(moving)), -np.ones(len(moving))])
    return ends, other, turn, np.tile(keep, 2)


def _radii(segments: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """For segments ``(B, C, 2, 2)`` relative to the pivot: their end points' distances ``(B, C, 2)``,
    and the nearest and farthest distance ``(B, C)`` of each segment from the pivot."""
    rho = np.sqrt(segments[..., 0] * segments[..., 0] + segments[..., 1] * segments[..., 1])
    near = point_segment_distance(np.zeros(2), segments[:, :, 0], segments[:, :, 1])
    return rho, near, np.maximum(rho[..., 0], rho[..., 1])


#: Pairs x configurations handled per numpy pass: bounds the memory of huge worlds.
_CHUNK = 1 << 14


def _contact_angles(world: World, body: _Body, margin: float,
                    should_stop: Callable[[], bool] | None = None) -> tuple[np.ndarray, np.ndarray]:
    """First contact angle turning each way, ``(hi > 0, lo < 0)`` per configuration (rad).

    Two segments kept ``offset + margin`` apart first touch where an end point of
    one meets the stadium around the other: circle-line and circle-circle
    intersections in closed form (after Lozano-Perez 1987). An end point already
    closer than ``offset + 1.5 margin`` is kept only ``offset`` away. Only pairs
    whose end point's circle reaches the stadium's annulus about the pivot are
    solved. If ``should_stop`` says so between chunks of a huge world, the
    answer is ``(0, 0)``: no motion, which is always safe.
    """
    pivot = body.pivot
    batch = len(pivot)
    pieces = np.concatenate([body.moving, body.static], axis=1) - pivot[:, None, None, :]  # (B, M + S, 2, 2)
    piece_rho, piece_near, piece_far = _radii(pieces)
    ends, other, turn, offsets = body.pairs
    index_parts, phi_parts = [], []
    step = max(1, _CHUNK // max(batch, 1))
    for first in range(0, len(offsets), step):
        if first and should_stop is not None and should_stop():
            return np.zeros(batch), np.zeros(batch)
        chunk = slice(first, first + step)
        ei, oi, keep = ends[chunk], other[chunk], offsets[chunk]
        # annulus test: the end point's circle about the pivot must reach the other segment's annulus
        rho = piece_rho[:, ei]  # (B, Q, 2)
        reach = (keep + margin)[None, :, None]
        hit = (rho >= piece_near[:, oi, None] - reach) & (rho <= piece_far[:, oi, None] + reach)
        b, q, e = np.nonzero(hit)
        if not len(b):
            continue
        point = pieces[b, ei[q], e]
        segment = pieces[b, oi[q]]  # (K, 2, 2)
        e1, e2 = segment[:, 0], segment[:, 1]
        keep = keep[q]
        keep = keep + np.where(point_segment_distance(point, e1, e2) > keep + 1.5 * margin, margin, 0.0)
        phi = _circle_stadium(rho[b, q, e], e1, e2, keep) - _angle(point)  # (8, K)
        phi_parts.append(phi * turn[chunk][q])
        index_parts.append(b)
    xmin, ymin, xmax, ymax = world.bounds
    rel = body.points - pivot[:, None, :]  # (B, P, 2)
    rho = np.sqrt(rel[..., 0] * rel[..., 0] + rel[..., 1] * rel[..., 1])
    limit = body.insets + margin  # (P,)
    # only points whose circle about the pivot reaches a bound can cross it
    px, py = pivot[:, 0, None], pivot[:, 1, None]
    b, p = np.nonzero((px - rho <= xmin + limit) | (px + rho >= xmax - limit)
                      | (py - rho <= ymin + limit) | (py + rho >= ymax - limit))
    if len(b):
        rho, rel, limit = rho[b, p], rel[b, p], limit[p]
        alpha = _angle(rel)
        safe_rho = np.where(rho > 0, rho, 1.0)
        candidates = []
        for axis, bound in ((0, xmin + limit), (0, xmax - limit), (1, ymin + limit), (1, ymax - limit)):
            c = (bound - pivot[b, axis]) / safe_rho
            ok = (np.abs(c) <= 1.0) & (rho > 0)
            if axis == 0:
                base = np.arccos(np.minimum(np.maximum(c, -1.0), 1.0))
                roots = (base, -base)
            else:
                base = np.arcsin(np.minimum(np.maximum(c, -1.0), 1.0))
                roots = (base, np.pi - base)
            candidates.extend(np.where(ok, root - alpha, np.nan) for root in roots)
        phi_parts.append(np.array(candidates))
        index_parts.append(b)
    if not phi_parts:
        return np.full(batch, np.inf), np.full(batch, -np.inf)
    return _nearest(batch, np.concatenate(index_parts), np.concatenate(phi_parts, axis=1))


def _nearest(batch: int, index: np.ndarray, phi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """First contact each way per configuration, ``hi`` (> 0) and ``lo`` (< 0), from candidate
    rotation angles ``phi`` ``(c, K)`` (rad, any turn, NaN for none) of configurations ``index`` ``(K,)``."""
    turns = np.rint(phi * (1.0 / _TWO_PI) - 0.5)  # floor, but rint is several times faster in numpy
    phi = phi - _TWO_PI * turns  # in [0, 2 pi] up to rounding
    with np.errstate(invalid="ignore"):
        phi = np.where(phi < 1e-12, np.nan, phi)  # a contact at the current angle is not a crossing
        hi = np.full(batch, np.inf)
        top = np.full(batch, -np.inf)
        np.fmin.at(hi, index, np.fmin.reduce(phi, axis=0))
        np.fmax.at(top, index, np.fmax.reduce(phi, axis=0))
    return hi, top - _TWO_PI


def free_intervals(world: World, q: np.ndarray, joint: int, *, object_poses: np.ndarray | None = None,
                   grasp_rel: np.ndarray | None = None, margin_m: float = 1e-3,
                   counters: Counters | None = None,
                   should_stop: Callable[[], bool] | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Free interval ``[dmin, dmax]`` (rad) of ``joint`` for each configuration of ``q`` ``(B, n)``.

    Transit: give the resting object's poses ``object_poses`` ``(B, 3)``.
    Transfer: give ``grasp_rel`` ``(B, 3)``, the object's pose in the
    end-effector frame. Every angle of the interval is valid and keeps
    ``margin_m`` metres of clearance wherever the start had it;
    ``dmin <= 0 <= dmax``. ``should_stop`` is asked between chunks of huge
    worlds; once it says so the intervals are empty (``[0, 0]``).
    """
    q = np.atleast_2d(q)
    hi, lo = _contact_angles(world, _body(world, q, joint, object_poses, grasp_rel), margin_m, should_stop)
    if counters is not None:
        counters.clearance_checks += len(q)
    robot = world.robot
    upper = np.minimum(np.maximum(robot.joint_upper[joint] - q[:, joint], 0.0), MAX_MOVE_RAD)
    lower = np.minimum(np.maximum(robot.joint_lower[joint] - q[:, joint], -MAX_MOVE_RAD), 0.0)
    high = np.minimum(upper, np.maximum(hi - BACKOFF_RAD, 0.0))
    low = np.maximum(lower, np.minimum(lo + BACKOFF_RAD, 0.0))
    return low, high


def bounce(x: np.ndarray, low: np.ndarray, high: np.ndarray) -> np.ndarray:
    """Fold ``x`` into ``[low, high]`` with a triangular wave of period ``2 (high - low)``.

    Values inside the interval map to themselves; outside, they bounce off its
    ends. An empty interval (``low == high``) maps everything to ``low``.

    >>> bounce(np.array([0.5, 1.5, -0.25, 2.5]), np.zeros(4), np.ones(4)).tolist()
    [0.5, 0.5, 0.25, 0.5]
    """
    width = high - low
    period = 2.0 * width
    safe = np.where(width > 0, period, 1.0)
    u = np.mod(x - low, safe)
    folded = low + np.where(u <= width, u, period - u)
    return np.where(width > 0, np.clip(folded, low, high), low)


@dataclass
class ManhattanPaths:
    """Decoded Manhattan paths of a batch."""

    waypoints: np.ndarray  # (B, k * n + 1, n)
    object_poses: np.ndarray  # (B, 3): where the object ends

    @property
    def final(self) -> np.ndarray:
        return self.waypoints[:, -1]


def run_manhattan(world: World, q0: np.ndarray, genes: np.ndarray, *, object_poses: np.ndarray | None = None,
                  grasp_rel: np.ndarray | None = None, margin_m: float = 1e-3,
                  counters: Counters | None = None,
                  should_stop: Callable[[], bool] | None = None) -> ManhattanPaths:
    """Decode genes ``(B, k, n)`` into collision-free Manhattan paths from ``q0`` ``(B, n)``.

    Transit when ``object_poses`` is given (the object rests there), transfer
    when ``grasp_rel`` is given (the object is carried). ``should_stop`` is
    asked before every move: once it says so, the remaining moves are skipped
    (the paths stay where they are, still collision-free), so a time limit or
    a cancel is honoured within one free-interval computation.
    """
    q = np.array(np.broadcast_to(q0, (genes.shape[0], genes.shape[2])), dtype=float)
    order, n = genes.shape[1], genes.shape[2]
    waypoints = np.empty((len(q), order * n + 1, n))
    waypoints[:, 0] = q
    for column in range(1, order * n + 1):
        if should_stop is not None and should_stop():
            waypoints[:, column:] = q[:, None]
            break
        k, joint = divmod(column - 1, n)
        low, high = free_intervals(world, q, joint, object_poses=object_poses, grasp_rel=grasp_rel,
                                   margin_m=margin_m, counters=counters, should_stop=should_stop)
        q[:, joint] += bounce(genes[:, k, joint], low, high)
        waypoints[:, column] = q
    if grasp_rel is None:
        final_poses = np.broadcast_to(object_poses, (len(q), 3)).copy()
    else:
        final_poses = compose(tip_poses(world.robot, q), grasp_rel)
    return ManhattanPaths(waypoints, final_poses)


def single_moves(world: World, q: np.ndarray, moves: np.ndarray, **kwargs) -> np.ndarray:
    """Apply joint moves ``moves`` ``(n,)`` one joint at a time, each clamped to its free interval.

    Returns the waypoints ``(n + 1, n)`` of the (collision-free) Manhattan path.
    Used by numeric refinement, where bouncing would undo the intended step.
    """
    q = np.array(q, dtype=float)[None]
    waypoints = [q[0].copy()]
    for joint in np.flatnonzero(np.abs(moves) > 1e-12):
        low, high = free_intervals(world, q, int(joint), **kwargs)
        q[0, joint] += float(np.clip(moves[joint], low[0], high[0]))
        waypoints.append(q[0].copy())
    return np.array(waypoints)
