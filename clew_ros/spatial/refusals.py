"""Answers knowable before planning (:func:`quick_refusal`): a goal that is no stable placement or that
collides, a start in collision, a goal no grasp can reach, a goal closed off by obstacles."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from clew_ros.core.settings import Outcome
from clew_ros.spatial.enclosure import enclosure_refusal
from clew_ros.spatial.placements import object_extent, resting_on
from clew_ros.spatial.settle import rests
from clew_ros.spatial.space_parts import SpaceParts
from clew_ros.spatial.tier import object_touches
from clew_ros.spatial.transforms import matrices
from clew_ros.spatial.world import SpatialWorld

__all__ = ["quick_refusal"]

Array = NDArray[np.float64]


def quick_refusal(parts: SpaceParts, goal: Array) -> tuple[Outcome, str] | None:
    """A goal that is no stable placement or that collides, a start in collision, a goal no grasp can
    reach (the tcp's distance from the first joint beyond the arm's reach: a proof), a goal the object
    cannot get to (closed off by obstacles: :func:`~clew_ros.spatial.enclosure.enclosure_refusal`)."""
    world = parts.world
    thing = world.object
    assert thing is not None
    goal = np.asarray(goal, dtype=float)
    if goal.shape != (6,) or not np.all(np.isfinite(goal)):
        return Outcome.INVALID_WORLD, "goal: expected a pose of six finite numbers [x, y, z, roll, pitch, yaw]"
    if not rests(world, goal):
        names = ", ".join(s.name for s in world.supports) or "none"
        return (
            Outcome.INVALID_WORLD,
            (
                f"goal {np.round(goal, 6).tolist()} is not a stable placement: no flat face of the "
                f"{thing.shape.shape} lies within {world.tolerances['placement_tolerance']} m of a support's "
                f"top face with its centre above it (supports: {names})"
            ),
        )
    hit = _object_collides(world, goal)
    if hit:
        return Outcome.GOAL_IN_COLLISION, f"the object at its goal placement touches {hit}"
    initial = np.asarray(thing.initial, dtype=float)
    if not parts.transit_checker(initial).valid(world.initial[None])[0]:
        return Outcome.START_IN_COLLISION, "the start configuration is not valid (object resting at initial)"
    tcps = matrices(goal)[0] @ parts.grasps
    nearest = float(np.min(np.linalg.norm(tcps[:, :3, 3] - parts.shoulder, axis=1)))
    if nearest > parts.reach:
        return (
            Outcome.GOAL_OUT_OF_REACH,
            (
                f"goal placement out of reach: its nearest grasp is {nearest:.3f} m from the first joint, "
                f"the arm reaches at most {parts.reach:.3f} m"
            ),
        )
    closed = enclosure_refusal(world, goal, initial)
    return (Outcome.NO_PATH_AT_RESOLUTION, f"no plan exists: {closed}") if closed else None


def _object_collides(world: SpatialWorld, object_pose: Array) -> str:
    """The obstacles (names) the object at ``object_pose`` touches, its support but from above allowed,
    or the bounds it leaves; "" if none (on its exact box or cylinder)."""
    thing = world.object
    assert thing is not None
    pose = matrices(object_pose)[0]
    found = resting_on(thing.shape, pose, world.supports, world.tolerances["placement_tolerance"])
    support = found[0].name if found is not None else ""
    hits = object_touches(thing.shape, pose, [o for o in world.obstacles if o.name != support])
    if world.bounds is not None:
        low, high = object_extent(thing.shape, pose)
        if np.any(low < world.bounds[:3]) or np.any(high > world.bounds[3:]):
            hits.append("the world's bounds")
    return ", ".join(hits)
