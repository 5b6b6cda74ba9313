"""Proof that one transfer cannot take the object from its start to its goal: a regrasp is needed.

Held rigidly, the object keeps the last link's direction in its own frame (the approach angle
``psi``) for a whole transfer. A plan with one transfer takes some grasp at the start and leaves it
at the goal, so some ``psi`` must be possible at both. :func:`clew_ros.planar.reach.approach_cells`
says, per cell of ``psi``, when no direction in it can hold a grasp at a placement (the last joint
out of the annulus the other links sweep; the goal with its position and orientation tolerances),
and :func:`clew_ros.planar.reach.carry_cells` when the object so held cannot be carried to the goal's
position. Both bound from geometry alone, ignoring obstacles and joint limits: a cell they refuse is
impossible. When, for every grasp, no cell is allowed by all three, every plan needs two transfers
or more. On two-joint arms (one direction per elbow for each tip position) with a tight goal
orientation this is often so, as in figure1.
"""

from __future__ import annotations

from clew_ros.planar.reach import approach_cells, carry_cells
from clew_ros.planar.world import World

__all__ = ["regrasp_needed"]


def regrasp_needed(world: World) -> str | None:
    """Why no plan of ``world`` can have a single transfer (a sentence), or ``None`` when this test
    proves nothing."""
    goal = world.object.goal
    for grasp in range(len(world.object.grasps)):
        at_start = approach_cells(world, world.object.initial, grasp)
        at_goal = approach_cells(
            world, goal, grasp, angle_spread=world.goal_angle_tolerance, position_slack=world.goal_tolerance
        )
        if (at_start & at_goal & carry_cells(world, goal, grasp)).any():
            return None
    return (
        "no grasp can be held the same way at the start and at the goal (approach angles bounded by the "
        "links' reach, obstacles and joint limits ignored): every plan needs a regrasp"
    )
