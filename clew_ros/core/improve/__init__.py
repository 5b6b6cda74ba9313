"""The improvement's parts that are generic over a space: what any space's improvement of a found plan uses.

The planar improvement (:mod:`clew_ros.planar.improve`) and the spatial one
(:meth:`clew_ros.spatial.space.SpatialSpace.improve`) both build on these; what they check and how (the planar
continuous check, the spatial validator's samples), what a check costs and the stages beyond shortcuts stay in
the spaces.

=============== ==========================================================================================
``compare``     joint travel, a plan's score and which plan is better (fewer transfers, then joint travel)
``budget``      the work budget: units spent and left, shares, the reserve, the clock's stop test
``prune``       pruning that needs no checking: collinear waypoints, loops, regrasps in place joined
``shortcuts``   random shortcuts of one segment with a ``clear`` callable
=============== ==========================================================================================
"""

from __future__ import annotations

from clew_ros.core.improve.budget import RoutingShare, WorkBudget, WorkCosts
from clew_ros.core.improve.compare import PathPiece, Score, better, joint_travel, plan_score
from clew_ros.core.improve.prune import JoinablePiece, joined_regrasps, pruned_path, without_repeats
from clew_ros.core.improve.shortcuts import shortcut_path

__all__ = [
    "JoinablePiece",
    "PathPiece",
    "RoutingShare",
    "Score",
    "WorkBudget",
    "WorkCosts",
    "better",
    "joined_regrasps",
    "joint_travel",
    "plan_score",
    "pruned_path",
    "shortcut_path",
    "without_repeats",
]
