"""Forward kinematics, validity and free intervals of a spatial arm's sphere model, batched (numba).

Conventions: frame 0 is ``base_link`` in ``world`` (``base_r``, ``base_t``); frame ``j + 1`` is frame
``j`` moved by joint ``j``'s constant origin (``org_r``, ``org_t``) and its motion about / along
``axes[j]``. A sphere ``k`` rides on frame ``sph_frame[k]`` at ``sph_c[k]`` with radius ``sph_r[k]``;
link ``i`` owns spheres ``link_start[i]:link_start[i + 1]`` and has the bounding sphere ``link_c[i]``,
``link_r[i]`` in its frame ``link_frame[i]``. Obstacle ``o`` is of kind ``obs_kind[o]`` (0 box, 1
cylinder, 2 sphere) at ``obs_t[o]`` with rotation ``obs_r[o]`` (local to world), ``obs_dims[o]`` (box:
half extents; cylinder: radius, half height; sphere: radius) and bounding radius ``obs_bound[o]``; link
``i`` never tests obstacle ``o`` where ``ignore[i, o]`` (a gripper link and the resting object).
``pairs`` (P, 2) are the link pairs checked for self-collision; ``bounds`` ``[xmin, ymin, zmin, xmax,
ymax, zmax]`` is used when ``has_bounds``. Touching counts as colliding (a clearance <= 0).

A held object is one more "link" (index ``held_link``, -1: none) riding on the tcp's frame. Against the
supports ``sup_index`` (tops ``sup_top``; ``ignore`` leaves them out of the sphere tests) it is valid when
its lowest point — of ``held_points`` (a box's corners, a cylinder's cap centres, in its frame) less
``held_disc`` (a cylinder's radius) times its cap's tilt (``held_axis``) — lies above the top less
``sup_tol``, or when its spheres are clear of the support.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import numba
import numpy as np
from numpy.typing import NDArray

if TYPE_CHECKING:
    from numba.core.decorators import _JITWrapper  # in numba's type stubs only

__all__ = ["clearance_of_sphere", "forward", "free_intervals", "static_collides", "valid_batch"]

Array = NDArray[Any]  # the kernels take float, int and bool arrays

_jit = numba.njit(cache=True, nogil=True, error_model="numpy")
# Functions that allocate nothing are compiled without reference counting (numba's ``_nrt`` option), as in
# clew_ros.planar.kernel: every array they get is borrowed from the caller, and the reference counting numba
# would otherwise emit around each call of a helper with many array arguments cost more than the geometry.
_leaf: _JITWrapper = numba.njit(  # type: ignore[call-overload]  # numba's stubs leave out its underscored options
    cache=True, nogil=True, error_model="numpy", _nrt=False
)

BOX, CYLINDER, SPHERE = 0, 1, 2


@_leaf
def forward(  # noqa: PLR0917
    q: Array,
    base_r: Array,
    base_t: Array,
    org_r: Array,
    org_t: Array,
    axes: Array,
    prismatic: Array,
    out_r: Array,
    out_t: Array,
) -> None:
    """Frames 0..n of configuration ``q`` into ``out_r`` (n+1, 3, 3) and ``out_t`` (n+1, 3)."""
    for a in range(3):
        out_t[0, a] = base_t[a]
        for c in range(3):
            out_r[0, a, c] = base_r[a, c]
    for j in range(q.shape[0]):
        pr = out_r[j]
        o = org_r[j]
        nr = out_r[j + 1]
        # placed = parent @ origin, written into frame j+1 first
        for a in range(3):
            out_t[j + 1, a] = out_t[j, a] + pr[a, 0] * org_t[j, 0] + pr[a, 1] * org_t[j, 1] + pr[a, 2] * org_t[j, 2]
            for c in range(3):
                nr[a, c] = pr[a, 0] * o[0, c] + pr[a, 1] * o[1, c] + pr[a, 2] * o[2, c]
        x, y, z = axes[j, 0], axes[j, 1], axes[j, 2]
        if prismatic[j]:
            for a in range(3):
                out_t[j + 1, a] += q[j] * (nr[a, 0] * x + nr[a, 1] * y + nr[a, 2] * z)
            continue
        cos = math.cos(q[j])
        sin = math.sin(q[j])
        v = 1.0 - cos
        m00, m01, m02 = cos + x * x * v, x * y * v - z * sin, x * z * v + y * sin
        m10, m11, m12 = y * x * v + z * sin, cos + y * y * v, y * z * v - x * sin
        m20, m21, m22 = z * x * v - y * sin, z * y * v + x * sin, cos + z * z * v
        for a in range(3):  # then times the joint's rotation
            p0, p1, p2 = nr[a, 0], nr[a, 1], nr[a, 2]
            nr[a, 0] = p0 * m00 + p1 * m10 + p2 * m20
            nr[a, 1] = p0 * m01 + p1 * m11 + p2 * m21
            nr[a, 2] = p0 * m02 + p1 * m12 + p2 * m22


@_leaf
def _place(frame_r: Array, frame_t: Array, frame: int, local: Array, out: Array) -> None:
    r = frame_r[frame]
    t = frame_t[frame]
    for a in range(3):
        out[a] = r[a, 0] * local[0] + r[a, 1] * local[1] + r[a, 2] * local[2] + t[a]


@_leaf
def clearance_of_sphere(p: Array, radius: float, kind: int, rot: Array, pos: Array, dims: Array) -> float:  # noqa: PLR0917
    """Signed distance (m) between a sphere (centre ``p``, ``radius``) and one obstacle; <= 0: they touch."""
    dx = p[0] - pos[0]
    dy = p[1] - pos[1]
    dz = p[2] - pos[2]
    if kind == SPHERE:
        return math.sqrt(dx * dx + dy * dy + dz * dz) - float(dims[0]) - radius
    # into the obstacle's frame: rot is local -> world, so local = rot^T d
    lx = rot[0, 0] * dx + rot[1, 0] * dy + rot[2, 0] * dz
    ly = rot[0, 1] * dx + rot[1, 1] * dy + rot[2, 1] * dz
    lz = rot[0, 2] * dx + rot[1, 2] * dy + rot[2, 2] * dz
    if kind == BOX:
        qx = abs(lx) - dims[0]
        qy = abs(ly) - dims[1]
        qz = abs(lz) - dims[2]
        ox = max(qx, 0.0)
        oy = max(qy, 0.0)
        oz = max(qz, 0.0)
        return math.sqrt(ox * ox + oy * oy + oz * oz) + float(min(max(qx, qy, qz), 0.0)) - radius
    radial = math.sqrt(lx * lx + ly * ly) - dims[0]
    axial = abs(lz) - dims[1]
    o_r = max(radial, 0.0)
    o_a = max(axial, 0.0)
    return math.sqrt(o_r * o_r + o_a * o_a) + float(min(max(radial, axial), 0.0)) - radius


@_leaf
def _bounds_clearance(p: Array, radius: float, bounds: Array) -> float:
    out = p[0] - bounds[0]
    out = min(out, p[1] - bounds[1])
    out = min(out, p[2] - bounds[2])
    out = min(out, bounds[3] - p[0])
    out = min(out, bounds[4] - p[1])
    out = min(out, bounds[5] - p[2])
    return float(out) - radius


@_leaf
def _distance(a: Array, b: Array) -> float:
    dx = a[0] - b[0]
    dy = a[1] - b[1]
    dz = a[2] - b[2]
    return math.sqrt(dx * dx + dy * dy + dz * dz)


@_leaf
def _place_link(  # noqa: PLR0917
    i: int,
    frame_r: Array,
    frame_t: Array,
    sph_c: Array,
    link_start: Array,
    link_frame: Array,
    sph_w: Array,
    placed: Array,
) -> None:
    """Place link ``i``'s spheres in ``world`` unless already done for this configuration."""
    if placed[i]:
        return
    placed[i] = True
    frame = link_frame[i]
    for k in range(link_start[i], link_start[i + 1]):
        _place(frame_r, frame_t, frame, sph_c[k], sph_w[k])


