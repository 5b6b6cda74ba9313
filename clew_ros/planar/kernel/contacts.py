"""Contact angles, one pair of pieces at a time: where an end point turning about the pivot first meets the
*stadium* of a segment (circle-line and circle-circle intersections), the nearest contact each way, and the
pseudo-angle screen that skips a contact before its ``atan2`` (:func:`_cannot_improve`)."""

from __future__ import annotations

import math

import numpy as np

from clew_ros.planar.kernel.jit import _leaf
from clew_ros.planar.kernel.packed import Stadium
from clew_ros.planar.kernel.segments import _point_segment_distance

_TWO_PI = 2.0 * math.pi
#: A contact closer than this to the current angle (rad) is where the start touches, not a crossing.
_AT_START = 1e-12
#: :func:`_cannot_improve` skips a contact only if it is this much (rad) past both nearest contacts:
#: far more than the rounding of the two ways of computing its angle, so the interval is unchanged.
_PRUNE_MARGIN = 1e-9


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
    px: float, py: float, rho: float, stadium: Stadium, keep: float, margin: float, turn: float, best: np.ndarray
) -> None:
    """Rotation angles (times ``turn``) at which point ``p`` (at distance ``rho`` from the pivot),
    turning about the pivot, meets the boundary of the stadium of radius ``keep`` (+ ``margin`` if it
    starts clear of it) around the segment of ``stadium``; all relative to the pivot."""
    ax, ay, bx, by, ra, rb, near, far = stadium
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
    still = Stadium(cx, cy, dx, dy, rc, rd, t[s, 0], t[s, 1])
    _point_meets_stadium(ax, ay, ra, still, keep, margin, 1.0, best)
    _point_meets_stadium(bx, by, rb, still, keep, margin, 1.0, best)
    turning = Stadium(ax, ay, bx, by, ra, rb, m[i, 0], m[i, 1])
    _point_meets_stadium(cx, cy, rc, turning, keep, margin, -1.0, best)
    _point_meets_stadium(dx, dy, rd, turning, keep, margin, -1.0, best)


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
