"""SEARCH in a spatial world: the jobs of SEARCH_TRANSIT (the tcp's pose error to the grasp) and SEARCH_TRANSFER
(the object's distance to the goal placement), run by :func:`clew_ros.core.search.local_search`.

Both get configurations meeting their target from inverse kinematics (:mod:`clew_ros.spatial.targets`) as
``toward`` (the greedy Manhattan probe) and ``straight`` (straight joint-space moves, checked at the validator's
0.002 rad: :func:`clew_ros.spatial.ways.way`) targets, and try those straight moves again from where the search
ended. A SEARCH_TRANSFER whose GA did not reach the goal grows the motion-only search's two trees
(:func:`transfer_trees`); one that ends in the air sets the object down where it got to, or is cut back to its
last resting waypoint."""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Protocol

import numpy as np
from numpy.typing import NDArray

from clew_ros.core.search import SearchJob, local_search, object_at, own_generator
from clew_ros.core.space import Mode, PathResult, PlanningContext, TransitRequest
from clew_ros.core.tree import Landmark, LandmarkTree
from clew_ros.spatial.distances import at_goal, goal_distance
from clew_ros.spatial.motion_plan import MotionSpace, add_branch, connect
from clew_ros.spatial.settle import rests, settle
from clew_ros.spatial.space_parts import SpaceParts, cache_key
from clew_ros.spatial.targets import goal_configurations, holds
from clew_ros.spatial.transforms import matrices, rotation_vectors
from clew_ros.spatial.ways import way, way_out

__all__ = [
    "CARRY_STREAM",
    "TRANSFER_TREES_STREAM",
    "SearchSpace",
    "carried_out_then_in",
    "search_transfer",
    "search_transits",
    "straight_probe",
]

Array = NDArray[np.float64]

#: A failed SEARCH_TRANSFER's two trees (:func:`transfer_trees`): their own stream (core.search.own_generator).
TRANSFER_TREES_STREAM = 23
#: The object carried out and in through a drawn configuration (:func:`carried_out_then_in`): its own stream.
CARRY_STREAM = 24


class SearchSpace(MotionSpace, Protocol):
    """What SEARCH asks of the spatial space (:class:`clew_ros.spatial.space.SpatialSpace`): the motion-only
    search's space (its trees join a transfer to the goal), the parts it shares, and whether decoded transfers
    end in the air, unsettled (:attr:`SpatialTuning.search_in_air`, inside SEARCH_TRANSFER)."""

    parts: SpaceParts
    in_air: bool


def pose_errors(transforms: Array, target: Array, weight: float) -> Array:
    """(B, 6): position error (m) and ``weight`` x rotation vector (m) of transforms (B, 4, 4) to ``target``."""
    dp = transforms[:, :3, 3] - target[:3, 3]
    rv = rotation_vectors(np.einsum("ji,bjk->bik", target[:3, :3], transforms[:, :3, :3]))
    return np.concatenate([dp, weight * rv], axis=1)


def search_transits(space: SearchSpace, ctx: PlanningContext, requests: list[TransitRequest]) -> list[PathResult]:
    """SEARCH_TRANSIT for each request: the tcp's pose error to the grasp minimised, the object at rest; a
    success holds the grasp within :attr:`SpatialTuning.hold_tolerance_m` / ``_rad``."""
    parts = space.parts
    tuning = parts.tuning
    results: list[PathResult | None] = []
    jobs: list[SearchJob] = []
    slots: list[int] = []
    targets: list[Array] = []
    weight = tuning.angle_weight_m
    for start, resting, grasp, _approach in requests:
        q0 = np.asarray(start, dtype=float)
        object_pose = np.asarray(resting, dtype=float)
        found = holds(parts, ctx, q0, object_pose, grasp)
        if not len(found):
            results.append(PathResult(False, q0[None], math.inf))
            continue
        target = matrices(object_pose)[0] @ parts.grasps[grasp]

        def error(q: Array, target: Array = target) -> Array:
            return pose_errors(parts.tcp(q), target, weight)

        def objective(q: Array, _poses: Array, error: Callable[[Array], Array] = error) -> Array:
            e = error(q)
            out: Array = np.linalg.norm(e[:, :3], axis=1) + np.linalg.norm(e[:, 3:], axis=1)
            return out

        slots.append(len(results))
        results.append(None)
        targets.append(found)
        jobs.append(
            SearchJob(
                q0,
                objective,
                error,
                accept=1e-7,
                mode=Mode.resting(object_pose[None]),
                toward=found[0],
                straight=found[: tuning.straight_probes],
            )
        )
    if jobs:
        answers = local_search(ctx, jobs)
        for slot, job, found, (searched, _value) in zip(slots, jobs, targets, answers, strict=True):
            waypoints = _finish(parts, ctx, job, searched, found)
            grasp = requests[slot][2]
            e = job.error(waypoints[-1:])[0]
            success = bool(
                np.linalg.norm(e[:3]) <= tuning.hold_tolerance_m
                and np.linalg.norm(e[3:]) / weight <= tuning.hold_tolerance_rad
            )
            distance = float(np.linalg.norm(e))
            results[slot] = PathResult(
                success, waypoints, distance, grasp_rel=parts.grasp_rel(grasp) if success else None
            )
    return [r for r in results if r is not None]


