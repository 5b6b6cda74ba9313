"""Random shortcuts of one segment's path, each a straight joint-space move that a ``clear`` callable
accepts (the space checks it: the planar continuous check, the spatial validator's 0.002 rad).

Points are drawn along the path (by joint travel, from the generator given) and joined straight when that is
shorter and clear; the path's ends never move (a segment's grasp and placement stay where they were), and its
joint travel only shrinks. The work is a fixed number of tries, so the same generator gives the same path; the
clock's stop test ends it early. The planar improvement draws its shortcuts in batches scored and checked by
compiled kernels instead (:mod:`clew_ros.planar.improve.shortcuts`): the same idea, specialised for speed.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

from clew_ros.core.improve.compare import joint_travel

__all__ = ["shortcut_path"]

Array = NDArray[np.float64]


def _dedupe(path: Array) -> Array:
    """``path`` without waypoints within 1e-12 rad of the one before, its last waypoint always kept."""
    keep = np.r_[True, np.max(np.abs(np.diff(path, axis=0)), axis=1) > 1e-12] if len(path) > 1 else np.ones(1, bool)
    keep[-1] = True
    return path[keep]


def _point(path: Array, cumulative: Array, s: float, steps: Array | None = None) -> tuple[int, Array]:
    """The piece index ``i`` (``path[i] -> path[i + 1]``) holding travel ``s`` and the point there; with
    ``steps`` (per joint), the nearest of the piece's own samples (``count`` evenly spaced, no joint moving
    more than its step between two: the validator's), so that each part of the piece is checked at samples
    of the whole."""
    i = int(np.clip(np.searchsorted(cumulative, s, side="right") - 1, 0, len(path) - 2))
    length = cumulative[i + 1] - cumulative[i]
    t = 0.0 if length <= 0 else (s - cumulative[i]) / length
    if steps is not None:
        count = max(1, math.ceil(float(np.max(np.abs(path[i + 1] - path[i]) / steps))))
        t = math.floor(t * count + 0.5) / count
    return i, path[i] + t * (path[i + 1] - path[i])


def shortcut_path(
    clear: Callable[[Array, Array], NDArray[np.bool_]],
    path: Array,
    *,
    tries: int,
    rng: np.random.Generator,
    stop: Callable[[], bool] | None = None,
    steps: Array | None = None,
) -> tuple[Array, int, int, bool]:
    """``path`` (m, n) shortened (``clear(starts, ends)``: whether each straight move is valid): first its two
    ends joined, then ``tries`` random shortcuts. ``steps`` (per joint: the validator's step): the shortcuts'
    ends fall on their pieces' own samples (see :func:`_point`). Returns the path, the shortcuts taken, the
    tries spent and whether ``stop()`` cut it short."""
    path = _dedupe(np.asarray(path, dtype=float))
    taken = spent = 0
    if len(path) < 3:
        return path, 0, 0, False
    if clear(path[:1], path[-1:])[0]:
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
        i, p = _point(path, cumulative, a, steps)
        j, r = _point(path, cumulative, b, steps)
        if j <= i:
            continue  # both on one straight piece: nothing to gain
        before = joint_travel([np.vstack([p, path[i + 1 : j + 1], r])])
        if np.abs(r - p).sum() >= before - 1e-9:
            continue
        # the shortcut, and (without ``steps``) the two pieces it cuts in part: a piece's validity is checked at
        # its own samples (interface.md's 0.002 rad), and a part of a piece is sampled elsewhere than the whole
        # was unless it is cut at one of them
        starts, ends = (
            (p[None], r[None]) if steps is not None else (np.stack([p, path[i], r]), np.stack([r, p, path[j + 1]]))
        )
        if not clear(starts, ends).all():
            continue
        path = _dedupe(np.vstack([path[: i + 1], p, r, path[j + 1 :]]))
        taken += 1
    return path, taken, spent, False