@_leaf
def _link_collides(  # noqa: PLR0917
    i: int,
    frame_r: Array,
    frame_t: Array,
    sph_c: Array,
    sph_w: Array,
    sph_r: Array,
    link_start: Array,
    link_frame: Array,
    link_w: Array,
    link_r: Array,
    obs_kind: Array,
    obs_r: Array,
    obs_t: Array,
    obs_dims: Array,
    obs_bound: Array,
    ignore: Array,
    bounds: Array,
    has_bounds: bool,
    placed: Array,
) -> bool:
    """Whether link ``i`` touches an obstacle (but those ``ignore[i]`` marks) or leaves the bounds (its
    bounding sphere first)."""
    if has_bounds and _bounds_clearance(link_w[i], link_r[i], bounds) <= 0.0:
        _place_link(i, frame_r, frame_t, sph_c, link_start, link_frame, sph_w, placed)
        for k in range(link_start[i], link_start[i + 1]):
            if _bounds_clearance(sph_w[k], sph_r[k], bounds) <= 0.0:
                return True
    for o in range(obs_kind.shape[0]):
        reach = obs_bound[o]
        if ignore[i, o] or _distance(link_w[i], obs_t[o]) > link_r[i] + reach:
            continue
        if clearance_of_sphere(link_w[i], link_r[i], obs_kind[o], obs_r[o], obs_t[o], obs_dims[o]) > 0.0:
            continue  # the link's bounding sphere misses the obstacle itself (a wide table, a long shelf)
        _place_link(i, frame_r, frame_t, sph_c, link_start, link_frame, sph_w, placed)
        for k in range(link_start[i], link_start[i + 1]):
            if clearance_of_sphere(sph_w[k], sph_r[k], obs_kind[o], obs_r[o], obs_t[o], obs_dims[o]) <= 0.0:
                return True
    return False


