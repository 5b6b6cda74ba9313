"""Which contacts of a batch of configurations the sphere models cannot settle (numba).

Two sphere models of one robot (:mod:`clew_ros.spatial.spheres`): the *outer* one contains every link's
collision geometry (its spheres touching nothing proves a configuration free), the *inner* one is contained
in it (its spheres touching an obstacle, the bounds or each other proves a collision). Between the two lies a
thin band where neither settles a contact: there the exact geometry decides
(:mod:`clew_ros.spatial.tier`). :func:`contacts_batch` classifies each configuration of a batch and lists the
contacts in the band, so that only those reach the exact checker.

Arguments are packed as tuples (conventions of :mod:`clew_ros.spatial.kernels.collide`):

- ``robot``: ``(lower, upper, base_r, base_t, org_r, org_t, axes, prismatic)``;
- ``outer``: ``(sph_c, sph_r, link_start, link_c, link_r, link_frame)``, the outer spheres (held object included
  as piece ``held_link``);
- ``inner``: ``(sph_c, sph_r, link_start)``, the inner spheres on the same pieces and frames (a piece may have
  none: then nothing about it is certain);
- ``scene``: ``(obs_kind, obs_r, obs_t, obs_dims, obs_bound, ignore, pairs, bounds, has_bounds)``;
- ``held``: ``(held_link, held_points, held_disc, held_axis, sup_index, sup_top, sup_tol)``.

A contact is a row ``(kind, a, b)``: :data:`OBSTACLE` (piece ``a``, obstacle ``b``), :data:`BOUNDS` (piece
``a``), :data:`PAIR` (pieces ``a`` and ``b``), :data:`SUPPORT` (the held piece ``a`` below the top of support
obstacle ``b``).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from clew_ros.spatial.kernels.collide import (
    _bounds_clearance,
    _distance,
    _held_lowest,
    _jit,
    _leaf,
    _place,
    _within,
    clearance_of_sphere,
    forward,
)

__all__ = ["BAND", "BOUNDS", "CERTAIN", "FREE", "OBSTACLE", "OVERFLOW", "PAIR", "SUPPORT", "contacts_batch"]

Array = NDArray[Any]

#: A configuration's status: its outer spheres touch nothing; its inner spheres touch something (or a joint is
#: outside its limits); contacts in the band only (listed); more band contacts than the list holds.
FREE, CERTAIN, BAND, OVERFLOW = 0, 1, 2, 3
#: The kinds of a contact.
OBSTACLE, BOUNDS, PAIR, SUPPORT = 0, 1, 2, 3


@_leaf
def _piece_touches(  # noqa: PLR0917
    start: int, stop: int, world: Array, radii: Array, o: int, scene: Any, margin: float
) -> bool:
    """Whether a sphere ``start:stop`` (centres ``world``, already placed) comes within ``margin`` of obstacle
    ``o``."""
    obs_kind, obs_r, obs_t, obs_dims = scene[0], scene[1], scene[2], scene[3]
    for k in range(start, stop):
        if clearance_of_sphere(world[k], radii[k], obs_kind[o], obs_r[o], obs_t[o], obs_dims[o]) <= margin:
            return True
    return False


@_leaf
def _piece_leaves(  # noqa: PLR0917
    start: int, stop: int, world: Array, radii: Array, bounds: Array, margin: float
) -> bool:
    """Whether a sphere ``start:stop`` comes within ``margin`` of the bounds' faces."""
    for k in range(start, stop):
        if _bounds_clearance(world[k], radii[k], bounds) <= margin:
            return True
    return False


@_leaf
def _pieces_touch(  # noqa: PLR0917
    a0: int, a1: int, b0: int, b1: int, world: Array, radii: Array, margin: float
) -> bool:
    """Whether a sphere ``a0:a1`` comes within ``margin`` of a sphere ``b0:b1``."""
    for k in range(a0, a1):
        for m in range(b0, b1):
            if _distance(world[k], world[m]) <= radii[k] + radii[m] + margin:
                return True
    return False


@_leaf
def _place_all(frame_r: Array, frame_t: Array, centres: Array, starts: Array, frames: Array, out: Array) -> None:
    for i in range(frames.shape[0]):
        for k in range(starts[i], starts[i + 1]):
            _place(frame_r, frame_t, frames[i], centres[k], out[k])