def _finish(parts: SpaceParts, ctx: PlanningContext, job: SearchJob, waypoints: Array, targets: Array) -> Array:
    """A search's waypoints, ended by straight moves (:func:`way`) to the nearest target they reach from its
    end (none: as they were)."""
    end = waypoints[-1]
    if ctx.termination() or not len(targets):
        return waypoints
    if np.min(np.max(np.abs(targets - end), axis=1)) < 1e-9:
        return waypoints
    order = np.argsort(np.abs(targets - end).sum(axis=1), kind="stable")
    found = way(parts, job.mode, end, targets[order], far=True)
    return waypoints if found is None else np.vstack([waypoints, found])


def search_transfer(
    space: SearchSpace, ctx: PlanningContext, q0: np.ndarray, grasp_rel: np.ndarray, goal: np.ndarray
) -> PathResult:
    """SEARCH_TRANSFER: the object held as ``grasp_rel`` carried from ``q0`` towards the goal placement; its
    path ends with the object resting (at the goal on success)."""
    parts = space.parts
    tuning = parts.tuning
    q0 = np.asarray(q0, dtype=float)
    rel = np.asarray(grasp_rel, dtype=float)
    goal = np.asarray(goal, dtype=float)
    found = goal_configurations(parts, ctx, q0, rel, goal)
    if not len(found) and tuning.hopeless_transfers:
        start = parts.held_object_poses(q0[None], rel)
        return PathResult(False, q0[None], float(goal_distance(parts, start, goal)[0]), object_pose=start[0])
    weight = tuning.angle_weight_m
    target = matrices(goal)[0]

    def error(q: Array) -> Array:
        return pose_errors(parts.tcp(q) @ matrices(rel)[0], target, weight)

    def objective(_q: Array, object_poses: Array) -> Array:
        return goal_distance(parts, object_poses, goal)

    job = SearchJob(
        q0,
        objective,
        error,
        accept=1e-7,
        mode=Mode.held(rel[None]),
        toward=found[0] if len(found) else None,
        straight=found[: tuning.straight_probes] if len(found) else None,
    )
    space.in_air = tuning.search_in_air
    try:
        waypoints, _ = local_search(ctx, [job])[0]
    finally:
        space.in_air = False
    waypoints = _finish(parts, ctx, job, waypoints, found)
    held = parts.held_object_poses(waypoints, rel)
    if not at_goal(parts, held[-1], goal) and len(found) and not ctx.termination():
        rng = own_generator(ctx, CARRY_STREAM, q0, np.r_[rel, goal])
        out_and_in = carried_out_then_in(parts, q0, rel, found, rng)
        if out_and_in is not None:
            waypoints, held = out_and_in, parts.held_object_poses(out_and_in, rel)
    if not at_goal(parts, held[-1], goal):
        joined = transfer_trees(space, ctx, q0, rel, goal, found=found, searched=waypoints)
        if joined is not None:
            waypoints, held = joined, parts.held_object_poses(joined, rel)
    if not at_goal(parts, held[-1], goal) and not rests(parts.world, held[-1]):
        settled, ok = settle(parts, parts.transfer_checker(rel), rel, waypoints[-1:])
        if ok[0]:  # the search's end set down where it got to (the closest attempt, for SEARCH's chain)
            waypoints = np.vstack([waypoints, settled])
            held = parts.held_object_poses(waypoints, rel)
    if not at_goal(parts, held[-1], goal):
        resting = [i for i in range(len(waypoints)) if rests(parts.world, held[i])]
        last = resting[-1] if resting else 0  # (the start rests)
        waypoints, held = waypoints[: last + 1], held[: last + 1]
    success = at_goal(parts, held[-1], goal)
    distance = float(goal_distance(parts, held[-1:], goal)[0])
    return PathResult(success, waypoints, 0.0 if success else distance, object_pose=held[-1])


def carried_out_then_in(
    parts: SpaceParts, q0: Array, grasp_rel: Array, found: Array, rng: np.random.Generator
) -> Array | None:
    """The object (held as ``grasp_rel``) carried out of where it rests at ``q0`` by its way out
    (:func:`~clew_ros.spatial.ways.way_out`: out of a bin, a cubby or a shelf), then by straight moves to the
    first goal configuration ``found`` it reaches (:func:`~clew_ros.spatial.ways.way`: directly, by its
    approach or slid in); else to the end of the way out of one of the first two of ``found``, through one
    of :attr:`SpatialTuning.carry_vias` valid configurations drawn from ``rng`` (a long swing of the arm's
    first joints that a straight move cannot make), and in along it. ``None`` where none is clear; the
    waypoints from ``q0``."""
    rel = np.asarray(grasp_rel, dtype=float)
    mode = Mode.held(rel[None])
    checker = parts.transfer_checker(rel)
    out = way_out(parts, checker, mode, q0)
    if out is None:
        return None
    into = way(parts, mode, out[-1], found)
    if into is not None:
        return np.vstack([out, into])
    robot = parts.world.robot
    vias = rng.uniform(robot.lower, robot.upper, size=(parts.tuning.carry_vias, robot.dof))
    vias = vias[checker.valid(vias)]
    for target in found[:2]:
        back = way_out(parts, checker, mode, target)
        if back is None or not len(vias):
            continue
        ends = np.broadcast_to(back[-1], vias.shape)
        through = parts.clear(checker, np.broadcast_to(out[-1], vias.shape), vias) & parts.clear(checker, vias, ends)
        if through.any():
            return np.vstack([out, vias[int(np.argmax(through))][None], back[::-1]])
    return None


