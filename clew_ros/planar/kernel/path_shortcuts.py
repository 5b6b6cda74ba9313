"""The improvement's path kernel: scoring batches of random shortcuts (straight between two waypoints or points,
or one joint evened out), the planar improvement's batched specialisation of
:func:`clew_ros.core.improve.shortcut_path` (the pruning of a path is generic:
:func:`clew_ros.core.improve.pruned_path`)."""

from __future__ import annotations

import numpy as np

from clew_ros.planar.kernel.jit import _leaf
from clew_ros.planar.kernel.packed import _arg


@_leaf
def _shortcuts(
    w: np.ndarray,
    draws: np.ndarray,
    cumulative: np.ndarray,
    first: np.ndarray,
    last: np.ndarray,
    paths: np.ndarray,
    gain: np.ndarray,
    fewer: np.ndarray,
) -> None:
    """:func:`shortcuts` into ``cumulative`` (scratch: the path's joint travel up to each waypoint),
    ``first``, ``last``, ``paths``, ``gain``, ``fewer``."""
    m, n = w.shape
    cumulative[0] = 0.0
    for i in range(1, m):
        cumulative[i] = cumulative[i - 1]
        for c in range(n):
            cumulative[i] += abs(w[i, c] - w[i - 1, c])
    pieces = paths.shape[1] - 2
    for k in range(draws.shape[0]):
        joined = draws[k, 0] < 1.0 / 3.0  # two waypoints joined straight
        partial = draws[k, 0] >= 2.0 / 3.0
        if joined:
            one = min(int(draws[k, 3] * m), m - 1)
            other = min(int(draws[k, 4] * (m - 1)), m - 2)
            other += other >= one  # distinct
            i, j = min(one, other), max(one, other)
            u0, u1 = cumulative[i], cumulative[j]
            start, end = i, j - 1
            _put(paths, k, 0, w, cumulative, i, u0)  # the waypoints themselves, not rounded
            _put(paths, k, pieces + 1, w, cumulative, j, u1)
        else:
            u0 = cumulative[m - 1] * min(draws[k, 1], draws[k, 2])
            u1 = cumulative[m - 1] * max(draws[k, 1], draws[k, 2])
            start, end = _piece_at(cumulative, u0), _piece_at(cumulative, u1)
            _put(paths, k, 0, w, cumulative, start, u0)
            _put(paths, k, pieces + 1, w, cumulative, end, u1)
        first[k], last[k] = start, end
        moved = min(int(draws[k, 5] * n), n - 1) if partial else -1
        _between(paths, k, w, cumulative, start, end, u0, u1, moved)
        replaces = end > start and not (partial and end - start > pieces)
        gain[k] = (u1 - u0) - _path_travel(paths, k) if replaces else -np.inf
        fewer[k] = replaces and (joined or (not partial and end - start > 2))  # as long, fewer waypoints


@_leaf
def _put(paths: np.ndarray, k: int, row: int, w: np.ndarray, cumulative: np.ndarray, piece: int, at: float) -> None:
    """``paths[k, row]`` = the point ``at`` (joint travel along the path ``w``) on ``piece`` (``w[piece]``
    itself when ``at`` is where the piece starts)."""
    span = cumulative[piece + 1] - cumulative[piece] if piece + 1 < cumulative.shape[0] else 0.0
    share = (at - cumulative[piece]) / span if span > 0 else 0.0
    for c in range(w.shape[1]):
        paths[k, row, c] = w[piece, c] if share == 0.0 else w[piece, c] + share * (w[piece + 1, c] - w[piece, c])


@_leaf
def _between(
    paths: np.ndarray,
    k: int,
    w: np.ndarray,
    cumulative: np.ndarray,
    start: int,
    end: int,
    u0: float,
    u1: float,
    moved: int,
) -> None:
    """The rows of ``paths[k]`` between its ends: the last one repeated (a straight shortcut, ``moved`` -1),
    or the path's waypoints ``start + 1 .. end``, padded with the last, joint ``moved`` evened out along them."""
    pieces = paths.shape[1] - 2
    stretch = max(u1 - u0, 1e-300)
    for p in range(pieces):
        inner = min(start + 1 + p, end)
        for c in range(w.shape[1]):
            if moved < 0:
                paths[k, 1 + p, c] = paths[k, pieces + 1, c]
            elif c == moved:
                a, b = paths[k, 0, c], paths[k, pieces + 1, c]
                paths[k, 1 + p, c] = a + (cumulative[inner] - u0) / stretch * (b - a)
            else:
                paths[k, 1 + p, c] = w[inner, c]


@_leaf
def _path_travel(paths: np.ndarray, k: int) -> float:
    """Joint travel along ``paths[k]`` (rad)."""
    travel = 0.0
    for p in range(paths.shape[1] - 1):
        for c in range(paths.shape[2]):
            travel += abs(paths[k, p + 1, c] - paths[k, p, c])
    return travel


@_leaf
def _piece_at(cumulative: np.ndarray, travel: float) -> int:
    """The piece of a path (by its cumulative joint travel) that the point ``travel`` along it lies on."""
    last: int = cumulative.shape[0] - 2
    low, high = 0, last + 2  # the first index whose cumulative travel is above ``travel``
    while low < high:
        middle = (low + high) // 2
        if cumulative[middle] <= travel:
            low = middle + 1
        else:
            high = middle
    return min(max(low - 1, 0), last)


def shortcuts(
    waypoints: np.ndarray, draws: np.ndarray, pieces: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Shortcuts of the path ``waypoints`` ``(m, n)``, one per row of ``draws`` ``(K, 6)`` (uniform in
    ``[0, 1)``). Column 0 picks the kind: below a third, two distinct waypoints (columns 3 and 4) joined
    straight; below two thirds, two points along the path (columns 1 and 2: shares of its joint travel)
    joined straight; else between those two points, one joint (column 5) evened out along the path while the
    others move as before. Returns ``first``, ``last`` (the pieces the two points lie on), ``paths`` ``(K,
    pieces + 2, n)`` (the first point, the path's waypoints in between padded with the last of them, and the
    last point), ``gain`` (joint travel saved; -inf when nothing is replaced, or when a partial one spans more
    than ``pieces`` pieces) and ``fewer`` (a straight one that drops waypoints: as long, it is still better).
    Compiled: :mod:`clew_ros.planar.improve` scores batches of them."""
    w, draws = _arg(waypoints), _arg(draws)
    m, n = w.shape
    if m < 2 or draws.ndim != 2 or draws.shape[1] != 6:
        raise ValueError(f"waypoints, draws: expected (m >= 2, n) and (K, 6) arrays, got {w.shape}, {draws.shape}")
    count = len(draws)
    first, last = np.empty(count, dtype=np.int64), np.empty(count, dtype=np.int64)
    paths, gain, fewer = np.empty((count, int(pieces) + 2, n)), np.empty(count), np.empty(count, dtype=np.bool_)
    _shortcuts(w, draws, np.empty(m), first, last, paths, gain, fewer)
    return first, last, paths, gain, fewer