@_leaf
def _classify(  # noqa: PLR0912, PLR0917
    frame_r: Array,
    frame_t: Array,
    outer: Any,
    inner: Any,
    scene: Any,
    held: Any,
    out_w: Array,
    in_w: Array,
    link_w: Array,
    scratch: Array,
    found: Array,
    margin: float,
) -> tuple[int, int]:
    """The status of the configuration whose frames are given, and how many band contacts ``found`` holds; a
    contact within ``margin`` (m; twice that between two pieces) of the outer spheres counts."""
    sph_c, sph_r, link_start, link_c, link_r, link_frame = outer
    in_c, in_r, in_start = inner
    obs_kind, obs_r, obs_t, obs_dims, obs_bound, ignore, pairs, bounds, has_bounds = scene
    held_link, held_points, held_disc, held_axis, sup_index, sup_top, sup_tol = held
    pieces = link_r.shape[0]
    cap = found.shape[0]
    count = 0
    for i in range(pieces):
        _place(frame_r, frame_t, link_frame[i], link_c[i], link_w[i])
    _place_all(frame_r, frame_t, sph_c, link_start, link_frame, out_w)
    _place_all(frame_r, frame_t, in_c, in_start, link_frame, in_w)
    for i in range(pieces):
        if link_frame[i] == 0:
            continue  # never moves: checked once, when the checker is made
        a0, a1 = link_start[i], link_start[i + 1]
        b0, b1 = in_start[i], in_start[i + 1]
        if has_bounds and _bounds_clearance(link_w[i], link_r[i], bounds) <= margin and _piece_leaves(
            a0, a1, out_w, sph_r, bounds, margin
        ):
            if _piece_leaves(b0, b1, in_w, in_r, bounds, 0.0):
                return CERTAIN, count
            if count < cap:
                found[count, 0], found[count, 1], found[count, 2] = BOUNDS, i, -1
            count += 1
        for o in range(obs_kind.shape[0]):
            if ignore[i, o] or _distance(link_w[i], obs_t[o]) > link_r[i] + obs_bound[o] + margin:
                continue
            if clearance_of_sphere(link_w[i], link_r[i], obs_kind[o], obs_r[o], obs_t[o], obs_dims[o]) > margin:
                continue
            if not _piece_touches(a0, a1, out_w, sph_r, o, scene, margin):
                continue
            if _piece_touches(b0, b1, in_w, in_r, o, scene, 0.0):
                return CERTAIN, count
            if count < cap:
                found[count, 0], found[count, 1], found[count, 2] = OBSTACLE, i, o
            count += 1
    for p in range(pairs.shape[0]):
        a, b = pairs[p, 0], pairs[p, 1]
        if _distance(link_w[a], link_w[b]) > link_r[a] + link_r[b] + 2 * margin:
            continue
        if not _pieces_touch(
            link_start[a], link_start[a + 1], link_start[b], link_start[b + 1], out_w, sph_r, 2 * margin
        ):
            continue
        if _pieces_touch(in_start[a], in_start[a + 1], in_start[b], in_start[b + 1], in_w, in_r, 0.0):
            return CERTAIN, count
        if count < cap:
            found[count, 0], found[count, 1], found[count, 2] = PAIR, a, b
        count += 1
    if held_link >= 0 and sup_index.shape[0] > 0:
        frame = link_frame[held_link]
        lowest = _held_lowest(frame_r, frame_t, frame, held_points, held_disc, held_axis, scratch)
        for m in range(sup_index.shape[0]):
            if lowest >= sup_top[m] - sup_tol + margin:
                continue
            o = sup_index[m]
            if not _piece_touches(link_start[held_link], link_start[held_link + 1], out_w, sph_r, o, scene, margin):
                continue
            if lowest < sup_top[m] - sup_tol and _piece_touches(
                in_start[held_link], in_start[held_link + 1], in_w, in_r, o, scene, 0.0
            ):
                return CERTAIN, count
            if count < cap:
                found[count, 0], found[count, 1], found[count, 2] = SUPPORT, held_link, o
            count += 1
    if count == 0:
        return FREE, 0
    return (BAND if count <= cap else OVERFLOW), min(count, cap)


@_jit
def contacts_batch(  # noqa: PLR0917
    qs: Array,
    robot: Any,
    outer: Any,
    inner: Any,
    scene: Any,
    held: Any,
    status: Array,
    contacts: Array,
    counts: Array,
    frames_r: Array,
    frames_t: Array,
    margin: float,
) -> None:
    """For each row ``b`` of ``qs``: ``status[b]`` (:data:`FREE`, :data:`CERTAIN`, :data:`BAND`,
    :data:`OVERFLOW`), its band contacts ``contacts[b, :counts[b]]`` (rows ``(kind, a, b)``) and, for a row in
    the band, its frames (``frames_r[b]`` (n+1, 3, 3), ``frames_t[b]`` (n+1, 3)) for the exact check. A contact
    counts within ``margin`` (m) of the outer spheres (see :func:`_classify`)."""
    lower, upper, base_r, base_t, org_r, org_t, axes, prismatic = robot
    sph_c, link_c = outer[0], outer[3]
    in_c = inner[0]
    n = qs.shape[1]
    frame_r = np.empty((n + 1, 3, 3))
    frame_t = np.empty((n + 1, 3))
    out_w = np.empty((sph_c.shape[0], 3))
    in_w = np.empty((max(in_c.shape[0], 1), 3))
    link_w = np.empty((link_c.shape[0], 3))
    scratch = np.empty((8, 3))
    for b in range(qs.shape[0]):
        counts[b] = 0
        q = qs[b]
        if not _within(q, lower, upper):
            status[b] = CERTAIN
            continue
        forward(q, base_r, base_t, org_r, org_t, axes, prismatic, frame_r, frame_t)
        state, count = _classify(
            frame_r, frame_t, outer, inner, scene, held, out_w, in_w, link_w, scratch, contacts[b], margin
        )
        status[b] = state
        counts[b] = count
        if state >= BAND:
            frames_r[b] = frame_r
            frames_t[b] = frame_t
