"""The warm-up: one call that compiles every kernel (or loads it from numba's on-disk cache) before the
first plan, so no plan waits for the compiler."""

from __future__ import annotations

import numpy as np

from clew_ros.core.improve import pruned_path
from clew_ros.planar.kernel.decoding import decode
from clew_ros.planar.kernel.free_intervals import bounce_array, intervals
from clew_ros.planar.kernel.kinematics import chain, solve_point
from clew_ros.planar.kernel.lattice import lattice_costs, lattice_repair, lattice_search, release_totals
from clew_ros.planar.kernel.moves import moves_clear, screen_routes
from clew_ros.planar.kernel.packed import MoveCheck, PackedWorld, Rounds, Solving, Trees
from clew_ros.planar.kernel.path_shortcuts import shortcuts
from clew_ros.planar.kernel.rrt_connect import connect_rounds
from clew_ros.planar.kernel.validity import clearly_valid

_WARMED_IN_S: list[float] = []  # how long the first warm-up took, once it is done


def warm_up() -> float:
    """Compile every kernel (or load them from numba's on-disk cache) before the first plan.

    Returns the seconds the first call took (later calls do nothing). numba
    caches next to this module when the package directory is writable, else
    in a per-user cache directory (``NUMBA_CACHE_DIR`` overrides both).
    """
    if _WARMED_IN_S:
        return _WARMED_IN_S[0]
    import time

    start = time.perf_counter()
    world = PackedWorld(
        np.zeros(2),
        np.ones(2),
        -np.pi * np.ones(2),
        np.pi * np.ones(2),
        0.01,
        True,
        np.array([-3.0, -3.0, 3.0, 3.0]),
        np.array([[[1.0, 1.0], [1.2, 1.0]]]),
        np.array([[[0.1, 0.0], [0.0, 0.1]]]),
        np.zeros((0, 2, 2)),
        np.array([0, 1]),
        np.array([[1.0, 1.0, 1.2, 1.0]]),
        np.array([0]),
        1e-9,
    )
    waypoints = np.zeros((1, 3, 2))
    genes = np.zeros((1, 1, 2))
    for transfer in (False, True):
        decode(world, waypoints, genes, 1, 3, transfer, np.zeros(3), 1e-3)
        decode(world, waypoints, genes, 1, 3, transfer, np.zeros(3), 1e-3, threads=0)
        intervals(world, waypoints[:, 0], 0, transfer, np.zeros(3), 1e-3)
    bounce_array(np.zeros(1), np.zeros(1), np.ones(1))
    pruned_path(np.zeros((3, 2)))
    shortcuts(np.eye(3, 2), np.linspace(0.0, 0.9, 18).reshape(3, 6), 8)
    clearly_valid(world, waypoints[:, 0], np.zeros(3))
    moving = {"min_margin": 1e-3, "max_margin": 0.05, "coarse_stride": 4}
    for held in (None, np.zeros(3)):
        at_rest = np.zeros(3) if held is None else None
        moves_clear(world, waypoints[:, 0], waypoints[:, 1] + 0.1, resting=at_rest, grasp_rel=held, **moving)  # type: ignore[arg-type]
        poses = np.zeros((1, 3))
        screen_routes(
            world,
            waypoints[:, 0],
            waypoints[:, 1] + 0.1,
            np.full(1, 8),
            resting=poses if held is None else None,
            grasp_rel=None if held is None else poses,
        )
        nodes, parents = np.zeros((2, 8, 2)), np.full((2, 8), -1, dtype=np.int64)
        connect_rounds(
            world,
            Trees(nodes, parents, np.ones(2, dtype=np.int64)),
            np.zeros(4, dtype=np.int64),
            np.zeros((1, 2)),
            Rounds(step_rad=0.35, allowed=1.0, check_work=1.0, round_work=1.0),
            resting=at_rest,
            grasp_rel=held,
            check=MoveCheck(**moving),  # type: ignore[arg-type]
        )
    for angles in (np.zeros(1), np.full(1, np.nan)):
        solving = Solving(
            angle_tolerance=0.1,
            angle_scale=1.0,
            iterations=2,
            damping=1e-6,
            max_step=0.4,
            tolerance=0.0,
            full_turns=False,
        )
        solve_point(world.model.chain, waypoints[:, 0], np.ones((1, 2)), np.zeros((1, 2)), angles, solving)
    chain(world.base, world.lengths, waypoints[:, 0])
    lattice_search(
        np.full(2, 3, dtype=np.int64),
        np.zeros(2),
        1.0,
        np.zeros((9, 2), dtype=np.uint8),
        np.zeros(1, dtype=np.int64),
        np.zeros(1),
        np.full(1, 8, dtype=np.int64),
        np.zeros(1),
        np.full(2, 2.0),
        np.inf,
    )
    counts, edges, sources, source_costs = (
        np.full(2, 3, dtype=np.int64),
        np.zeros((9, 2), dtype=np.uint8),
        np.zeros(1, dtype=np.int64),
        np.zeros(1),
    )
    cost, previous, _ = lattice_costs(counts, 1.0, edges, sources, source_costs, np.inf)
    lattice_repair(counts, 1.0, edges, sources, source_costs, np.inf, cost, previous)
    corners = np.zeros((2, 1, 4), dtype=np.int64)
    release_totals(cost, cost, sources, np.zeros((2, 1)), corners, np.zeros((2, 1, 4)))
    _WARMED_IN_S.append(time.perf_counter() - start)
    return _WARMED_IN_S[0]
