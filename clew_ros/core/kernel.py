"""The compiled kernel: free intervals and Manhattan decoding over whole batches (numba).

What :mod:`clew_ros.core.manhattan` describes is computed here, one compiled
call per batch: forward kinematics, the closed-form free interval of the
moving joint (contact angles of everything that turns with it against
everything that does not, after Lozano-Perez 1987), bouncing, and the whole
Manhattan path of every individual of a population. The world is packed
once into plain arrays (:func:`clew_ros.core.collision.packed_world`); the
kernels take arrays, not objects, and release the GIL. :func:`clearly_valid`
is the compiled first pass of the validity test; :func:`solve_point` the
inverse kinematics, :func:`pruned_path` the improvement's path pruning and :func:`shortcuts` its
shortcuts.

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
(:func:`_cannot_improve`), which leaves every interval bit for bit the same.
"""

from __future__ import annotations

import functools
import heapq
import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numba
import numpy as np

if TYPE_CHECKING:
    from numba.core.decorators import _JITWrapper  # in numba's type stubs only

__all__ = [
    "BACKOFF_RAD",
    "MAX_MOVE_RAD",
    "PackedWorld",
    "available_threads",
    "bounce_array",
    "chain",
    "clearly_valid",
    "connect_rounds",
    "decode",
    "intervals",
    "lattice_costs",
    "lattice_path",
    "lattice_repair",
    "lattice_search",
    "moves_clear",
    "pruned_path",
    "release_totals",
    "screen_routes",
    "shortcuts",
    "solve_point",
    "warm_up",
]

#: Largest move of one joint in one Manhattan move (rad), as in the paper.
MAX_MOVE_RAD = 2.0 * math.pi
#: Free intervals stop this far (rad) short of the first contact.
BACKOFF_RAD = 1e-6
_TWO_PI = 2.0 * math.pi
#: Limits at least this far apart (rad) let a joint turn all the way round (worlds write +-3.14159, just inside
#: pi): inverse kinematics takes such a joint past one limit to the same angle a turn short of the other.
FULL_TURN_RAD = _TWO_PI - 1e-3
#: A contact closer than this to the current angle (rad) is where the start touches, not a crossing.
_AT_START = 1e-12
#: :func:`_cannot_improve` skips a contact only if it is this much (rad) past both nearest contacts:
#: far more than the rounding of the two ways of computing its angle, so the interval is unchanged.
_PRUNE_MARGIN = 1e-9

_jit = numba.njit(cache=True, nogil=True, fastmath=False, error_model="numpy")
# Functions that allocate nothing are compiled without reference counting (numba's ``_nrt`` option):
# every array they get is borrowed from the caller, and the atomic increments and decrements numba would
# otherwise emit around each call and view took a tenth of the free intervals' time.
_leaf: _JITWrapper = numba.njit(  # type: ignore[call-overload]  # numba's stubs leave out its underscored options
    cache=True, nogil=True, fastmath=False, error_model="numpy", _nrt=False
)
# Parallel kernels may be launched from several threads at once (several planners in one process):
# only a thread-safe layer (TBB or OpenMP) allows it; without one the kernels run on one thread.
# GNU OpenMP is not fork-safe: start other processes with subprocess (fork + exec) or "spawn".
# (numba.config sets its attributes from the environment at run time: mypy cannot see them.)
if numba.config.THREADING_LAYER == "default":  # type: ignore[attr-defined]
    numba.config.THREADING_LAYER = "threadsafe"  # type: ignore[attr-defined]

#: :meth:`PackedWorld.arguments`: the world in the order the interval and decode kernels take it.
_WorldArguments = tuple[
    np.ndarray,
    np.ndarray,
    np.ndarray,
    np.ndarray,
    float,
    bool,
    np.ndarray,
    np.ndarray,
    np.ndarray,
    np.ndarray,
    np.ndarray,
]
#: :attr:`PackedWorld.move_arguments`: the world in the order :func:`_moves_clear` takes it.
_MoveArguments = tuple[
    np.ndarray,
    np.ndarray,
    np.ndarray,
    np.ndarray,
    float,
    bool,
    np.ndarray,
    np.ndarray,
    np.ndarray,
    np.ndarray,
    np.ndarray,
    np.ndarray,
    np.ndarray,
    float,
]
#: The broad phase of :func:`_interval` keeps an obstacle whose bounding circle is within this (m) of the
#: moving pieces' reach: far more than the rounding of the distances it compares.
_BROAD_PHASE_SLACK = 1e-6
#: :meth:`PackedWorld.validity_arguments`: the world in the order :func:`_clearly_valid` takes it.
_ValidityArguments = tuple[
    np.ndarray,
    np.ndarray,
    float,
    bool,
    np.ndarray,
    np.ndarray,
    np.ndarray,
    np.ndarray,
    np.ndarray,
    np.ndarray,
    np.ndarray,
    float,
]


@dataclass(frozen=True, eq=False)
class PackedWorld:
    """A world's geometry as contiguous float64 arrays, the kernel's only view of it."""

    base: np.ndarray  # (2,)
    lengths: np.ndarray  # (n,)
    lower: np.ndarray  # (n,)
    upper: np.ndarray  # (n,)
    link_radius: float
    self_collision: bool
    bounds: np.ndarray  # (4,) xmin, ymin, xmax, ymax
    obstacle_edges: np.ndarray  # (E, 2, 2)
    object_edges: np.ndarray  # (V, 2, 2) object frame
    shrunk_edges: np.ndarray  # (Es, 2, 2) object frame
    obstacle_starts: np.ndarray  # (O + 1,) int64: obstacle o's edges are obstacle_edges[starts[o]:starts[o + 1]]
    obstacle_boxes: np.ndarray  # (O, 4) xmin, ymin, xmax, ymax
    shrunk_starts: np.ndarray  # (parts + 1,) int64, the shrunk object's rings in shrunk_edges
    rounding: float  # distances within this of a threshold are left to the exact test (m)

    @functools.cached_property
    def pairs_per_move(self) -> int:
        """Rough count of piece pairs one free interval checks (for splitting huge batches)."""
        n = len(self.lengths)
        e = len(self.obstacle_edges)
        return 1 + n * (e + n + len(self.shrunk_edges)) + len(self.object_edges) * e

    @functools.cached_property
    def obstacle_groups(self) -> np.ndarray:
        """``(O, 5)``: each obstacle's first and end edge (as floats) and its bounding circle (centre x,
        y, radius), the broad phase of the free intervals."""
        boxes = self.obstacle_boxes.reshape(-1, 4)
        centres = 0.5 * (boxes[:, :2] + boxes[:, 2:])
        radii = 0.5 * np.hypot(boxes[:, 2] - boxes[:, 0], boxes[:, 3] - boxes[:, 1])
        starts = self.obstacle_starts.astype(np.float64)
        groups = np.column_stack([starts[:-1], starts[1:], centres, radii]) if len(boxes) else np.zeros((0, 5))
        return np.ascontiguousarray(groups, dtype=np.float64)

    def arguments(self) -> _WorldArguments:
        return self._arguments

    @functools.cached_property
    def _arguments(self) -> _WorldArguments:
        """Built once: the free intervals are asked for in small batches, thousands of times a plan."""
        return (
            self.base,
            self.lengths,
            self.lower,
            self.upper,
            self.link_radius,
            self.self_collision,
            self.bounds,
            self.obstacle_edges,
            self.obstacle_groups,
            self.object_edges,
            self.shrunk_edges,
        )

    @functools.cached_property
    def move_arguments(self) -> _MoveArguments:
        """The world in the order :func:`_moves_clear` takes it (built once: it checks one move at a time)."""
        return (self.base, self.lengths, self.lower, self.upper, *self.validity_arguments()[2:])

    def validity_arguments(self) -> _ValidityArguments:
        return (
            self.base,
            self.lengths,
            self.link_radius,
            self.self_collision,
            self.bounds,
            self.obstacle_edges,
            self.obstacle_starts,
            self.obstacle_boxes,
            self.object_edges,
            self.shrunk_edges,
            self.shrunk_starts,
            self.rounding,
        )


def _arg(array: np.ndarray) -> np.ndarray:
    """``array`` as the kernels take it: C-contiguous, aligned, writable float64 (numba compiles one
    version per layout and write flag, so read-only or strided arrays would compile again)."""
    if isinstance(array, np.ndarray) and array.dtype == np.float64 and array.flags.carray:
        return array
    return np.array(array, dtype=np.float64, order="C")


# --------------------------------------------------------------------------- scalar pieces


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
def _nearest(phi: float, best: np.ndarray) -> None:
    """Fold a candidate rotation ``phi`` (rad, any turn) into ``(0, 2 pi]`` and keep the nearest
    contact each way: ``best[0]`` the smallest (turning up), ``best[1]`` the largest (turning down);
    ``best[2:4]`` follow them as :func:`_pseudo_angle` bounds for :func:`_cannot_improve`."""
    if phi != phi:  # noqa: PLR0124 - NaN, as the compiled kernel has always tested it
        return
    phi -= _TWO_PI * math.floor(phi / _TWO_PI)
    if phi < _AT_START:
        return
    if phi < best[0]:
        best[0] = phi
        bound = phi + _PRUNE_MARGIN
        best[2] = _pseudo_angle(math.cos(bound), math.sin(bound)) if bound < _TWO_PI else 4.0
    if phi > best[1]:
        best[1] = phi
        bound = phi - _PRUNE_MARGIN
        best[3] = _pseudo_angle(math.cos(bound), math.sin(bound)) if bound > 0.0 else 0.0


@_leaf
def _reset(best: np.ndarray) -> None:
    """No contact yet: nothing can be pruned (:func:`_cannot_improve`)."""
    best[0], best[1], best[2], best[3] = math.inf, -math.inf, 4.0, 0.0


@_leaf
def _pseudo_angle(x: float, y: float) -> float:
    """A number in ``[0, 4)`` that grows with the angle of ``(x, y)`` over ``[0, 2 pi)``, without a
    transcendental function (the "diamond angle"); NaN for the zero vector."""
    if y >= 0.0:
        return y / (x + y) if x >= 0.0 else 1.0 - x / (y - x)
    return 2.0 - y / (-x - y) if x < 0.0 else 3.0 + x / (x - y)


@_leaf
def _cannot_improve(cos_rel: float, sin_rel: float, best: np.ndarray) -> bool:
    """Whether a contact at direction ``(cos_rel, sin_rel)`` (any scale) from the start, taken the way
    the joint turns, lies strictly between the nearest contacts found each way, with
    :data:`_PRUNE_MARGIN` to spare: :func:`_nearest` would keep neither bound, so its exact angle
    (an ``atan2``, the kernel's costliest step) need not be computed. In doubt (near a bound, NaN),
    False: the exact test decides, and the interval is the same number either way."""
    p = _pseudo_angle(cos_rel, sin_rel)
    return bool(best[2] < p < best[3])


