"""The plan file (``clew-plan/1``, ``interface.md`` section 2) and its validator."""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np

from clew_ros.core.clew import PlanResult
from clew_ros.core.collision import explain_invalid, is_valid
from clew_ros.core.errors import PlanFileError
from clew_ros.core.kinematics import compose, relative, tip_poses, wrap_angle
from clew_ros.core.world import World

__all__ = ["FORMAT", "CHECK_STEP_RAD", "plan_to_dict", "dumps_plan", "read_plan", "validate_plan", "replay"]

FORMAT = "clew-plan/1"
#: Largest joint step (rad) between two checked configurations.
CHECK_STEP_RAD = 0.002


def _round(values) -> list[float]:
    return [float(v) for v in np.asarray(values, dtype=float).ravel()]


def plan_to_dict(world: World, result: PlanResult) -> dict[str, Any]:
    """The plan file as a JSON-ready dict."""
    tree = result.tree
    landmarks = [{
        "id": lm.id,
        "parent": lm.parent,
        "joints": _round(lm.joints),
        "object_pose": _round(lm.object_pose),
        "grasp": lm.grasp,
    } for lm in tree]
    return {
        "format": FORMAT,
        "world": world.name,
        "success": result.success,
        "message": result.message,
        "code": result.outcome.name,
        "joint_names": world.robot.joint_names,
        "segments": [{"kind": s.kind, "grasp": s.grasp, "waypoints": [_round(w) for w in s.waypoints]}
                     for s in result.segments] if result.success else [],
        "final_object_pose": _round(result.final_object_pose) if result.success else None,
        "landmarks": landmarks,
        "stats": dict(result.stats),
    }


def dumps_plan(plan: dict) -> str:
    """Serialise a plan dict deterministically."""
    return json.dumps(plan, indent=1, sort_keys=False) + "\n"


def read_plan(path: str | Path) -> dict:
    try:
        plan = json.loads(Path(path).read_text())
    except (OSError, json.JSONDecodeError) as error:
        raise PlanFileError(f"{path}: cannot read the plan ({error})") from None
    if not isinstance(plan, dict) or plan.get("format") != FORMAT:
        raise PlanFileError(f"{path}: expected a JSON object with format {FORMAT!r}")
    return plan


def _pieces(waypoints: np.ndarray, step_rad: float) -> np.ndarray:
    """Configurations along straight joint-space pieces, at most ``step_rad`` apart per joint."""
    out = [waypoints[:1]]
    for a, b in zip(waypoints[:-1], waypoints[1:]):
        count = max(1, int(math.ceil(np.max(np.abs(b - a)) / step_rad)))
        t = np.arange(1, count + 1)[:, None] / count
        out.append(a + t * (b - a))
    return np.concatenate(out)


def replay(world: World, plan: dict, step_rad: float = CHECK_STEP_RAD):
    """Yield ``(kind, grasp, configurations (M, n), object_poses (M, 3))`` for each segment."""
    pose = np.asarray(world.object.initial, dtype=float)
    for segment in plan["segments"]:
        waypoints = np.asarray(segment["waypoints"], dtype=float)
        configurations = _pieces(waypoints, step_rad)
        if segment["kind"] == "transfer":
            grasp_rel = relative(tip_poses(world.robot, waypoints[:1])[0], pose)
            poses = compose(tip_poses(world.robot, configurations), grasp_rel)
            pose = poses[-1]
        else:
            poses = np.broadcast_to(pose, (len(configurations), 3))
        yield segment["kind"], segment.get("grasp"), configurations, poses


