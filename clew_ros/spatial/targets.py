"""The configurations SEARCH aims at: those holding a grasp of the resting object (:func:`holds`, a transit's
targets) and those holding the object at the goal (:func:`goal_configurations`, a transfer's), from inverse
kinematics drawing from generators of each request's own."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from clew_ros.core.search import own_generator
from clew_ros.core.space import PlanningContext
from clew_ros.spatial.space_parts import SpaceParts
from clew_ros.spatial.transforms import inverse_matrix, matrices, rpy_matrix

__all__ = ["GOAL_STREAM", "HOLD_STREAM", "goal_configurations", "goal_poses", "holds"]

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
    return ordered


def goal_configurations(parts: SpaceParts, ctx: PlanningContext, q0: Array, grasp_rel: Array, goal: Array) -> Array:
    """Valid configurations (m, n) holding the object (as ``grasp_rel``) at the goal (:func:`goal_poses`),
    nearest ``q0`` first: inverse kinematics seeded at ``q0`` and ``SearchSettings.goal_seeds`` random
    starts drawn from a generator of the request's own."""
    rng = own_generator(ctx, GOAL_STREAM, q0, np.r_[grasp_rel, goal])
    back = inverse_matrix(matrices(grasp_rel)[0])
    tcp_goals = [pose @ back for pose in goal_poses(parts, goal)]
    solutions = parts.ik(ctx.search.goal_seeds).solve_many(
        tcp_goals, rng, seeds=[q0[None]] * len(tcp_goals), checker=parts.transfer_checker(grasp_rel)
    )
    found = parts.nearest_turns(q0, np.vstack(solutions))
    ordered: Array = found[np.argsort(np.abs(found - q0).sum(axis=1), kind="stable")]
    return ordered


def goal_poses(parts: SpaceParts, goal: Array) -> list[Array]:
    """The goal placement (4x4) turned about world z through its centre by each of
    :attr:`SpatialTuning.goal_yaws` within ``world.goal_angle_tolerance`` (the goal's own first): every
    one of them reaches the goal."""
    base = matrices(goal)[0]
    tolerance = parts.world.tolerances["goal_angle_tolerance"]
    out = []
    for yaw in parts.tuning.goal_yaws:
        if abs(yaw) <= tolerance + 1e-12:
            turned = base.copy()
            turned[:3, :3] = rpy_matrix(0.0, 0.0, yaw) @ base[:3, :3]
            out.append(turned)
    return out
