"""Inverse kinematics for grasps and placements: every distinct joint solution the damped least-squares
solver (:mod:`clew_ros.spatial.kernels.ik`) reaches from many seeds, within the joint limits.

A redundant arm (a Panda's 7 joints) has a continuum of solutions for one tcp pose; the solver returns a
sample of it: the converged seeds, kept when they differ from every solution kept before by more than
``distinct_rad`` on some joint. Whether a solution collides is the caller's to test (the checker).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from clew_ros.spatial.kernels import ik
from clew_ros.spatial.robot import RobotModel

__all__ = ["IkSettings", "solve_tcp_pose"]


@dataclass(frozen=True)
class IkSettings:
    """How hard the solver tries, and what it calls a solution."""

    #: Random starts (drawn uniformly within the limits): more find more of a redundant arm's solutions.
    seeds: int = 32
    #: Iterations per start: damped least squares converges in tens from a reasonable start.
    iterations: int = 150
    #: Damping (m, rad): keeps steps bounded near singular configurations, slows convergence elsewhere.
    damping: float = 0.05
    #: Largest change of one joint in one iteration (rad or m): keeps the linearisation honest.
    max_step: float = 0.3
    #: A solution puts the tcp within this distance (m) ...
    position_tolerance_m: float = 1e-4
    #: ... and this angle (rad) of the target.
    angle_tolerance_rad: float = 1e-3
    #: Two solutions are distinct when some joint differs by more than this (rad or m).
    distinct_rad: float = 1e-2


def solve_tcp_pose(
    robot: RobotModel, target: NDArray[np.float64], rng: np.random.Generator, settings: IkSettings | None = None
) -> NDArray[np.float64]:
    """Distinct joint values (k, n) that put ``robot``'s tcp at ``target`` (a 4x4 pose in ``world``), within
    the joint limits; empty (0, n) when no seed converged. Same ``rng`` state, same answer."""
    settings = settings or IkSettings()
    seeds = rng.uniform(robot.lower, robot.upper, size=(settings.seeds, robot.dof))
    out = np.empty_like(seeds)
    converged = np.zeros(len(seeds), dtype=np.bool_)
    ik.solve_tcp(
        seeds, np.ascontiguousarray(target[:3, :3]), np.ascontiguousarray(target[:3, 3]), robot.lower, robot.upper,
        np.ascontiguousarray(robot.base[:3, :3]), np.ascontiguousarray(robot.base[:3, 3]),
        np.ascontiguousarray(robot.origins[:, :3, :3]), np.ascontiguousarray(robot.origins[:, :3, 3]),
        np.ascontiguousarray(robot.axes), robot.prismatic, robot.tcp_frame, np.ascontiguousarray(robot.tcp[:3, :3]),
        np.ascontiguousarray(robot.tcp[:3, 3]), settings.iterations, settings.damping, settings.max_step,
        settings.position_tolerance_m, settings.angle_tolerance_rad, out, converged,
    )  # fmt: skip
    kept: list[NDArray[np.float64]] = []
    for q in out[converged]:
        if all(np.max(np.abs(q - other)) > settings.distinct_rad for other in kept):
            kept.append(q)
    return np.array(kept).reshape(-1, robot.dof)
