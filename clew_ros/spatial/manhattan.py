"""Manhattan paths in a spatial world (paper 1.3.1, 1.3.3): each move bounced
(:func:`clew_ros.core.manhattan.bounce`) into its joint's free interval from
:meth:`SpatialChecker.free_intervals` (one compiled call per joint move and per distinct mode in the batch: a
resting pose in transit, a grasp in transfer, each with its own checker, cached); a decoded transfer ends with
the object set down (:func:`clew_ros.spatial.settle.settle`) or, where it cannot be, stays at its start."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

from clew_ros.core.manhattan import Counters, ManhattanPaths, bounce
from clew_ros.core.space import Mode
from clew_ros.spatial.checker import SpatialChecker
from clew_ros.spatial.settle import settle
from clew_ros.spatial.space_parts import SpaceParts

__all__ = ["decode", "single_moves"]

Array = NDArray[np.float64]


def _groups(parts: SpaceParts, rows: Array, transfer: bool) -> list[tuple[SpatialChecker, np.ndarray]]:
    """The batch's rows grouped by their mode's pose, each with its checker (first-seen order)."""
    keys = np.round(rows, 9)
    _, first, inverse = np.unique(keys, axis=0, return_index=True, return_inverse=True)
    inverse = inverse.reshape(-1)
    out = []
    for u in np.argsort(first):
        idx = np.flatnonzero(inverse == u)
        pose = rows[idx[0]]
        out.append((parts.transfer_checker(pose) if transfer else parts.transit_checker(pose), idx))
    return out


def decode(
    parts: SpaceParts,
    q0: Array,
    genes: Array,
    mode: Mode,
    *,
    counters: Counters | None,
    should_stop: Callable[[], bool] | None,
    in_air: bool,
) -> ManhattanPaths:
    """Genes (B, k, n) decoded from ``q0`` (B, n) in ``mode``: each move bounced into its joint's free interval; a
    transfer then sets the object down (unless ``in_air``: SEARCH_TRANSFER's ends stay in the air). The
    waypoints are (B, k n + 2, n): the moves, then the settled end (a repeat of the last move's in transit)."""
    genes = np.asarray(genes, dtype=float)
    count, order, n = genes.shape
    q = np.array(q0, dtype=float).reshape(count, n)
    transfer = mode.transfer
    modes = np.asarray(mode.poses, dtype=float).reshape(-1, 6)
    modes = np.broadcast_to(modes, (count, 6))
    groups = _groups(parts, modes, transfer)
    way = np.empty((count, order * n + 2, n))
    way[:, 0] = q
    for step in range(order * n):
        r, j = divmod(step, n)
        if j == 0 and r > 0 and should_stop is not None and should_stop():
            way[:, step + 1 :] = q[:, None]
            break
        for checker, idx in groups:
            move = genes[idx, r, j]
            # searched only as far as the move and its fold reach: the same fold as over the whole interval,
            # unless a path folds twice (then it folds inside the reach, as free)
            lo, hi, ok = checker.free_intervals(q[idx], j, parts.tuning.intervals, move=move + np.copysign(1e-9, move))
            moved = bounce(q[idx, j] + move, lo, hi)
            q[idx, j] = np.where(ok, moved, q[idx, j])
        if counters is not None:
            counters.clearance_checks += count
        way[:, step + 1] = q
    way[:, -1] = way[:, -2]
    if transfer:
        for checker, idx in groups:
            if in_air:
                break  # SEARCH_TRANSFER's ends stay in the air: search_transfer sets its last one down
            settled, ok = settle(parts, checker, modes[idx[0]], way[idx, -2])
            way[idx[ok], -1] = settled[ok]
            way[idx[~ok]] = way[idx[~ok], :1]  # no stable end: the path stays where the object rests
        held = parts.held_object_poses(way[:, -1], modes)
        return ManhattanPaths(way, held)
    return ManhattanPaths(way, np.array(modes, dtype=float))


def single_moves(q: Array, moves: Array, *, checker: SpatialChecker, counters: Counters | None) -> Array:
    """Joint moves ``(n,)`` applied one joint at a time, each clamped to its free interval (``checker``): the
    waypoints ``(m, n)``."""
    current = np.array(q, dtype=float)
    out = [current.copy()]
    for j in np.flatnonzero(np.abs(moves) > 0.0):
        lo, hi, ok = checker.free_intervals(current[None], int(j), reach=abs(float(moves[j])) + 1e-9)
        if counters is not None:
            counters.clearance_checks += 1
        if not ok[0]:
            break
        current[j] = float(np.clip(current[j] + moves[j], lo[0], hi[0]))
        out.append(current.copy())
    return np.array(out)
