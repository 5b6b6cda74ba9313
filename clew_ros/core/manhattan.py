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

from dataclasses import dataclass, field

import numpy as np

from clew_ros.core.collision import scene_of
from clew_ros.core.geometry import polygon_edges, segment_distance
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
    groups: list = field(default_factory=list)  # (moving (B,M,2,2), static (B|1,S,2,2), offset, mask (M,S)|None)
    points: list = field(default_factory=list)  # (moving points (B,P,2), inset)


def _body(world: World, q: np.ndarray, joint: int, object_poses: np.ndarray | None,
          grasp_rel: np.ndarray | None) -> _Body:
    scene = scene_of(world)
    robot = world.robot
    r = scene.link_radius
    pts = joint_positions(robot, q)
    n = robot.dof
    links = np.stack([pts[:, :-1], pts[:, 1:]], axis=2)  # (B, n, 2, 2)
    moving_links = links[:, joint:]
    static_links = links[:, :joint]
    body = _Body(pivot=pts[:, joint])
    obstacles = scene.obstacle_edges[None]
    if obstacles.shape[1]:
        body.groups.append((moving_links, obstacles, r, None))
    if joint >= 1 and len(scene.adjacent_pairs):
        moving_index = np.arange(joint, n)[:, None]
        static_index = np.arange(joint)[None, :]
        mask = (moving_index - static_index) >= 2
        if mask.any():
            body.groups.append((moving_links, static_links, 2 * r, mask))
    body.points.append((pts[:, joint + 1:], r))
    if grasp_rel is None:
        if len(scene.shrunk_edges):
            shrunk = _edges_at(object_poses, scene.shrunk_edges)
            body.groups.append((moving_links, shrunk, 0.0, None))
    else:
        object_pose = compose(tip_poses(robot, q), grasp_rel)
        object_edges = _edges_at(object_pose, scene.object_edges)
        if obstacles.shape[1]:
            body.groups.append((object_edges, obstacles, 0.0, None))
        if joint >= 1 and len(scene.shrunk_edges):
            body.groups.append((_edges_at(object_pose, scene.shrunk_edges), static_links, 0.0, None))
        body.points.append((object_edges[:, :, 0], 0.0))
    return body


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

    def take(self, phi: np.ndarray) -> None:
        """Add candidate rotation angles ``(B, ...)``; NaN entries are ignored."""
        phi = np.mod(phi.reshape(self.batch, -1), _TWO_PI)
        phi = np.where(phi < 1e-12, np.nan, phi)  # a contact at the current angle is not a crossing
        self.hi = np.minimum(self.hi, np.min(np.where(np.isnan(phi), np.inf, phi), axis=1))
        last = np.max(np.where(np.isnan(phi), -np.inf, phi), axis=1)
        self.lo = np.maximum(self.lo, last - _TWO_PI)


def _contact_angles(world: World, body: _Body, margin: float) -> tuple[np.ndarray, np.ndarray]:
    """First contact angle turning each way, ``(hi > 0, lo < 0)`` per configuration (rad).

    Two segments kept ``offset + margin`` apart first touch where an end point of
    one meets the stadium around the other: circle-line and circle-circle
    intersections in closed form (after Lozano-Perez 1987). A pair already
    closer than ``offset + 1.5 margin`` is kept only ``offset`` apart.
    """
    pivot = body.pivot
    nearest = _Nearest(len(pivot))
    for moving, static, offset, mask in body.groups:
        m_rel = moving - pivot[:, None, None, :]  # (B, M, 2, 2)
        s_rel = static - pivot[:, None, None, :]  # (B, S, 2, 2)
        d0 = segment_distance(m_rel[:, :, None, 0], m_rel[:, :, None, 1], s_rel[:, None, :, 0], s_rel[:, None, :, 1])
        pair_offset = offset + np.where(d0 > offset + 1.5 * margin, margin, 0.0)  # (B, M, S)
        if mask is not None:
            pair_offset = np.where(mask[None], pair_offset, np.nan)
        skip = np.isnan(pair_offset)[..., None, None]
        pair_offset = np.nan_to_num(pair_offset)[..., None]
        # moving end points against static stadiums: phi = psi - alpha
        ends = m_rel[:, :, None, :, :]  # (B, M, 1, 2, 2)
        psi = _circle_stadium(np.linalg.norm(ends, axis=-1), s_rel[:, None, :, None, 0], s_rel[:, None, :, None, 1],
                              pair_offset)
        nearest.take(np.where(skip, np.nan, psi - _angle(ends)[..., None]))
        # static end points against moving stadiums: phi = alpha - psi
        points = s_rel[:, None, :, :, :]  # (B, 1, S, 2, 2)
        psi = _circle_stadium(np.linalg.norm(points, axis=-1), m_rel[:, :, None, None, 0],
                              m_rel[:, :, None, None, 1], pair_offset)
        nearest.take(np.where(skip, np.nan, _angle(points)[..., None] - psi))
    xmin, ymin, xmax, ymax = world.bounds
    for points, inset in body.points:
        if points.shape[1] == 0:
            continue
        rel = points - pivot[:, None, :]
        rho = np.linalg.norm(rel, axis=-1)
        alpha = _angle(rel)
        safe_rho = np.where(rho > 0, rho, 1.0)
        limit = inset + margin
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
        nearest.take(np.stack(candidates, axis=-1))
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