@_leaf
def _pair_collides(  # noqa: PLR0917
    a: int,
    b: int,
    frame_r: Array,
    frame_t: Array,
    sph_c: Array,
    sph_w: Array,
    sph_r: Array,
    link_start: Array,
    link_frame: Array,
    link_w: Array,
    link_r: Array,
    placed: Array,
) -> bool:
    """Whether links ``a`` and ``b`` touch (their bounding spheres first)."""
    if _distance(link_w[a], link_w[b]) > link_r[a] + link_r[b]:
        return False
    _place_link(a, frame_r, frame_t, sph_c, link_start, link_frame, sph_w, placed)
    _place_link(b, frame_r, frame_t, sph_c, link_start, link_frame, sph_w, placed)
    for k in range(link_start[a], link_start[a + 1]):
        if _distance(sph_w[k], link_w[b]) > sph_r[k] + link_r[b]:
            continue
        for m in range(link_start[b], link_start[b + 1]):
            if _distance(sph_w[k], sph_w[m]) <= sph_r[k] + sph_r[m]:
                return True
    return False


@_leaf
def _collides(  # noqa: PLR0917
    frame_r: Array,
    frame_t: Array,
    sph_c: Array,
    sph_w: Array,
    sph_r: Array,
    link_start: Array,
    link_c: Array,
    link_frame: Array,
    link_w: Array,
    link_r: Array,
    obs_kind: Array,
    obs_r: Array,
    obs_t: Array,
    obs_dims: Array,
    obs_bound: Array,
    ignore: Array,
    pairs: Array,
    bounds: Array,
    has_bounds: bool,
    placed: Array,
) -> bool:
    """Whether the configuration whose frames are given touches an obstacle, leaves the bounds, or touches
    itself (``pairs``); each link's spheres are placed only when its bounding sphere cannot settle it.
    Links on frame 0 never move: :func:`static_collides` checks them once, not here."""
    placed[:] = False
    for i in range(link_r.shape[0]):
        _place(frame_r, frame_t, link_frame[i], link_c[i], link_w[i])
    for i in range(link_r.shape[0]):
        if link_frame[i] != 0 and _link_collides(
            i,
            frame_r,
            frame_t,
            sph_c,
            sph_w,
            sph_r,
            link_start,
            link_frame,
            link_w,
            link_r,
            obs_kind,
            obs_r,
            obs_t,
            obs_dims,
            obs_bound,
            ignore,
            bounds,
            has_bounds,
            placed,
        ):
            return True
    for p in range(pairs.shape[0]):
        if _pair_collides(
            pairs[p, 0],
            pairs[p, 1],
            frame_r,
            frame_t,
            sph_c,
            sph_w,
            sph_r,
            link_start,
            link_frame,
            link_w,
            link_r,
            placed,
        ):
            return True
    return False


@_leaf
def _within(q: Array, lower: Array, upper: Array) -> bool:
    """Whether every joint value lies within its limits."""
    for j in range(q.shape[0]):  # noqa: SIM110  # a loop: numba compiles no generator inside all()
        if not lower[j] <= q[j] <= upper[j]:
            return False
    return True


@_leaf
def _held_lowest(  # noqa: PLR0917
    frame_r: Array, frame_t: Array, frame: int, held_points: Array, held_disc: float, held_axis: Array, out: Array
) -> float:
    """The held object's lowest height (m): a box's lowest corner, or a cylinder's lowest cap rim (the cap
    centre less the radius times the cap's tilt). ``out`` receives the points (corners, cap centres) in
    ``world``."""
    r = frame_r[frame]
    t = frame_t[frame]
    tilt = 0.0
    if held_disc > 0.0:
        nz = r[2, 0] * held_axis[0] + r[2, 1] * held_axis[1] + r[2, 2] * held_axis[2]
        tilt = held_disc * math.sqrt(max(1.0 - nz * nz, 0.0))
    lowest = np.inf
    for k in range(held_points.shape[0]):
        for a in range(3):
            out[k, a] = r[a, 0] * held_points[k, 0] + r[a, 1] * held_points[k, 1] + r[a, 2] * held_points[k, 2] + t[a]
        lowest = min(lowest, out[k, 2] - tilt)
    return lowest


@_leaf
def _held_clear_of(  # noqa: PLR0917
    o: int,
    held_link: int,
    link_start: Array,
    sph_w: Array,
    sph_r: Array,
    obs_kind: Array,
    obs_r: Array,
    obs_t: Array,
    obs_dims: Array,
) -> float:
    """The least clearance (m) of the held object's spheres to obstacle ``o``."""
    best = np.inf
    for k in range(link_start[held_link], link_start[held_link + 1]):
        best = min(best, clearance_of_sphere(sph_w[k], sph_r[k], obs_kind[o], obs_r[o], obs_t[o], obs_dims[o]))
    return best


