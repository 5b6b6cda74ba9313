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
    for k in range(start, stop):  # noqa: SIM110  # a loop: numba compiles no generator inside any()
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
def _place_all(  # noqa: PLR0917
    frame_r: Array, frame_t: Array, centres: Array, starts: Array, frames: Array, out: Array
) -> None:
    for i in range(frames.shape[0]):
        for k in range(starts[i], starts[i + 1]):
            _place(frame_r, frame_t, frames[i], centres[k], out[k])


@_leaf
def _record(found: Array, count: int, kind: int, a: int, b: int) -> int:
    """Contact ``(kind, a, b)`` listed as the ``count``-th (if ``found`` has room); the new count."""
    if count < found.shape[0]:
        found[count, 0], found[count, 1], found[count, 2] = kind, a, b
    return count + 1


@_leaf
def _against_scene(  # noqa: PLR0917
    outer: Any, inner: Any, scene: Any, placed: Any, found: Array, margin: float
) -> int:
    """Each moving piece against the bounds and the obstacles: the band contacts' count, -1 for a certain one."""
    sph_r, link_start, link_r, link_frame = outer[1], outer[2], outer[4], outer[5]
    in_r, in_start = inner[1], inner[2]
    obs_kind, obs_r, obs_t, obs_dims, obs_bound, ignore, bounds, has_bounds = (
        scene[0], scene[1], scene[2], scene[3], scene[4], scene[5], scene[7], scene[8]
    )  # fmt: skip
    out_w, in_w, link_w = placed
    count = 0
    for i in range(link_r.shape[0]):
        if link_frame[i] == 0:
            continue  # never moves: checked once, when the checker is made
        a0, a1, b0, b1 = link_start[i], link_start[i + 1], in_start[i], in_start[i + 1]
        near = has_bounds and _bounds_clearance(link_w[i], link_r[i], bounds) <= margin
        if near and _piece_leaves(a0, a1, out_w, sph_r, bounds, margin):
            if _piece_leaves(b0, b1, in_w, in_r, bounds, 0.0):
                return -1
            count = _record(found, count, BOUNDS, i, -1)
        for o in range(obs_kind.shape[0]):
            if ignore[i, o] or _distance(link_w[i], obs_t[o]) > link_r[i] + obs_bound[o] + margin:
                continue
            if clearance_of_sphere(link_w[i], link_r[i], obs_kind[o], obs_r[o], obs_t[o], obs_dims[o]) > margin:
                continue
            if not _piece_touches(a0, a1, out_w, sph_r, o, scene, margin):
                continue
            if _piece_touches(b0, b1, in_w, in_r, o, scene, 0.0):
                return -1
            count = _record(found, count, OBSTACLE, i, o)
    return count


@_leaf
def _self_pairs(  # noqa: PLR0917
    outer: Any, inner: Any, pairs: Array, placed: Any, found: Array, count: int, margin: float
) -> int:
    """The pairs of pieces checked for self-collision: the band contacts' count, -1 for a certain one."""
    sph_r, link_start, link_r = outer[1], outer[2], outer[4]
    in_r, in_start = inner[1], inner[2]
    out_w, in_w, link_w = placed
    for p in range(pairs.shape[0]):
        a, b = pairs[p, 0], pairs[p, 1]
        if _distance(link_w[a], link_w[b]) > link_r[a] + link_r[b] + 2 * margin:
            continue
        if not _pieces_touch(
            link_start[a], link_start[a + 1], link_start[b], link_start[b + 1], out_w, sph_r, 2 * margin
        ):
            continue
        if _pieces_touch(in_start[a], in_start[a + 1], in_start[b], in_start[b + 1], in_w, in_r, 0.0):
            return -1
        count = _record(found, count, PAIR, a, b)
    return count


@_leaf
def _against_supports(  # noqa: PLR0917
    frames: Any, outer: Any, inner: Any, scene: Any, held: Any, placed: Any, found: Array, count: int, margin: float
) -> int:
    """The held piece below the top of a support it may touch only from above: the band contacts' count, -1
    for a certain one."""
    held_link, held_points, held_disc, held_axis, sup_index, sup_top, sup_tol = held
    if held_link < 0 or sup_index.shape[0] == 0:
        return count
    sph_r, link_start, link_frame = outer[1], outer[2], outer[5]
    in_r, in_start = inner[1], inner[2]
    out_w, in_w, scratch = placed[0], placed[1], placed[3]
    lowest = _held_lowest(frames[0], frames[1], link_frame[held_link], held_points, held_disc, held_axis, scratch)
    a0, a1, b0, b1 = link_start[held_link], link_start[held_link + 1], in_start[held_link], in_start[held_link + 1]
    for m in range(sup_index.shape[0]):
        if lowest >= sup_top[m] - sup_tol + margin:
            continue
        o = sup_index[m]
        if not _piece_touches(a0, a1, out_w, sph_r, o, scene, margin):
            continue
        if lowest < sup_top[m] - sup_tol and _piece_touches(b0, b1, in_w, in_r, o, scene, 0.0):
            return -1
        count = _record(found, count, SUPPORT, held_link, o)
    return count


@_leaf
def _classify(  # noqa: PLR0917
    frames: Any, outer: Any, inner: Any, scene: Any, held: Any, placed: Any, found: Array, margin: float
) -> tuple[int, int]:
    """The status of the configuration whose ``frames`` (rotations, translations) are given, and how many band
    contacts ``found`` holds; a contact within ``margin`` (m; twice that between two pieces) of the outer
    spheres counts. ``placed``: scratch for the outer, inner and bounding spheres in ``world`` and the held
    object's points."""
    frame_r, frame_t = frames
    out_w, in_w, link_w = placed[0], placed[1], placed[2]
    for i in range(outer[4].shape[0]):
        _place(frame_r, frame_t, outer[5][i], outer[3][i], link_w[i])
    _place_all(frame_r, frame_t, outer[0], outer[2], outer[5], out_w)
    _place_all(frame_r, frame_t, inner[0], inner[2], outer[5], in_w)
    spheres = (out_w, in_w, link_w)
    count = _against_scene(outer, inner, scene, spheres, found, margin)
    if count >= 0:
        count = _self_pairs(outer, inner, scene[6], spheres, found, count, margin)
    if count >= 0:
        count = _against_supports(frames, outer, inner, scene, held, placed, found, count, margin)
    if count < 0:
        return CERTAIN, 0
    if count == 0:
        return FREE, 0
    return (BAND if count <= found.shape[0] else OVERFLOW), min(count, found.shape[0])


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
    placed = (out_w, in_w, link_w, np.empty((8, 3)))
    for b in range(qs.shape[0]):
        counts[b] = 0
        q = qs[b]
        if not _within(q, lower, upper):
            status[b] = CERTAIN
            continue
        forward(q, base_r, base_t, org_r, org_t, axes, prismatic, frame_r, frame_t)
        state, count = _classify((frame_r, frame_t), outer, inner, scene, held, placed, contacts[b], margin)
        status[b] = state
        counts[b] = count
        if state >= BAND:
            frames_r[b] = frame_r
            frames_t[b] = frame_t
