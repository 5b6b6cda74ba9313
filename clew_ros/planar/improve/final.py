"""The final check of an improved plan at the validator's step (its work is reserved from the budget as segments
change) and what it refuses."""

from __future__ import annotations

import numpy as np

from clew_ros.planar.continuous import CHECK_STEP_RAD, path_valid
from clew_ros.planar.improve.pieces import _Piece
from clew_ros.planar.search import goal_reached
from clew_ros.planar.world import World


def _dense_count(waypoints: np.ndarray) -> int:
    """Configurations the validator's check of a path takes (:data:`CHECK_STEP_RAD` per joint at most)."""
    if len(waypoints) < 2:
        return 1
    steps = np.ceil(np.max(np.abs(np.diff(waypoints, axis=0)), axis=1) / CHECK_STEP_RAD)
    return 1 + int(np.maximum(steps, 1).sum())


def _dense_clear(world: World, piece: _Piece) -> bool:
    """The validator's check of one segment."""
    if piece.grasp_rel is None:
        return path_valid(world, piece.waypoints, object_pose=piece.start_pose)
    return path_valid(world, piece.waypoints, grasp_rel=piece.grasp_rel)


def _refusal(world: World, changed: list[_Piece | None], final: np.ndarray, goal: np.ndarray) -> str:
    """What the final checks find wrong with an improved plan, "" when nothing: a changed segment not clear at
    the validator's step, or the object off the goal. Every step checks what it builds, so either is a fault;
    the first plan is returned then, and the plan's stats name the fault (``improve_refused``)."""
    if any(p is not None and not _dense_clear(world, p) for p in changed):
        return "a changed segment collides at the validator's step"
    if not goal_reached(world, final, goal):
        return "the object ends off the goal"
    return ""