@_leaf
def _held_on_supports(  # noqa: PLR0917
    frame_r: Array,
    frame_t: Array,
    link_frame: Array,
    link_start: Array,
    sph_c: Array,
    sph_w: Array,
    sph_r: Array,
    obs_kind: Array,
    obs_r: Array,
    obs_t: Array,
    obs_dims: Array,
    held_link: int,
    held_points: Array,
    held_disc: float,
    held_axis: Array,
    sup_index: Array,
    sup_top: Array,
    sup_tol: float,
    scratch: Array,
) -> bool:
    """Whether the held object keeps off every support but from above: either all of it lies above the
    support's top (within ``sup_tol``: it may touch), or its spheres are clear of the support."""
    if held_link < 0 or sup_index.shape[0] == 0:
        return True
    lowest = _held_lowest(frame_r, frame_t, link_frame[held_link], held_points, held_disc, held_axis, scratch)
    frame = link_frame[held_link]
    for k in range(link_start[held_link], link_start[held_link + 1]):
        _place(frame_r, frame_t, frame, sph_c[k], sph_w[k])
    for m in range(sup_index.shape[0]):
        if lowest >= sup_top[m] - sup_tol:
            continue
        o = sup_index[m]
        if _held_clear_of(o, held_link, link_start, sph_w, sph_r, obs_kind, obs_r, obs_t, obs_dims) <= 0.0:
            return False
    return True


@_leaf
def _held_support_step(  # noqa: PLR0917
    frame_r: Array,
    frame_t: Array,
    link_frame: Array,
    link_start: Array,
    sph_w: Array,
    sph_r: Array,
    obs_kind: Array,
    obs_r: Array,
    obs_t: Array,
    obs_dims: Array,
    held_link: int,
    held_points: Array,
    held_disc: float,
    held_axis: Array,
    sup_index: Array,
    sup_top: Array,
    sup_tol: float,
    axis_p: Array,
    axis_d: Array,
    is_prismatic: bool,
    margin: float,
    best: float,
    scratch: Array,
) -> float:
    """``best`` lowered to the move the held object is certain to make keeping off every support but from
    above: for each support, the longer of the move its lowest point stays above the top (its height over
    the top less ``sup_tol``, over how fast it can sink) and the move its spheres stay clear (clearance
    over speed); either condition keeps it valid."""
    if held_link < 0 or sup_index.shape[0] == 0:
        return best
    lowest = _held_lowest(frame_r, frame_t, link_frame[held_link], held_points, held_disc, held_axis, scratch)
    sink = 0.0  # how fast the lowest point can sink: a point's speed, and the cap's tilt at most 1 per radian
    for k in range(held_points.shape[0]):
        sink = max(sink, _speed(scratch[k], axis_p, axis_d, is_prismatic) + (0.0 if is_prismatic else held_disc))
    for m in range(sup_index.shape[0]):
        above = lowest - (sup_top[m] - sup_tol) - margin
        plane = 0.0
        if above > 0.0:
            plane = above / sink if sink > 0.0 else np.inf
        o = sup_index[m]
        spheres = np.inf
        for k in range(link_start[held_link], link_start[held_link + 1]):
            speed = _speed(sph_w[k], axis_p, axis_d, is_prismatic)
            c = clearance_of_sphere(sph_w[k], sph_r[k], obs_kind[o], obs_r[o], obs_t[o], obs_dims[o]) - margin
            if c <= 0.0:
                spheres = 0.0
                break
            if speed > 0.0:
                spheres = min(spheres, c / speed)
        best = min(best, max(plane, spheres))
    return best


@_jit
def valid_batch(  # noqa: PLR0917
    qs: Array,
    lower: Array,
    upper: Array,
    base_r: Array,
    base_t: Array,
    org_r: Array,
    org_t: Array,
    axes: Array,
    prismatic: Array,
    sph_c: Array,
    sph_r: Array,
    sph_frame: Array,
    link_start: Array,
    link_c: Array,
    link_r: Array,
    link_frame: Array,
    obs_kind: Array,
    obs_r: Array,
    obs_t: Array,
    obs_dims: Array,
    obs_bound: Array,
    ignore: Array,
    pairs: Array,
    bounds: Array,
    has_bounds: bool,
    held_link: int,
    held_points: Array,
    held_disc: float,
    held_axis: Array,
    sup_index: Array,
    sup_top: Array,
    sup_tol: float,
    out: Array,
) -> None:
    """``out[b]``: configuration ``qs[b]`` is inside its limits and its spheres touch nothing."""
    n = qs.shape[1]
    frame_r = np.empty((n + 1, 3, 3))
    frame_t = np.empty((n + 1, 3))
    sph_w = np.empty((sph_c.shape[0], 3))
    link_w = np.empty((link_c.shape[0], 3))
    scratch = np.empty((8, 3))  # the held object's corners or cap centres in world
    placed = np.zeros(link_c.shape[0], dtype=np.bool_)
    for b in range(qs.shape[0]):
        q = qs[b]
        if not _within(q, lower, upper):
            out[b] = False
            continue
        forward(q, base_r, base_t, org_r, org_t, axes, prismatic, frame_r, frame_t)
        out[b] = not _collides(
            frame_r,
            frame_t,
            sph_c,
            sph_w,
            sph_r,
            link_start,
            link_c,
            link_frame,
            link_w,
            link_r,
            obs_kind,
            obs_r,
            obs_t,
            obs_dims,
            obs_bound,
            ignore,
            pairs,
            bounds,
            has_bounds,
            placed,
        )
        if out[b]:
            out[b] = _held_on_supports(
                frame_r, frame_t, link_frame, link_start, sph_c, sph_w, sph_r, obs_kind, obs_r, obs_t, obs_dims,
                held_link, held_points, held_disc, held_axis, sup_index, sup_top, sup_tol, scratch,
            )  # fmt: skip


