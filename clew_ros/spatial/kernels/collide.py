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

The kernels take these packed (:mod:`clew_ros.spatial.kernels.packed`): the :class:`~.packed.Model` (chain,
sphere models, scene, held object) they read, the :class:`~.packed.Work` they write one configuration into.
:func:`config_valid` is the one validity test, shared by :func:`valid_batch`, the free intervals
(:mod:`clew_ros.spatial.kernels.intervals`) and the band (:mod:`clew_ros.spatial.kernels.band`).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import numba
import numpy as np
from numpy.typing import NDArray

from clew_ros.spatial.kernels.packed import Chain, HeldObject, Model, Spheres, Work

if TYPE_CHECKING:
    from numba.core.decorators import _JITWrapper  # in numba's type stubs only

__all__ = ["clearance_of_sphere", "config_valid", "forward", "new_work", "static_collides", "valid_batch"]

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
def forward(q: Array, chain: Chain, out_r: Array, out_t: Array) -> None:
    """Frames 0..n of configuration ``q`` into ``out_r`` (n+1, 3, 3) and ``out_t`` (n+1, 3)."""
    base_r, base_t, org_r, org_t, axes = chain.base_r, chain.base_t, chain.org_r, chain.org_t, chain.axes
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
        if chain.prismatic[j]:
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
def clearance_of_sphere(p: Array, radius: float, kind: int, rot: Array, pos: Array, dims: Array) -> float:  # noqa: PLR0917  # one obstacle's fields, as Python callers hold them
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
def clearance_to(p: Array, radius: float, scene: Any, o: int) -> float:
    """:func:`clearance_of_sphere` to obstacle ``o`` of ``scene`` (a :class:`~.packed.Scene`)."""
    return clearance_of_sphere(p, radius, scene.obs_kind[o], scene.obs_r[o], scene.obs_t[o], scene.obs_dims[o])


@_leaf
def bounds_clearance(p: Array, radius: float, bounds: Array) -> float:
    """Signed distance (m) of a sphere (centre ``p``, ``radius``) to the faces of the bounds, inwards."""
    out = p[0] - bounds[0]
    out = min(out, p[1] - bounds[1])
    out = min(out, p[2] - bounds[2])
    out = min(out, bounds[3] - p[0])
    out = min(out, bounds[4] - p[1])
    out = min(out, bounds[5] - p[2])
    return float(out) - radius


@_leaf
def distance(a: Array, b: Array) -> float:
    """Distance (m) between two points."""
    dx = a[0] - b[0]
    dy = a[1] - b[1]
    dz = a[2] - b[2]
    return math.sqrt(dx * dx + dy * dy + dz * dz)


@_leaf
def place_link(i: int, spheres: Spheres, work: Work) -> None:
    """Place link ``i``'s spheres in ``world`` unless already done for this configuration."""
    if work.placed[i]:
        return
    work.placed[i] = True
    frame = spheres.link_frame[i]
    for k in range(spheres.link_start[i], spheres.link_start[i + 1]):
        _place(work.frame_r, work.frame_t, frame, spheres.sph_c[k], work.sph_w[k])


@_leaf
def place_bounding(spheres: Spheres, work: Work) -> None:
    """Every piece's bounding sphere in ``world``, no piece's spheres placed yet."""
    for i in range(spheres.link_c.shape[0]):
        _place(work.frame_r, work.frame_t, spheres.link_frame[i], spheres.link_c[i], work.link_w[i])
    work.placed[:] = False


@_leaf
def _link_collides(i: int, model: Model, work: Work) -> bool:
    """Whether link ``i`` touches an obstacle (but those ``ignore[i]`` marks) or leaves the bounds (its
    bounding sphere first)."""
    spheres, scene = model.spheres, model.scene
    link_start, link_w, link_r, sph_w, sph_r = (
        spheres.link_start, work.link_w, spheres.link_r, work.sph_w, spheres.sph_r
    )  # fmt: skip
    if scene.has_bounds and bounds_clearance(link_w[i], link_r[i], scene.bounds) <= 0.0:
        place_link(i, spheres, work)
        for k in range(link_start[i], link_start[i + 1]):
            if bounds_clearance(sph_w[k], sph_r[k], scene.bounds) <= 0.0:
                return True
    for o in range(scene.obs_kind.shape[0]):
        reach = scene.obs_bound[o]
        if scene.ignore[i, o] or distance(link_w[i], scene.obs_t[o]) > link_r[i] + reach:
            continue
        if clearance_to(link_w[i], link_r[i], scene, o) > 0.0:
            continue  # the link's bounding sphere misses the obstacle itself (a wide table, a long shelf)
        place_link(i, spheres, work)
        for k in range(link_start[i], link_start[i + 1]):
            if clearance_to(sph_w[k], sph_r[k], scene, o) <= 0.0:
                return True
    return False


@_leaf
def _pair_collides(a: int, b: int, spheres: Spheres, work: Work) -> bool:
    """Whether links ``a`` and ``b`` touch (their bounding spheres first)."""
    link_start, link_w, link_r, sph_w, sph_r = (
        spheres.link_start, work.link_w, spheres.link_r, work.sph_w, spheres.sph_r
    )  # fmt: skip
    if distance(link_w[a], link_w[b]) > link_r[a] + link_r[b]:
        return False
    place_link(a, spheres, work)
    place_link(b, spheres, work)
    for k in range(link_start[a], link_start[a + 1]):
        if distance(sph_w[k], link_w[b]) > sph_r[k] + link_r[b]:
            continue
        for m in range(link_start[b], link_start[b + 1]):
            if distance(sph_w[k], sph_w[m]) <= sph_r[k] + sph_r[m]:
                return True
    return False


