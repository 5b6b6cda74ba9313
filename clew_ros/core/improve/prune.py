"""Pruning that needs no checking: what is left of a path or a plan only visits configurations it already
visited, with the object where it already was, so it is valid wherever the first one was.

- :func:`pruned_path`: repeated waypoints, loops back to an earlier waypoint and waypoints between collinear
  pieces (a move undone or continued along the same line) dropped from a waypoint path (compiled: the planar
  improvement prunes every shortcut it tries, and plans of many joints have hundreds of waypoints);
- :func:`without_repeats`: only the repeats dropped;
- :func:`joined_regrasps`: a transfer put down and taken again by the same grasp without the arm moving made one
  transfer.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Protocol, Self, TypeVar

import numba
import numpy as np

from clew_ros.core.improve.compare import PathPiece

if TYPE_CHECKING:
    from numba.core.decorators import _JITWrapper  # in numba's type stubs only

__all__ = ["JoinablePiece", "joined_regrasps", "pruned_path", "without_repeats"]

# numba's options as the spaces' kernels use them (cached on disk, no GIL, numpy's error model); the kernel
# allocates nothing, so it is compiled without reference counting.
_leaf: _JITWrapper = numba.njit(  # type: ignore[call-overload]  # numba's stubs leave out its underscored options
    cache=True, nogil=True, fastmath=False, error_model="numpy", _nrt=False
)


@_leaf
def _pruned(waypoints: np.ndarray, points: np.ndarray) -> int:
    """:func:`pruned_path` into ``points`` (as large as ``waypoints``); returns how many it kept."""
    n = waypoints.shape[1]
    size = 0
    for k in range(waypoints.shape[0]):
        back = -1  # the first point kept so far that this one is back at (a loop)
        for i in range(size):
            largest = 0.0
            for j in range(n):
                largest = max(largest, abs(points[i, j] - waypoints[k, j]))
            if largest <= 1e-12:
                back = i
                break
        if back >= 0:
            size = back + 1
        else:
            for j in range(n):
                points[size, j] = waypoints[k, j]
            size += 1
        while size >= 3:  # the last three collinear (a move undone or continued): drop the middle one
            scale = 0.0
            uv = 0.0
            vv = 0.0
            for j in range(n):
                u = points[size - 2, j] - points[size - 3, j]
                v = points[size - 1, j] - points[size - 2, j]
                scale = max(scale, abs(u), abs(v))
                uv += u * v
                vv += v * v
            off = 0.0
            for j in range(n):
                u = points[size - 2, j] - points[size - 3, j]
                v = points[size - 1, j] - points[size - 2, j]
                off = max(off, abs(u * vv - v * uv))
            if scale > 0 and off > 1e-12 * scale**3:
                break
            for j in range(n):
                points[size - 2, j] = points[size - 1, j]
            size -= 1
    return size


def pruned_path(waypoints: np.ndarray) -> np.ndarray:
    """``waypoints`` ``(m, n)`` without repeated waypoints, loops back to an earlier waypoint (within 1e-12
    rad), and waypoints between collinear pieces (a move undone or continued along the same line): the path
    left only visits configurations the old one visited, starts where it started and ends within 1e-12 rad of
    where it ended (a loop back ends on the earlier waypoint), and is never longer in joint travel."""
    if not (isinstance(waypoints, np.ndarray) and waypoints.dtype == np.float64 and waypoints.flags.carray):
        waypoints = np.array(waypoints, dtype=np.float64, order="C")  # one compiled version: C-contiguous float64
    if waypoints.ndim != 2:
        raise ValueError(f"waypoints: expected an (m, n) array, got shape {waypoints.shape}")
    points = np.empty_like(waypoints)
    return points[: _pruned(waypoints, points)].copy()


def without_repeats(waypoints: Sequence[np.ndarray] | np.ndarray) -> np.ndarray:
    """``waypoints`` without those within 1e-12 rad (each joint) of the one before."""
    points = np.array(waypoints, dtype=float)
    moved = np.max(np.abs(np.diff(points, axis=0)), axis=1) > 1e-12
    kept: np.ndarray = points[np.concatenate([[True], moved])]
    return kept


class JoinablePiece(PathPiece, Protocol):
    """A piece that can be copied with other waypoints, everything else it carries kept (:func:`joined_regrasps`
    gives the joined transfer what the first of the two carried: where the object was when it started, how it
    is held)."""

    def with_waypoints(self, waypoints: np.ndarray) -> Self: ...


PieceT = TypeVar("PieceT", bound=JoinablePiece)


def joined_regrasps(pieces: Sequence[PieceT], same_rad: float) -> list[PieceT]:
    """``pieces`` with each transfer that is put down and taken again by the same grasp without the arm moving
    (a transit of no joint travel between two transfers of one grasp) made one transfer: the arm and the
    object move exactly as before, the object held the same way (the tool and the object did not move in
    between), so nothing needs checking, and the plan has one transfer fewer. Configurations within ``same_rad``
    (rad, largest joint difference) count as the same."""
    joined: list[PieceT] = []
    for piece in pieces:
        if len(joined) >= 2 and piece.kind == "transfer" and [p.kind for p in joined[-2:]] == ["transfer", "transit"]:
            carried, still = joined[-2], joined[-1]
            junction = np.vstack([carried.waypoints[-1:], still.waypoints, piece.waypoints[:1]])
            if piece.grasp == carried.grasp and float(np.abs(junction - junction[0]).max()) <= same_rad:
                joined[-2:] = [carried.with_waypoints(np.vstack([carried.waypoints, piece.waypoints[1:]]))]
                continue
        joined.append(piece)
    return joined