@_jit
def static_collides(  # noqa: PLR0917
    base_r: Array,
    base_t: Array,
    sph_c: Array,
    sph_r: Array,
    sph_frame: Array,
    sph_link: Array,
    obs_kind: Array,
    obs_r: Array,
    obs_t: Array,
    obs_dims: Array,
    ignore: Array,
    bounds: Array,
    has_bounds: bool,
) -> bool:
    """Whether a sphere on frame 0 (which no joint moves) touches an obstacle (but those its link's
    ``ignore`` row marks) or leaves the bounds."""
    p = np.empty(3)
    for k in range(sph_c.shape[0]):
        if sph_frame[k] != 0:
            continue
        for a in range(3):
            p[a] = base_r[a, 0] * sph_c[k, 0] + base_r[a, 1] * sph_c[k, 1] + base_r[a, 2] * sph_c[k, 2] + base_t[a]
        if has_bounds and _bounds_clearance(p, sph_r[k], bounds) <= 0.0:
            return True
        for o in range(obs_kind.shape[0]):
            if ignore[sph_link[k], o]:
                continue
            if clearance_of_sphere(p, sph_r[k], obs_kind[o], obs_r[o], obs_t[o], obs_dims[o]) <= 0.0:
                return True
    return False


@_leaf
def _speed(p: Array, axis_p: Array, axis_d: Array, is_prismatic: bool) -> float:
    """Largest displacement (m) of point ``p`` per unit of the joint's motion."""
    if is_prismatic:
        return 1.0
    dx = p[0] - axis_p[0]
    dy = p[1] - axis_p[1]
    dz = p[2] - axis_p[2]
    along = dx * axis_d[0] + dy * axis_d[1] + dz * axis_d[2]
    return math.sqrt(max(dx * dx + dy * dy + dz * dz - along * along, 0.0))


@_leaf
def _link_step(  # noqa: PLR0917
    i: int,
    best: float,
    axis_p: Array,
    axis_d: Array,
    is_prismatic: bool,
    sph_w: Array,
    sph_r: Array,
    link_start: Array,
    link_w: Array,
    link_r: Array,
    obs_kind: Array,
    obs_r: Array,
    obs_t: Array,
    obs_dims: Array,
    obs_bound: Array,
    bounds: Array,
    has_bounds: bool,
    margin: float,
    rel_obs: Array,
    rel_bounds: Array,
    frame_r: Array,
    frame_t: Array,
    sph_c: Array,
    link_frame: Array,
    placed: Array,
) -> float:
    """``best`` lowered to what moving link ``i``'s clearances to the obstacles and bounds allow (those
    ``rel_obs[i]`` / ``rel_bounds[i]`` leave in: :func:`_relevance`); its spheres are placed only when its
    bounding sphere cannot settle it (:func:`_place_link`)."""
    link_speed = _speed(link_w[i], axis_p, axis_d, is_prismatic) + (0.0 if is_prismatic else link_r[i])
    if link_speed <= 0.0:
        return best
    if has_bounds and rel_bounds[i]:
        coarse = _bounds_clearance(link_w[i], link_r[i], bounds)
        if coarse <= margin or (coarse - margin) / link_speed < best:
            _place_link(i, frame_r, frame_t, sph_c, link_start, link_frame, sph_w, placed)
            for k in range(link_start[i], link_start[i + 1]):
                speed = _speed(sph_w[k], axis_p, axis_d, is_prismatic)
                if speed > 0.0:
                    best = min(best, (_bounds_clearance(sph_w[k], sph_r[k], bounds) - margin) / speed)
    for o in range(obs_kind.shape[0]):
        if not rel_obs[i, o]:
            continue
        coarse = _distance(link_w[i], obs_t[o]) - link_r[i] - obs_bound[o]
        if coarse > margin and (coarse - margin) / link_speed >= best:
            continue
        # the link's bounding sphere against the obstacle itself: no sphere of the link is nearer
        coarse = clearance_of_sphere(link_w[i], link_r[i], obs_kind[o], obs_r[o], obs_t[o], obs_dims[o])
        if coarse > margin and (coarse - margin) / link_speed >= best:
            continue
        _place_link(i, frame_r, frame_t, sph_c, link_start, link_frame, sph_w, placed)
        for k in range(link_start[i], link_start[i + 1]):
            speed = _speed(sph_w[k], axis_p, axis_d, is_prismatic)
            if speed > 0.0:
                c = clearance_of_sphere(sph_w[k], sph_r[k], obs_kind[o], obs_r[o], obs_t[o], obs_dims[o])
                best = min(best, (c - margin) / speed)
    return best