def validate_plan(world: World, plan: dict, step_rad: float = CHECK_STEP_RAD) -> list[str]:
    """Check a plan against a world exactly as section 2 states; returns the problems found (empty: valid)."""
    problems: list[str] = []
    try:
        _check_structure(world, plan, problems)
    except (KeyError, TypeError, ValueError) as error:
        return [f"malformed plan: {error!r}"]
    if problems or not plan["success"]:
        return problems
    last_pose = np.asarray(world.object.initial, float)
    object_poses = None
    for index, (kind, grasp, configurations, poses) in enumerate(replay(world, plan, step_rad)):
        if kind == "transfer":
            first = configurations[0]
            held = transform_points_one(last_pose, world.object.grasps[grasp])
            tip = tip_poses(world.robot, first[None])[0, :2]
            if np.linalg.norm(tip - held) > world.grasp_tolerance:
                problems.append(f"segment {index}: the tip is {np.linalg.norm(tip - held):.6f} m from grasp {grasp} "
                                f"(more than world.grasp_tolerance {world.grasp_tolerance})")
        valid = is_valid(world, configurations, poses)
        if not valid.all():
            bad = int(np.flatnonzero(~valid)[0])
            reason = explain_invalid(world, configurations[bad], poses[bad])
            problems.append(f"segment {index} ({kind}): configuration {np.round(configurations[bad], 6).tolist()} "
                            f"is invalid: {reason}")
        last_pose = poses[-1]
        object_poses = poses
    if object_poses is None:
        return problems + ["a successful plan has no segments"]
    final = np.asarray(plan["final_object_pose"], float)
    if np.max(np.abs(np.r_[final[:2] - last_pose[:2], wrap_angle(final[2] - last_pose[2])])) > 1e-4:
        problems.append(f"final_object_pose {final.tolist()} differs from the replayed {last_pose.tolist()}")
    goal = world.object.goal
    distance = float(np.hypot(*(last_pose[:2] - goal[:2])))
    angle = float(abs(wrap_angle(last_pose[2] - goal[2])))
    if distance > world.goal_tolerance:
        problems.append(f"the object ends {distance:.4f} m from the goal (goal_tolerance {world.goal_tolerance})")
    if angle > world.goal_angle_tolerance + 1e-9:
        problems.append(f"the object ends {angle:.4f} rad from the goal orientation "
                        f"(goal_angle_tolerance {world.goal_angle_tolerance})")
    return problems


def transform_points_one(pose: np.ndarray, point: np.ndarray) -> np.ndarray:
    c, s = math.cos(pose[2]), math.sin(pose[2])
    return np.array([pose[0] + c * point[0] - s * point[1], pose[1] + s * point[0] + c * point[1]])


def _check_structure(world: World, plan: dict, problems: list[str]) -> None:
    n = world.robot.dof
    if plan.get("format") != FORMAT:
        problems.append(f"format: expected {FORMAT!r}")
    if plan.get("world") != world.name:
        problems.append(f"world: expected {world.name!r}, got {plan.get('world')!r}")
    if plan.get("joint_names") != world.robot.joint_names:
        problems.append(f"joint_names: expected {world.robot.joint_names}")
    if not plan["success"]:
        if plan["segments"] or plan["final_object_pose"] is not None:
            problems.append("a failed plan must have no segments and a null final_object_pose")
        return
    segments = plan["segments"]
    if not segments or segments[0]["kind"] != "transit":
        problems.append("a plan starts with a transit segment")
        return
    previous_end = np.asarray(world.robot.initial, float)
    for index, segment in enumerate(segments):
        kind = segment["kind"]
        waypoints = np.asarray(segment["waypoints"], float)
        if kind not in ("transit", "transfer"):
            problems.append(f"segment {index}: unknown kind {kind!r}")
            continue
        if index and kind == segments[index - 1]["kind"]:
            problems.append(f"segment {index}: kinds must alternate")
        if waypoints.ndim != 2 or waypoints.shape[1] != n or len(waypoints) < 1:
            problems.append(f"segment {index}: expected waypoints of {n} joints")
            continue
        if not np.all(np.isfinite(waypoints)):
            problems.append(f"segment {index}: waypoints must be finite")
            continue
        if np.any(waypoints < world.robot.joint_lower - 1e-9) or np.any(waypoints > world.robot.joint_upper + 1e-9):
            problems.append(f"segment {index}: a waypoint leaves the joint limits")
        grasp = segment.get("grasp")
        if kind == "transfer" and (not isinstance(grasp, int) or not 0 <= grasp < len(world.object.grasps)):
            problems.append(f"segment {index}: transfer needs a grasp index in [0, {len(world.object.grasps)})")
        if kind == "transit" and grasp is not None:
            problems.append(f"segment {index}: transit has grasp null")
        if np.max(np.abs(waypoints[0] - previous_end)) > 1e-6:
            what = "robot.initial" if index == 0 else "the end of the previous segment"
            problems.append(f"segment {index}: starts at {waypoints[0].tolist()}, not at {what}")
        previous_end = waypoints[-1]
