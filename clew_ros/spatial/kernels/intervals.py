"""The conservative free interval of one joint, the others fixed, over a batch of configurations (numba).

From a valid configuration, joint ``joint`` steps each way by the largest move within which no moving sphere
can touch anything (:func:`_step_bound`: a sphere's clearance over its speed about the joint's axis), its
held object keeping off its supports but from above (:func:`_held_support_step`). Conventions and packed
arguments as in :mod:`clew_ros.spatial.kernels.collide` and :mod:`clew_ros.spatial.kernels.packed`.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import NDArray

from clew_ros.spatial.kernels.collide import (
    _jit,
    _leaf,
    bounds_clearance,
    clearance_to,
    config_valid,
    distance,
    forward,
    held_lowest,
    new_work,
    place_bounding,
    place_link,
)
from clew_ros.spatial.kernels.packed import Model, Motion, Stepping, Work

__all__ = ["free_intervals"]

Array = NDArray[Any]


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
def _link_step(i: int, best: float, motion: Motion, model: Model, work: Work) -> float:
    """``best`` lowered to what moving link ``i``'s clearances to the obstacles and bounds allow (those
    ``rel_obs[i]`` / ``rel_bounds[i]`` leave in: :func:`_relevance`); its spheres are placed only when its
    bounding sphere cannot settle it (:func:`~.collide.place_link`)."""
    spheres, scene = model.spheres, model.scene
    axis_p, axis_d, is_prismatic, margin = motion.axis_p, motion.axis_d, motion.prismatic, motion.margin
    sph_w, sph_r, link_start, link_w, link_r = (
        work.sph_w, spheres.sph_r, spheres.link_start, work.link_w, spheres.link_r
    )  # fmt: skip
    link_speed = _speed(link_w[i], axis_p, axis_d, is_prismatic) + (0.0 if is_prismatic else link_r[i])
    if link_speed <= 0.0:
        return best
    if scene.has_bounds and motion.rel_bounds[i]:
        coarse = bounds_clearance(link_w[i], link_r[i], scene.bounds)
        if coarse <= margin or (coarse - margin) / link_speed < best:
            place_link(i, spheres, work)
            for k in range(link_start[i], link_start[i + 1]):
                speed = _speed(sph_w[k], axis_p, axis_d, is_prismatic)
                if speed > 0.0:
                    best = min(best, (bounds_clearance(sph_w[k], sph_r[k], scene.bounds) - margin) / speed)
    for o in range(scene.obs_kind.shape[0]):
        if not motion.rel_obs[i, o]:
            continue
        coarse = distance(link_w[i], scene.obs_t[o]) - link_r[i] - scene.obs_bound[o]
        if coarse > margin and (coarse - margin) / link_speed >= best:
            continue
        # the link's bounding sphere against the obstacle itself: no sphere of the link is nearer
        coarse = clearance_to(link_w[i], link_r[i], scene, o)
        if coarse > margin and (coarse - margin) / link_speed >= best:
            continue
        place_link(i, spheres, work)
        for k in range(link_start[i], link_start[i + 1]):
            speed = _speed(sph_w[k], axis_p, axis_d, is_prismatic)
            if speed > 0.0:
                c = clearance_to(sph_w[k], sph_r[k], scene, o)
                best = min(best, (c - margin) / speed)
    return best


@_leaf
def _pair_step(p: int, best: float, motion: Motion, model: Model, work: Work) -> float:
    """``best`` lowered to what pair ``p``'s clearance allows: its moving link ``a`` against its static link
    ``b`` (:func:`_relevance` keeps only such pairs)."""
    spheres = model.spheres
    axis_p, axis_d, is_prismatic, margin = motion.axis_p, motion.axis_d, motion.prismatic, motion.margin
    sph_w, sph_r, link_start, link_w, link_r = (
        work.sph_w, spheres.sph_r, spheres.link_start, work.link_w, spheres.link_r
    )  # fmt: skip
    a = model.scene.pairs[p, 0]
    b = model.scene.pairs[p, 1]
    if spheres.link_frame[a] <= motion.joint:
        a, b = b, a
    link_speed = _speed(link_w[a], axis_p, axis_d, is_prismatic) + (0.0 if is_prismatic else link_r[a])
    coarse = distance(link_w[a], link_w[b]) - link_r[a] - link_r[b]
    if link_speed <= 0.0 or (coarse > margin and (coarse - margin) / link_speed >= best):
        return best
    place_link(a, spheres, work)
    place_link(b, spheres, work)
    for k in range(link_start[a], link_start[a + 1]):
        speed = _speed(sph_w[k], axis_p, axis_d, is_prismatic)
        if speed <= 0.0:
            continue
        for m in range(link_start[b], link_start[b + 1]):
            best = min(best, (distance(sph_w[k], sph_w[m]) - sph_r[k] - sph_r[m] - margin) / speed)
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
def _relevance(motion: Motion, model: Model, work: Work) -> None:
    """Which obstacles, bounds and self pairs can limit the joint's interval at all (into ``motion``'s
    ``rel_obs``, ``rel_bounds``, ``rel_pair``): a moving link's bounding sphere, turned a whole turn about the
    axis, sweeps a torus; an obstacle (or a static link) whose bounding sphere stays clear of that torus, or
    bounds that hold its bounding box, never matter. Computed once per configuration: the axis and each link's
    distance to it do not change as the joint turns. A prismatic joint keeps everything."""
    spheres, scene = model.spheres, model.scene
    joint, axis_p, axis_d, is_prismatic, margin = (
        motion.joint, motion.axis_p, motion.axis_d, motion.prismatic, motion.margin
    )  # fmt: skip
    link_w, link_r, link_frame, bounds, has_bounds = (
        work.link_w, spheres.link_r, spheres.link_frame, scene.bounds, scene.has_bounds
    )  # fmt: skip
    rel_obs, rel_bounds, rel_pair = motion.rel_obs, motion.rel_bounds, motion.rel_pair
    for i in range(link_r.shape[0]):
        moving = link_frame[i] > joint
        for o in range(scene.obs_t.shape[0]):
            rel_obs[i, o] = (
                moving
                and not scene.ignore[i, o]
                and (
                    is_prismatic
                    or _sweep_gap(link_w[i], scene.obs_t[o], axis_p, axis_d) - link_r[i] - scene.obs_bound[o] <= margin
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
    pairs = scene.pairs
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
def _step_bound(motion: Motion, model: Model, work: Work) -> float:
    """The largest move (rad or m) of the joint either way within which no moving sphere can touch: the least
    (clearance - margin) / speed over the moving spheres (a sphere's centre moves at most its distance to the
    axis per radian; 1 m per m along a prismatic axis), against obstacles, bounds and the spheres of links
    that do not move (over ``pairs``). 0 when one is already that close."""
    link_frame = model.spheres.link_frame
    best = np.inf
    for i in range(model.spheres.link_r.shape[0]):
        if link_frame[i] > motion.joint:
            best = _link_step(i, best, motion, model, work)
            if best <= 0.0:
                return 0.0
    for p in range(model.scene.pairs.shape[0]):
        if not motion.rel_pair[p]:
            continue  # both move, neither moves, or they never meet in a whole turn (:func:`_relevance`)
        best = _pair_step(p, best, motion, model, work)
        if best <= 0.0:
            return 0.0
    return best


@_leaf
def _held_support_step(best: float, motion: Motion, model: Model, work: Work) -> float:
    """``best`` lowered to the move the held object is certain to make keeping off every support but from
    above: for each support, the longer of the move its lowest point stays above the top (its height over
    the top less ``sup_tol``, over how fast it can sink) and the move its spheres stay clear (clearance
    over speed); either condition keeps it valid."""
    held, spheres = model.held, model.spheres
    held_link, sup_index = held.held_link, held.sup_index
    if held_link < 0 or sup_index.shape[0] == 0:
        return best
    axis_p, axis_d, is_prismatic, margin = motion.axis_p, motion.axis_d, motion.prismatic, motion.margin
    lowest = held_lowest(held, spheres.link_frame[held_link], work)
    scratch, sph_w, sph_r = work.held_w, work.sph_w, spheres.sph_r
    sink = 0.0  # how fast the lowest point can sink: a point's speed, and the cap's tilt at most 1 per radian
    for k in range(held.held_points.shape[0]):
        sink = max(sink, _speed(scratch[k], axis_p, axis_d, is_prismatic) + (0.0 if is_prismatic else held.held_disc))
    for m in range(sup_index.shape[0]):
        above = lowest - (held.sup_top[m] - held.sup_tol) - margin
        plane = 0.0
        if above > 0.0:
            plane = above / sink if sink > 0.0 else np.inf
        o = sup_index[m]
        clear = np.inf
        for k in range(spheres.link_start[held_link], spheres.link_start[held_link + 1]):
            speed = _speed(sph_w[k], axis_p, axis_d, is_prismatic)
            c = clearance_to(sph_w[k], sph_r[k], model.scene, o) - margin
            if c <= 0.0:
                clear = 0.0
                break
            if speed > 0.0:
                clear = min(clear, c / speed)
        best = min(best, max(plane, clear))
    return best


@_leaf
def _axis(motion: Motion, model: Model, work: Work) -> None:
    """The joint's axis direction in ``world`` (into ``motion.axis_d``) at the frames ``work`` holds; its point
    ``motion.axis_p`` is frame ``joint + 1``'s origin, a view of ``work.frame_t``."""
    joint, axes = motion.joint, model.chain.axes
    rot = work.frame_r[joint + 1]
    for a in range(3):
        motion.axis_d[a] = rot[a, 0] * axes[joint, 0] + rot[a, 1] * axes[joint, 1] + rot[a, 2] * axes[joint, 2]