@_leaf
def _pair_step(  # noqa: PLR0917
    a: int,
    b: int,
    best: float,
    axis_p: Array,
    axis_d: Array,
    is_prismatic: bool,
    sph_w: Array,
    sph_r: Array,
    link_start: Array,
    link_w: Array,
    link_r: Array,
    margin: float,
    frame_r: Array,
    frame_t: Array,
    sph_c: Array,
    link_frame: Array,
    placed: Array,
) -> float:
    """``best`` lowered to what moving link ``a``'s clearance to static link ``b`` allows."""
    link_speed = _speed(link_w[a], axis_p, axis_d, is_prismatic) + (0.0 if is_prismatic else link_r[a])
    coarse = _distance(link_w[a], link_w[b]) - link_r[a] - link_r[b]
    if link_speed <= 0.0 or (coarse > margin and (coarse - margin) / link_speed >= best):
        return best
    _place_link(a, frame_r, frame_t, sph_c, link_start, link_frame, sph_w, placed)
    _place_link(b, frame_r, frame_t, sph_c, link_start, link_frame, sph_w, placed)
    for k in range(link_start[a], link_start[a + 1]):
        speed = _speed(sph_w[k], axis_p, axis_d, is_prismatic)
        if speed <= 0.0:
            continue
        for m in range(link_start[b], link_start[b + 1]):
            best = min(best, (_distance(sph_w[k], sph_w[m]) - sph_r[k] - sph_r[m] - margin) / speed)
    return best


@_leaf
def _sweep_gap(p: Array, c: Array, axis_p: Array, axis_d: Array) -> float:
    """Distance (m) between point ``c`` and the circle that point ``p`` runs on turning about the axis."""
    px, py, pz = p[0] - axis_p[0], p[1] - axis_p[1], p[2] - axis_p[2]
    cx, cy, cz = c[0] - axis_p[0], c[1] - axis_p[1], c[2] - axis_p[2]
    hp = px * axis_d[0] + py * axis_d[1] + pz * axis_d[2]
    hc = cx * axis_d[0] + cy * axis_d[1] + cz * axis_d[2]
    rp = math.sqrt(max(px * px + py * py + pz * pz - hp * hp, 0.0))
    rc = math.sqrt(max(cx * cx + cy * cy + cz * cz - hc * hc, 0.0))
    return math.sqrt((rp - rc) * (rp - rc) + (hp - hc) * (hp - hc))


@_leaf
def _relevance(  # noqa: PLR0917
    joint: int,
    axis_p: Array,
    axis_d: Array,
    is_prismatic: bool,
    link_w: Array,
    link_r: Array,
    link_frame: Array,
    obs_t: Array,
    obs_bound: Array,
    ignore: Array,
    pairs: Array,
    bounds: Array,
    has_bounds: bool,
    margin: float,
    rel_obs: Array,
    rel_bounds: Array,
    rel_pair: Array,
) -> None:
    """Which obstacles, bounds and self pairs can limit joint ``joint``'s interval at all: a moving link's
    bounding sphere, turned a whole turn about the axis, sweeps a torus; an obstacle (or a static link)
    whose bounding sphere stays clear of that torus, or bounds that hold its bounding box, never matter.
    Computed once per configuration: the axis and each link's distance to it do not change as the joint
    turns. A prismatic joint keeps everything."""
    for i in range(link_r.shape[0]):
        moving = link_frame[i] > joint
        for o in range(obs_t.shape[0]):
            rel_obs[i, o] = (
                moving
                and not ignore[i, o]
                and (
                    is_prismatic or _sweep_gap(link_w[i], obs_t[o], axis_p, axis_d) - link_r[i] - obs_bound[o] <= margin
                )
            )
        rel_bounds[i] = moving and has_bounds
        if moving and has_bounds and not is_prismatic:
            # the torus's bounding box: its circle's extent along world axis k is radius * sqrt(1 - u_k^2)
            px, py, pz = link_w[i, 0] - axis_p[0], link_w[i, 1] - axis_p[1], link_w[i, 2] - axis_p[2]
            along = px * axis_d[0] + py * axis_d[1] + pz * axis_d[2]
            radius = math.sqrt(max(px * px + py * py + pz * pz - along * along, 0.0))
            inside = True
            for k in range(3):
                middle = axis_p[k] + along * axis_d[k]
                reach = radius * math.sqrt(max(1.0 - axis_d[k] * axis_d[k], 0.0)) + link_r[i] + margin
                if middle - reach <= bounds[k] or middle + reach >= bounds[k + 3]:
                    inside = False
            rel_bounds[i] = not inside
    for p in range(pairs.shape[0]):
        a, b = pairs[p, 0], pairs[p, 1]
        if link_frame[a] <= joint:
            a, b = b, a  # a: the one that moves, if either does
        if link_frame[a] <= joint or link_frame[b] > joint:
            rel_pair[p] = False  # neither moves, or both: their relative pose does not change
        else:
            gap = _sweep_gap(link_w[a], link_w[b], axis_p, axis_d) - link_r[a] - link_r[b]
            rel_pair[p] = is_prismatic or gap <= margin


