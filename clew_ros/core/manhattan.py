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
    offsets: np.ndarray  # (M, S) distance to keep (m), NaN for pairs never checked
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
    links = np.stack([pts[:, :-1], pts[:, 1:]], axis=2)  # (B, n, 2, 2)
    obstacles = np.broadcast_to(scene.obstacle_edges[None], (batch,) + scene.obstacle_edges.shape)
    transfer = grasp_rel is not None
    offsets, insets = _pair_offsets(world, joint, transfer)
    moving = [links[:, joint:]]
    static = [obstacles, links[:, :joint]]
    points = [pts[:, joint + 1:]]
    if transfer:
        object_pose = compose(tip_poses(world.robot, q), grasp_rel)
        object_edges = _edges_at(object_pose, scene.object_edges)
        moving += [object_edges, _edges_at(object_pose, scene.shrunk_edges)]
        points.append(object_edges[:, :, 0])
    else:
        static.append(_edges_at(np.broadcast_to(object_poses, (batch, 3)), scene.shrunk_edges))
    return _Body(pts[:, joint], np.concatenate(moving, axis=1), np.concatenate(static, axis=1), offsets,
                 np.concatenate(points, axis=1), insets)


def _edges_at(poses: np.ndarray, local_edges: np.ndarray) -> np.ndarray:
    flat = local_edges.reshape(-1, 2)
    return transform_points(poses, flat).reshape(len(poses), -1, 2, 2)


_TWO_PI = 2.0 * np.pi


def _angle(v: np.ndarray) -> np.ndarray:
    return np.arctan2(v[..., 1], v[..., 0])


def _dot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.einsum("...i,...i->...", a, b)


def _circle_stadium(rho: np.ndarray, e1: np.ndarray, e2: np.ndarray, offset: np.ndarray) -> np.ndarray:
    """Polar angles where the circle of radius ``rho`` about the origin meets the boundary of the
    stadium of radius ``offset`` around segment ``[e1, e2]`` (points relative to the pivot).

    Returns ``(..., 8)`` angles, NaN where there is no crossing: two offset lines (two roots
    each) and two end circles (two roots each). Extra roots inside the stadium are harmless:
    starting outside it, the first crossing met is always on its boundary.
    """
    d = e2 - e1
    length2 = _dot(d, d)
    has_length = length2 > 0
    safe_length2 = np.where(has_length, length2, 1.0)
    normal = np.stack([-d[..., 1], d[..., 0]], axis=-1) / np.sqrt(safe_length2)[..., None]
    rho2 = rho * rho
    out = []
    for side in (1.0, -1.0):
        a = e1 + side * offset[..., None] * normal
        ad = _dot(a, d)
        disc = ad * ad - length2 * (_dot(a, a) - rho2)
        root = np.sqrt(np.maximum(disc, 0.0))
        for sign in (1.0, -1.0):
            t = (-ad + sign * root) / safe_length2
            ok = (disc >= 0) & (t >= 0) & (t <= 1) & has_length
            out.append(np.where(ok, _angle(a + t[..., None] * d), np.nan))
    for end in (e1, e2):
        e = np.sqrt(_dot(end, end))
        denominator = 2.0 * rho * e
        cos_beta = (rho2 + e * e - offset * offset) / np.where(denominator > 0, denominator, 1.0)
        ok = (np.abs(cos_beta) <= 1.0) & (denominator > 0) & (offset > 0)
        beta = np.arccos(np.clip(cos_beta, -1.0, 1.0))
        base = _angle(end)
        out.append(np.where(ok, base + beta, np.nan))
        out.append(np.where(ok, base - beta, np.nan))
    return np.stack(out, axis=-1)


class _Nearest:
    """Running first contact each way: ``hi`` (> 0) and ``lo`` (< 0), per configuration."""

    def __init__(self, batch: int) -> None:
        self.batch = batch
        self.hi = np.full(batch, np.inf)
        self.lo = np.full(batch, -np.inf)

    def take(self, index: np.ndarray, phi: np.ndarray) -> None:
        """Add candidate rotation angles ``phi`` ``(K, c)`` of configurations ``index`` ``(K,)``, sorted."""
        if not len(index):
            return
        phi = np.mod(phi, _TWO_PI)
        phi[phi < 1e-12] = np.nan  # a contact at the current angle is not a crossing
        which, starts = np.unique(index, return_index=True)
        with np.errstate(invalid="ignore"):
            first = np.fmin.reduceat(np.fmin.reduce(phi, axis=1), starts)
            last = np.fmax.reduceat(np.fmax.reduce(phi, axis=1), starts)
        self.hi[which] = np.fmin(self.hi[which], first)
        self.lo[which] = np.fmax(self.lo[which], last - _TWO_PI)


