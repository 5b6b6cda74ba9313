"""Which contacts of a batch of configurations the sphere models cannot settle (numba).

Two sphere models of one robot (:mod:`clew_ros.spatial.spheres`): the *outer* one contains every link's
collision geometry (its spheres touching nothing proves a configuration free), the *inner* one is contained
in it (its spheres touching an obstacle, the bounds or each other proves a collision). Between the two lies a
thin band where neither settles a contact: there the exact geometry decides
(:mod:`clew_ros.spatial.tier`). :func:`contacts_batch` classifies each configuration of a batch and lists the
contacts in the band, so that only those reach the exact checker.

Arguments are packed as in :mod:`clew_ros.spatial.kernels.packed`: the :class:`~.packed.Model` (its
``spheres`` the outer spheres, the held object included as piece ``held_link``; its ``inner`` the inner spheres
on the same pieces and frames: a piece may have none, then nothing about it is certain) and the
:class:`~.packed.Work` one configuration is worked out in.

A contact is a row ``(kind, a, b)``: :data:`OBSTACLE` (piece ``a``, obstacle ``b``), :data:`BOUNDS` (piece
``a``), :data:`PAIR` (pieces ``a`` and ``b``), :data:`SUPPORT` (the held piece ``a`` below the top of support
obstacle ``b``).
"""

from __future__ import annotations

from typing import Any

from numpy.typing import NDArray

from clew_ros.spatial.kernels.collide import (
    _jit,
    _leaf,
    _place,
    bounds_clearance,
    clearance_to,
    config_valid,
    distance,
    forward,
    held_lowest,
    new_work,
    within,
)
from clew_ros.spatial.kernels.packed import Model, Scene, Work

__all__ = ["BAND", "BOUNDS", "CERTAIN", "FREE", "OBSTACLE", "OVERFLOW", "PAIR", "SUPPORT", "contacts_batch"]

Array = NDArray[Any]

#: A configuration's status: its outer spheres touch nothing; its inner spheres touch something (or a joint is
#: outside its limits); contacts in the band only (listed); more band contacts than the list holds.
FREE, CERTAIN, BAND, OVERFLOW = 0, 1, 2, 3
#: The kinds of a contact.
OBSTACLE, BOUNDS, PAIR, SUPPORT = 0, 1, 2, 3


@_leaf
def _piece_touches(span: Any, spheres: Any, scene: Scene, o: int, margin: float) -> bool:
    """Whether a sphere ``span`` (``(start, stop)``) of ``spheres`` (``(centres in world, radii)``) comes
    within ``margin`` of obstacle ``o``."""
    world, radii = spheres
    for k in range(span[0], span[1]):  # noqa: SIM110  # a loop: numba compiles no generator inside any()
        if clearance_to(world[k], radii[k], scene, o) <= margin:
            return True
    return False


@_leaf
def _piece_leaves(span: Any, spheres: Any, bounds: Array, margin: float) -> bool:
    """Whether a sphere ``span`` of ``spheres`` comes within ``margin`` of the bounds' faces."""
    world, radii = spheres
    for k in range(span[0], span[1]):  # noqa: SIM110  # a loop: numba compiles no generator inside any()
        if bounds_clearance(world[k], radii[k], bounds) <= margin:
            return True
    return False


@_leaf
def _pieces_touch(span_a: Any, span_b: Any, spheres: Any, margin: float) -> bool:
    """Whether a sphere ``span_a`` comes within ``margin`` of a sphere ``span_b`` (both of ``spheres``)."""
    world, radii = spheres
    for k in range(span_a[0], span_a[1]):
        for m in range(span_b[0], span_b[1]):
            if distance(world[k], world[m]) <= radii[k] + radii[m] + margin:
                return True
    return False


@_leaf
def _place_all(work: Work, centres: Array, starts: Array, frames: Array, out: Array) -> None:
    for i in range(frames.shape[0]):
        for k in range(starts[i], starts[i + 1]):
            _place(work.frame_r, work.frame_t, frames[i], centres[k], out[k])


@_leaf
def _record(found: Array, count: int, kind: int, a: int, b: int) -> int:
    """Contact ``(kind, a, b)`` listed as the ``count``-th (if ``found`` has room); the new count."""
    if count < found.shape[0]:
        found[count, 0], found[count, 1], found[count, 2] = kind, a, b
    return count + 1


@_leaf
def _against_scene(model: Model, work: Work, found: Array, margin: float) -> int:
    """Each moving piece against the bounds and the obstacles: the band contacts' count, -1 for a certain one."""
    outer, inner, scene = model.spheres, model.inner, model.scene
    link_start, link_r, link_frame, link_w = outer.link_start, outer.link_r, outer.link_frame, work.link_w
    in_start = inner.link_start
    out_s, in_s = (work.sph_w, outer.sph_r), (work.inner_w, inner.sph_r)
    count = 0
    for i in range(link_r.shape[0]):
        if link_frame[i] == 0:
            continue  # never moves: checked once, when the checker is made
        out_span, in_span = (link_start[i], link_start[i + 1]), (in_start[i], in_start[i + 1])
        near = scene.has_bounds and bounds_clearance(link_w[i], link_r[i], scene.bounds) <= margin
        if near and _piece_leaves(out_span, out_s, scene.bounds, margin):
            if _piece_leaves(in_span, in_s, scene.bounds, 0.0):
                return -1
            count = _record(found, count, BOUNDS, i, -1)
        for o in range(scene.obs_kind.shape[0]):
            if scene.ignore[i, o] or distance(link_w[i], scene.obs_t[o]) > link_r[i] + scene.obs_bound[o] + margin:
                continue
            if clearance_to(link_w[i], link_r[i], scene, o) > margin:
                continue
            if not _piece_touches(out_span, out_s, scene, o, margin):
                continue
            if _piece_touches(in_span, in_s, scene, o, 0.0):
                return -1
            count = _record(found, count, OBSTACLE, i, o)
    return count


