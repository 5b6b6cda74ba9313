"""SEARCH_TRANSFER's way in: when the genetic algorithm stalls near the goal, join it by RRT-Connect.

SEARCH_TRANSFER minimises the object's distance to the goal in the workspace.
Where the goal lies in a pocket, behind a block or among clutter, that
distance has a local minimum at the way in: the carried object ends a few
centimetres from the goal, pressed against what separates them, and the
landmark is wasted. In configuration space the way in is often short.

So when SEARCH_TRANSFER ends within :data:`JOIN_RADIUS` (a fraction of the
arm's reach) of the goal without reaching it, :func:`join_goal` looks for a
path in the same mode, the object held the same way:

1. **Goal configurations**: inverse kinematics
   (:func:`clew_ros.core.inverse.solve_point`) puts the carried object within
   the goal's tolerances, from the stalled configuration and from
   :data:`GOAL_SEEDS` - 1 random ones (other postures, the other elbow); the
   valid ones are kept.
2. **RRT-Connect** (:func:`clew_ros.core.connect.rrt_connect`) from the stalled
   configuration to any of them (a tree rooted at each), every extension a
   straight joint-space move checked continuously with at least half the
   clearance (:func:`clew_ros.core.improve.straight_move_clear`, as the
   improvement's moves), at most :data:`ROUNDS` rounds; then shortened.

The path found extends the transfer, which then ends at the goal: valid at
any checking resolution, and drawn from the planner's generator with its
work bounded by rounds, so the same seed gives the same plan. It departs
from the paper, whose SEARCH is the optimisation alone (docs/algorithm.md).
"""

from __future__ import annotations

import numpy as np

from clew_ros.core.collision import is_valid
from clew_ros.core.connect import rrt_connect, shortened
from clew_ros.core.improve import MIN_MARGIN_FACTOR, straight_move_clear
from clew_ros.core.inverse import solve_point
from clew_ros.core.kinematics import compose, tip_poses
from clew_ros.core.search import PlanningContext, goal_error, goal_reached

__all__ = ["GOAL_SEEDS", "JOIN_RADIUS", "ROUNDS", "goal_configurations", "join_goal"]

#: SEARCH_TRANSFER ending closer to the goal than this fraction of the arm's reach (m / m) tries to join it.
JOIN_RADIUS = 0.3
#: Seeds of the inverse kinematics for the goal configurations: the stalled configuration and random ones.
GOAL_SEEDS = 8
#: Rounds of RRT-Connect at most (each extends one tree a step, and the other as far as it is clear).
ROUNDS = 60


def goal_configurations(ctx: PlanningContext, q0: np.ndarray, grasp_rel: np.ndarray, goal: np.ndarray) -> np.ndarray:
    """Valid configurations ``(m, n)`` holding the object (as ``grasp_rel``) within the goal's tolerances, as
    SEARCH_TRANSFER's success asks, nearest ``q0`` first; from :data:`GOAL_SEEDS` seeds (``q0`` and random)."""
    world = ctx.world
    robot = world.robot
    drawn = ctx.rng.uniform(robot.joint_lower, robot.joint_upper, (GOAL_SEEDS - 1, robot.dof))
    seeds = np.vstack([np.asarray(q0, float)[None], drawn])
    grasp_rel = np.asarray(grasp_rel, float)
    within = np.pi if world.goal_angle_tolerance >= np.pi - 1e-6 else 0.8 * world.goal_angle_tolerance
    # the goal's own angle (the middle of the tolerance: clear of the walls of a pocket, when an arm can hold
    # it there) and anywhere within the tolerance (for an arm that cannot)
    q = np.vstack(
        [
            solve_point(
                robot,
                seeds,
                np.asarray(goal[:2], float)[None],
                offsets=grasp_rel[None, :2],
                angles=np.array([goal[2] - grasp_rel[2]]),
                angle_tolerance=tolerance,
                angle_scale=world.object.radius,
                tolerance_m=0.1 * world.goal_tolerance,
            ).q
            for tolerance in (0.0, within)
        ]
    )
    poses = compose(tip_poses(robot, q), grasp_rel)
    close = np.linalg.norm(goal_error(world, poses, goal), axis=1) <= 0.5 * world.goal_tolerance
    held = np.array([bool(c) and goal_reached(world, pose, goal) for c, pose in zip(close, poses, strict=True)])
    if held.any():
        held[held] = is_valid(world, q[held], poses[held])
    found = q[held][np.argsort(np.max(np.abs(q[held] - q0), axis=1), kind="stable")]
    distinct = [i for i in range(len(found)) if not any(np.max(np.abs(found[i] - found[:i]), axis=1) < 1e-3)]
    kept: np.ndarray = found[distinct]
    return kept


def join_goal(ctx: PlanningContext, q0: np.ndarray, grasp_rel: np.ndarray, goal: np.ndarray) -> np.ndarray | None:
    """Waypoints ``(m, n)`` from ``q0`` to a configuration holding the object (carried as ``grasp_rel``) at the
    goal, every move checked continuously; ``None`` when none was found (module docstring)."""
    world = ctx.world
    goals = goal_configurations(ctx, q0, grasp_rel, goal)
    if not len(goals):
        return None
    margin = MIN_MARGIN_FACTOR * ctx.settings.clearance

    def clear(a: np.ndarray, b: np.ndarray) -> bool:
        return straight_move_clear(world, a, b, grasp_rel=grasp_rel, min_margin=margin)

    path = rrt_connect(
        clear,
        np.asarray(q0, float),
        goals,
        ctx.rng,
        limits=(world.robot.joint_lower, world.robot.joint_upper),
        rounds=ROUNDS,
        stop=ctx.termination,
    )
    return None if path is None else shortened(clear, path, ctx.termination)