@_leaf
def _forward(q: np.ndarray, base: np.ndarray, lengths: np.ndarray, links: np.ndarray) -> tuple[float, float, float]:
    """Forward kinematics of configuration ``q (n,)``: the links as segments ``links (n, 2, 2)``
    (world frame), and the end-effector frame ``(x, y, theta)``."""
    x, y, phi = base[0], base[1], 0.0
    for i in range(lengths.shape[0]):
        phi += q[i]
        nx, ny = x + lengths[i] * math.cos(phi), y + lengths[i] * math.sin(phi)
        links[i, 0, 0], links[i, 0, 1], links[i, 1, 0], links[i, 1, 1] = x, y, nx, ny
        x, y = nx, ny
    return x, y, phi


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
def _known(angle: float, x: float, y: float) -> float:
    """``angle`` if computed already, else (NaN) ``atan2(y, x)``."""
    return math.atan2(y, x) if angle != angle else angle  # noqa: PLR0124 - NaN: not computed yet


@_leaf
def _contact(px: float, py: float, cx: float, cy: float, start: float, turn: float, best: np.ndarray) -> float:
    """Point ``p`` (angle ``start``, NaN until computed) turned by ``turn`` times the angle to ``c``
    meets a stadium: a candidate for :func:`_nearest`, unless :func:`_cannot_improve`. Returns
    ``start``, computed if it was needed."""
    if _cannot_improve(px * cx + py * cy, turn * (px * cy - py * cx), best):
        return start
    start = _known(start, px, py)
    _nearest(turn * (math.atan2(cy, cx) - start), best)
    return start


@_leaf
def _point_meets_stadium(
    px: float,
    py: float,
    rho: float,
    ax: float,
    ay: float,
    bx: float,
    by: float,
    ra: float,
    rb: float,
    near: float,
    far: float,
    keep: float,
    margin: float,
    turn: float,
    best: np.ndarray,
) -> None:
    """Rotation angles (times ``turn``) at which point ``p`` (at distance ``rho`` from the pivot),
    turning about the pivot, meets the boundary of the stadium of radius ``keep`` (+ ``margin`` if it
    starts clear of it) around segment ``[a, b]`` (end points at ``ra``, ``rb``; nearest and farthest
    points at ``near``, ``far``); all relative to the pivot."""
    reach = keep + margin
    if rho < near - reach or rho > far + reach:
        return  # the point's circle misses the stadium's annulus about the pivot
    if _point_segment_distance(px, py, ax, ay, bx, by) > keep + 1.5 * margin:
        keep += margin
    start = math.nan  # the point's own angle, computed when a contact needs it
    rho2 = rho * rho
    dx, dy = bx - ax, by - ay
    length2 = dx * dx + dy * dy
    if length2 > 0.0:
        scale = keep / math.sqrt(length2)
        nx, ny = -dy * scale, dx * scale
        for side in (1.0, -1.0):  # the two offset lines
            lx, ly = ax + side * nx, ay + side * ny
            ad = lx * dx + ly * dy
            disc = ad * ad - length2 * (lx * lx + ly * ly - rho2)
            if disc >= 0.0:
                root = math.sqrt(disc)
                for sign in (1.0, -1.0):
                    t = (-ad + sign * root) / length2
                    if 0.0 <= t <= 1.0:
                        start = _contact(px, py, lx + t * dx, ly + t * dy, start, turn, best)
    if keep > 0.0:
        for ex, ey, e in ((ax, ay, ra), (bx, by, rb)):  # the two end circles
            denominator = 2.0 * rho * e
            if denominator > 0.0:
                cos_beta = (rho2 + e * e - keep * keep) / denominator
                if abs(cos_beta) <= 1.0:
                    beta = math.acos(cos_beta)
                    start = _known(start, px, py)
                    base = math.atan2(ey, ex) - start
                    _nearest(turn * (base + beta), best)
                    _nearest(turn * (base - beta), best)


@_leaf
def _pair(
    moving: np.ndarray,
    m: np.ndarray,
    i: int,
    static: np.ndarray,
    t: np.ndarray,
    s: int,
    keep: float,
    margin: float,
    best: np.ndarray,
) -> None:
    """Segment ``moving[i]`` turning against ``static[s]`` (both ``(., 2, 2)`` relative to the pivot,
    radii ``m``, ``t`` from :func:`_annulus`): the moving end points against the static stadium,
    and the static end points against the moving stadium (turning the other way)."""
    ax, ay, bx, by = moving[i, 0, 0], moving[i, 0, 1], moving[i, 1, 0], moving[i, 1, 1]
    cx, cy, dx, dy = static[s, 0, 0], static[s, 0, 1], static[s, 1, 0], static[s, 1, 1]
    ra, rb, rc, rd = m[i, 2], m[i, 3], t[s, 2], t[s, 3]
    _point_meets_stadium(ax, ay, ra, cx, cy, dx, dy, rc, rd, t[s, 0], t[s, 1], keep, margin, 1.0, best)
    _point_meets_stadium(bx, by, rb, cx, cy, dx, dy, rc, rd, t[s, 0], t[s, 1], keep, margin, 1.0, best)
    _point_meets_stadium(cx, cy, rc, ax, ay, bx, by, ra, rb, m[i, 0], m[i, 1], keep, margin, -1.0, best)
    _point_meets_stadium(dx, dy, rd, ax, ay, bx, by, ra, rb, m[i, 0], m[i, 1], keep, margin, -1.0, best)


@_leaf
def _annulus_of(segments: np.ndarray, radii: np.ndarray, c: int) -> None:
    """Segment ``c`` of ``segments`` (relative to the origin): ``radii[c]`` is its nearest and farthest
    distance from the origin, and its end points' distances."""
    ax, ay, bx, by = segments[c, 0, 0], segments[c, 0, 1], segments[c, 1, 0], segments[c, 1, 1]
    ra, rb = math.sqrt(ax * ax + ay * ay), math.sqrt(bx * bx + by * by)
    radii[c, 0] = _point_segment_distance(0.0, 0.0, ax, ay, bx, by)
    radii[c, 1] = max(ra, rb)
    radii[c, 2] = ra
    radii[c, 3] = rb


@_leaf
def _annulus(segments: np.ndarray, radii: np.ndarray) -> None:
    """For each segment ``(C, 2, 2)`` relative to the origin, ``radii (C, 4)``: its nearest and farthest
    distance from the origin, and its end points' distances."""
    for c in range(segments.shape[0]):
        _annulus_of(segments, radii, c)


@_leaf
def _pieces(
    moving: np.ndarray,
    m_radii: np.ndarray,
    m_first: int,
    m_last: int,
    static: np.ndarray,
    s_radii: np.ndarray,
    s_first: int,
    s_last: int,
    keep: float,
    margin: float,
    best: np.ndarray,
) -> None:
    """Moving pieces ``m_first .. m_last - 1`` against static pieces ``s_first .. s_last - 1``, kept
    ``keep`` apart. A pair whose annuli about the pivot (grown by the clearance) do not overlap cannot
    meet. (Ranges, not slices: a slice is an array object whose reference count every call would
    touch, a cost comparable to the test itself.)"""
    reach = keep + margin
    for i in range(m_first, m_last):
        low, high = m_radii[i, 0] - reach, m_radii[i, 1] + reach
        for s in range(s_first, s_last):
            if s_radii[s, 1] < low or s_radii[s, 0] > high:
                continue
            _pair(moving, m_radii, i, static, s_radii, s, keep, margin, best)


@_leaf
def _place(edges: np.ndarray, x: float, y: float, theta: float, px: float, py: float, out: np.ndarray) -> None:
    """``edges`` (object frame) at pose ``(x, y, theta)``, relative to the pivot ``p``, into ``out``."""
    c, s = math.cos(theta), math.sin(theta)
    for e in range(edges.shape[0]):
        for v in range(2):
            ex, ey = edges[e, v, 0], edges[e, v, 1]
            out[e, v, 0] = x + c * ex - s * ey - px
            out[e, v, 1] = y + s * ex + c * ey - py


@_leaf
def _bound_crossings(
    px: float, py: float, rx: float, ry: float, inset: float, margin: float, bounds: np.ndarray, best: np.ndarray
) -> None:
    """Rotations at which the point ``p + r`` (turning about ``p``) reaches a bound moved in by
    ``inset + margin``, or by ``inset`` alone for a bound it starts closer to than ``inset + 1.5 margin``
    (as for the stadiums: it is kept from getting closer than it starts, not pushed out)."""
    rho = math.sqrt(rx * rx + ry * ry)
    if not rho > 0.0:
        return
    x, y = px + rx, py + ry
    near = inset + 1.5 * margin
    xmin = bounds[0] + inset + (margin if x - bounds[0] > near else 0.0)
    ymin = bounds[1] + inset + (margin if y - bounds[1] > near else 0.0)
    xmax = bounds[2] - inset - (margin if bounds[2] - x > near else 0.0)
    ymax = bounds[3] - inset - (margin if bounds[3] - y > near else 0.0)
    if px - rho > xmin and px + rho < xmax and py - rho > ymin and py + rho < ymax:
        return  # its circle reaches no bound
    alpha = math.atan2(ry, rx)
    for bound in (xmin, xmax):
        c = (bound - px) / rho
        if abs(c) <= 1.0:
            base = math.acos(c)
            _nearest(base - alpha, best)
            _nearest(-base - alpha, best)
    for bound in (ymin, ymax):
        c = (bound - py) / rho
        if abs(c) <= 1.0:
            base = math.asin(c)
            _nearest(base - alpha, best)
            _nearest(math.pi - base - alpha, best)


# --------------------------------------------------------------------------- one free interval


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


