"""Rebuild a plan (``clew-plan/1``) from a recorded ``~/trajectory`` (interface.md section 3).

The trajectory's points are the plan's waypoints in order; ``gripper`` is 1.0
on every point of a transfer segment and 0.0 on transit points, so a grasp or
an ungrasp shows as two consecutive points with the same joints and a
different ``gripper``. Which grasp a transfer holds is not in the trajectory:
it comes from the run's ``grasp`` events when given, else it is the grasp
point nearest to the tip where the transfer starts.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace
from typing import Any

import numpy as np

from clew_ros.core.errors import short_repr
from clew_ros.core.plan import Plan, PlanSegment
from clew_ros.core.settings import Outcome
from clew_ros.planar.kinematics import tip_poses, transform_points
from clew_ros.planar.plan import replay
from clew_ros.planar.world import World
from clew_ros.recording.errors import TrajectoryError
from clew_ros.spatial import WORLD_KIND as SPATIAL_WORLD_KIND

__all__ = ["GRIPPER_JOINT", "spatial_trajectory_plan", "trajectory_to_plan"]

#: Name of the extra joint that says whether the arm holds the object.
GRIPPER_JOINT = "gripper"


def _segments_of(points: np.ndarray, gripper: np.ndarray) -> list[tuple[str, list[np.ndarray]]]:
    segments: list[tuple[str, list[np.ndarray]]] = []
    for joints, closed in zip(points, gripper >= 0.5, strict=True):
        kind = "transfer" if closed else "transit"
        if not segments or segments[-1][0] != kind:
            segments.append((kind, []))
        segments[-1][1].append(joints)
    if segments and segments[0][0] == "transfer":  # the start already holds a grasp
        segments.insert(0, ("transit", [segments[0][1][0]]))
    for index in range(1, len(segments)):  # a segment starts where the previous one ended
        previous_end = segments[index - 1][1][-1]
        if np.max(np.abs(segments[index][1][0] - previous_end)) > 1e-9:
            segments[index][1].insert(0, previous_end)
    return segments


def _positions(rows: list[list[Any]], width: int, source: str) -> np.ndarray:
    """``rows`` as an array of finite floats, ``width`` of them each, or :class:`TrajectoryError`."""
    for number, row in enumerate(rows):
        if len(row) != width:
            raise TrajectoryError(
                f"{source}: point {number} has {len(row)} positions, expected {width} "
                "(one per joint name, at least one per joint of the world)"
            )
    try:
        positions = np.asarray(rows, dtype=float)
    except (TypeError, ValueError, OverflowError):
        raise TrajectoryError(f"{source}: the points' positions are not numbers") from None
    if not np.all(np.isfinite(positions)):
        number = int(np.flatnonzero(~np.isfinite(positions).all(axis=1))[0])
        raise TrajectoryError(f"{source}: point {number} has a position that is not a finite number")
    return positions


def trajectory_to_plan(
    world: World,
    trajectory: Any,
    *,
    grasps: Sequence[int] | None = None,
    message: str = "rebuilt from the recorded trajectory",
    strict: bool = False,
    source: str = "trajectory",
) -> Plan:
    """The :class:`~clew_ros.core.plan.Plan` that a ``JointTrajectory`` plays.

    Parameters
    ----------
    world:
        The world the trajectory was planned in.
    trajectory:
        Anything with ``joint_names`` and ``points[i].positions`` (an rclpy
        ``JointTrajectory`` or a message decoded from a recording).
    grasps:
        Grasp index of each transfer segment, in order (from the run's
        ``grasp`` events); when absent or of the wrong length each transfer
        gets the grasp point nearest to the tip at its first waypoint.
    message:
        The plan's ``message``.
    strict:
        Hold the trajectory to the contract (interface.md section 3): raise
        :class:`~clew_ros.recording.errors.TrajectoryError` unless
        ``joint_names`` are exactly the world's joints then ``gripper`` and
        there is at least one point. Without it, joints are found by name (in
        column order when a name is missing) and an empty trajectory gives a
        plan with ``success`` false.
    source:
        Where the trajectory comes from (a recording's path and topic), for
        the messages of errors.

    Returns
    -------
    Plan
        A plan with ``success`` true when the trajectory has points, no
        ``code`` (the trajectory does not say it) and no ``landmarks`` (nor
        does it hold the tree).

    Raises
    ------
    TrajectoryError
        Names that are not text, points whose positions are not one finite
        number per joint name (or fewer than the world's joints), grasp
        indices the world's object does not have; the message names
        ``source``.
    """
    names = list(trajectory.joint_names)
    if not all(isinstance(name, str) for name in names):
        raise TrajectoryError(f"{source}: joint_names: expected names, got {short_repr(names)}")
    robot_names = list(world.robot.joint_names)
    if strict:
        if names != [*robot_names, GRIPPER_JOINT]:
            raise TrajectoryError(f"{source}: joint_names: expected {[*robot_names, GRIPPER_JOINT]}, got {names}")
        if not len(trajectory.points):
            raise TrajectoryError(f"{source}: the trajectory has no points")
    n = world.robot.dof
    columns = [names.index(j) for j in robot_names] if all(j in names for j in robot_names) else list(range(n))
    gripper_column = names.index(GRIPPER_JOINT) if GRIPPER_JOINT in names else None
    rows = [list(p.positions) for p in trajectory.points]
    if not rows:
        return Plan(
            world=world.name,
            joint_names=tuple(robot_names),
            success=False,
            message="the recorded trajectory has no points",
        )
    positions = _positions(rows, max(len(names), n), source)
    points = positions[:, columns]
    gripper = positions[:, gripper_column] if gripper_column is not None else np.zeros(len(points))
    segments = [PlanSegment(kind, None, np.asarray(waypoints)) for kind, waypoints in _segments_of(points, gripper)]
    rebuilt = Plan(
        world=world.name, joint_names=tuple(robot_names), success=True, message=message, segments=tuple(segments)
    )

    # the object's replay does not depend on the grasp indices: it gives where each transfer takes the object
    transfers = [motion for motion in replay(world, rebuilt, step_rad=None) if motion.kind == "transfer"]
    given = list(grasps) if grasps is not None and len(grasps) == len(transfers) else None
    count = len(world.object.grasps)
    if given is not None and not all(isinstance(g, int | np.integer) and 0 <= g < count for g in given):
        raise TrajectoryError(f"{source}: grasps: expected indices in [0, {count}), got {short_repr(given)}")
    if transfers and given is None and not count:
        raise TrajectoryError(f"{source}: the trajectory carries the object, but the world's object has no grasps")
    for number, motion in enumerate(transfers):
        if given is not None:
            grasp = int(given[number])
        else:
            tip = tip_poses(world.robot, motion.configurations[:1])[0]
            held = transform_points(motion.object_poses[0], world.object.grasps)
            grasp = int(np.argmin(np.linalg.norm(held - tip[:2], axis=1)))
        segments[motion.index] = replace(segments[motion.index], grasp=grasp)
    final = transfers[-1].object_poses[-1] if transfers else np.asarray(world.object.initial, dtype=float)
    return replace(rebuilt, segments=tuple(segments), final_object_pose=np.array(final))


def spatial_trajectory_plan(trajectory: Any, fields: dict[str, Any], message: str, world: str) -> Plan:
    """A spatial run's plan, rebuilt from its ``~/trajectory`` and its ``succeeded`` event's ``segments``
    (each ``kind``, ``grasp`` and how many of the trajectory's points it has, in order) and
    ``final_object_pose``; ``ValueError`` when they do not fit together."""
    points = np.array([list(p.positions) for p in trajectory.points], dtype=float)
    segments, start = [], 0
    for segment in fields["segments"]:
        count = int(segment["points"])
        if count < 1 or start + count > len(points):
            raise ValueError(f"the event's segments do not fit the trajectory's {len(points)} points")
        grasp = segment["grasp"]
        segments.append(
            PlanSegment(str(segment["kind"]), None if grasp is None else int(grasp), points[start : start + count])
        )
        start += count
    if start != len(points):
        raise ValueError(f"the event's segments hold {start} points, the trajectory {len(points)}")
    final = fields.get("final_object_pose")
    return Plan(
        world=world,
        joint_names=tuple(trajectory.joint_names),
        success=True,
        message=message,
        code=Outcome.SUCCEEDED.name,
        segments=tuple(segments),
        final_object_pose=None if final is None else np.array(final, dtype=float),
        landmarks=(),
        stats={},
        world_kind=SPATIAL_WORLD_KIND,
    )