@_leaf
def _collides(model: Model, work: Work) -> bool:
    """Whether the configuration whose frames ``work`` holds touches an obstacle, leaves the bounds, or touches
    itself (``pairs``); each link's spheres are placed only when its bounding sphere cannot settle it.
    Links on frame 0 never move: :func:`static_collides` checks them once, not here."""
    spheres, pairs = model.spheres, model.scene.pairs
    place_bounding(spheres, work)
    for i in range(spheres.link_r.shape[0]):
        if spheres.link_frame[i] != 0 and _link_collides(i, model, work):
            return True
    for p in range(pairs.shape[0]):  # noqa: SIM110  # a loop: numba compiles no generator inside any()
        if _pair_collides(pairs[p, 0], pairs[p, 1], spheres, work):
            return True
    return False


@_leaf
def within(q: Array, lower: Array, upper: Array) -> bool:
    """Whether every joint value lies within its limits."""
    for j in range(q.shape[0]):  # noqa: SIM110  # a loop: numba compiles no generator inside all()
        if not lower[j] <= q[j] <= upper[j]:
            return False
    return True


@_leaf
def held_lowest(held: HeldObject, frame: int, work: Work) -> float:
    """The held object's lowest height (m): a box's lowest corner, or a cylinder's lowest cap rim (the cap
    centre less the radius times the cap's tilt), on frame ``frame``. ``work.held_w`` receives the points
    (corners, cap centres) in ``world``."""
    r = work.frame_r[frame]
    t = work.frame_t[frame]
    held_points, held_disc, held_axis, out = held.held_points, held.held_disc, held.held_axis, work.held_w
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
def _held_clear_of(o: int, model: Model, work: Work) -> float:
    """The least clearance (m) of the held object's spheres to obstacle ``o``."""
    held_link, link_start, sph_r = model.held.held_link, model.spheres.link_start, model.spheres.sph_r
    best = np.inf
    for k in range(link_start[held_link], link_start[held_link + 1]):
        best = min(best, clearance_to(work.sph_w[k], sph_r[k], model.scene, o))
    return best


@_leaf
def _held_on_supports(model: Model, work: Work) -> bool:
    """Whether the held object keeps off every support but from above: either all of it lies above the
    support's top (within ``sup_tol``: it may touch), or its spheres are clear of the support."""
    held, spheres = model.held, model.spheres
    held_link, sup_index = held.held_link, held.sup_index
    if held_link < 0 or sup_index.shape[0] == 0:
        return True
    frame = spheres.link_frame[held_link]
    lowest = held_lowest(held, frame, work)
    for k in range(spheres.link_start[held_link], spheres.link_start[held_link + 1]):
        _place(work.frame_r, work.frame_t, frame, spheres.sph_c[k], work.sph_w[k])
    for m in range(sup_index.shape[0]):
        if lowest >= held.sup_top[m] - held.sup_tol:
            continue
        if _held_clear_of(sup_index[m], model, work) <= 0.0:
            return False
    return True


@_leaf
def config_valid(q: Array, model: Model, work: Work) -> bool:
    """Whether configuration ``q`` is inside its limits, its spheres touch nothing and the held object keeps
    off its supports but from above: the one validity test of the kernels. ``work`` is left holding ``q``'s
    frames (when inside its limits) and the bounding spheres and spheres placed on the way."""
    chain = model.chain
    if not within(q, chain.lower, chain.upper):
        return False
    forward(q, chain, work.frame_r, work.frame_t)
    if _collides(model, work):
        return False
    return _held_on_supports(model, work)


@_jit
def new_work(n: int, model: Model) -> Work:
    """Scratch for the configurations of an ``n``-joint chain with ``model``'s spheres."""
    pieces = model.spheres.link_c.shape[0]
    return Work(
        np.empty((n + 1, 3, 3)),
        np.empty((n + 1, 3)),
        np.empty((model.spheres.sph_c.shape[0], 3)),
        np.empty((pieces, 3)),
        np.zeros(pieces, dtype=np.bool_),
        np.empty((8, 3)),  # the held object's corners or cap centres in world
        np.empty((max(model.inner.sph_c.shape[0], 1), 3)),
    )


@_jit
def valid_batch(qs: Array, model: Model, out: Array) -> None:
    """``out[b]``: configuration ``qs[b]`` is inside its limits and its spheres touch nothing
    (:func:`config_valid`)."""
    work = new_work(qs.shape[1], model)
    for b in range(qs.shape[0]):
        out[b] = config_valid(qs[b], model, work)


@_jit
def static_collides(model: Model) -> bool:
    """Whether a sphere on frame 0 (which no joint moves) touches an obstacle (but those its link's
    ``ignore`` row marks) or leaves the bounds."""
    base_r, base_t = model.chain.base_r, model.chain.base_t
    spheres, scene = model.spheres, model.scene
    sph_c, sph_r = spheres.sph_c, spheres.sph_r
    p = np.empty(3)
    for k in range(sph_c.shape[0]):
        if spheres.sph_frame[k] != 0:
            continue
        for a in range(3):
            p[a] = base_r[a, 0] * sph_c[k, 0] + base_r[a, 1] * sph_c[k, 1] + base_r[a, 2] * sph_c[k, 2] + base_t[a]
        if scene.has_bounds and bounds_clearance(p, sph_r[k], scene.bounds) <= 0.0:
            return True
        for o in range(scene.obs_kind.shape[0]):
            if scene.ignore[spheres.sph_link[k], o]:
                continue
            if clearance_to(p, sph_r[k], scene, o) <= 0.0:
                return True
    return False
