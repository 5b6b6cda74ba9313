"""Necessary conditions that spare hopeless searches.

Each function answers "could this possibly succeed?" from geometry alone,
ignoring joint limits and everything it cannot bound: ``False`` means a search
would fail whatever it tried, ``True`` means nothing. SEARCH_TRANSIT and
SEARCH_TRANSFER ask them first, because a search that cannot succeed costs as
much as a successful one (it runs every generation before giving up).
"""

from __future__ import annotations

import numpy as np

from clew_ros.core.kinematics import compose, relative
from clew_ros.core.world import World

__all__ = ["within_reach", "goal_within_reach"]


def within_reach(world: World, point: np.ndarray, slack: float = 0.0, lengths: np.ndarray | None = None) -> bool:
    """Whether the chain's end could be at ``point``: inside the annulus its links ``lengths``
    (default the robot's) sweep about the base."""
    lengths = world.robot.link_lengths if lengths is None else lengths
    distance = float(np.hypot(*(np.asarray(point) - world.robot.base)))
    inner = max(0.0, 2.0 * float(lengths.max()) - float(lengths.sum()))
    return inner - slack <= distance <= float(lengths.sum()) + slack


def goal_within_reach(world: World, grasp_rel: np.ndarray, goal: np.ndarray) -> bool:
    """Whether the object, held as ``grasp_rel``, could be at the goal.

    Held rigidly, the object's origin is a point of the last link's frame, so
    it sweeps the annulus of the chain whose last link ends there instead of at
    the tip. Also some goal orientation within tolerance must put the tip in
    reach.
    """
    grasp_rel = np.asarray(grasp_rel, float)
    lengths = np.array(world.robot.link_lengths, dtype=float)
    lengths[-1] = np.hypot(lengths[-1] + grasp_rel[0], grasp_rel[1])
    if not within_reach(world, goal[:2], world.goal_tolerance, lengths):
        return False
    span = min(world.goal_angle_tolerance, np.pi)
    thetas = goal[2] + np.linspace(-span, span, 65)
    poses = np.stack([np.full_like(thetas, goal[0]), np.full_like(thetas, goal[1]), thetas], axis=1)
    tips = compose(poses, relative(grasp_rel, np.zeros(3)))[:, :2]  # end effector in the object frame
    slack = world.goal_tolerance + world.grasp_tolerance
    return any(within_reach(world, tip, slack) for tip in tips)
