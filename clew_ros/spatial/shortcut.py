"""The spatial plans' improvement: shortcuts between points of a segment, each checked at the validator's
resolution, taken only when shorter.

Within each segment (a transit with the object at rest where it lies then, a transfer holding it), points
are drawn along the path (by joint travel, from the run's improvement generator) and joined by a straight
joint-space move when every configuration the validator would check on it is valid under that segment's
checker; the segment's ends never move (the grasp, the placement). Joint travel (the sum over joints of
the absolute motion) only shrinks: a straight move is never longer than the path it replaces. The work is
a fixed number of tries per segment (:attr:`~clew_ros.spatial.space.SpatialTuning.shortcut_tries`), so the
same seed gives the same plan; the time limit or a cancel stops it early.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from clew_ros.core.space import Improvement, PlanningContext
from clew_ros.core.tree import Segment

if TYPE_CHECKING:
    from clew_ros.spatial.checker import SpatialChecker
    from clew_ros.spatial.space import SpatialSpace

__all__ = ["shortcut_path", "shortcut_segments"]

Array = NDArray[np.float64]


def _travel(path: Array) -> float:
    return float(np.abs(np.diff(path, axis=0)).sum()) if len(path) > 1 else 0.0


def _dedupe(path: Array) -> Array:
    keep = np.r_[True, np.max(np.abs(np.diff(path, axis=0)), axis=1) > 1e-12] if len(path) > 1 else np.ones(1, bool)
    keep[-1] = True
    return path[keep]


def _point(path: Array, cumulative: Array, s: float) -> tuple[int, Array]:
    """The piece index ``i`` (``path[i] -> path[i + 1]``) holding travel ``s`` and the point there."""
    i = int(np.clip(np.searchsorted(cumulative, s, side="right") - 1, 0, len(path) - 2))
    length = cumulative[i + 1] - cumulative[i]
    t = 0.0 if length <= 0 else (s - cumulative[i]) / length
    return i, path[i] + t * (path[i + 1] - path[i])


def shortcut_path(
    space: SpatialSpace,
    checker: SpatialChecker,
    path: Array,
    *,
    tries: int,
    rng: np.random.Generator,
    stop: Callable[[], bool] | None = None,
) -> tuple[Array, int, int, bool]:
    """``path`` (m, n) shortened: first its two ends joined, then ``tries`` random shortcuts. Returns the
    path, the shortcuts taken, the tries spent and whether ``stop()`` cut it short."""
    path = _dedupe(np.asarray(path, dtype=float))
    taken = spent = 0
    if len(path) < 3:
        return path, 0, 0, False
    if space.clear(checker, path[:1], path[-1:])[0]:
        return np.array([path[0], path[-1]]), 1, 1, False
    for _ in range(tries):
        if stop is not None and stop():
            return path, taken, spent, True
        spent += 1
        cumulative = np.r_[0.0, np.cumsum(np.abs(np.diff(path, axis=0)).sum(axis=1))]
        total = cumulative[-1]
        if total <= 0 or len(path) < 3:
            break
        a, b = np.sort(rng.uniform(0.0, total, size=2))
        i, p = _point(path, cumulative, a)
        j, r = _point(path, cumulative, b)
        if j <= i:
            continue  # both on one straight piece: nothing to gain
        before = _travel(np.vstack([p, path[i + 1 : j + 1], r]))
        if np.abs(r - p).sum() >= before - 1e-9:
            continue
        if not space.clear(checker, p[None], r[None])[0]:
            continue
        path = _dedupe(np.vstack([path[: i + 1], p, r, path[j + 1 :]]))
        taken += 1
    return path, taken, spent, False


def shortcut_segments(
    space: SpatialSpace, ctx: PlanningContext, segments: list[Segment], object_pose: Array
) -> Improvement:
    """The plan's segments shortcut (the module's docstring); ``object_pose``: where the object ends."""
    first_travel = sum(_travel(np.array(s.waypoints)) for s in segments)
    transfers = sum(s.kind == "transfer" for s in segments)
    if ctx.settings.improve_time <= 0:
        return Improvement(segments, object_pose, first_travel, transfers, first_travel, transfers, 0, 0, False)
    resting = space.initial_object_pose
    out: list[Segment] = []
    shortcuts = work = 0
    stopped = False
    for segment in segments:
        path = np.array(segment.waypoints)
        if segment.kind == "transfer":
            assert segment.grasp is not None
            rel = space.grasp_rel(segment.grasp)
            checker = space.transfer_checker(rel)
        else:
            rel = None
            checker = space.transit_checker(resting)
        if not stopped:
            path, taken, spent, stopped = shortcut_path(
                space, checker, path, tries=space.tuning.shortcut_tries, rng=ctx.rng, stop=ctx.termination
            )
            shortcuts += taken
            work += spent
        out.append(Segment(segment.kind, segment.grasp, list(path)))
        if rel is not None:
            resting = space.held_object_poses(path[-1:], rel)[0]
    travel = sum(_travel(np.array(s.waypoints)) for s in out)
    if travel > first_travel:  # (never: each shortcut is shorter than what it replaces)
        return Improvement(segments, object_pose, first_travel, transfers, first_travel, transfers, 0, work, stopped)
    return Improvement(out, object_pose, first_travel, transfers, travel, transfers, shortcuts, work, stopped)