def _reach(segments: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Nearest and farthest distance (m) of segments ``(..., 2, 2)`` from the origin."""
    origin = np.zeros(segments.shape[:-2] + (2,))
    near = point_segment_distance(origin, segments[..., 0, :], segments[..., 1, :])
    far = np.linalg.norm(segments, axis=-1).max(axis=-1)
    return near, far


def _ends_against_stadiums(nearest: _Nearest, ends: np.ndarray, segments: np.ndarray, offset: np.ndarray,
                           margin: float, sign: float) -> None:
    """Contacts of end points ``ends`` ``(B, A, 2, 2)`` with stadiums around ``segments`` ``(B, C, 2, 2)``.

    ``offset`` ``(A, C)`` is the distance to keep (NaN: pair skipped), plus
    ``margin`` for end points that start outside ``offset + 1.5 margin``. With
    ``sign`` +1 the end points turn (``phi = psi - alpha``), with -1 the
    stadiums do (``phi = alpha - psi``). Only pairs whose end point's circle
    reaches the stadium's annulus about the pivot are solved.
    """
    rho = np.linalg.norm(ends, axis=-1)  # (B, A, 2)
    near, far = _reach(segments)  # (B, C)
    reach = (offset + margin)[None, :, :, None]  # (1, A, C, 1)
    r = rho[:, :, None, :]
    with np.errstate(invalid="ignore"):
        hit = (r >= near[:, None, :, None] - reach) & (r <= far[:, None, :, None] + reach)
    b, a, c, e = np.nonzero(hit)
    if not len(b):
        return
    point = ends[b, a, e]
    e1 = segments[b, c, 0]
    e2 = segments[b, c, 1]
    keep = offset[a, c]
    keep = keep + np.where(point_segment_distance(point, e1, e2) > keep + 1.5 * margin, margin, 0.0)
    psi = _circle_stadium(rho[b, a, e], e1, e2, keep)
    alpha = _angle(point)[:, None]
    nearest.take(b, psi - alpha if sign > 0 else alpha - psi)


def _contact_angles(world: World, body: _Body, margin: float) -> tuple[np.ndarray, np.ndarray]:
    """First contact angle turning each way, ``(hi > 0, lo < 0)`` per configuration (rad).

    Two segments kept ``offset + margin`` apart first touch where an end point of
    one meets the stadium around the other: circle-line and circle-circle
    intersections in closed form (after Lozano-Perez 1987). An end point already
    closer than ``offset + 1.5 margin`` is kept only ``offset`` away.
    """
    pivot = body.pivot
    nearest = _Nearest(len(pivot))
    m_rel = body.moving - pivot[:, None, None, :]  # (B, M, 2, 2)
    s_rel = body.static - pivot[:, None, None, :]  # (B, S, 2, 2)
    if m_rel.shape[1] and s_rel.shape[1]:
        _ends_against_stadiums(nearest, m_rel, s_rel, body.offsets, margin, +1.0)
        _ends_against_stadiums(nearest, s_rel, m_rel, body.offsets.T, margin, -1.0)
    xmin, ymin, xmax, ymax = world.bounds
    rel = body.points - pivot[:, None, :]
    rho = np.linalg.norm(rel, axis=-1)
    alpha = _angle(rel)
    safe_rho = np.where(rho > 0, rho, 1.0)
    limit = body.insets + margin
    candidates = []
    for axis, bound in ((0, xmin + limit), (0, xmax - limit), (1, ymin + limit), (1, ymax - limit)):
        c = (bound - pivot[:, axis, None]) / safe_rho
        ok = (np.abs(c) <= 1.0) & (rho > 0)
        if axis == 0:
            base = np.arccos(np.clip(c, -1.0, 1.0))
            roots = (base, -base)
        else:
            base = np.arcsin(np.clip(c, -1.0, 1.0))
            roots = (base, np.pi - base)
        candidates.extend(np.where(ok, root - alpha, np.nan) for root in roots)
    nearest.take(np.repeat(np.arange(len(pivot)), rel.shape[1]), np.stack(candidates, axis=-1).reshape(-1, 8))
    return nearest.hi, nearest.lo


def free_intervals(world: World, q: np.ndarray, joint: int, *, object_poses: np.ndarray | None = None,
                   grasp_rel: np.ndarray | None = None, margin_m: float = 1e-3,
                   counters: Counters | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Free interval ``[dmin, dmax]`` (rad) of ``joint`` for each configuration of ``q`` ``(B, n)``.

    Transit: give the resting object's poses ``object_poses`` ``(B, 3)``.
    Transfer: give ``grasp_rel`` ``(B, 3)``, the object's pose in the
    end-effector frame. Every angle of the interval is valid and keeps
    ``margin_m`` metres of clearance wherever the start had it;
    ``dmin <= 0 <= dmax``.
    """
    q = np.atleast_2d(q)
    hi, lo = _contact_angles(world, _body(world, q, joint, object_poses, grasp_rel), margin_m)
    if counters is not None:
        counters.clearance_checks += len(q)
    robot = world.robot
    upper = np.clip(robot.joint_upper[joint] - q[:, joint], 0.0, MAX_MOVE_RAD)
    lower = np.clip(robot.joint_lower[joint] - q[:, joint], -MAX_MOVE_RAD, 0.0)
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
                  counters: Counters | None = None) -> ManhattanPaths:
    """Decode genes ``(B, k, n)`` into collision-free Manhattan paths from ``q0`` ``(B, n)``.

    Transit when ``object_poses`` is given (the object rests there), transfer
    when ``grasp_rel`` is given (the object is carried).
    """
    q = np.array(np.broadcast_to(q0, (genes.shape[0], genes.shape[2])), dtype=float)
    order, n = genes.shape[1], genes.shape[2]
    waypoints = np.empty((len(q), order * n + 1, n))
    waypoints[:, 0] = q
    column = 1
    for k in range(order):
        for joint in range(n):
            low, high = free_intervals(world, q, joint, object_poses=object_poses, grasp_rel=grasp_rel,
                                       margin_m=margin_m, counters=counters)
            q[:, joint] += bounce(genes[:, k, joint], low, high)
            waypoints[:, column] = q
            column += 1
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
