"""A planner for ``benchmarks.spatial_motion``'s ``--planners module:function``: the straight move, obstacles
ignored (it collides on every generated problem, so the harness must call its path invalid)."""

from __future__ import annotations

import numpy as np

from benchmarks.spatial_motion import PlannerResult
from benchmarks.spatial_scenes import MotionProblem


def straight_line(problem: MotionProblem, seed: int, time_limit_s: float) -> PlannerResult:
    """The path start -> goal in one straight joint-space piece, reported as a success."""
    del seed, time_limit_s
    return PlannerResult(True, np.array([problem.start, problem.goal]), 0.001, 0.001, 2)
