"""Inverse kinematics of the planar chain, over batches (damped least squares, any number of joints).

:func:`solve_point` moves configurations from given seeds until a point fixed in the end-effector
frame (the tip, or the origin of an object it holds) lies on a target, optionally with the frame's
orientation (plus a fixed offset) within a tolerance of a target angle. Damped least squares takes
small, least-norm steps, so each answer lies near its seed: a redundant arm keeps its posture
where it can. Joint limits are enforced at every step. :func:`mirrored` reflects configurations
about a line through the base: a configuration whose point lies on the line stays on it, so a
reflected seed finds the other elbow of a two-link arm. Its tuning is :class:`InverseSettings`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from clew_ros.planar import kernel
from clew_ros.planar.world import Robot

__all__ = ["FULL_TURN_RAD", "InverseSettings", "Solution", "mirrored", "solve_point"]

#: Joint limits at least this far apart (rad) let the joint turn all the way round (``full_turns``).
FULL_TURN_RAD = kernel.FULL_TURN_RAD


@dataclass(frozen=True)
class InverseSettings:
    """Tuning of :func:`solve_point` (a call's ``iterations`` and ``tolerance_m`` override the first two)."""

    #: Iterations (steps per configuration) at most: from a seed near its answer, as the planner's seeds are,
    #: damped least squares is within micrometres in well under this many.
    iterations: int = 40
    #: A configuration whose point is this close to its target (m) stops moving: far below any tolerance of a
    #: world, so a caller's own tolerance decides.
    tolerance_m: float = 1e-12
    #: Damping (m^2) of the least-squares step: keeps the step small near a singular configuration (an arm
    #: stretched out) without slowing it elsewhere.
    damping_m2: float = 1e-6
    #: Largest change of one joint in one step (rad): a step stays within the region where the arm is close to
    #: linear, and the answer near its seed.
    max_step_rad: float = 0.4


class Solution(NamedTuple):
    """What :func:`solve_point` found: configurations ``(B, n)``, the error left ``(B,)`` (m) and the steps
    taken by all of them (a measure of the work done)."""

    q: np.ndarray
    error: np.ndarray
    steps: int


def solve_point(
    robot: Robot,
    seeds: np.ndarray,
    targets: np.ndarray,
    *,
    offsets: np.ndarray | None = None,
    angles: np.ndarray | None = None,
    angle_tolerance: float = np.pi,
    angle_scale: float = 1.0,
    iterations: int | None = None,
    tolerance_m: float | None = None,
    full_turns: bool = False,
    settings: InverseSettings | None = None,
) -> Solution:
    """Configurations ``(B, n)`` from ``seeds`` ``(B, n)`` that put the point at ``offsets`` ``(B, 2)`` (default
    the tip) in the end-effector frame on ``targets`` ``(B, 2)``; with ``angles`` ``(B,)``, also the frame's
    angle within ``angle_tolerance`` of them (the angle error counts ``angle_scale`` m per rad). A
    configuration stops moving once its error is at most ``tolerance_m``, or after ``iterations`` steps (each by
    default that of ``settings``, default :class:`InverseSettings`).

    Joint limits always hold. With ``full_turns``, a joint whose limits are a whole turn apart (to 1e-3 rad, as
    worlds write +-3.14159) goes on past one a turn back from the other (the same angle, to within the gap between
    the limits): a target behind the base is reached whichever way round the seed lies (without it, a seed on the
    wrong side stops at the limit).
    Compiled (:func:`clew_ros.planar.kernel.solve_point`).
    """
    tuning = settings if settings is not None else InverseSettings()
    seeds = np.array(seeds, dtype=float, ndmin=2)
    count = len(seeds)
    q, error, steps = kernel.solve_point(
        kernel.Chain(robot.base, robot.link_lengths, robot.joint_lower, robot.joint_upper),
        np.clip(seeds, robot.joint_lower, robot.joint_upper),
        np.broadcast_to(np.asarray(targets, float), (count, 2)),
        np.zeros((count, 2)) if offsets is None else np.broadcast_to(np.asarray(offsets, float), (count, 2)),
        np.full(count, np.nan) if angles is None else np.broadcast_to(np.asarray(angles, float), (count,)),
        kernel.Solving(
            angle_tolerance=angle_tolerance,
            angle_scale=angle_scale,
            iterations=tuning.iterations if iterations is None else iterations,
            damping=tuning.damping_m2,
            max_step=tuning.max_step_rad,
            tolerance=tuning.tolerance_m if tolerance_m is None else tolerance_m,
            full_turns=full_turns,
        ),
    )
    return Solution(q, error, int(steps.sum()))


def mirrored(robot: Robot, q: np.ndarray, directions: np.ndarray) -> np.ndarray:
    """``q`` ``(B, n)`` reflected about the lines through the base at angles ``directions`` ``(B,)``: every link
    angle ``phi`` becomes ``2 direction - phi`` (joint 1 taken by whole turns into its limits, when it can be)."""
    q = np.array(q, dtype=float, ndmin=2)
    out = -q
    first = 2.0 * np.asarray(directions, float) - q[:, 0]
    lower, upper = float(robot.joint_lower[0]), float(robot.joint_upper[0])
    out[:, 0] = lower + np.mod(first - lower, 2.0 * np.pi)
    out[:, 0] = np.where(out[:, 0] > upper, first, out[:, 0])
    return out
