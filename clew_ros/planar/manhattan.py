"""Manhattan paths with bouncing decoded in a planar world (paper 1.3.1 and 1.3.3; the coding is
:mod:`clew_ros.core.manhattan`'s).

Before each move the free interval ``[dmin, dmax]`` of the moving joint is
computed given the moves before it (:func:`free_intervals`), and the gene is
folded into that interval (:func:`clew_ros.core.manhattan.bounce`, compiled
into the decoding kernel).

The free intervals are closed-form (circle-line and circle-circle
intersections, after Lozano-Perez 1987, which the paper cites) and computed
by the compiled kernel :mod:`clew_ros.planar.kernel`: a whole population's
paths are decoded in one call. Every angle inside an interval keeps the
clearance, continuously, so plans are valid at any checking resolution,
which is what the plan validator checks at 0.002 rad.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from clew_ros.core.manhattan import Counters, ManhattanPaths
from clew_ros.planar import kernel
from clew_ros.planar.collision import packed_world
from clew_ros.planar.kernel import BACKOFF_RAD, MAX_MOVE_RAD
from clew_ros.planar.kinematics import compose, tip_poses
from clew_ros.planar.world import World

__all__ = [
    "BACKOFF_RAD",
    "DECODING",
    "MAX_MOVE_RAD",
    "DecodingSettings",
    "free_intervals",
    "run_manhattan",
    "single_moves",
]


@dataclass(frozen=True)
class DecodingSettings:
    """How the decoding is split so that a stop request is heard."""

    #: piece pairs (count: configurations x pairs per free interval) one kernel call may check: beyond it the
    #: batch is split so that ``should_stop`` is asked often enough on huge worlds (cancel within 100 ms)
    pairs_per_call: int = 1 << 20


#: The defaults, which the functions below take unless given other settings.
DECODING = DecodingSettings()


def _mode(object_poses: np.ndarray | None, grasp_rel: np.ndarray | None) -> tuple[bool, np.ndarray]:
    if object_poses is not None and grasp_rel is None:
        return False, object_poses
    if grasp_rel is not None and object_poses is None:
        return True, grasp_rel
    raise ValueError("give exactly one of object_poses (transit) and grasp_rel (transfer)")


def free_intervals(
    world: World,
    q: np.ndarray,
    joint: int,
    *,
    object_poses: np.ndarray | None = None,
    grasp_rel: np.ndarray | None = None,
    margin_m: float = 1e-3,
    counters: Counters | None = None,
    should_stop: Callable[[], bool] | None = None,
    decoding: DecodingSettings = DECODING,
) -> tuple[np.ndarray, np.ndarray]:
    """Free interval ``[dmin, dmax]`` (rad) of ``joint`` for each configuration of ``q`` ``(B, n)``.

    Transit: give the resting object's poses ``object_poses`` ``(B, 3)``.
    Transfer: give ``grasp_rel`` ``(B, 3)``, the object's pose in the
    end-effector frame. Every angle of the interval is valid and keeps
    ``margin_m`` metres of clearance wherever the start had it;
    ``dmin <= 0 <= dmax``. ``should_stop`` is asked between chunks of huge
    batches; once it says so the remaining intervals are empty (``[0, 0]``).
    """
    q = np.asarray(q)
    if q.ndim < 2:  # one configuration (or one joint's angle): a batch of one, as np.atleast_2d
        q = q.reshape(1, -1)
    transfer, poses = _mode(object_poses, grasp_rel)
    packed = packed_world(world)
    step = max(1, decoding.pairs_per_call // packed.pairs_per_move)
    if len(q) <= step:  # the usual case: one call
        low, high = kernel.intervals(packed, q, joint, transfer, poses, margin_m)
        if counters is not None:
            counters.clearance_checks += len(q)
        return low, high
    poses = np.broadcast_to(np.asarray(poses, dtype=float), (len(q), 3))
    low, high = np.zeros(len(q)), np.zeros(len(q))
    for first in range(0, len(q), step):
        if first and should_stop is not None and should_stop():
            break
        rows = slice(first, first + step)
        low[rows], high[rows] = kernel.intervals(packed, q[rows], joint, transfer, poses[rows], margin_m)
    if counters is not None:
        counters.clearance_checks += len(q)
    return low, high


def run_manhattan(
    world: World,
    q0: np.ndarray,
    genes: np.ndarray,
    *,
    object_poses: np.ndarray | None = None,
    grasp_rel: np.ndarray | None = None,
    margin_m: float = 1e-3,
    counters: Counters | None = None,
    should_stop: Callable[[], bool] | None = None,
    threads: int = 1,
    decoding: DecodingSettings = DECODING,
) -> ManhattanPaths:
    """Decode genes ``(B, k, n)`` into collision-free Manhattan paths from ``q0`` ``(B, n)``.

    Transit when ``object_poses`` is given (the object rests there), transfer
    when ``grasp_rel`` is given (the object is carried). The whole batch is
    decoded by one compiled call, unless the world is so big that this would
    take long: then it is decoded move by move (and individuals in chunks),
    asking ``should_stop`` between calls. Once it says so, the remaining moves
    are skipped (the paths stay where they are, still collision-free), so a
    time limit or a cancel is honoured within one call. ``threads`` (0: all
    cores) spreads the individuals over threads; the paths do not depend on it.
    """
    genes = np.asarray(genes, dtype=float)
    batch, order, n = genes.shape
    transfer, poses = _mode(object_poses, grasp_rel)
    poses = np.array(np.broadcast_to(np.asarray(poses, dtype=float), (batch, 3)))
    packed = packed_world(world)
    columns = order * n + 1
    waypoints = np.empty((batch, columns, n))
    waypoints[:, 0] = q0
    per_move = packed.pairs_per_move * batch
    if should_stop is None or per_move * (columns - 1) <= decoding.pairs_per_call:
        kernel.decode(packed, waypoints, genes, 1, columns, transfer, poses, margin_m, threads)
    else:
        step = max(1, decoding.pairs_per_call // packed.pairs_per_move)
        for column in range(1, columns):
            for first in range(0, batch, step):
                if should_stop():
                    waypoints[first:, column:] = waypoints[first:, column - 1 : column]
                    waypoints[:first, column + 1 :] = waypoints[:first, column : column + 1]
                    break
                rows = slice(first, first + step)
                kernel.decode(
                    packed, waypoints[rows], genes[rows], column, column + 1, transfer, poses[rows], margin_m, threads
                )
            else:
                continue
            break
    if counters is not None:
        counters.clearance_checks += batch * (columns - 1)
    q = waypoints[:, -1]
    final_poses = compose(tip_poses(world.robot, q), poses) if transfer else poses.copy()
    return ManhattanPaths(waypoints, final_poses)


def single_moves(world: World, q: np.ndarray, moves: np.ndarray, **kwargs: Any) -> np.ndarray:
    """Apply joint moves ``moves`` ``(n,)`` one joint at a time, each clamped to its free interval.

    Returns the waypoints ``(n + 1, n)`` of the (collision-free) Manhattan path.
    Used by numeric refinement, where bouncing would undo the intended step.
    """
    q = np.array(q, dtype=float)[None]
    waypoints = [q[0].copy()]
    for joint in np.flatnonzero(np.abs(moves) > 1e-12):
        low, high = free_intervals(world, q, int(joint), **kwargs)
        q[0, joint] += float(np.clip(moves[joint], low[0], high[0]))
        waypoints.append(q[0].copy())
    return np.array(waypoints)