@_leaf
def _step_bound(  # noqa: PLR0917
    joint: int,
    axis_p: Array,
    axis_d: Array,
    is_prismatic: bool,
    sph_w: Array,
    sph_r: Array,
    link_start: Array,
    link_w: Array,
    link_r: Array,
    link_frame: Array,
    obs_kind: Array,
    obs_r: Array,
    obs_t: Array,
    obs_dims: Array,
    obs_bound: Array,
    pairs: Array,
    bounds: Array,
    has_bounds: bool,
    margin: float,
    rel_obs: Array,
    rel_bounds: Array,
    rel_pair: Array,
    frame_r: Array,
    frame_t: Array,
    sph_c: Array,
    placed: Array,
) -> float:
    """The largest move (rad or m) of joint ``joint`` either way within which no moving sphere can touch:
    the least (clearance - margin) / speed over the moving spheres (a sphere's centre moves at most its
    distance to the axis per radian; 1 m per m along a prismatic axis), against obstacles, bounds and
    the spheres of links that do not move (over ``pairs``). 0 when one is already that close."""
    best = np.inf
    for i in range(link_r.shape[0]):
        if link_frame[i] > joint:
            best = _link_step(
                i,
                best,
                axis_p,
                axis_d,
                is_prismatic,
                sph_w,
                sph_r,
                link_start,
                link_w,
                link_r,
                obs_kind,
                obs_r,
                obs_t,
                obs_dims,
                obs_bound,
                bounds,
                has_bounds,
                margin,
                rel_obs,
                rel_bounds,
                frame_r,
                frame_t,
                sph_c,
                link_frame,
                placed,
            )
            if best <= 0.0:
                return 0.0
    for p in range(pairs.shape[0]):
        if not rel_pair[p]:
            continue  # both move, neither moves, or they never meet in a whole turn (:func:`_relevance`)
        a = pairs[p, 0]
        b = pairs[p, 1]
        if link_frame[a] <= joint:
            a, b = b, a
        best = _pair_step(
            a, b, best, axis_p, axis_d, is_prismatic, sph_w, sph_r, link_start, link_w, link_r, margin, frame_r,
            frame_t, sph_c, link_frame, placed,
        )  # fmt: skip
        if best <= 0.0:
            return 0.0
    return best


@_leaf
def _advance(  # noqa: PLR0917
    q: Array,
    joint: int,
    start: float,
    limit: float,
    direction: float,
    min_step: float,
    max_steps: int,
    base_r: Array,
    base_t: Array,
    org_r: Array,
    org_t: Array,
    axes: Array,
    prismatic: Array,
    sph_c: Array,
    sph_r: Array,
    link_start: Array,
    link_c: Array,
    link_r: Array,
    link_frame: Array,
    obs_kind: Array,
    obs_r: Array,
    obs_t: Array,
    obs_dims: Array,
    obs_bound: Array,
    pairs: Array,
    bounds: Array,
    has_bounds: bool,
    held_link: int,
    held_points: Array,
    held_disc: float,
    held_axis: Array,
    sup_index: Array,
    sup_top: Array,
    sup_tol: float,
    margin: float,
    frame_r: Array,
    frame_t: Array,
    sph_w: Array,
    link_w: Array,
    axis_d: Array,
    scratch: Array,
    placed: Array,
    rel_obs: Array,
    rel_bounds: Array,
    rel_pair: Array,
) -> float:
    """How far joint ``joint`` of ``q`` goes from ``start`` towards ``limit`` (``direction``: +1 or -1) in
    certified steps (:func:`_step_bound`): ``limit`` if it gets there; else where a step falls under
    ``min_step`` or after ``max_steps`` steps. Each step places the links' bounding spheres, and a link's
    spheres only when its bounding sphere cannot settle it. ``q[joint]`` is left changed."""
    value = start
    for _ in range(max_steps):
        q[joint] = value
        forward(q, base_r, base_t, org_r, org_t, axes, prismatic, frame_r, frame_t)
        for i in range(link_c.shape[0]):
            _place(frame_r, frame_t, link_frame[i], link_c[i], link_w[i])
        placed[:] = False
        if held_link >= 0:
            _place_link(held_link, frame_r, frame_t, sph_c, link_start, link_frame, sph_w, placed)
        rot = frame_r[joint + 1]
        for a in range(3):
            axis_d[a] = rot[a, 0] * axes[joint, 0] + rot[a, 1] * axes[joint, 1] + rot[a, 2] * axes[joint, 2]
        step = _step_bound(
            joint, frame_t[joint + 1], axis_d, prismatic[joint], sph_w, sph_r, link_start, link_w, link_r, link_frame,
            obs_kind, obs_r, obs_t, obs_dims, obs_bound, pairs, bounds, has_bounds, margin, rel_obs, rel_bounds,
            rel_pair, frame_r, frame_t, sph_c, placed,
        )  # fmt: skip
        step = _held_support_step(
            frame_r, frame_t, link_frame, link_start, sph_w, sph_r, obs_kind, obs_r, obs_t, obs_dims, held_link,
            held_points, held_disc, held_axis, sup_index, sup_top, sup_tol, frame_t[joint + 1], axis_d,
            prismatic[joint], margin, step, scratch,
        )  # fmt: skip
        if abs(limit - value) <= step:
            return limit
        if step < min_step:
            return value
        value += direction * step
    return value


