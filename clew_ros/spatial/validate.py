"""The validator's check of a spatial transit path (interface.md section 1b, "A spatial configuration is valid").

:func:`validate_transit` takes joint waypoints and checks every configuration along the straight
joint-space pieces between consecutive ones, sampled so that no revolute joint moves more than
:attr:`ValidationSettings.step_rad` (0.002 rad, the contract's step) and no prismatic joint more than
:attr:`ValidationSettings.step_m` (0.001 m) between two checks, each against a
:class:`~clew_ros.spatial.checker.SpatialChecker` (joint limits, obstacles, bounds, self-collision, on
the sphere model that covers the URDF's geometry). It returns the problems found, one per piece that has
any (empty: the path is valid), each naming the piece, the first invalid configuration on it and why.
Transit only: no object is carried.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from clew_ros.spatial.checker import SpatialChecker

__all__ = ["ValidationSettings", "explain_invalid", "validate_transit", "validation_samples"]


@dataclass(frozen=True)
class ValidationSettings:
    """How finely :func:`validate_transit` samples a path."""

    #: Largest move of a revolute joint between two checked configurations (rad): the contract's 0.002.
    step_rad: float = 0.002
    #: Largest move of a prismatic joint between two checked configurations (m): the contract's 0.001.
    step_m: float = 0.001

    def __post_init__(self) -> None:
        for name in ("step_rad", "step_m"):
            value = getattr(self, name)
            if not (isinstance(value, int | float) and math.isfinite(value) and value > 0):
                raise ValueError(f"ValidationSettings.{name}: expected a positive finite number, got {value!r}")


def validation_samples(
    a: NDArray[np.float64], b: NDArray[np.float64], steps: NDArray[np.float64]
) -> NDArray[np.float64]:
    """The configurations from ``a`` to ``b`` (both included) on the straight piece between them, evenly
    spaced so that no joint moves more than its ``steps`` entry between consecutive ones."""
    count = max(1, math.ceil(float(np.max(np.abs(b - a) / steps))))
    t = np.arange(count + 1)[:, None] / count
    out: NDArray[np.float64] = a + t * (b - a)
    out[-1] = b
    return out


def explain_invalid(checker: SpatialChecker, q: NDArray[np.float64]) -> str:
    """Why ``checker`` calls configuration ``q`` invalid: a joint outside its limits, the obstacles it
    touches, a self-collision, or the bounds."""
    robot = checker.robot
    for j, name in enumerate(robot.joint_names):
        if not robot.lower[j] <= q[j] <= robot.upper[j]:
            return f"joint {name} = {q[j]:.6g} is outside its limits [{robot.lower[j]:.6g}, {robot.upper[j]:.6g}]"
    if checker.static_collision:
        return "a link no joint moves touches an obstacle or leaves the bounds"
    row = q[None]
    reasons = [
        f"touches obstacle {obstacle.name!r}"
        for obstacle in checker.obstacles
        if not SpatialChecker(robot, checker.spheres, [obstacle]).valid(row)[0]
    ]
    if not SpatialChecker(robot, checker.spheres).valid(row)[0]:
        reasons.append("a self-collision (two links not exempted touch)")
    return ", ".join(reasons) or "leaves the bounds"


def validate_transit(checker: SpatialChecker, waypoints: Any, settings: ValidationSettings | None = None) -> list[str]:
    """The problems of a transit path through ``waypoints`` (k, n) (planned joints, chain order) under
    ``checker``: one per straight piece (``piece i``: waypoints i -> i + 1) with an invalid configuration,
    naming the first. Empty: every configuration along the path is valid. One waypoint: that
    configuration alone."""
    settings = settings or ValidationSettings()
    robot = checker.robot
    try:
        path = np.asarray(waypoints, dtype=np.float64)
    except (TypeError, ValueError):
        raise ValueError(f"waypoints: expected a (k, {robot.dof}) array of joint values") from None
    if path.ndim != 2 or path.shape[1] != robot.dof or len(path) == 0 or not np.all(np.isfinite(path)):
        raise ValueError(
            f"waypoints: expected a (k, {robot.dof}) array (k >= 1) of finite joint values, got shape {path.shape}"
        )
    steps = np.where(robot.prismatic, settings.step_m, settings.step_rad)
    if len(path) == 1:
        return [] if checker.valid(path)[0] else [f"waypoint 0 is invalid: {explain_invalid(checker, path[0])}"]
    problems = []
    for i in range(len(path) - 1):
        samples = validation_samples(path[i], path[i + 1], steps)
        valid = checker.valid(samples)
        if valid.all():
            continue
        bad = int(np.flatnonzero(~valid)[0])
        where = bad / (len(samples) - 1)
        problems.append(
            f"piece {i} (waypoints {i} -> {i + 1}): configuration {np.round(samples[bad], 6).tolist()} at "
            f"{where:.1%} of the piece is invalid: {explain_invalid(checker, samples[bad])}"
        )
    return problems
