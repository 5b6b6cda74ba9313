"""The configurations SEARCH aims at: those holding a grasp of the resting object (:func:`holds`, a transit's
targets) and those holding the object at the goal (:func:`goal_configurations`, a transfer's), from inverse
kinematics drawing from generators of each request's own."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from clew_ros.core.search import own_generator
from clew_ros.core.space import Mode, PlanningContext
from clew_ros.spatial.checker import SpatialChecker
from clew_ros.spatial.space_parts import SpaceParts, cache_key
from clew_ros.spatial.transforms import inverse_matrix, matrices, turned_about_z
from clew_ros.spatial.ways import way_out

__all__ = ["GOAL_STREAM", "HOLD_STREAM", "goal_configurations", "goal_poses", "holds", "movable_first"]

Array = NDArray[np.float64]

#: The holding configurations' inverse kinematics draws from a generator seeded with (planner.seed, this,
#: the request): the same request gets the same sample, and the run's stream is left as it was.
HOLD_STREAM = 21
#: The goal configurations' inverse kinematics: its own stream too.
GOAL_STREAM = 22


def holds(parts: SpaceParts, ctx: PlanningContext, q0: Array, object_pose: Array, grasp: int) -> Array:
    """Configurations (m, n) holding ``grasp`` with the object at ``object_pose``, valid in transit and
    in transfer, nearest ``q0`` first (joint travel)."""
    target = matrices(object_pose)[0] @ parts.grasps[grasp]
    rng = own_generator(ctx, HOLD_STREAM, q0, np.r_[object_pose, grasp])
    found = parts.ik(ctx.hold_samples).solve(target, rng, seeds=q0[None], checker=parts.transit_checker(object_pose))
    if len(found):
        found = parts.nearest_turns(q0, found[parts.transfer_checker(parts.grasp_rel(grasp)).valid(found)])
    ordered: Array = found[np.argsort(np.abs(found - q0).sum(axis=1), kind="stable")]
    return movable_first(parts, ordered, object_pose, grasp)


def movable_first(parts: SpaceParts, found: Array, object_pose: Array, grasp: int) -> Array:
    """``found`` (holding configurations, nearest first) without those of the first
    :attr:`SpatialTuning.hold_way_out_checks` whose way out carries the object less than
    :attr:`SpatialTuning.approach_m`, where one of them carries it that far; as they are where the nearest does
    (one way out measured) or none does."""
    tuning = parts.tuning
    if not len(found) or tuning.hold_way_out_checks <= 0:
        return found
    rel = parts.grasp_rel(grasp)
    checker = parts.transfer_checker(rel)
    far = np.zeros(min(len(found), tuning.hold_way_out_checks), dtype=bool)
    for k in range(len(far)):
        far[k] = _carried_out_m(parts, checker, rel, object_pose, found[k]) >= tuning.approach_m - 1e-9
        if k == 0 and far[0]:
            return found
    if not far.any():
        return found
    kept: Array = np.vstack([found[: len(far)][far], found[len(far) :]])
    return kept


def _carried_out_m(parts: SpaceParts, checker: SpatialChecker, grasp_rel: Array, object_pose: Array, q: Array) -> float:
    """How far (m) the object held as ``grasp_rel`` from ``q`` gets by its way out
    (:func:`~clew_ros.spatial.ways.way_out`), once per grasp, placement and configuration."""
    return _out_m(parts, checker, grasp_rel, q, cache_key(grasp_rel, object_pose, q))


def _out_m(parts: SpaceParts, checker: SpatialChecker, grasp_rel: Array, q: Array, key: bytes) -> float:
    """How far (m) the object held as ``grasp_rel`` from ``q`` gets by its way out, cached under ``key``."""
    if key not in parts.way_out_lengths:
        rel = np.asarray(grasp_rel, dtype=float)
        way = way_out(parts, checker, Mode.held(rel[None]), q)
        held = parts.held_object_poses(np.vstack([q[None], q[None] if way is None else way[-1:]]), rel)
        parts.way_out_lengths[key] = float(np.linalg.norm(held[1, :3] - held[0, :3]))
    return parts.way_out_lengths[key]


def goal_configurations(parts: SpaceParts, ctx: PlanningContext, q0: Array, grasp_rel: Array, goal: Array) -> Array:
    """Valid configurations (m, n) holding the object (as ``grasp_rel``) at the goal (:func:`goal_poses`): those
    of the goal poses the object gets farthest out of by its way out (:func:`_way_out_m`, to the cm) first, then
    nearest ``q0``; inverse kinematics seeded at ``q0`` and ``SearchSettings.goal_seeds`` random starts drawn
    from a generator of the request's own."""
    rng = own_generator(ctx, GOAL_STREAM, q0, np.r_[grasp_rel, goal])
    back = inverse_matrix(matrices(grasp_rel)[0])
    tcp_goals = [pose @ back for pose in goal_poses(parts, goal)]
    checker = parts.transfer_checker(grasp_rel)
    solutions = parts.ik(ctx.search.goal_seeds).solve_many(
        tcp_goals, rng, seeds=[q0[None]] * len(tcp_goals), checker=checker
    )
    found = parts.nearest_turns(q0, np.vstack(solutions))
    travel = np.abs(found - q0).sum(axis=1)
    pose_of = np.repeat(np.arange(len(solutions)), [len(s) for s in solutions])
    out_m = np.zeros(len(solutions))
    for k in np.unique(pose_of).tolist():
        rows = np.flatnonzero(pose_of == k)
        out_m[k] = _way_out_m(parts, checker, grasp_rel, goal, pose=k, q=found[rows[np.argmin(travel[rows])]])
    order = np.lexsort((travel, -np.round(out_m[pose_of], 2)))
    ordered: Array = found[order]
    return ordered


def _way_out_m(
    parts: SpaceParts, checker: SpatialChecker, grasp_rel: Array, goal: Array, *, pose: int, q: Array
) -> float:
    """How far (m) the object held as ``grasp_rel`` at the goal pose ``pose`` (:func:`goal_poses`' index) gets
    by its way out (:func:`~clew_ros.spatial.ways.way_out`) from ``q``, once per grasp, goal and pose: a hand
    that can only lift its object a little in a cubby (its slide out meets a wall) comes in that way no more."""
    return _out_m(parts, checker, grasp_rel, q, cache_key(grasp_rel, goal, np.array([float(pose)])))


def goal_poses(parts: SpaceParts, goal: Array) -> list[Array]:
    """The goal placement (4x4) turned about world z through its centre by each of
    :attr:`SpatialTuning.goal_yaws` within ``world.goal_angle_tolerance`` (the goal's own first): every
    one of them reaches the goal."""
    tolerance = parts.world.tolerances["goal_angle_tolerance"]
    return turned_about_z(matrices(goal)[0], parts.tuning.goal_yaws, tolerance)
