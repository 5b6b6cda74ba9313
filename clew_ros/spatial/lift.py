"""Transfers that lift the object off its support and set it down from above, as a robot cell needs them.

A transfer found by Manhattan moves may slide the object over its support before it rises (the checker lets a
carried object touch a support from above). :func:`lifted_segments` mends such a transfer's ends: the object
is first lifted straight up (the tcp raised a few mm, its orientation kept), and the path joins the transfer
again at the first of its samples that has left the support's band; the same at the other end, reversed
(set down from above). Each new move is straight and checked at the validator's resolution; a transfer whose
ends cannot be mended so is kept as it was (:func:`clew_ros.spatial.handling.drag_problems` reports it).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Protocol

import numpy as np
from numpy.typing import NDArray

from clew_ros.core.tree import Segment
from clew_ros.spatial.checker import SpatialChecker
from clew_ros.spatial.handling import DragSettings, slides
from clew_ros.spatial.inverse import pose_rows
from clew_ros.spatial.transforms import pose_matrix
from clew_ros.spatial.validate import validation_samples
from clew_ros.spatial.views import HeldObjectView

__all__ = ["LiftSettings", "drag_free", "lift_up", "lifted_segments", "slid_level"]

Array = NDArray[np.float64]

#: a tcp pose with its turn about the vertical free: the pose error's rows but its rotation's z
_YAW_FREE = pose_rows(("x", "y", "z", "rx", "ry"))


class SpatialSpace(HeldObjectView, Protocol):
    """What the mending ask of :class:`clew_ros.spatial.space.SpatialSpace` beyond :class:`HeldObjectView`."""

    @property
    def validation_steps(self) -> Array: ...

    def tcp(self, q: Array) -> Array: ...

    def clear(self, checker: SpatialChecker, starts: Array, ends: Array) -> NDArray[np.bool_]: ...


@dataclass(frozen=True)
class LiftSettings:
    """How a dragging transfer's ends are mended."""

    #: what counts as dragging (the band above a support, the slide allowed in it)
    drag: DragSettings = field(default_factory=DragSettings)
    #: the tcp is raised straight up by the first of these (m) that gives a clear lift
    lifts_m: tuple[float, ...] = (0.008, 0.015, 0.03)
    #: samples of the transfer (count) tried as the place where the lifted path joins it again
    joins: int = 8
    #: stretches (count) mended in the middle of one transfer at most: the object set down on a support on
    #: its way and slid, replaced by the same move with both ends raised
    middles: int = 3
    #: where no straight joint move joins the lifted start to the transfer (under a cubby's ceiling or a
    #: shelf's lid), the lifted object first slides level in this many short moves (count), as far as the
    #: transfer took it sideways before it left the band
    slide_steps: int = 4


def lifted_segments(
    space: SpatialSpace, segments: list[Segment], settings: LiftSettings | None = None
) -> list[Segment]:
    """``segments`` with every transfer that drags the object off or onto a support mended at that end (see the
    module docstring); the others as they are."""
    settings = settings or LiftSettings()
    if space.world.object is None:
        return segments
    out = []
    for segment in segments:
        if segment.kind != "transfer" or segment.grasp is None:
            out.append(segment)
            continue
        rel = space.grasp_rel(segment.grasp)
        waypoints = np.asarray(segment.waypoints, dtype=float)
        waypoints = _lifted_start(space, waypoints, rel, settings)
        waypoints = _lifted_start(space, waypoints[::-1], rel, settings)[::-1]
        for _ in range(settings.middles):
            mended = _lifted_middle(space, waypoints, rel, settings)
            if mended is None:
                break
            waypoints = mended
        out.append(Segment(segment.kind, segment.grasp, list(waypoints)))
    return out