@_leaf
def _advance(motion: Motion, start: float, limit: float, model: Model, work: Work) -> float:
    """How far the joint of ``motion.q`` goes from ``start`` towards ``limit`` in certified steps
    (:func:`_step_bound`): ``limit`` if it gets there; else where a step falls under ``min_step`` or after
    ``max_steps`` steps. Each step places the links' bounding spheres, and a link's spheres only when its
    bounding sphere cannot settle it. ``motion.q[joint]`` is left changed."""
    q, joint = motion.q, motion.joint
    direction = 1.0 if limit > start else -1.0
    value = start
    for _ in range(motion.max_steps):
        q[joint] = value
        forward(q, model.chain, work.frame_r, work.frame_t)
        place_bounding(model.spheres, work)
        if model.held.held_link >= 0:
            place_link(model.held.held_link, model.spheres, work)
        _axis(motion, model, work)
        step = _step_bound(motion, model, work)
        step = _held_support_step(step, motion, model, work)
        if abs(limit - value) <= step:
            return limit
        if step < motion.min_step:
            return value
        value += direction * step
    return value


@_jit
def free_intervals(qs: Array, joint: int, model: Model, stepping: Stepping, out: Any) -> None:
    """For each configuration ``qs[b]``: ``[lo[b], hi[b]]`` (``out``: ``(lo, hi, valid)``), an interval of joint
    ``joint``'s value around ``qs[b, joint]`` (within its limits, and within ``stepping.reach[b]`` of it:
    ``inf`` for no bound) over which, the other joints fixed, no sphere touches anything (``valid[b]``: the
    configuration itself is valid, :func:`~.collide.config_valid`; else the interval is the point).

    With ``stepping.fold``, ``reach[b]`` is the signed move the caller folds into the interval
    (:func:`clew_ros.core.manhattan.bounce`): the side it heads for is searched as far as ``|reach[b]|``,
    the other only as far as the move, bounced off the first side's end, can go past the start
    (``|reach[b]|`` less twice the first side's extent; nothing when the move fits): the fold comes out
    the same as with both sides searched to ``|reach[b]|``.

    Conservative: from the current value it steps, each way, by the largest move no moving sphere can
    collide within (:func:`_step_bound`), and stops at a limit, where a step falls under ``min_step``, or
    after ``max_steps`` steps.
    """
    out_lo, out_hi, out_valid = out
    lower, upper = model.chain.lower, model.chain.upper
    reach, fold = stepping.reach, stepping.fold
    n = qs.shape[1]
    pieces = model.spheres.link_c.shape[0]
    work = new_work(n, model)
    motion = Motion(
        joint,
        np.empty(n),
        work.frame_t[joint + 1],
        np.empty(3),
        model.chain.prismatic[joint],
        stepping.margin,
        stepping.min_step,
        stepping.max_steps,
        np.zeros((pieces, model.scene.obs_t.shape[0]), dtype=np.bool_),
        np.zeros(pieces, dtype=np.bool_),
        np.zeros(model.scene.pairs.shape[0], dtype=np.bool_),
    )
    q = motion.q
    for b in range(qs.shape[0]):
        q[:] = qs[b]
        start = q[joint]
        out_lo[b] = start
        out_hi[b] = start
        inside = config_valid(q, model, work)
        out_valid[b] = inside
        if not inside:
            continue
        _axis(motion, model, work)
        _relevance(motion, model, work)
        first = -1.0 if fold and reach[b] < 0.0 else 1.0
        near = start  # the first side's end
        for direction in (first, -first):
            extent = abs(reach[b])
            if fold and direction != first:
                extent = max(extent - 2.0 * abs(near - start), 0.0)
            limit = min(upper[joint], start + extent) if direction > 0.0 else max(lower[joint], start - extent)
            value = start
            if limit != start:
                value = _advance(motion, start, limit, model, work)
            near = value
            if direction > 0.0:
                out_hi[b] = value
            else:
                out_lo[b] = value
