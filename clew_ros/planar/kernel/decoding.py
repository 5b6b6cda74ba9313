"""Manhattan decoding of a whole population in one compiled call: each individual's genes become its
Manhattan path, one joint move at a time within its free interval, bounced (serial and parallel)."""

from __future__ import annotations

from typing import Any

import numba
import numpy as np

from clew_ros.planar.kernel.free_intervals import _bounce, _interval, _scratch
from clew_ros.planar.kernel.jit import _jit, _leaf
from clew_ros.planar.kernel.packed import Chain, IntervalWork, Model, PackedWorld, Scene, Shape, _arg, _named, _poses


@_leaf
def _decode_one(
    b: int,
    waypoints: np.ndarray,
    genes: np.ndarray,
    first: int,
    last: int,
    transfer: bool,
    poses: np.ndarray,
    margin: float,
    model: Model,
    work: IntervalWork,
    q: np.ndarray,
) -> None:
    """Individual ``b``: fill columns ``first .. last - 1`` (>= 1) of ``waypoints[b]`` from column
    ``first - 1``: move ``c`` turns joint ``(c - 1) mod n`` by gene ``(c - 1)`` bounced into its free
    interval."""
    n = model.chain.lengths.shape[0]
    for j in range(n):
        q[j] = waypoints[b, first - 1, j]
    for column in range(first, last):
        k, joint = (column - 1) // n, (column - 1) % n
        low, high = _interval(q, joint, transfer, poses[b], margin, model, work)
        q[joint] += _bounce(genes[b, k, joint], low, high)
        for j in range(n):
            waypoints[b, column, j] = q[j]


@_jit
def _decode(
    waypoints: np.ndarray,
    genes: np.ndarray,
    first: int,
    last: int,
    transfer: bool,
    poses: np.ndarray,
    margin: float,
    world: tuple[Any, ...],
) -> None:
    """Columns ``first .. last - 1`` of every individual of ``waypoints`` ``(B, k n + 1, n)`` (genes
    ``(B, k, n)``, ``poses`` ``(B, 3)`` per individual), one after the other. ``world``:
    :attr:`~.packed.PackedWorld.plain`."""
    model = _named(world)
    q = np.empty(model.chain.lengths.shape[0])
    _decode_rows(waypoints, genes, first, last, transfer, poses, margin, model, _scratch(model), q)


@_leaf
def _decode_rows(
    waypoints: np.ndarray,
    genes: np.ndarray,
    first: int,
    last: int,
    transfer: bool,
    poses: np.ndarray,
    margin: float,
    model: Model,
    work: IntervalWork,
    q: np.ndarray,
) -> None:
    """The loop of :func:`_decode`, counting no references (:func:`~.free_intervals._interval_rows`)."""
    for b in range(waypoints.shape[0]):
        _decode_one(b, waypoints, genes, first, last, transfer, poses, margin, model, work, q)


@numba.njit(cache=True, nogil=True, parallel=True, error_model="numpy")
def _decode_parallel(
    waypoints: np.ndarray,
    genes: np.ndarray,
    first: int,
    last: int,
    transfer: bool,
    poses: np.ndarray,
    margin: float,
    world: tuple[Any, ...],
) -> None:
    """:func:`_decode` with the individuals spread over threads (each computed alone, with work arrays
    of its own: the same numbers whatever the number of threads). numba's parallel loops take arrays and
    numbers only: the world enters the loop unpacked, and is packed again for each individual."""
    (base, lengths, lower, upper), link_radius, self_collision, scene, shape, rounding = world
    bounds, edges, starts, boxes, groups = scene
    object_edges, shrunk_edges, shrunk_starts = shape
    for b in numba.prange(waypoints.shape[0]):
        model = Model(
            Chain(base, lengths, lower, upper),
            link_radius,
            self_collision,
            Scene(bounds, edges, starts, boxes, groups),
            Shape(object_edges, shrunk_edges, shrunk_starts),
            rounding,
        )
        _decode_one(
            b,
            waypoints,
            genes,
            first,
            last,
            transfer,
            poses,
            margin,
            model,
            _scratch(model),
            np.empty(lengths.shape[0]),
        )


def available_threads() -> int:
    """Threads the parallel kernel may use here: numba's thread count when a thread-safe threading
    layer (TBB or OpenMP) loads, else 1."""
    if not _PARALLEL:
        try:
            _decode_parallel(
                np.zeros((1, 2, 1)), np.zeros((1, 1, 1)), 1, 2, False, np.zeros((1, 3)), 0.0, _nothing().plain
            )
            # the workqueue layer (chosen by a user's NUMBA_THREADING_LAYER) aborts on concurrent launches
            safe = numba.threading_layer() in ("tbb", "omp")  # type: ignore[attr-defined]
            _PARALLEL.append(int(numba.config.NUMBA_NUM_THREADS) if safe else 1)  # type: ignore[attr-defined]
        except (ValueError, RuntimeError, ImportError):  # no thread-safe threading layer
            _PARALLEL.append(1)
    return _PARALLEL[0]


_PARALLEL: list[int] = []


def _nothing() -> PackedWorld:
    """A one-joint arm in an empty world: what :func:`available_threads` decodes to find the threading layer."""
    none = np.zeros((0, 2, 2))
    one = np.ones(1)
    start = np.zeros(1, np.int64)
    bounds = np.array([-9.0, -9.0, 9.0, 9.0])
    return PackedWorld(
        np.zeros(2), one, -one, one, 0.0, False, bounds, none, none, none, start, np.zeros((0, 4)), start, 0.0
    )


def decode(
    world: PackedWorld,
    waypoints: np.ndarray,
    genes: np.ndarray,
    first: int,
    last: int,
    transfer: bool,
    poses: np.ndarray,
    margin: float,
    threads: int = 1,
) -> None:
    """Compiled: columns ``first .. last - 1`` of ``waypoints`` (C-contiguous float64, filled in place),
    on ``threads`` threads (0: all); every individual is computed alone, so the numbers do not depend
    on the number of threads."""
    if threads != 1:
        threads = min(threads or available_threads(), available_threads(), len(waypoints))
    arguments = (
        waypoints,
        _arg(genes),
        first,
        last,
        transfer,
        _poses(poses, len(waypoints)),
        float(margin),
        world.plain,
    )
    if threads > 1:
        numba.set_num_threads(threads)  # for this calling thread only
        _decode_parallel(*arguments)
    else:
        _decode(*arguments)
