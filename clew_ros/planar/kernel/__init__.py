"""The compiled kernels of the planar world (numba), one module per concern.

They take the world packed once into arrays (:func:`clew_ros.planar.collision.packed_world`,
:class:`PackedWorld`) and read it as a few named tuples (:mod:`~clew_ros.planar.kernel.packed`: the arm's chain,
the scene, the object's shape, the mode, the tuning, the scratch), never objects, so that no kernel takes more than
12 arguments; they loop over whole batches and release the GIL. What
:mod:`clew_ros.core.manhattan` describes is computed here, one compiled call per batch.

=============================================  =======================================================================
module                                         what it holds
=============================================  =======================================================================
:mod:`~clew_ros.planar.kernel.jit`             numba's options for every kernel, the threading layer
:mod:`~clew_ros.planar.kernel.packed`          :class:`PackedWorld`, the named tuples the kernels take
:mod:`~clew_ros.planar.kernel.segments`        a point's distance to a segment, an edge placed at a pose
:mod:`~clew_ros.planar.kernel.kinematics`      forward kinematics (:func:`chain`), inverse (:func:`solve_point`)
:mod:`~clew_ros.planar.kernel.contacts`        contact angles of a turning point against a stadium
:mod:`~clew_ros.planar.kernel.free_intervals`  the free interval of one joint (:func:`intervals`), bouncing
:mod:`~clew_ros.planar.kernel.decoding`        Manhattan paths of a whole population (:func:`decode`)
:mod:`~clew_ros.planar.kernel.validity`        the validity test's first pass (:func:`clearly_valid`)
:mod:`~clew_ros.planar.kernel.moves`           straight moves (:func:`moves_clear`), :func:`screen_routes`
:mod:`~clew_ros.planar.kernel.rrt_connect`     RRT-Connect's rounds (:func:`connect_rounds`)
:mod:`~clew_ros.planar.kernel.path_shortcuts`  :func:`shortcuts`: random shortcuts scored in batches
:mod:`~clew_ros.planar.kernel.lattice`         the lattice's A*, Dijkstra costs and repair, regrasp totals
:mod:`~clew_ros.planar.kernel.warmup`          :func:`warm_up`: every kernel compiled before the first plan
=============================================  =======================================================================

The names below are the kernels' public face; import them from here.
"""

from __future__ import annotations

from clew_ros.planar.kernel.decoding import available_threads, decode
from clew_ros.planar.kernel.free_intervals import BACKOFF_RAD, MAX_MOVE_RAD, bounce_array, intervals
from clew_ros.planar.kernel.kinematics import FULL_TURN_RAD, chain, solve_point
from clew_ros.planar.kernel.lattice import (
    EDGE_BLOCKED,
    EDGE_CLEAR,
    EDGE_UNKNOWN,
    lattice_costs,
    lattice_path,
    lattice_repair,
    lattice_search,
    release_totals,
)
from clew_ros.planar.kernel.moves import moves_clear, screen_routes
from clew_ros.planar.kernel.packed import Chain, MoveCheck, PackedWorld, Rounds, Solving, Trees
from clew_ros.planar.kernel.path_shortcuts import shortcuts
from clew_ros.planar.kernel.rrt_connect import connect_rounds
from clew_ros.planar.kernel.validity import clearly_valid
from clew_ros.planar.kernel.warmup import warm_up

__all__ = [
    "BACKOFF_RAD",
    "EDGE_BLOCKED",
    "EDGE_CLEAR",
    "EDGE_UNKNOWN",
    "FULL_TURN_RAD",
    "MAX_MOVE_RAD",
    "Chain",
    "MoveCheck",
    "PackedWorld",
    "Rounds",
    "Solving",
    "Trees",
    "available_threads",
    "bounce_array",
    "chain",
    "clearly_valid",
    "connect_rounds",
    "decode",
    "intervals",
    "lattice_costs",
    "lattice_path",
    "lattice_repair",
    "lattice_search",
    "moves_clear",
    "release_totals",
    "screen_routes",
    "shortcuts",
    "solve_point",
    "warm_up",
]