@_leaf
def _interval(  # noqa: C901, PLR0912 - one compiled loop nest over every pair kind, commented step by step
    q: np.ndarray,
    joint: int,
    transfer: bool,
    pose: np.ndarray,
    margin: float,
    base: np.ndarray,
    lengths: np.ndarray,
    lower: np.ndarray,
    upper: np.ndarray,
    r: float,
    self_collision: bool,
    bounds: np.ndarray,
    obstacles: np.ndarray,
    groups: np.ndarray,
    object_edges: np.ndarray,
    shrunk_edges: np.ndarray,
    scratch: tuple[np.ndarray, ...],
) -> tuple[float, float]:
    """Free interval ``(low <= 0, high >= 0)`` of ``joint`` at configuration ``q`` ``(n,)``.

    ``pose``: the resting object's pose (transit) or its pose in the end-effector frame
    (transfer). ``scratch`` holds the work arrays of :func:`_scratch`.
    """
    links, link_radii, obstacle_rel, obstacle_radii, object_rel, object_radii, shrunk_rel, shrunk_radii, best = scratch
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
def _scratch(n: int, n_obstacles: int, n_object: int, n_shrunk: int) -> tuple[np.ndarray, ...]:
    return (
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


# --------------------------------------------------------------------------- batches


@_leaf
def _decode_one(
    b: int,
    waypoints: np.ndarray,
    genes: np.ndarray,
    first: int,
    last: int,
    transfer: bool,
    poses: np.ndarray,
    margin: float,
    base: np.ndarray,
    lengths: np.ndarray,
    lower: np.ndarray,
    upper: np.ndarray,
    r: float,
    self_collision: bool,
    bounds: np.ndarray,
    obstacles: np.ndarray,
    groups: np.ndarray,
    object_edges: np.ndarray,
    shrunk_edges: np.ndarray,
    scratch: tuple[np.ndarray, ...],
    q: np.ndarray,
) -> None:
    """Individual ``b``: fill columns ``first .. last - 1`` (>= 1) of ``waypoints[b]`` from column
    ``first - 1``: move ``c`` turns joint ``(c - 1) mod n`` by gene ``(c - 1)`` bounced into its free
    interval."""
    n = lengths.shape[0]
    for j in range(n):
        q[j] = waypoints[b, first - 1, j]
    for column in range(first, last):
        k, joint = (column - 1) // n, (column - 1) % n
        low, high = _interval(
            q,
            joint,
            transfer,
            poses[b],
            margin,
            base,
            lengths,
            lower,
            upper,
            r,
            self_collision,
            bounds,
            obstacles,
            groups,
            object_edges,
            shrunk_edges,
            scratch,
        )
        q[joint] += _bounce(genes[b, k, joint], low, high)
        for j in range(n):
            waypoints[b, column, j] = q[j]


@_jit
def _decode(
    waypoints: np.ndarray,
    genes: np.ndarray,
    first: int,
    last: int,
    transfer: bool,
    poses: np.ndarray,
    margin: float,
    base: np.ndarray,
    lengths: np.ndarray,
    lower: np.ndarray,
    upper: np.ndarray,
    r: float,
    self_collision: bool,
    bounds: np.ndarray,
    obstacles: np.ndarray,
    groups: np.ndarray,
    object_edges: np.ndarray,
    shrunk_edges: np.ndarray,
) -> None:
    """Columns ``first .. last - 1`` of every individual of ``waypoints`` ``(B, k n + 1, n)`` (genes
    ``(B, k, n)``, ``poses`` ``(B, 3)`` per individual), one after the other."""
    n = lengths.shape[0]
    scratch = _scratch(n, obstacles.shape[0], object_edges.shape[0], shrunk_edges.shape[0])
    q = np.empty(n)
    for b in range(waypoints.shape[0]):
        _decode_one(
            b,
            waypoints,
            genes,
            first,
            last,
            transfer,
            poses,
            margin,
            base,
            lengths,
            lower,
            upper,
            r,
            self_collision,
            bounds,
            obstacles,
            groups,
            object_edges,
            shrunk_edges,
            scratch,
            q,
        )


@numba.njit(cache=True, nogil=True, parallel=True, error_model="numpy")
def _decode_parallel(
    waypoints: np.ndarray,
    genes: np.ndarray,
    first: int,
    last: int,
    transfer: bool,
    poses: np.ndarray,
    margin: float,
    base: np.ndarray,
    lengths: np.ndarray,
    lower: np.ndarray,
    upper: np.ndarray,
    r: float,
    self_collision: bool,
    bounds: np.ndarray,
    obstacles: np.ndarray,
    groups: np.ndarray,
    object_edges: np.ndarray,
    shrunk_edges: np.ndarray,
) -> None:
    """:func:`_decode` with the individuals spread over threads (each computed alone, with work arrays
    of its own: the same numbers whatever the number of threads)."""
    n = lengths.shape[0]
    for b in numba.prange(waypoints.shape[0]):
        scratch = _scratch(n, obstacles.shape[0], object_edges.shape[0], shrunk_edges.shape[0])
        _decode_one(
            b,
            waypoints,
            genes,
            first,
            last,
            transfer,
            poses,
            margin,
            base,
            lengths,
            lower,
            upper,
            r,
            self_collision,
            bounds,
            obstacles,
            groups,
            object_edges,
            shrunk_edges,
            scratch,
            np.empty(n),
        )


@_jit
def _intervals(
    q: np.ndarray,
    joint: int,
    transfer: bool,
    poses: np.ndarray,
    margin: float,
    out: np.ndarray,
    base: np.ndarray,
    lengths: np.ndarray,
    lower: np.ndarray,
    upper: np.ndarray,
    r: float,
    self_collision: bool,
    bounds: np.ndarray,
    obstacles: np.ndarray,
    groups: np.ndarray,
    object_edges: np.ndarray,
    shrunk_edges: np.ndarray,
) -> None:
    """Free intervals ``out[0]`` (low) and ``out[1]`` (high), ``(2, B)``, of ``joint`` for configurations
    ``q (B, n)``; ``poses`` is ``(B, 3)`` or one pose ``(1, 3)`` for all."""
    scratch = _scratch(lengths.shape[0], obstacles.shape[0], object_edges.shape[0], shrunk_edges.shape[0])
    shared = poses.shape[0] == 1
    for b in range(q.shape[0]):
        out[0, b], out[1, b] = _interval(
            q[b],
            joint,
            transfer,
            poses[0] if shared else poses[b],
            margin,
            base,
            lengths,
            lower,
            upper,
            r,
            self_collision,
            bounds,
            obstacles,
            groups,
            object_edges,
            shrunk_edges,
            scratch,
        )


@_leaf
def _bounce_all(x: np.ndarray, low: np.ndarray, high: np.ndarray, out: np.ndarray) -> None:
    for i in range(x.shape[0]):
        out[i] = _bounce(x[i], low[i], high[i])


# --------------------------------------------------------------------------- validity


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
def _clearly_valid(
    q: np.ndarray,
    poses: np.ndarray,
    out: np.ndarray,
    base: np.ndarray,
    lengths: np.ndarray,
    r: float,
    self_collision: bool,
    bounds: np.ndarray,
    obstacles: np.ndarray,
    obstacle_starts: np.ndarray,
    boxes: np.ndarray,
    object_edges: np.ndarray,
    shrunk_edges: np.ndarray,
    shrunk_starts: np.ndarray,
    eps: float,
) -> None:
    """``out[b]``: configuration ``q[b]`` with the object at ``poses[b]`` passes the validity test of
    interface.md section 1 with every distance at least ``eps`` past its threshold. False means
    "not sure": the exact test decides (touching, within rounding, or invalid)."""
    n = lengths.shape[0]
    links = np.empty((n, 2, 2))
    shape = np.empty((object_edges.shape[0], 2, 2))
    shrunk = np.empty((shrunk_edges.shape[0], 2, 2))
    for b in range(q.shape[0]):
        out[b] = _valid_beyond(
            q[b],
            poses[b, 0],
            poses[b, 1],
            poses[b, 2],
            eps,
            n,
            links,
            shape,
            shrunk,
            base,
            lengths,
            r,
            self_collision,
            bounds,
            obstacles,
            obstacle_starts,
            boxes,
            object_edges,
            shrunk_edges,
            shrunk_starts,
        )


@_leaf
def _valid_beyond(  # noqa: C901, PLR0911, PLR0912 - one compiled pass per configuration, leaving at the first doubt
    q: np.ndarray,
    px: float,
    py: float,
    pt: float,
    eps: float,
    shrunk_links: int,
    links: np.ndarray,
    shape: np.ndarray,
    shrunk: np.ndarray,
    base: np.ndarray,
    lengths: np.ndarray,
    r: float,
    self_collision: bool,
    bounds: np.ndarray,
    obstacles: np.ndarray,
    obstacle_starts: np.ndarray,
    boxes: np.ndarray,
    object_edges: np.ndarray,
    shrunk_edges: np.ndarray,
    shrunk_starts: np.ndarray,
) -> bool:
    """One configuration ``q (n,)`` of :func:`_clearly_valid`, the object at ``(px, py, pt)``; only the
    first ``shrunk_links`` links are tested against the shrunk object. ``links``, ``shape`` and ``shrunk``
    are scratch arrays of the sizes of the links, ``object_edges`` and ``shrunk_edges``."""
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


# --------------------------------------------------------------------------- straight moves


@_leaf
def _at(
    a: np.ndarray,
    b: np.ndarray,
    t: float,
    q: np.ndarray,
    transfer: bool,
    grasp_rel: np.ndarray,
    resting: np.ndarray,
    base: np.ndarray,
    lengths: np.ndarray,
    links: np.ndarray,
) -> tuple[float, float, float]:
    """``q = a + t (b - a)`` and the object's pose there: at ``resting``, or held as ``grasp_rel`` by the tip
    (the tip's frame composed with ``grasp_rel``, as :func:`clew_ros.core.kinematics.compose` does)."""
    for j in range(q.shape[0]):
        q[j] = a[j] + t * (b[j] - a[j])
    if not transfer:
        return resting[0], resting[1], resting[2]
    return _held(q, grasp_rel[0], grasp_rel[1], grasp_rel[2], base, lengths, links)


@_leaf
def _held(
    q: np.ndarray, gx: float, gy: float, gt: float, base: np.ndarray, lengths: np.ndarray, links: np.ndarray
) -> tuple[float, float, float]:
    """The pose of the object held as ``(gx, gy, gt)`` (``grasp_rel``) by the tip at configuration ``q`` (the
    tip's frame composed with it, as :func:`clew_ros.core.kinematics.compose` does); ``links`` filled."""
    x, y, phi = _forward(q, base, lengths, links)
    c, s = math.cos(phi), math.sin(phi)
    return x + c * gx - s * gy, y + s * gx + c * gy, phi + gt


@_jit
def _move_clear(  # noqa: C901, PLR0911, PLR0912 - the levels of one move, commented step by step
    a: np.ndarray,
    b: np.ndarray,
    transfer: bool,
    grasp_rel: np.ndarray,
    resting: np.ndarray,
    min_margin: float,
    max_margin: float,
    coarse_stride: int,
    checked: np.ndarray,
    base: np.ndarray,
    lengths: np.ndarray,
    lower: np.ndarray,
    upper: np.ndarray,
    r: float,
    self_collision: bool,
    bounds: np.ndarray,
    obstacles: np.ndarray,
    obstacle_starts: np.ndarray,
    boxes: np.ndarray,
    object_edges: np.ndarray,
    shrunk_edges: np.ndarray,
    shrunk_starts: np.ndarray,
    rounding: float,
) -> bool:
    """:func:`clew_ros.core.continuous.straight_move_clear` of one move ``a -> b`` (its docstring says why it
    is sound); adds the configurations it checks to ``checked[0]``."""
    n = lengths.shape[0]
    q = np.empty(n)
    links = np.empty((n, 2, 2))
    shape = np.empty((object_edges.shape[0], 2, 2))
    shrunk = np.empty((shrunk_edges.shape[0], 2, 2))
    for j in range(n):  # both ends within the joint limits
        if a[j] < lower[j] or a[j] > upper[j] or b[j] < lower[j] or b[j] > upper[j]:
            return False
    # V: how far any point of the arm (and of the object held) moves; R_j sums links j..n-1 and the object
    held = 0.0
    if transfer:
        c, s = math.cos(grasp_rel[2]), math.sin(grasp_rel[2])
        for e in range(object_edges.shape[0]):
            vx, vy = object_edges[e, 0, 0], object_edges[e, 0, 1]
            held = max(held, math.hypot(grasp_rel[0] + c * vx - s * vy, grasp_rel[1] + s * vx + c * vy))
    motion = 0.0
    reach = 0.0
    for j in range(n - 1, -1, -1):
        reach += lengths[j]
        motion += abs(b[j] - a[j]) * (reach + held)
    motion = motion * (1.0 + 1e-9) + 1e-12
    # in a transfer the last link and the object it holds keep their distance: it is checked once, at a
    tested = n - 1 if transfer else n
    if transfer:
        px, py, pt = _at(a, b, 0.0, q, transfer, grasp_rel, resting, base, lengths, links)
        checked[0] += 1
        if not _valid_beyond(
            q, px, py, pt, min_margin, n, links, shape, shrunk, base, lengths, r, self_collision, bounds,
            obstacles, obstacle_starts, boxes, object_edges, shrunk_edges, shrunk_starts,
        ):  # fmt: skip
            return False
    # level k: 2**k pieces, each cleared by its midpoint with margin motion / 2**(k + 1)
    level = max(0, math.ceil(math.log2(max(motion / (2.0 * max_margin), 1.0))))
    count = 2**level
    if count >= 2 * coarse_stride:  # a long move: every coarse_stride-th midpoint first, valid at all?
        for piece in range(coarse_stride // 2, count, coarse_stride):
            px, py, pt = _at(a, b, (piece + 0.5) / count, q, transfer, grasp_rel, resting, base, lengths, links)
            checked[0] += 1
            if not _valid_beyond(
                q, px, py, pt, rounding, n, links, shape, shrunk, base, lengths, r, self_collision, bounds,
                obstacles, obstacle_starts, boxes, object_edges, shrunk_edges, shrunk_starts,
            ):  # fmt: skip
                return False  # most blocked moves end here, for a fraction of the first level's checks
    pending = np.arange(count)  # piece indices at this level
    while pending.shape[0]:
        pieces = float(count)
        margin = max(motion / (2.0 * pieces), min_margin)  # the last level: a short piece needs only the least
        failed = np.empty(pending.shape[0], np.int64)
        nfailed = 0
        for k in range(pending.shape[0]):
            t = (pending[k] + 0.5) / pieces
            px, py, pt = _at(a, b, t, q, transfer, grasp_rel, resting, base, lengths, links)
            checked[0] += 1
            if _valid_beyond(
                q, px, py, pt, margin, tested, links, shape, shrunk, base, lengths, r, self_collision, bounds,
                obstacles, obstacle_starts, boxes, object_edges, shrunk_edges, shrunk_starts,
            ):  # fmt: skip
                continue
            if margin <= min_margin:
                return False
            # a midpoint that is not valid at all rejects the move at once (halving would only find it later)
            checked[0] += 1
            if not _valid_beyond(
                q, px, py, pt, rounding, n, links, shape, shrunk, base, lengths, r, self_collision, bounds,
                obstacles, obstacle_starts, boxes, object_edges, shrunk_edges, shrunk_starts,
            ):  # fmt: skip
                return False
            failed[nfailed] = pending[k]
            nfailed += 1
        if nfailed == 0:
            return True
        pending = np.empty(2 * nfailed, np.int64)
        for k in range(nfailed):
            pending[2 * k], pending[2 * k + 1] = 2 * failed[k], 2 * failed[k] + 1
        count *= 2
    return True


@_jit
def _moves_clear(
    starts: np.ndarray,
    ends: np.ndarray,
    every: bool,
    transfer: bool,
    grasp_rel: np.ndarray,
    resting: np.ndarray,
    min_margin: float,
    max_margin: float,
    coarse_stride: int,
    out: np.ndarray,
    base: np.ndarray,
    lengths: np.ndarray,
    lower: np.ndarray,
    upper: np.ndarray,
    r: float,
    self_collision: bool,
    bounds: np.ndarray,
    obstacles: np.ndarray,
    obstacle_starts: np.ndarray,
    boxes: np.ndarray,
    object_edges: np.ndarray,
    shrunk_edges: np.ndarray,
    shrunk_starts: np.ndarray,
    rounding: float,
) -> int:
    """``out[k]``: :func:`_move_clear` of ``starts[k] -> ends[k]``; when ``every``, the moves after the first
    that is not clear are left unchecked (False). Returns how many configurations were checked."""
    out[:] = False
    checked = np.zeros(1, np.int64)
    for k in range(starts.shape[0]):
        out[k] = _move_clear(
            starts[k], ends[k], transfer, grasp_rel, resting, min_margin, max_margin, coarse_stride, checked,
            base, lengths, lower, upper, r, self_collision, bounds, obstacles, obstacle_starts, boxes,
            object_edges, shrunk_edges, shrunk_starts, rounding,
        )  # fmt: skip
        if every and not out[k]:
            break
    return int(checked[0])


# --------------------------------------------------------------------------- RRT-Connect


@_jit
def _extend(
    nodes: np.ndarray,
    parents: np.ndarray,
    sizes: np.ndarray,
    which: int,
    target: np.ndarray,
    step_rad: float,
    greedy: bool,
    transfer: bool,
    grasp_rel: np.ndarray,
    resting: np.ndarray,
    min_margin: float,
    max_margin: float,
    coarse_stride: int,
    checked: np.ndarray,
    base: np.ndarray,
    lengths: np.ndarray,
    lower: np.ndarray,
    upper: np.ndarray,
    r: float,
    self_collision: bool,
    bounds: np.ndarray,
    obstacles: np.ndarray,
    obstacle_starts: np.ndarray,
    boxes: np.ndarray,
    object_edges: np.ndarray,
    shrunk_edges: np.ndarray,
    shrunk_starts: np.ndarray,
    rounding: float,
) -> int:
    """Grow tree ``which`` (``nodes[which, :sizes[which]]``) from its node nearest ``target`` (largest joint
    difference, the first of equals) towards it by steps of at most ``step_rad``: one step, or while clear
    when ``greedy``. Returns the last node added (the nearest itself when it is the target), -1 when not
    even one step was clear."""
    n = nodes.shape[2]
    if sizes[which] == 0:
        return -1
    near = 0
    best = math.inf
    for i in range(sizes[which]):
        far = 0.0
        for j in range(n):
            far = max(far, abs(nodes[which, i, j] - target[j]))
        if far < best:
            near, best = i, far
    added = -1
    step = np.empty(n)
    while True:
        gap = 0.0
        for j in range(n):
            gap = max(gap, abs(target[j] - nodes[which, near, j]))
        if gap <= 1e-12:
            return added if added >= 0 else near
        for j in range(n):
            q = nodes[which, near, j]
            step[j] = target[j] if gap <= step_rad else q + (step_rad / gap) * (target[j] - q)
        if not _move_clear(
            nodes[which, near], step, transfer, grasp_rel, resting, min_margin, max_margin, coarse_stride, checked,
            base, lengths, lower, upper, r, self_collision, bounds, obstacles, obstacle_starts, boxes,
            object_edges, shrunk_edges, shrunk_starts, rounding,
        ):  # fmt: skip
            return added
        added = int(sizes[which])
        nodes[which, added] = step
        parents[which, added] = near
        sizes[which] += 1
        near = added
        if not greedy:
            return added


@_jit
def _connect_rounds(
    nodes: np.ndarray,
    parents: np.ndarray,
    sizes: np.ndarray,
    state: np.ndarray,
    targets: np.ndarray,
    step_rad: float,
    allowed: float,
    check_work: float,
    round_work: float,
    transfer: bool,
    grasp_rel: np.ndarray,
    resting: np.ndarray,
    min_margin: float,
    max_margin: float,
    coarse_stride: int,
    base: np.ndarray,
    lengths: np.ndarray,
    lower: np.ndarray,
    upper: np.ndarray,
    r: float,
    self_collision: bool,
    bounds: np.ndarray,
    obstacles: np.ndarray,
    obstacle_starts: np.ndarray,
    boxes: np.ndarray,
    object_edges: np.ndarray,
    shrunk_edges: np.ndarray,
    shrunk_starts: np.ndarray,
    rounding: float,
) -> float:
    """Rounds of RRT-Connect, one per row of ``targets``, while the work spent (``round_work`` a round,
    ``check_work`` a configuration checked) is within ``allowed``; returns the work spent. ``state``:
    ``[tree extended first, node grown, node reached, met]``; tree 0 grows from the start, tree 1 from the
    goals, and they take turns."""
    checked = np.zeros(1, np.int64)
    spent = 0.0
    for k in range(targets.shape[0]):
        if spent >= allowed:
            break
        first = state[0]
        checked[0] = 0
        grown = _extend(
            nodes, parents, sizes, first, targets[k], step_rad, False, transfer, grasp_rel, resting, min_margin,
            max_margin, coarse_stride, checked, base, lengths, lower, upper, r, self_collision, bounds, obstacles,
            obstacle_starts, boxes, object_edges, shrunk_edges, shrunk_starts, rounding,
        )  # fmt: skip
        if grown >= 0:
            reached = _extend(
                nodes, parents, sizes, 1 - first, nodes[first, grown], step_rad, True, transfer, grasp_rel,
                resting, min_margin, max_margin, coarse_stride, checked, base, lengths, lower, upper, r,
                self_collision, bounds, obstacles, obstacle_starts, boxes, object_edges, shrunk_edges,
                shrunk_starts, rounding,
            )  # fmt: skip
            met = reached >= 0
            for j in range(nodes.shape[2]):
                met = met and nodes[1 - first, reached, j] == nodes[first, grown, j]
            if met:
                state[1], state[2], state[3] = grown, reached, 1
                return spent + round_work + float(checked[0]) * check_work
        spent += round_work + float(checked[0]) * check_work
        state[0] = 1 - first
    return spent


# --------------------------------------------------------------------------- kinematics


@_jit
def _chain(q: np.ndarray, base: np.ndarray, lengths: np.ndarray, points: np.ndarray, tips: np.ndarray) -> None:
    """Joint positions ``points (B, n + 1, 2)`` and end-effector frames ``tips (B, 3)`` of ``q (B, n)``."""
    links = np.empty((lengths.shape[0], 2, 2))
    for b in range(q.shape[0]):
        tips[b, 0], tips[b, 1], tips[b, 2] = _forward(q[b], base, lengths, links)
        points[b, 0, 0], points[b, 0, 1] = base[0], base[1]
        for i in range(lengths.shape[0]):
            points[b, i + 1, 0], points[b, i + 1, 1] = links[i, 1, 0], links[i, 1, 1]


@_leaf
def _within_limits(angle: float, lower: float, upper: float, full_turns: bool) -> float:
    """``angle`` stopped at the limits; but with ``full_turns``, on a joint that turns all the way round
    (:data:`FULL_TURN_RAD`), past one limit it goes on a turn back from the other (the same angle, to within the
    gap between the limits, where it stops; ``angle`` is less than a turn past)."""
    if full_turns and upper - lower >= FULL_TURN_RAD:
        if angle > upper:
            angle -= _TWO_PI
        elif angle < lower:
            angle += _TWO_PI
    return min(max(angle, lower), upper)


@_jit
def _solve_point(  # noqa: PLR0915 - one compiled loop per row: kinematics, Jacobian, a 2x2 or 3x3 solve, the step
    q: np.ndarray,
    targets: np.ndarray,
    offsets: np.ndarray,
    angles: np.ndarray,
    angle_tolerance: float,
    angle_scale: float,
    iterations: int,
    damping: float,
    max_step: float,
    base: np.ndarray,
    lengths: np.ndarray,
    lower: np.ndarray,
    upper: np.ndarray,
    tolerance: float,
    full_turns: bool,
    error: np.ndarray,
    steps: np.ndarray,
) -> None:
    """Damped least squares, in place on ``q (B, n)``: the point ``offsets[b]`` of the end-effector frame
    to ``targets[b]``, and (``angles[b]`` not NaN) the frame's angle within ``angle_tolerance`` of it;
    a row stops once its error is at most ``tolerance``; a step past a limit is :func:`_within_limits`.
    ``error[b]``: what is left (m; the angle's excess counts ``angle_scale`` m per rad); ``steps[b]``: the
    steps taken."""
    n = lengths.shape[0]
    px = np.empty(n)
    py = np.empty(n)
    jx = np.empty(n)
    jy = np.empty(n)
    for b in range(q.shape[0]):
        use_angle = angles[b] == angles[b]
        for it in range(iterations + 1):
            x, y, phi = base[0], base[1], 0.0
            for i in range(n):
                px[i], py[i] = x, y
                phi += q[b, i]
                x += lengths[i] * math.cos(phi)
                y += lengths[i] * math.sin(phi)
            c, s = math.cos(phi), math.sin(phi)
            x += c * offsets[b, 0] - s * offsets[b, 1]
            y += s * offsets[b, 0] + c * offsets[b, 1]
            ex, ey, et = x - targets[b, 0], y - targets[b, 1], 0.0
            if use_angle:
                turn = phi - angles[b]
                turn -= _TWO_PI * math.floor((turn + math.pi) / _TWO_PI)
                if turn > angle_tolerance:
                    et = angle_scale * (turn - angle_tolerance)
                elif turn < -angle_tolerance:
                    et = angle_scale * (turn + angle_tolerance)
            error[b] = math.sqrt(ex * ex + ey * ey + et * et)
            steps[b] = it
            if it == iterations or error[b] <= tolerance:
                break
            a11 = a12 = a22 = a13 = a23 = 0.0
            for i in range(n):
                jx[i], jy[i] = py[i] - y, x - px[i]
                a11 += jx[i] * jx[i]
                a12 += jx[i] * jy[i]
                a22 += jy[i] * jy[i]
                a13 += jx[i] * angle_scale
                a23 += jy[i] * angle_scale
            a11 += damping
            a22 += damping
            if use_angle:
                a33 = n * angle_scale * angle_scale + damping
                c11, c12, c13 = a22 * a33 - a23 * a23, a13 * a23 - a12 * a33, a12 * a23 - a13 * a22
                c22, c23, c33 = a11 * a33 - a13 * a13, a12 * a13 - a11 * a23, a11 * a22 - a12 * a12
                det = a11 * c11 + a12 * c12 + a13 * c13
                w1 = (c11 * ex + c12 * ey + c13 * et) / det
                w2 = (c12 * ex + c22 * ey + c23 * et) / det
                w3 = (c13 * ex + c23 * ey + c33 * et) / det
            else:
                det = a11 * a22 - a12 * a12
                w1 = (a22 * ex - a12 * ey) / det
                w2 = (a11 * ey - a12 * ex) / det
                w3 = 0.0
            largest = 0.0
            for i in range(n):
                jx[i] = -(jx[i] * w1 + jy[i] * w2 + angle_scale * w3)  # the step, in place
                largest = max(largest, abs(jx[i]))
            scale = min(1.0, max_step / largest) if largest > 0.0 else 0.0
            for i in range(n):
                q[b, i] = _within_limits(q[b, i] + scale * jx[i], lower[i], upper[i], full_turns)


# --------------------------------------------------------------------------- Python entry points


def _poses(poses: np.ndarray, batch: int) -> np.ndarray:
    poses = np.asarray(poses, dtype=np.float64)
    return _arg(poses) if poses.shape == (batch, 3) else np.array(np.broadcast_to(poses, (batch, 3)))


def available_threads() -> int:
    """Threads the parallel kernel may use here: numba's thread count when a thread-safe threading
    layer (TBB or OpenMP) loads, else 1."""
    if not _PARALLEL:
        try:
            _decode_parallel(
                np.zeros((1, 2, 1)),
                np.zeros((1, 1, 1)),
                1,
                2,
                False,
                np.zeros((1, 3)),
                0.0,
                np.zeros(2),
                np.ones(1),
                -np.ones(1),
                np.ones(1),
                0.0,
                False,
                np.array([-9.0, -9.0, 9.0, 9.0]),
                np.zeros((0, 2, 2)),
                np.zeros((0, 5)),
                np.zeros((0, 2, 2)),
                np.zeros((0, 2, 2)),
            )
            # the workqueue layer (chosen by a user's NUMBA_THREADING_LAYER) aborts on concurrent launches
            safe = numba.threading_layer() in ("tbb", "omp")  # type: ignore[attr-defined]
            _PARALLEL.append(int(numba.config.NUMBA_NUM_THREADS) if safe else 1)  # type: ignore[attr-defined]
        except (ValueError, RuntimeError, ImportError):  # no thread-safe threading layer
            _PARALLEL.append(1)
    return _PARALLEL[0]


_PARALLEL: list[int] = []


def decode(
    world: PackedWorld,
    waypoints: np.ndarray,
    genes: np.ndarray,
    first: int,
    last: int,
    transfer: bool,
    poses: np.ndarray,
    margin: float,
    threads: int = 1,
) -> None:
    """Compiled: columns ``first .. last - 1`` of ``waypoints`` (C-contiguous float64, filled in place),
    on ``threads`` threads (0: all); every individual is computed alone, so the numbers do not depend
    on the number of threads."""
    if threads != 1:
        threads = min(threads or available_threads(), available_threads(), len(waypoints))
    arguments = (
        waypoints,
        _arg(genes),
        first,
        last,
        transfer,
        _poses(poses, len(waypoints)),
        float(margin),
        *world.arguments(),
    )
    if threads > 1:
        numba.set_num_threads(threads)  # for this calling thread only
        _decode_parallel(*arguments)
    else:
        _decode(*arguments)


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
    _intervals(q, int(joint), transfer, rows, float(margin), out, *world.arguments())
    return out[0], out[1]


def clearly_valid(world: PackedWorld, q: np.ndarray, poses: np.ndarray) -> np.ndarray:
    """Compiled: which configurations ``q (B, n)`` (object at ``poses``) are valid beyond doubt; the
    others (invalid, touching, or within rounding of a threshold) need the exact test."""
    q = _arg(np.atleast_2d(q))
    out = np.empty(len(q), dtype=np.bool_)
    _clearly_valid(q, _poses(poses, len(q)), out, *world.validity_arguments())
    return out


def _mode(resting: np.ndarray | None, grasp_rel: np.ndarray | None) -> tuple[bool, np.ndarray, np.ndarray]:
    """A mode as the move kernels take it: whether the object is held, its pose held, its pose at rest."""
    if (resting is None) == (grasp_rel is None):
        raise ValueError("give the object's pose at rest (a transit) or the grasp_rel it is held by (a transfer)")
    if grasp_rel is None:
        return False, _NOWHERE, _arg(resting)  # type: ignore[arg-type]  # not None: tested above
    return True, _arg(grasp_rel), _NOWHERE


_NOWHERE = np.zeros(3)  # the pose a mode does not use


def moves_clear(
    world: PackedWorld,
    starts: np.ndarray,
    ends: np.ndarray,
    *,
    resting: np.ndarray | None,
    grasp_rel: np.ndarray | None,
    min_margin: float,
    max_margin: float,
    coarse_stride: int,
    every: bool = False,
) -> tuple[np.ndarray, int]:
    """Compiled :func:`clew_ros.core.continuous.straight_move_clear` of moves ``starts[k] -> ends[k]``
    ``(K, n)``, the object at ``resting`` (a transit) or held as ``grasp_rel`` (a transfer; give one): which
    are clear, and how many configurations were checked. With ``every``, the moves after the first that is
    not clear are not checked (and not clear)."""
    # called for every move the improvement tries: the Python here is kept to what the call needs
    starts, ends = _arg(starts), _arg(ends)
    if starts.ndim != 2 or starts.shape != ends.shape or starts.shape[1] != len(world.lengths):
        raise ValueError(
            f"starts, ends: expected two (K, {len(world.lengths)}) arrays, got {starts.shape}, {ends.shape}"
        )
    out = np.empty(len(starts), dtype=np.bool_)
    transfer, held, at_rest = _mode(resting, grasp_rel)
    checked = _moves_clear(
        starts,
        ends,
        bool(every),
        transfer,
        held,
        at_rest,
        float(min_margin),
        float(max_margin),
        int(coarse_stride),
        out,
        *world.move_arguments,
    )
    return out, int(checked)


def connect_rounds(
    world: PackedWorld,
    nodes: np.ndarray,
    parents: np.ndarray,
    sizes: np.ndarray,
    state: np.ndarray,
    targets: np.ndarray,
    *,
    step_rad: float,
    allowed: float,
    check_work: float,
    round_work: float,
    resting: np.ndarray | None,
    grasp_rel: np.ndarray | None,
    min_margin: float,
    max_margin: float,
    coarse_stride: int,
) -> float:
    """Compiled rounds of RRT-Connect (:func:`clew_ros.core.connect.rrt_connect` keeps the trees: ``nodes``
    ``(2, capacity, n)``, ``parents`` ``(2, capacity)`` int64, ``sizes`` ``(2,)`` int64 (each at least 1) and
    ``state`` ``(4,)`` int64, all updated in place; room for every node the rounds may add), one per row of
    ``targets``, while the work spent is within ``allowed``; the object at ``resting`` or held as
    ``grasp_rel`` (give one). Returns the work spent."""
    transfer, held, at_rest = _mode(resting, grasp_rel)
    return float(
        _connect_rounds(
            nodes,
            parents,
            sizes,
            state,
            _arg(targets),
            float(step_rad),
            float(allowed),
            float(check_work),
            float(round_work),
            transfer,
            held,
            at_rest,
            float(min_margin),
            float(max_margin),
            int(coarse_stride),
            *world.move_arguments,
        )
    )


def chain(base: np.ndarray, lengths: np.ndarray, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Compiled forward kinematics: joint positions ``(B, n + 1, 2)`` and tip frames ``(B, 3)``."""
    q = _arg(q)
    points = np.empty((len(q), len(lengths) + 1, 2))
    tips = np.empty((len(q), 3))
    _chain(q, base, lengths, points, tips)
    return points, tips


def solve_point(
    base: np.ndarray,
    lengths: np.ndarray,
    lower: np.ndarray,
    upper: np.ndarray,
    seeds: np.ndarray,
    targets: np.ndarray,
    offsets: np.ndarray,
    angles: np.ndarray,
    *,
    angle_tolerance: float,
    angle_scale: float,
    iterations: int,
    damping: float,
    max_step: float,
    tolerance: float = 0.0,
    full_turns: bool = False,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Compiled damped least squares from ``seeds (B, n)`` (see :func:`clew_ros.core.inverse.solve_point`):
    the configurations, the error left and the steps taken ``(B,)``."""
    q = np.array(seeds, dtype=np.float64, order="C")
    error = np.empty(len(q))
    steps = np.zeros(len(q), dtype=np.int64)
    _solve_point(
        q,
        _arg(targets),
        _arg(offsets),
        _arg(angles),
        float(angle_tolerance),
        float(angle_scale),
        int(iterations),
        float(damping),
        float(max_step),
        _arg(base),
        _arg(lengths),
        _arg(lower),
        _arg(upper),
        float(tolerance),
        bool(full_turns),
        error,
        steps,
    )
    return q, error, steps


@_leaf
def _pruned(waypoints: np.ndarray, points: np.ndarray) -> int:
    """:func:`pruned_path` into ``points`` (as large as ``waypoints``); returns how many it kept."""
    n = waypoints.shape[1]
    size = 0
    for k in range(waypoints.shape[0]):
        back = -1  # the first point kept so far that this one is back at (a loop)
        for i in range(size):
            largest = 0.0
            for j in range(n):
                largest = max(largest, abs(points[i, j] - waypoints[k, j]))
            if largest <= 1e-12:
                back = i
                break
        if back >= 0:
            size = back + 1
        else:
            for j in range(n):
                points[size, j] = waypoints[k, j]
            size += 1
        while size >= 3:  # the last three collinear (a move undone or continued): drop the middle one
            scale = 0.0
            uv = 0.0
            vv = 0.0
            for j in range(n):
                u = points[size - 2, j] - points[size - 3, j]
                v = points[size - 1, j] - points[size - 2, j]
                scale = max(scale, abs(u), abs(v))
                uv += u * v
                vv += v * v
            off = 0.0
            for j in range(n):
                u = points[size - 2, j] - points[size - 3, j]
                v = points[size - 1, j] - points[size - 2, j]
                off = max(off, abs(u * vv - v * uv))
            if scale > 0 and off > 1e-12 * scale**3:
                break
            for j in range(n):
                points[size - 2, j] = points[size - 1, j]
            size -= 1
    return size


@_jit
def _screen(
    a: np.ndarray,
    b: np.ndarray,
    samples: np.ndarray,
    transfer: bool,
    held: np.ndarray,
    at_rest: np.ndarray,
    route: np.ndarray,
    base: np.ndarray,
    lengths: np.ndarray,
    r: float,
    self_collision: bool,
    bounds: np.ndarray,
    obstacles: np.ndarray,
    obstacle_starts: np.ndarray,
    boxes: np.ndarray,
    object_edges: np.ndarray,
    shrunk_edges: np.ndarray,
    shrunk_starts: np.ndarray,
    eps: float,
) -> int:
    """:func:`screen_routes` into ``route``; returns how many configurations were checked."""
    m, n = a.shape
    links = np.empty((n, 2, 2))
    shape = np.empty((object_edges.shape[0], 2, 2))
    shrunk = np.empty((shrunk_edges.shape[0], 2, 2))
    q, moved, start = np.empty(n), np.empty(n), np.empty(n)
    checked = 0
    for k in range(m):
        route[k] = -1
        total = 0.0
        for j in range(n):
            moved[j] = abs(b[k, j] - a[k, j])
            total += moved[j]
        for way in range(3):
            sofar = 0.0
            for step in range(n):  # where each joint starts moving along the way (one joint after the other)
                j = step if way == 1 else n - 1 - step
                sofar += moved[j]
                start[j] = sofar - moved[j]
            clear = True
            for sample in range(2 * samples[k]):  # every fourth sample first: most blocked moves stop there
                coarse = sample < samples[k]
                index = sample if coarse else sample - samples[k]
                if (index % 4 == 0) != coarse:
                    continue
                share = _end_share(index, samples[k])
                _way_point(a, b, k, way, share * total, share, moved, start, q)
                px, py, pt = at_rest[k, 0], at_rest[k, 1], at_rest[k, 2]
                if transfer:
                    px, py, pt = _held(q, held[k, 0], held[k, 1], held[k, 2], base, lengths, links)
                checked += 1
                if not _valid_beyond(
                    q, px, py, pt, eps, n, links, shape, shrunk, base, lengths, r, self_collision, bounds,
                    obstacles, obstacle_starts, boxes, object_edges, shrunk_edges, shrunk_starts,
                ):  # fmt: skip
                    clear = False
                    break
            if clear:
                route[k] = way
                break
    return checked


@_leaf
def _end_share(sample: int, count: int) -> float:
    """Sample ``sample`` of ``count`` along a move, as a share of it, closer together near both ends (cosine
    spacing, as ``0.5 - 0.5 cos(linspace(0, pi, count))``)."""
    angle = math.pi if sample == count - 1 else sample * (math.pi / (count - 1))
    return 0.5 - 0.5 * math.cos(angle)


@_leaf
def _way_point(
    a: np.ndarray,
    b: np.ndarray,
    k: int,
    way: int,
    travel: float,
    share: float,
    moved: np.ndarray,
    start: np.ndarray,
    q: np.ndarray,
) -> None:
    """``q`` = the point of way ``way`` (straight, or one joint after the other from ``start``) from ``a[k]``
    to ``b[k]`` at ``share`` of it, ``travel`` rad of joint travel along it."""
    for j in range(q.shape[0]):
        if way == 0:
            q[j] = a[k, j] + share * (b[k, j] - a[k, j])
        else:
            done = min(max((travel - start[j]) / max(moved[j], 1e-300), 0.0), 1.0)
            q[j] = a[k, j] + done * (b[k, j] - a[k, j])


def screen_routes(
    world: PackedWorld,
    starts: np.ndarray,
    ends: np.ndarray,
    samples: np.ndarray,
    *,
    resting: np.ndarray | None,
    grasp_rel: np.ndarray | None,
) -> tuple[np.ndarray, int]:
    """The proposals' screen (:meth:`clew_ros.core.regrasp._Kinematics.routes`), compiled: per move
    ``starts[k] -> ends[k]`` ``(M, n)``, the first way (0 straight, 1 one joint after the other from the
    first, 2 from the last) whose ``samples[k]`` configurations (cosine-spaced along the way's joint travel,
    every fourth first) pass :func:`clearly_valid` with the world's rounding as the margin, the object resting
    at ``resting[k]`` or held as ``grasp_rel[k]`` (``(M, 3)``; give one); -1 when none does. Returns the ways
    and how many configurations were checked (a way stops at its first sample that does not pass)."""
    starts, ends = _arg(starts), _arg(ends)
    count = np.ascontiguousarray(samples, dtype=np.int64)
    n = len(world.lengths)
    if starts.shape != (len(starts), n) or ends.shape != starts.shape or count.shape != (len(starts),):
        raise ValueError(
            f"starts, ends, samples: expected (M, {n}), (M, {n}) and (M,), got {starts.shape}, {ends.shape}, "
            f"{count.shape}"
        )
    if np.any(count < 2):
        raise ValueError(f"samples: expected at least 2 per move, got {count.min()}")
    transfer, held, at_rest = _mode(resting, grasp_rel)
    held, at_rest = held.reshape(-1, 3), at_rest.reshape(-1, 3)
    if len(held if transfer else at_rest) != len(starts):
        raise ValueError(
            f"resting, grasp_rel: expected ({len(starts)}, 3), got {(held if transfer else at_rest).shape}"
        )
    route = np.empty(len(starts), dtype=np.int64)
    checked = _screen(starts, ends, count, transfer, held, at_rest, route, *world.validity_arguments())
    return route, int(checked)


@_leaf
def _shortcuts(
    w: np.ndarray,
    draws: np.ndarray,
    cumulative: np.ndarray,
    first: np.ndarray,
    last: np.ndarray,
    paths: np.ndarray,
    gain: np.ndarray,
    fewer: np.ndarray,
) -> None:
    """:func:`shortcuts` into ``cumulative`` (scratch: the path's joint travel up to each waypoint),
    ``first``, ``last``, ``paths``, ``gain``, ``fewer``."""
    m, n = w.shape
    cumulative[0] = 0.0
    for i in range(1, m):
        cumulative[i] = cumulative[i - 1]
        for c in range(n):
            cumulative[i] += abs(w[i, c] - w[i - 1, c])
    pieces = paths.shape[1] - 2
    for k in range(draws.shape[0]):
        joined = draws[k, 0] < 1.0 / 3.0  # two waypoints joined straight
        partial = draws[k, 0] >= 2.0 / 3.0
        if joined:
            one = min(int(draws[k, 3] * m), m - 1)
            other = min(int(draws[k, 4] * (m - 1)), m - 2)
            other += other >= one  # distinct
            i, j = min(one, other), max(one, other)
            u0, u1 = cumulative[i], cumulative[j]
            start, end = i, j - 1
            _put(paths, k, 0, w, cumulative, i, u0)  # the waypoints themselves, not rounded
            _put(paths, k, pieces + 1, w, cumulative, j, u1)
        else:
            u0 = cumulative[m - 1] * min(draws[k, 1], draws[k, 2])
            u1 = cumulative[m - 1] * max(draws[k, 1], draws[k, 2])
            start, end = _piece_at(cumulative, u0), _piece_at(cumulative, u1)
            _put(paths, k, 0, w, cumulative, start, u0)
            _put(paths, k, pieces + 1, w, cumulative, end, u1)
        first[k], last[k] = start, end
        moved = min(int(draws[k, 5] * n), n - 1) if partial else -1
        _between(paths, k, w, cumulative, start, end, u0, u1, moved)
        replaces = end > start and not (partial and end - start > pieces)
        gain[k] = (u1 - u0) - _path_travel(paths, k) if replaces else -np.inf
        fewer[k] = replaces and (joined or (not partial and end - start > 2))  # as long, fewer waypoints


@_leaf
def _put(paths: np.ndarray, k: int, row: int, w: np.ndarray, cumulative: np.ndarray, piece: int, at: float) -> None:
    """``paths[k, row]`` = the point ``at`` (joint travel along the path ``w``) on ``piece`` (``w[piece]``
    itself when ``at`` is where the piece starts)."""
    span = cumulative[piece + 1] - cumulative[piece] if piece + 1 < cumulative.shape[0] else 0.0
    share = (at - cumulative[piece]) / span if span > 0 else 0.0
    for c in range(w.shape[1]):
        paths[k, row, c] = w[piece, c] if share == 0.0 else w[piece, c] + share * (w[piece + 1, c] - w[piece, c])


@_leaf
def _between(
    paths: np.ndarray,
    k: int,
    w: np.ndarray,
    cumulative: np.ndarray,
    start: int,
    end: int,
    u0: float,
    u1: float,
    moved: int,
) -> None:
    """The rows of ``paths[k]`` between its ends: the last one repeated (a straight shortcut, ``moved`` -1),
    or the path's waypoints ``start + 1 .. end``, padded with the last, joint ``moved`` evened out along them."""
    pieces = paths.shape[1] - 2
    stretch = max(u1 - u0, 1e-300)
    for p in range(pieces):
        inner = min(start + 1 + p, end)
        for c in range(w.shape[1]):
            if moved < 0:
                paths[k, 1 + p, c] = paths[k, pieces + 1, c]
            elif c == moved:
                a, b = paths[k, 0, c], paths[k, pieces + 1, c]
                paths[k, 1 + p, c] = a + (cumulative[inner] - u0) / stretch * (b - a)
            else:
                paths[k, 1 + p, c] = w[inner, c]


@_leaf
def _path_travel(paths: np.ndarray, k: int) -> float:
    """Joint travel along ``paths[k]`` (rad)."""
    travel = 0.0
    for p in range(paths.shape[1] - 1):
        for c in range(paths.shape[2]):
            travel += abs(paths[k, p + 1, c] - paths[k, p, c])
    return travel


@_leaf
def _piece_at(cumulative: np.ndarray, travel: float) -> int:
    """The piece of a path (by its cumulative joint travel) that the point ``travel`` along it lies on."""
    last: int = cumulative.shape[0] - 2
    low, high = 0, last + 2  # the first index whose cumulative travel is above ``travel``
    while low < high:
        middle = (low + high) // 2
        if cumulative[middle] <= travel:
            low = middle + 1
        else:
            high = middle
    return min(max(low - 1, 0), last)


def shortcuts(
    waypoints: np.ndarray, draws: np.ndarray, pieces: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Shortcuts of the path ``waypoints`` ``(m, n)``, one per row of ``draws`` ``(K, 6)`` (uniform in
    ``[0, 1)``). Column 0 picks the kind: below a third, two distinct waypoints (columns 3 and 4) joined
    straight; below two thirds, two points along the path (columns 1 and 2: shares of its joint travel)
    joined straight; else between those two points, one joint (column 5) evened out along the path while the
    others move as before. Returns ``first``, ``last`` (the pieces the two points lie on), ``paths`` ``(K,
    pieces + 2, n)`` (the first point, the path's waypoints in between padded with the last of them, and the
    last point), ``gain`` (joint travel saved; -inf when nothing is replaced, or when a partial one spans more
    than ``pieces`` pieces) and ``fewer`` (a straight one that drops waypoints: as long, it is still better).
    Compiled: :mod:`clew_ros.core.improve` scores batches of them."""
    w, draws = _arg(waypoints), _arg(draws)
    m, n = w.shape
    if m < 2 or draws.ndim != 2 or draws.shape[1] != 6:
        raise ValueError(f"waypoints, draws: expected (m >= 2, n) and (K, 6) arrays, got {w.shape}, {draws.shape}")
    count = len(draws)
    first, last = np.empty(count, dtype=np.int64), np.empty(count, dtype=np.int64)
    paths, gain, fewer = np.empty((count, int(pieces) + 2, n)), np.empty(count), np.empty(count, dtype=np.bool_)
    _shortcuts(w, draws, np.empty(m), first, last, paths, gain, fewer)
    return first, last, paths, gain, fewer


def pruned_path(waypoints: np.ndarray) -> np.ndarray:
    """``waypoints`` ``(m, n)`` without repeated waypoints, loops back to an earlier waypoint (within 1e-12
    rad), and waypoints between collinear pieces (a move undone or continued along the same line): the path
    left only visits configurations the old one visited. Compiled: the improvement prunes every shortcut it
    tries, and plans of many joints have hundreds of waypoints."""
    waypoints = _arg(waypoints)
    points = np.empty_like(waypoints)
    return points[: _pruned(waypoints, points)].copy()


def bounce_array(x: np.ndarray, low: np.ndarray, high: np.ndarray) -> np.ndarray:
    """Compiled :func:`_bounce` over arrays of one shape."""
    x, low, high = np.broadcast_arrays(*(np.asarray(a, dtype=np.float64) for a in (x, low, high)))
    out = np.empty(x.shape)
    _bounce_all(_arg(x).reshape(-1), _arg(low).reshape(-1), _arg(high).reshape(-1), out.reshape(-1))
    return out


_WARMED_IN_S: list[float] = []  # how long the first warm-up took, once it is done


#: :func:`lattice_search`'s edge states: not checked yet (taken as clear), checked clear, checked blocked.
EDGE_UNKNOWN, EDGE_CLEAR, EDGE_BLOCKED = 0, 1, 2


@_jit
def _lattice_node(
    u: int | np.int64, strides: np.ndarray, lower: np.ndarray, step: float, goal: np.ndarray, k: np.ndarray
) -> float:
    """Node ``u``'s indices into ``k``; returns its joint travel to ``goal``."""
    estimate = 0.0
    rest = u
    for j in range(len(strides)):
        k[j] = rest // strides[j]
        rest %= strides[j]
        estimate += abs(lower[j] + k[j] * step - goal[j])
    return estimate


@_jit
def lattice_path(previous: np.ndarray, last: int) -> np.ndarray:
    """The nodes that led to ``last`` (excluded), first to last."""
    count = 0
    v = previous[last]
    while v >= 0:
        count += 1
        v = previous[v]
    path = np.empty(count, dtype=np.int64)
    v = previous[last]
    for i in range(count - 1, -1, -1):
        path[i] = v
        v = previous[v]
    return path


@_jit
def _lattice_neighbour(
    u: int | np.int64,
    j: int,
    sign: int,
    k: np.ndarray,
    counts: np.ndarray,
    strides: np.ndarray,
    edges: np.ndarray,
) -> int:
    """Node ``u``'s neighbour one step along joint ``j`` (up if ``sign`` > 0; ``u``'s indices ``k``), or -1 when
    that is off the lattice or the edge is blocked."""
    if sign > 0:
        if k[j] + 1 >= counts[j] or edges[u, j] == EDGE_BLOCKED:
            return -1
        return int(u + strides[j])
    if k[j] == 0 or edges[u - strides[j], j] == EDGE_BLOCKED:
        return -1
    return int(u - strides[j])


@_jit
def _lattice_expand(
    u: int | np.int64,
    estimate: float,
    k: np.ndarray,
    counts: np.ndarray,
    strides: np.ndarray,
    lower: np.ndarray,
    step: float,
    goal: np.ndarray,
    edges: np.ndarray,
    cost: np.ndarray,
    previous: np.ndarray,
    heap: list[tuple[float, np.int64]],
) -> None:
    """Relax the edges of node ``u`` (indices ``k``, joint travel ``estimate`` to ``goal``) that are not blocked."""
    g = cost[u] + step
    for j in range(len(counts)):
        for sign in (1, -1):
            v = _lattice_neighbour(u, j, sign, k, counts, strides, edges)
            if v < 0:
                continue
            if g < cost[v]:
                cost[v] = g
                previous[v] = u
                here = lower[j] + k[j] * step
                f = g + estimate - abs(here - goal[j]) + abs(here + sign * step - goal[j])
                heapq.heappush(heap, (f, np.int64(v)))


@_jit
def lattice_search(
    counts: np.ndarray,
    lower: np.ndarray,
    step: float,
    edges: np.ndarray,
    sources: np.ndarray,
    source_costs: np.ndarray,
    targets: np.ndarray,
    target_costs: np.ndarray,
    goal: np.ndarray,
    bound: float,
) -> tuple[np.ndarray, float, int]:
    """Compiled A* over a joint-space lattice, in joint travel (L1).

    Node ``u`` has index ``k_j`` along joint ``j`` (``u = sum_j k_j stride_j``, the last joint fastest) and
    the configuration ``lower + k step``; an edge moves one joint by one step. ``edges[u, j]`` is the state
    of the edge from ``u`` to its neighbour one step up joint ``j``: :data:`EDGE_BLOCKED` is never taken, the
    others are. Paths start at one of ``sources`` (at ``source_costs``: the joint travel from the true
    start) and end at one of ``targets`` (``target_costs`` more to the true end ``goal``, at least the joint
    travel from the target to it), shorter than ``bound``. The heuristic, the joint travel left to ``goal``,
    is then admissible and consistent. Returns the
    shortest path's nodes (none when no path is shorter than ``bound``), its cost and the nodes expanded.
    """
    n = len(counts)
    strides = np.empty(n, dtype=np.int64)
    total = 1
    for j in range(n - 1, -1, -1):
        strides[j] = total
        total *= counts[j]
    cost = np.full(total + 1, np.inf)  # the last entry: the true end, reached from a target
    previous = np.full(total + 1, -1, dtype=np.int64)
    extra = np.full(total, np.inf)
    for i in range(len(targets)):
        extra[targets[i]] = min(extra[targets[i]], target_costs[i])
    k = np.empty(n, dtype=np.int64)
    heap = [(0.0, np.int64(0)) for _ in range(0)]
    for i in range(len(sources)):
        if source_costs[i] < cost[sources[i]]:
            cost[sources[i]] = source_costs[i]
            f = source_costs[i] + _lattice_node(sources[i], strides, lower, step, goal, k)
            heapq.heappush(heap, (f, np.int64(sources[i])))
    expanded = 0
    while heap:
        f, u = heapq.heappop(heap)
        if f >= bound:
            break
        if u == total:
            return lattice_path(previous, total), cost[total], expanded
        estimate = _lattice_node(u, strides, lower, step, goal, k)
        if f > cost[u] + estimate + 1e-9:
            continue  # a stale entry
        expanded += 1
        if cost[u] + extra[u] < cost[total]:
            cost[total] = cost[u] + extra[u]
            previous[total] = u
            heapq.heappush(heap, (cost[total], np.int64(total)))
        _lattice_expand(u, estimate, k, counts, strides, lower, step, goal, edges, cost, previous, heap)
    return np.empty(0, dtype=np.int64), np.inf, expanded


@_jit
def _strides(counts: np.ndarray) -> tuple[np.ndarray, int]:
    """A lattice's node-number strides (the last joint fastest) and its node count."""
    n = len(counts)
    strides = np.empty(n, dtype=np.int64)
    total = 1
    for j in range(n - 1, -1, -1):
        strides[j] = total
        total *= counts[j]
    return strides, total


@_jit
def _flood(
    heap: list[tuple[float, np.int64]],
    counts: np.ndarray,
    strides: np.ndarray,
    step: float,
    edges: np.ndarray,
    cost: np.ndarray,
    previous: np.ndarray,
    bound: float,
) -> int:
    """Dijkstra's loop of :func:`lattice_costs` and :func:`lattice_repair` from the entries of ``heap``, updating
    ``cost`` and ``previous`` in place; the nodes expanded."""
    n = len(counts)
    k = np.empty(n, dtype=np.int64)
    expanded = 0
    while heap:
        f, u = heapq.heappop(heap)
        if f > cost[u]:
            continue  # a stale entry
        expanded += 1
        rest = u
        for j in range(n):
            k[j] = rest // strides[j]
            rest %= strides[j]
        g = f + step
        if g >= bound:
            continue
        for j in range(n):
            for sign in (1, -1):
                v = _lattice_neighbour(u, j, sign, k, counts, strides, edges)
                if v < 0:
                    continue
                if g < cost[v]:
                    cost[v] = g
                    previous[v] = u
                    heapq.heappush(heap, (g, np.int64(v)))
    return expanded


@_jit
def lattice_costs(
    counts: np.ndarray, step: float, edges: np.ndarray, sources: np.ndarray, source_costs: np.ndarray, bound: float
) -> tuple[np.ndarray, np.ndarray, int]:
    """Compiled Dijkstra over a joint-space lattice (the nodes and edges of :func:`lattice_search`), in joint
    travel: from ``sources`` (at ``source_costs``), the least cost of every node reached below ``bound``
    (``inf`` for a node not reached; a source keeps its own cost even when that is not below ``bound``) and
    the node it is reached from (-1 for a node not reached or reached at its own source cost), and the
    nodes expanded."""
    strides, total = _strides(counts)
    cost = np.full(total, np.inf)
    previous = np.full(total, -1, dtype=np.int64)
    heap = [(0.0, np.int64(0)) for _ in range(0)]
    for i in range(len(sources)):
        if source_costs[i] < cost[sources[i]]:
            cost[sources[i]] = source_costs[i]
            heapq.heappush(heap, (source_costs[i], np.int64(sources[i])))
    return cost, previous, _flood(heap, counts, strides, step, edges, cost, previous, bound)


@_jit
def _losing(strides: np.ndarray, edges: np.ndarray, previous: np.ndarray) -> np.ndarray:
    """Which nodes' way back to a source (by ``previous``) takes a blocked edge: one pass, each chain followed
    until a node already known."""
    total = len(previous)
    state = np.zeros(total, dtype=np.int8)  # 0 not known yet, 1 keeps its cost, 2 loses it
    chain = np.empty(total, dtype=np.int64)
    for v in range(total):
        length = 0
        u = np.int64(v)
        while state[u] == 0:
            p = previous[u]
            if p < 0:  # a source at its own cost, or a node not reached: either stands
                state[u] = 1
                break
            j = 0
            while j < len(strides) - 1 and strides[j] != abs(u - p):  # the joint of the edge (p is a neighbour)
                j += 1
            if edges[min(u, p), j] == EDGE_BLOCKED:
                state[u] = 2
                break
            chain[length] = u
            length += 1
            u = p
        for i in range(length):
            state[chain[i]] = state[u]
    lose: np.ndarray = state == 2
    return lose


@_jit
def lattice_repair(
    counts: np.ndarray,
    step: float,
    edges: np.ndarray,
    sources: np.ndarray,
    source_costs: np.ndarray,
    bound: float,
    cost: np.ndarray,
    previous: np.ndarray,
) -> int:
    """:func:`lattice_costs`' ``cost`` and ``previous`` brought up to date in place after edges were blocked (and
    none unblocked), as a search from scratch would give them (ties apart): the nodes whose way back to a source
    takes a blocked edge lose their cost, and Dijkstra's loop runs again from their neighbours that kept theirs
    (blocking only makes costs higher, so those are still least). Returns the nodes expanded again."""
    n = len(counts)
    strides, _ = _strides(counts)
    lose = _losing(strides, edges, previous)
    lost = np.flatnonzero(lose)
    cost[lost] = np.inf
    previous[lost] = -1
    for i in range(len(sources)):
        if lose[sources[i]]:
            cost[sources[i]] = min(cost[sources[i]], source_costs[i])
    heap = [(0.0, np.int64(0)) for _ in range(0)]
    k = np.empty(n, dtype=np.int64)
    for v in lost:
        rest = v
        for j in range(n):
            k[j] = rest // strides[j]
            rest %= strides[j]
        for j in range(n):
            for sign in (1, -1):
                u = _lattice_neighbour(v, j, sign, k, counts, strides, edges)  # the edge is the same both ways
                if u >= 0 and not lose[u] and cost[u] + step < min(bound, cost[v]):
                    cost[v] = cost[u] + step
                    previous[v] = u
        if cost[v] < np.inf:
            heapq.heappush(heap, (cost[v], np.int64(v)))
    return _flood(heap, counts, strides, step, edges, cost, previous, bound)


@_jit
def release_totals(
    first_cost: np.ndarray,
    last_cost: np.ndarray,
    releases: np.ndarray,
    put_travel: np.ndarray,
    corners: np.ndarray,
    join_travel: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """The regrasp search's totals (:func:`clew_ros.core.lattice.lattice_regrasp`): for each elbow ``e`` and
    release ``r``, the joint travel ``first_cost[releases[r]] + put_travel[e, r]`` plus the least over the
    corners ``c`` of ``last_cost[corners[e, r, c]] + join_travel[e, r, c]``, and the corner that gives it (the
    first of equals)."""
    sides, count, nearby = corners.shape
    totals = np.empty((sides, count))
    joined = np.empty((sides, count), dtype=np.int64)
    for e in range(sides):
        for r in range(count):
            best = np.inf
            pick = corners[e, r, 0]
            for c in range(nearby):
                via = last_cost[corners[e, r, c]] + join_travel[e, r, c]
                if via < best:
                    best = via
                    pick = corners[e, r, c]
            joined[e, r] = pick
            totals[e, r] = first_cost[releases[r]] + put_travel[e, r] + best
    return totals, joined


def warm_up() -> float:
    """Compile every kernel (or load them from numba's on-disk cache) before the first plan.

    Returns the seconds the first call took (later calls do nothing). numba
    caches next to this module when the package directory is writable, else
    in a per-user cache directory (``NUMBA_CACHE_DIR`` overrides both).
    """
    if _WARMED_IN_S:
        return _WARMED_IN_S[0]
    import time

    start = time.perf_counter()
    world = PackedWorld(
        np.zeros(2),
        np.ones(2),
        -np.pi * np.ones(2),
        np.pi * np.ones(2),
        0.01,
        True,
        np.array([-3.0, -3.0, 3.0, 3.0]),
        np.array([[[1.0, 1.0], [1.2, 1.0]]]),
        np.array([[[0.1, 0.0], [0.0, 0.1]]]),
        np.zeros((0, 2, 2)),
        np.array([0, 1]),
        np.array([[1.0, 1.0, 1.2, 1.0]]),
        np.array([0]),
        1e-9,
    )
    waypoints = np.zeros((1, 3, 2))
    genes = np.zeros((1, 1, 2))
    for transfer in (False, True):
        decode(world, waypoints, genes, 1, 3, transfer, np.zeros(3), 1e-3)
        decode(world, waypoints, genes, 1, 3, transfer, np.zeros(3), 1e-3, threads=0)
        intervals(world, waypoints[:, 0], 0, transfer, np.zeros(3), 1e-3)
    bounce_array(np.zeros(1), np.zeros(1), np.ones(1))
    pruned_path(np.zeros((3, 2)))
    shortcuts(np.eye(3, 2), np.linspace(0.0, 0.9, 18).reshape(3, 6), 8)
    clearly_valid(world, waypoints[:, 0], np.zeros(3))
    moving = {"min_margin": 1e-3, "max_margin": 0.05, "coarse_stride": 4}
    for held in (None, np.zeros(3)):
        at_rest = np.zeros(3) if held is None else None
        moves_clear(world, waypoints[:, 0], waypoints[:, 1] + 0.1, resting=at_rest, grasp_rel=held, **moving)  # type: ignore[arg-type]
        poses = np.zeros((1, 3))
        screen_routes(
            world,
            waypoints[:, 0],
            waypoints[:, 1] + 0.1,
            np.full(1, 8),
            resting=poses if held is None else None,
            grasp_rel=None if held is None else poses,
        )
        nodes, parents = np.zeros((2, 8, 2)), np.full((2, 8), -1, dtype=np.int64)
        connect_rounds(
            world,
            nodes,
            parents,
            np.ones(2, dtype=np.int64),
            np.zeros(4, dtype=np.int64),
            np.zeros((1, 2)),
            step_rad=0.35,
            allowed=1.0,
            check_work=1.0,
            round_work=1.0,
            resting=at_rest,
            grasp_rel=held,
            **moving,  # type: ignore[arg-type]
        )
    for angles in (np.zeros(1), np.full(1, np.nan)):
        solve_point(
            world.base,
            world.lengths,
            world.lower,
            world.upper,
            waypoints[:, 0],
            np.ones((1, 2)),
            np.zeros((1, 2)),
            angles,
            angle_tolerance=0.1,
            angle_scale=1.0,
            iterations=2,
            damping=1e-6,
            max_step=0.4,
        )
    chain(world.base, world.lengths, waypoints[:, 0])
    lattice_search(
        np.full(2, 3, dtype=np.int64),
        np.zeros(2),
        1.0,
        np.zeros((9, 2), dtype=np.uint8),
        np.zeros(1, dtype=np.int64),
        np.zeros(1),
        np.full(1, 8, dtype=np.int64),
        np.zeros(1),
        np.full(2, 2.0),
        np.inf,
    )
    counts, edges, sources, source_costs = (
        np.full(2, 3, dtype=np.int64),
        np.zeros((9, 2), dtype=np.uint8),
        np.zeros(1, dtype=np.int64),
        np.zeros(1),
    )
    cost, previous, _ = lattice_costs(counts, 1.0, edges, sources, source_costs, np.inf)
    lattice_repair(counts, 1.0, edges, sources, source_costs, np.inf, cost, previous)
    corners = np.zeros((2, 1, 4), dtype=np.int64)
    release_totals(cost, cost, sources, np.zeros((2, 1)), corners, np.zeros((2, 1, 4)))
    _WARMED_IN_S.append(time.perf_counter() - start)
    return _WARMED_IN_S[0]
