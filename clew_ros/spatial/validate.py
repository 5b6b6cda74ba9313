"""The validator's check of a spatial path (interface.md section 1b, "A spatial configuration is valid").

:func:`validate_transit` takes joint waypoints and checks every configuration along the straight
joint-space pieces between consecutive ones (a continuous joint the short way round), sampled so that no
revolute joint moves more than :attr:`ValidationSettings.step_rad` (0.002 rad, the contract's step) and no
prismatic joint more than :attr:`ValidationSettings.step_m` (0.001 m) between two checks, each against a
:class:`~clew_ros.spatial.checker.SpatialChecker` (joint limits, obstacles, bounds, self-collision, on
the URDF's exact geometry: the sphere models first, coal where they cannot settle it). It returns the
problems found, one per piece that has any (empty: the path is valid), each naming the piece, the first
invalid configuration on it and why.
The checker says what the object does: resting where it lies (a transit) or held (a transfer, with
:class:`~clew_ros.spatial.checker.Held`); :func:`explain_invalid` names the held object's collisions too.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
from numpy.typing import NDArray

from clew_ros.spatial.checker import Held, SpatialChecker
from clew_ros.spatial.scene import Obstacle
from clew_ros.spatial.turns import short_way, wrapped

__all__ = ["ValidationSettings", "explain_invalid", "validate_transit", "validation_samples"]


@dataclass(frozen=True)
class ValidationSettings:
    """How finely :func:`validate_transit` samples a path."""

    #: Largest move of a revolute joint between two checked configurations (rad): the contract's 0.002.
    step_rad: float = 0.002
    #: Largest move of a prismatic joint between two checked configurations (m): the contract's 0.001.
    step_m: float = 0.001
    #: How far (rad, m) a segment's first waypoint may be from where the previous one ended (or from
    #: ``world.robot.initial``), and a motion-only plan's end from ``world.robot.goal``: the contract's 1e-6.
    match_rad: float = 1e-6
    #: How far ``final_object_pose`` may be from the replayed pose (m, and rad of rotation): the contract's 1e-4.
    pose_match: float = 1e-4
    #: How far a motion-only plan's last tcp may be from ``world.robot.goal_pose`` (m, and rad of rotation):
    #: the contract's 0.001 m and 0.01 rad.
    goal_pose_m: float = 0.001
    goal_pose_rad: float = 0.01

    def __post_init__(self) -> None:
        for name in ("step_rad", "step_m", "match_rad", "pose_match", "goal_pose_m", "goal_pose_rad"):
            value = getattr(self, name)
            if not (isinstance(value, int | float) and math.isfinite(value) and value > 0):
                raise ValueError(f"ValidationSettings.{name}: expected a positive finite number, got {value!r}")


def validation_samples(
    a: NDArray[np.float64],
    b: NDArray[np.float64],
    steps: NDArray[np.float64],
    continuous: NDArray[np.bool_] | None = None,
    lower: NDArray[np.float64] | None = None,
) -> NDArray[np.float64]:
    """The configurations from ``a`` to ``b`` (both included) on the straight piece between them, evenly
    spaced so that no joint moves more than its ``steps`` entry between consecutive ones. ``continuous``
    (a mask of the joints, :mod:`clew_ros.spatial.turns`): those joints take the short way round, every
    sample of them written within ``[lower, lower + 2 pi)`` (the ends too: a plan may carry them unwrapped)."""
    end = short_way(a, b, continuous)
    count = max(1, math.ceil(float(np.max(np.abs(end - a) / steps))))
    t = np.arange(count + 1)[:, None] / count
    out: NDArray[np.float64] = a + t * (end - a)
    if end is not b:
        return wrapped(out, continuous, lower)
    out[-1] = b
    return out


def explain_invalid(checker: SpatialChecker, q: NDArray[np.float64]) -> str:
    """Why ``checker`` calls configuration ``q`` invalid: a joint outside its limits, the obstacles a link
    touches, the resting object touched by a link that may not touch it, a self-collision, the held object
    touching an obstacle or a link, or the bounds (each cause tried alone)."""
    robot = checker.robot
    for j, name in enumerate(robot.joint_names):
        if not robot.lower[j] <= q[j] <= robot.upper[j]:
            return f"joint {name} = {q[j]:.6g} is outside its limits [{robot.lower[j]:.6g}, {robot.upper[j]:.6g}]"
    if checker.static_collision:
        return "a link no joint moves touches an obstacle or leaves the bounds"
    row = q[None]

    def free(obstacles: Sequence[Obstacle] = (), **options: Any) -> bool:
        alone = SpatialChecker(robot, checker.spheres, obstacles, self_collision=False, **options)
        return bool(alone.valid(row)[0])

    arm_touches = [o for o in checker.scene_obstacles if not free([o])]
    reasons = [f"touches obstacle {o.name!r}" for o in arm_touches]
    if checker.resting_object is not None and not free(resting_object=checker.resting_object):
        reasons.append("a link other than the gripper links touches the object where it rests")
    if not SpatialChecker(robot, checker.spheres).valid(row)[0]:
        reasons.append("a self-collision (two links not exempted touch)")
    held = checker.held
    if held is not None:
        reasons += _held_reasons(checker, held, arm_touches, free)
    if checker.bounds is not None and not reasons:
        if not free(bounds=checker.bounds):
            reasons.append("leaves the bounds")
        elif held is not None and not free(bounds=checker.bounds, held=replace(held, supports=())):
            reasons.append("the held object leaves the bounds")
    return ", ".join(reasons) or "leaves the bounds"


def _held_reasons(
    checker: SpatialChecker, held: Held, arm_touches: Sequence[Obstacle], free: Callable[..., bool]
) -> list[str]:
    """What the held object touches: a link other than the gripper links, or obstacles (a support from
    below its top) the arm itself does not touch."""
    if not free(held=replace(held, supports=())):
        return ["the held object touches a link other than the gripper links"]
    reasons = []
    for obstacle in checker.scene_obstacles:
        if obstacle in arm_touches:
            continue
        own = tuple(s for s in held.supports if s.name == obstacle.name)
        if not free([obstacle], held=replace(held, supports=own)):
            where = "sinks below the top of support" if own else "touches obstacle"
            reasons.append(f"the held object {where} {obstacle.name!r}")
    return reasons


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
        path = wrapped(path, robot.continuous, robot.lower)
        return [] if checker.valid(path)[0] else [f"waypoint 0 is invalid: {explain_invalid(checker, path[0])}"]
    problems = []
    for i in range(len(path) - 1):
        samples = validation_samples(path[i], path[i + 1], steps, robot.continuous, robot.lower)
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
