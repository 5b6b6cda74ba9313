"""A plan in a planar world: its replay and its validator (``interface.md`` section 2).

The plan file itself is :mod:`clew_ros.core.plan`; :func:`replay` is the one
place that carries the object through a planar plan (the object rests during
a transit; during a transfer it keeps its pose relative to the tip where the
transfer starts).
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from clew_ros.core.clew import PlanResult
from clew_ros.core.errors import PlanFileError
from clew_ros.core.plan import Plan, PlanSegment
from clew_ros.core.settings import Outcome
from clew_ros.planar.collision import explain_invalid, is_valid
from clew_ros.planar.continuous import CHECK_STEP_RAD, interpolate
from clew_ros.planar.kinematics import compose, relative, tip_poses, transform_points, wrap_angle
from clew_ros.planar.world import World

__all__ = ["CHECK_STEP_RAD", "SegmentMotion", "checked_plan", "interpolate", "replay", "validate_plan"]


# -- replay: the one place that carries the object through a plan ----------------------------------------


@dataclass(frozen=True, eq=False)
class SegmentMotion:
    """One segment replayed: ``configurations`` (M, n) rad and the object's pose at each (M, 3).

    ``grasp_rel`` is the held object's pose in the end-effector frame during
    a transfer (``None`` during a transit, when the object rests).
    """

    index: int
    kind: str
    grasp: int | None
    configurations: np.ndarray
    object_poses: np.ndarray
    grasp_rel: np.ndarray | None


def replay(world: World, plan: Plan, step_rad: float | None = CHECK_STEP_RAD) -> Iterator[SegmentMotion]:
    """The plan's segments with the object carried along, from ``world.object.initial``.

    ``step_rad``: the configurations are the straight pieces between
    waypoints sampled at most this far apart per joint; ``None``: the
    waypoints themselves.
    """
    pose = np.asarray(world.object.initial, dtype=float)
    for index, segment in enumerate(plan.segments):
        waypoints = np.asarray(segment.waypoints, dtype=float)
        configurations = waypoints if step_rad is None else interpolate(waypoints, step_rad)
        grasp_rel = None
        if segment.kind == "transfer":
            grasp_rel = relative(tip_poses(world.robot, waypoints[:1])[0], pose)
            poses = compose(tip_poses(world.robot, configurations), grasp_rel)
            pose = poses[-1]
        else:
            poses = np.broadcast_to(pose, (len(configurations), 3))
        yield SegmentMotion(index, segment.kind, segment.grasp, configurations, poses, grasp_rel)


# -- validation ------------------------------------------------------------------------------------------


def validate_plan(world: World, plan: Plan | Mapping[str, Any], step_rad: float = CHECK_STEP_RAD) -> list[str]:
    """Check a plan against a world exactly as section 2 states; returns the problems found (empty: valid).

    ``plan`` may also be a parsed plan file (a dict): a malformed one gives
    one problem naming the field at fault.
    """
    if not isinstance(plan, Plan):
        try:
            plan = Plan.from_dict(plan)
        except PlanFileError as error:
            return [f"malformed plan: {error}"]
    problems = _structure_problems(world, plan)
    if problems or not plan.success:
        return problems
    last_pose = np.asarray(world.object.initial, float)
    for motion in replay(world, plan, step_rad):
        index, kind, configurations, poses = motion.index, motion.kind, motion.configurations, motion.object_poses
        if kind == "transfer":
            held = transform_points(last_pose, world.object.grasps[motion.grasp][None])[0]
            tip = tip_poses(world.robot, configurations[:1])[0, :2]
            if np.linalg.norm(tip - held) > world.grasp_tolerance:
                problems.append(
                    f"segment {index}: the tip is {np.linalg.norm(tip - held):.6f} m from grasp "
                    f"{motion.grasp} (more than world.grasp_tolerance {world.grasp_tolerance})"
                )
        valid = is_valid(world, configurations, poses)
        if not valid.all():
            bad = int(np.flatnonzero(~valid)[0])
            reason = explain_invalid(world, configurations[bad], poses[bad])
            problems.append(
                f"segment {index} ({kind}): configuration {np.round(configurations[bad], 6).tolist()} "
                f"is invalid: {reason}"
            )
        last_pose = poses[-1]
    final = plan.final_object_pose
    if final is None:
        return [*problems, "a successful plan has a final_object_pose"]
    if not np.all(np.isfinite(final)) or not (
        np.max(np.abs(np.r_[final[:2] - last_pose[:2], wrap_angle(final[2] - last_pose[2])])) <= 1e-4
    ):
        problems.append(f"final_object_pose {final.tolist()} differs from the replayed {last_pose.tolist()}")
    goal = world.object.goal
    distance = float(np.hypot(*(last_pose[:2] - goal[:2])))
    angle = float(abs(wrap_angle(last_pose[2] - goal[2])))
    if distance > world.goal_tolerance:
        problems.append(f"the object ends {distance:.4f} m from the goal (goal_tolerance {world.goal_tolerance})")
    if angle > world.goal_angle_tolerance + 1e-9:
        problems.append(
            f"the object ends {angle:.4f} rad from the goal orientation "
            f"(goal_angle_tolerance {world.goal_angle_tolerance})"
        )
    return problems


def _structure_problems(world: World, plan: Plan) -> list[str]:
    """What section 2 says of the plan's shape, before any configuration is checked."""
    problems = []
    if plan.world_kind != "planar":
        return [f"world_kind: expected planar (the world's kind), got {plan.world_kind!r}"]
    if plan.world != world.name:
        problems.append(f"world: expected {world.name!r}, got {plan.world!r}")
    if list(plan.joint_names) != world.robot.joint_names:
        problems.append(f"joint_names: expected {world.robot.joint_names}")
    if not plan.success:
        if plan.segments or plan.final_object_pose is not None:
            problems.append("a failed plan must have no segments and a null final_object_pose")
        return problems
    segments = plan.segments
    if not segments:
        return [*problems, "a successful plan has no segments"]
    if segments[0].kind != "transit":
        return [*problems, "a plan starts with a transit segment"]
    return problems + _segment_problems(world, segments)