@_leaf
def _self_pairs(model: Model, work: Work, found: Array, count: int, margin: float) -> int:
    """The pairs of pieces checked for self-collision: the band contacts' count, -1 for a certain one."""
    outer, inner, pairs = model.spheres, model.inner, model.scene.pairs
    link_start, link_r, link_w, in_start = outer.link_start, outer.link_r, work.link_w, inner.link_start
    out_s, in_s = (work.sph_w, outer.sph_r), (work.inner_w, inner.sph_r)
    for p in range(pairs.shape[0]):
        a, b = pairs[p, 0], pairs[p, 1]
        if distance(link_w[a], link_w[b]) > link_r[a] + link_r[b] + 2 * margin:
            continue
        if not _pieces_touch((link_start[a], link_start[a + 1]), (link_start[b], link_start[b + 1]), out_s, 2 * margin):
            continue
        if _pieces_touch((in_start[a], in_start[a + 1]), (in_start[b], in_start[b + 1]), in_s, 0.0):
            return -1
        count = _record(found, count, PAIR, a, b)
    return count


@_leaf
def _against_supports(model: Model, work: Work, found: Array, count: int, margin: float) -> int:
    """The held piece below the top of a support it may touch only from above: the band contacts' count, -1
    for a certain one."""
    held, outer, inner = model.held, model.spheres, model.inner
    held_link, sup_index, sup_top, sup_tol = held.held_link, held.sup_index, held.sup_top, held.sup_tol
    if held_link < 0 or sup_index.shape[0] == 0:
        return count
    out_s, in_s = (work.sph_w, outer.sph_r), (work.inner_w, inner.sph_r)
    lowest = held_lowest(held, outer.link_frame[held_link], work)
    out_span = (outer.link_start[held_link], outer.link_start[held_link + 1])
    in_span = (inner.link_start[held_link], inner.link_start[held_link + 1])
    for m in range(sup_index.shape[0]):
        if lowest >= sup_top[m] - sup_tol + margin:
            continue
        o = sup_index[m]
        if not _piece_touches(out_span, out_s, model.scene, o, margin):
            continue
        if lowest < sup_top[m] - sup_tol and _piece_touches(in_span, in_s, model.scene, o, 0.0):
            return -1
        count = _record(found, count, SUPPORT, held_link, o)
    return count


@_leaf
def _classify(model: Model, work: Work, found: Array, margin: float) -> tuple[int, int]:
    """The status of the configuration whose frames ``work`` holds, and how many band contacts ``found`` holds;
    a contact within ``margin`` (m; twice that between two pieces) of the outer spheres counts. ``work``
    receives the outer, inner and bounding spheres in ``world`` and the held object's points."""
    outer, inner = model.spheres, model.inner
    for i in range(outer.link_r.shape[0]):
        _place(work.frame_r, work.frame_t, outer.link_frame[i], outer.link_c[i], work.link_w[i])
    _place_all(work, outer.sph_c, outer.link_start, outer.link_frame, work.sph_w)
    _place_all(work, inner.sph_c, inner.link_start, outer.link_frame, work.inner_w)
    count = _against_scene(model, work, found, margin)
    if count >= 0:
        count = _self_pairs(model, work, found, count, margin)
    if count >= 0:
        count = _against_supports(model, work, found, count, margin)
    if count < 0:
        return CERTAIN, 0
    if count == 0:
        return FREE, 0
    return (BAND if count <= found.shape[0] else OVERFLOW), min(count, found.shape[0])


@_jit
def contacts_batch(qs: Array, model: Model, out: Any, margin: float, spheres_first: bool) -> None:
    """For each row ``b`` of ``qs`` (``out``: ``(status, contacts, counts, frames_r, frames_t)``): ``status[b]``
    (:data:`FREE`, :data:`CERTAIN`, :data:`BAND`, :data:`OVERFLOW`), its band contacts ``contacts[b,
    :counts[b]]`` (rows ``(kind, a, b)``) and, for a row in the band, its frames (``frames_r[b]`` (n+1, 3, 3),
    ``frames_t[b]`` (n+1, 3)) for the exact check. A contact counts within ``margin`` (m) of the outer spheres
    (see :func:`_classify`). With ``spheres_first`` (and ``margin`` 0), a row the validity test
    (:func:`~.collide.config_valid`) passes is :data:`FREE` without its contacts listed: the status of the
    other rows is as without it."""
    status, contacts, counts, frames_r, frames_t = out
    chain = model.chain
    work = new_work(qs.shape[1], model)
    for b in range(qs.shape[0]):
        counts[b] = 0
        q = qs[b]
        if not within(q, chain.lower, chain.upper):
            status[b] = CERTAIN
            continue
        if not spheres_first:
            forward(q, chain, work.frame_r, work.frame_t)
        elif config_valid(q, model, work):  # it leaves q's frames in work
            status[b] = FREE
            continue
        state, count = _classify(model, work, contacts[b], margin)
        status[b] = state
        counts[b] = count
        if state >= BAND:
            frames_r[b] = work.frame_r
            frames_t[b] = work.frame_t