@_jit
def free_intervals(  # noqa: PLR0917
    qs: Array,
    joint: int,
    lower: Array,
    upper: Array,
    base_r: Array,
    base_t: Array,
    org_r: Array,
    org_t: Array,
    axes: Array,
    prismatic: Array,
    sph_c: Array,
    sph_r: Array,
    sph_frame: Array,
    link_start: Array,
    link_c: Array,
    link_r: Array,
    link_frame: Array,
    obs_kind: Array,
    obs_r: Array,
    obs_t: Array,
    obs_dims: Array,
    obs_bound: Array,
    ignore: Array,
    pairs: Array,
    bounds: Array,
    has_bounds: bool,
    held_link: int,
    held_points: Array,
    held_disc: float,
    held_axis: Array,
    sup_index: Array,
    sup_top: Array,
    sup_tol: float,
    margin: float,
    min_step: float,
    max_steps: int,
    reach: Array,
    fold: bool,
    out_lo: Array,
    out_hi: Array,
    out_valid: Array,
) -> None:
    """For each configuration ``qs[b]``: ``[out_lo[b], out_hi[b]]``, an interval of joint ``joint``'s value
    around ``qs[b, joint]`` (within its limits, and within ``reach[b]`` of it: ``inf`` for no bound) over
    which, the other joints fixed, no sphere touches anything (``out_valid[b]``: the configuration itself is
    valid; else the interval is the point).

    With ``fold``, ``reach[b]`` is the signed move the caller folds into the interval
    (:func:`clew_ros.core.manhattan.bounce`): the side it heads for is searched as far as ``|reach[b]|``,
    the other only as far as the move, bounced off the first side's end, can go past the start
    (``|reach[b]|`` less twice the first side's extent; nothing when the move fits): the fold comes out
    the same as with both sides searched to ``|reach[b]|``.

    Conservative: from the current value it steps, each way, by the largest move no moving sphere can
    collide within (:func:`_step_bound`), and stops at a limit, where a step falls under ``min_step``, or
    after ``max_steps`` steps.
    """
    n = qs.shape[1]
    frame_r = np.empty((n + 1, 3, 3))
    frame_t = np.empty((n + 1, 3))
    sph_w = np.empty((sph_c.shape[0], 3))
    link_w = np.empty((link_c.shape[0], 3))
    q = np.empty(n)
    axis_d = np.empty(3)
    scratch = np.empty((8, 3))  # the held object's corners or cap centres in world
    placed = np.zeros(link_c.shape[0], dtype=np.bool_)
    rel_obs = np.zeros((link_c.shape[0], obs_t.shape[0]), dtype=np.bool_)
    rel_bounds = np.zeros(link_c.shape[0], dtype=np.bool_)
    rel_pair = np.zeros(pairs.shape[0], dtype=np.bool_)
    for b in range(qs.shape[0]):
        q[:] = qs[b]
        start = q[joint]
        out_lo[b] = start
        out_hi[b] = start
        inside = _within(q, lower, upper)
        if inside:
            forward(q, base_r, base_t, org_r, org_t, axes, prismatic, frame_r, frame_t)
            inside = not _collides(
                frame_r,
                frame_t,
                sph_c,
                sph_w,
                sph_r,
                link_start,
                link_c,
                link_frame,
                link_w,
                link_r,
                obs_kind,
                obs_r,
                obs_t,
                obs_dims,
                obs_bound,
                ignore,
                pairs,
                bounds,
                has_bounds,
                placed,
            )
            inside = inside and _held_on_supports(
                frame_r, frame_t, link_frame, link_start, sph_c, sph_w, sph_r, obs_kind, obs_r, obs_t, obs_dims,
                held_link, held_points, held_disc, held_axis, sup_index, sup_top, sup_tol, scratch,
            )  # fmt: skip
        out_valid[b] = inside
        if not inside:
            continue
        rot = frame_r[joint + 1]
        for a in range(3):
            axis_d[a] = rot[a, 0] * axes[joint, 0] + rot[a, 1] * axes[joint, 1] + rot[a, 2] * axes[joint, 2]
        _relevance(
            joint, frame_t[joint + 1], axis_d, prismatic[joint], link_w, link_r, link_frame, obs_t, obs_bound,
            ignore, pairs,
            bounds, has_bounds, margin, rel_obs, rel_bounds, rel_pair,
        )  # fmt: skip
        first = -1.0 if fold and reach[b] < 0.0 else 1.0
        near = start  # the first side's end
        for direction in (first, -first):
            extent = abs(reach[b])
            if fold and direction != first:
                extent = max(extent - 2.0 * abs(near - start), 0.0)
            limit = min(upper[joint], start + extent) if direction > 0.0 else max(lower[joint], start - extent)
            value = start
            if limit != start:
                value = _advance(
                    q, joint, start, limit, direction, min_step, max_steps, base_r, base_t, org_r, org_t, axes,
                    prismatic, sph_c, sph_r, link_start, link_c, link_r, link_frame, obs_kind, obs_r, obs_t, obs_dims,
                    obs_bound, pairs, bounds, has_bounds, held_link, held_points, held_disc, held_axis, sup_index,
                    sup_top, sup_tol, margin, frame_r, frame_t, sph_w, link_w, axis_d, scratch, placed, rel_obs,
                    rel_bounds, rel_pair,
                )  # fmt: skip
            near = value
            if direction > 0.0:
                out_hi[b] = value
            else:
                out_lo[b] = value