def drag_free(
    space: SpatialSpace, starts: Array, ends: Array, rel: Array, settings: DragSettings | None = None
) -> NDArray[np.bool_]:
    """Whether each straight move ``starts[i] -> ends[i]`` (the object held as ``rel``) keeps from dragging it:
    no stretch near a support where it slides more than ``settings.slide_m`` (at the validator's samples)."""
    settings = settings or DragSettings()
    out = np.ones(len(starts), dtype=bool)
    for i, (a, b) in enumerate(zip(starts, ends, strict=True)):
        samples, _ = _samples(space, np.vstack([a, b]))
        poses = _matrices(space, samples, rel)
        out[i] = all(moved <= settings.slide_m for _, _, _, moved in slides(space.world, poses, settings))
    return out


def _samples(space: SpatialSpace, waypoints: Array) -> tuple[Array, NDArray[np.int64]]:
    """The validator's samples along ``waypoints`` and the piece each lies on (a junction: the later piece)."""
    robot = space.world.robot
    rows, pieces = [waypoints[:1]], [np.zeros(1, dtype=np.int64)]
    for p in range(len(waypoints) - 1):
        along = validation_samples(
            waypoints[p], waypoints[p + 1], space.validation_steps, robot.continuous, robot.lower
        )
        rows.append(along[1:])
        pieces.append(np.full(len(along) - 1, p, dtype=np.int64))
    return np.vstack(rows), np.concatenate(pieces)


def _drags(space: SpatialSpace, path: Array, rel: Array, settings: DragSettings) -> bool:
    samples, _ = _samples(space, path)
    poses = _matrices(space, samples, rel)
    return any(moved > settings.slide_m for _, _, _, moved in slides(space.world, poses, settings))


def _matrices(space: SpatialSpace, q: Array, rel: Array) -> Array:
    """The carried object's 4x4 poses at configurations ``q`` (held as ``rel``, 6 numbers)."""
    return np.asarray(space.tcp(q) @ pose_matrix([float(v) for v in rel]))


def lift_up(space: SpatialSpace, q: Array, rise: float, checker: SpatialChecker) -> Array | None:
    """The valid configuration nearest ``q`` with the tcp ``rise`` higher, its orientation kept (``None``: none)."""
    target = space.tcp(q[None])[0].copy()
    target[2, 3] += rise
    return _tcp_at(space, target, q, checker)


def _tcp_at(space: SpatialSpace, target: Array, q: Array, checker: SpatialChecker) -> Array | None:
    """The valid configuration nearest ``q`` with the tcp at ``target`` (4x4); where inverse kinematics finds
    none for the whole pose (an arm at a joint limit), one seeded at ``q`` with the tcp's turn about the vertical
    left free (the object still level, turned a little as it rises or slides: no drag); ``None``: neither."""
    found = space.ik(1).solve_many([target], np.random.default_rng(0), seeds=[q[None]], checker=checker)[0]
    if len(found):
        return np.asarray(found[np.argmin(np.abs(found - q).sum(axis=1))])
    reached, ok = space.ik(1).solve_rows(target[None], q[None], _YAW_FREE)
    if not ok[0] or not checker.valid(reached[:1])[0]:
        return None
    return np.asarray(reached[0])


def _lifted_middle(space: SpatialSpace, waypoints: Array, rel: Array, settings: LiftSettings) -> Array | None:
    """``waypoints`` with the last stretch in their middle that drags the object over a support replaced: from
    the sample before it to the sample after it, raised at both ends (straight moves, checked); ``None``
    when none drags or none can be mended so."""
    samples, piece = _samples(space, waypoints)
    poses = _matrices(space, samples, rel)
    last = len(samples) - 1
    bad = [
        s
        for s in slides(space.world, poses, settings.drag)
        if s[3] > settings.drag.slide_m and s[1] > 0 and s[2] < last
    ]
    if not bad:
        return None
    _, first, end, _ = max(bad, key=lambda s: s[1])
    a, b = samples[first - 1], samples[end + 1]
    checker = space.transfer_checker(rel)
    before, after = waypoints[: int(piece[first - 1]) + 1], waypoints[int(piece[end + 1]) + 1 :]
    for rise in settings.lifts_m:
        a_up, b_up = lift_up(space, a, rise, checker), lift_up(space, b, rise, checker)
        if a_up is None or b_up is None:
            continue
        path = np.vstack([before[-1:], a, a_up, b_up, b, after[:1]])
        if not space.clear(checker, path[:-1], path[1:]).all() or _drags(space, path[1:5], rel, settings.drag):
            continue
        return np.vstack([before, a, a_up, b_up, b, after])
    return None