def _segment_problems(world: World, segments: Sequence[PlanSegment]) -> list[str]:
    problems = []
    robot, grasps = world.robot, len(world.object.grasps)
    previous_end = np.asarray(robot.initial, float)
    for index, segment in enumerate(segments):
        kind, waypoints, grasp = segment.kind, segment.waypoints, segment.grasp
        if index and kind == segments[index - 1].kind:
            problems.append(f"segment {index}: kinds must alternate")
        if waypoints.shape[1] != robot.dof or len(waypoints) < 1:
            problems.append(f"segment {index}: expected waypoints of {robot.dof} joints")
            continue
        if not np.all(np.isfinite(waypoints)):
            problems.append(f"segment {index}: waypoints must be finite")
            continue
        if np.any(waypoints < robot.joint_lower - 1e-9) or np.any(waypoints > robot.joint_upper + 1e-9):
            problems.append(f"segment {index}: a waypoint leaves the joint limits")
        if kind == "transfer" and (grasp is None or not 0 <= grasp < grasps):
            problems.append(f"segment {index}: transfer needs a grasp index in [0, {grasps})")
        if kind == "transit" and grasp is not None:
            problems.append(f"segment {index}: transit has grasp null")
        if np.max(np.abs(waypoints[0] - previous_end)) > 1e-6:
            what = "robot.initial" if index == 0 else "the end of the previous segment"
            problems.append(f"segment {index}: starts at {waypoints[0].tolist()}, not at {what}")
        previous_end = waypoints[-1]
    return problems


# -- never hand out an invalid plan ---------------------------------------------------------------------


def checked_plan(world: World, result: PlanResult) -> Plan:
    """The plan of a planner run, validated: a success whose plan fails :func:`validate_plan` becomes
    ``INTERNAL_ERROR`` with no segments (a bug in the planner; never hand out an invalid plan).

    The one place the command line, the node and the benchmarks turn a result into a plan.
    """
    plan = Plan.from_result(world, result)
    if not plan.success:
        return plan
    problems = validate_plan(world, plan)
    if not problems:
        return plan
    return plan.failed(Outcome.INTERNAL_ERROR, "internal error: the plan failed validation: " + "; ".join(problems[:3]))