def transfer_trees(
    space: SearchSpace,
    ctx: PlanningContext,
    q0: Array,
    grasp_rel: Array,
    goal: Array,
    *,
    found: Array,
    searched: Array | None = None,
) -> Array | None:
    """When SEARCH_TRANSFER's GA did not reach the goal: the motion-only search's two trees of landmarks
    (:func:`clew_ros.spatial.motion_plan.connect`: EXPLORE for transfer paths, the object carried as
    ``grasp_rel``) given :attr:`SpatialTuning.transfer_tree_landmarks` steps; the path from ``q0`` to the
    goal, or ``None``. One tree is rooted at ``q0``, with the GA's path ``searched`` (from ``q0``, the
    object in the air) and the object's way out from there (:func:`~clew_ros.spatial.ways.way_out`) as
    landmarks; the other at the goal configuration nearest ``q0`` (``found``:
    :func:`~clew_ros.spatial.targets.goal_configurations`), with its way out as a landmark, and kept for the
    later SEARCH_TRANSFERs of the same grasp and goal (:func:`goal_tree`), which grow it further: where the
    object rests in a shelf, single-joint moves from the root barely move it."""
    parts = space.parts
    budget = parts.tuning.transfer_tree_landmarks
    if budget <= 0 or not len(found) or ctx.termination():
        return None
    rel = np.asarray(grasp_rel, dtype=float)
    rng = own_generator(ctx, TRANSFER_TREES_STREAM, q0, np.r_[rel, goal])
    mode = Mode.held(rel[None])
    checker = parts.transfer_checker(rel)
    tree = goal_tree(parts, rel, goal)
    if tree is None:
        tree = parts.goal_trees[cache_key(rel, goal)] = LandmarkTree(found[0], np.zeros(6))
        root: Landmark | None = tree[0]
    else:  # a goal configuration with a way in that the tree's roots may lack
        roots = [k for k in range(len(tree)) if tree[k].parent is None]
        apart = parts.tuning.transfer_goal_apart_rad
        root = None
        if len(roots) < parts.tuning.transfer_goal_roots and all(
            np.max(np.abs(found[0] - tree[k].joints)) >= apart for k in roots
        ):
            root = tree.add(
                parent=None, joints=found[0].copy(), object_pose=np.zeros(6), grasp=None, grasp_rel=None,
                transit=None, transfer=None,
            )  # fmt: skip
    if root is not None:
        out_of_goal = way_out(parts, checker, mode, found[0])
        if out_of_goal is not None:
            add_branch(tree, root.id, out_of_goal)
    ways = [way_out(parts, checker, mode, q0)]
    if searched is not None and len(searched) > 1 and np.max(np.abs(searched[-1] - q0)) > 0:
        ways.append(searched)
    return connect(
        space,
        ctx,
        q0,
        found[0],
        mode=mode,
        checker=checker,
        landmarks=budget,
        rng=rng,
        goal_tree=tree,
        start_ways=[w for w in ways if w is not None],
    )


def goal_tree(parts: SpaceParts, grasp_rel: Array, goal: Array) -> LandmarkTree | None:
    """The goal tree :func:`transfer_trees` keeps for the object held as ``grasp_rel`` and set down at
    ``goal`` (``None``: none grown yet)."""
    return parts.goal_trees.get(cache_key(np.asarray(grasp_rel, dtype=float), np.asarray(goal, dtype=float)))


def straight_probe(
    parts: SpaceParts,
    ctx: PlanningContext,
    jobs: list[SearchJob],
    q: np.ndarray,
    best: np.ndarray,
    *,
    waypoints: list[list[np.ndarray]],
) -> None:
    """Each job with ``straight`` targets tries straight moves to them (:func:`way`); kept where it gets
    closer."""
    for i, job in enumerate(jobs):
        if job.straight is None or not len(job.straight) or ctx.termination():
            continue
        found = way(parts, job.mode, q[i], job.straight)
        if found is None:
            continue
        reached = found[-1]
        value = float(job.objective(reached[None], object_at(ctx, reached[None], job.mode))[0])
        if value < best[i]:
            waypoints[i].append(found.copy())
            q[i] = reached
            best[i] = value