def _lifted_start(space: SpatialSpace, waypoints: Array, rel: Array, settings: LiftSettings) -> Array:
    """``waypoints`` (a transfer, from where the object rests) lifting the object straight up first where they
    drag it at their start; as they are when they do not, or when no lift joins them clear."""
    if len(waypoints) < 2:
        return waypoints
    samples, piece = _samples(space, waypoints)
    poses = _matrices(space, samples, rel)
    leading = [s for s in slides(space.world, poses, settings.drag) if s[1] == 0]
    if not leading or max(s[3] for s in leading) <= settings.drag.slide_m:
        return waypoints
    leave = max(s[2] for s in leading) + 1  # the first sample out of the band
    if leave >= len(samples):
        return waypoints
    checker = space.transfer_checker(rel)
    start = samples[0]
    joins = np.unique(np.linspace(leave, len(samples) - 1, settings.joins).astype(np.int64))
    for rise in settings.lifts_m:
        up = lift_up(space, start, rise, checker)
        if up is None or not space.clear(checker, start[None], up[None])[0]:
            continue
        shift = poses[leave, :3, 3] - poses[0, :3, 3]
        shift[2] = 0.0
        for ways in ([up], slid_level(space, up, shift, settings.slide_steps, checker)):
            joined = (
                None
                if ways is None
                else _joined(
                    space, [start, *ways], waypoints, along=(samples, piece), joins=joins, rel=rel, drag=settings.drag
                )
            )
            if joined is not None:
                return joined
    return waypoints


def _joined(
    space: SpatialSpace,
    lead: list[Array],
    waypoints: Array,
    *,
    along: tuple[Array, NDArray[np.int64]],
    joins: NDArray[np.int64],
    rel: Array,
    drag: DragSettings,
) -> Array | None:
    """``lead`` (from the transfer's start, lifted) joined by a straight move to the first of the ``joins`` (of
    ``along``: :func:`_samples` of ``waypoints``) it reaches clear without dragging, then the rest of
    ``waypoints``; ``None``: none."""
    samples, piece = along
    checker = space.transfer_checker(rel)
    for k in joins.tolist():
        p = int(piece[k])
        rest = waypoints[p + 1 :]
        if len(rest) and np.allclose(rest[0], samples[k]):
            rest = rest[1:]
        path = np.vstack([*lead, samples[k]])
        ends = np.vstack([samples[k], rest[:1]])  # the join, and the part of piece p left after it
        if not space.clear(checker, np.vstack([lead[-1], samples[k]])[: len(ends)], ends).all():
            continue
        if _drags(space, path, rel, drag):
            continue
        return np.vstack([path, rest])
    return None


def slid_level(space: SpatialSpace, up: Array, shift: Array, steps: int, checker: SpatialChecker) -> list[Array] | None:
    """``up`` then the configurations moving its tcp level by ``shift`` (3,) in ``steps`` short moves, each found
    by inverse kinematics seeded at the one before and clear from it (``None``: one is not)."""
    if steps <= 0 or float(np.linalg.norm(shift)) <= 0.0:
        return None
    way = [up]
    start = space.tcp(up[None])[0]
    for i in range(1, steps + 1):
        target = start.copy()
        target[:3, 3] += shift * i / steps
        step = _tcp_at(space, target, way[-1], checker)
        if step is None or not space.clear(checker, way[-1][None], step[None])[0]:
            return None
        way.append(step)
    return way
