"""Spatial plans (interface.md section 1b "Plan file", and section 2): the file, its replay and validator.

The file is core's ``clew-plan/1`` (:class:`~clew_ros.core.plan.Plan`: one reader, one writer, the same
limits and errors) with ``"world_kind": "spatial"`` and object poses of 6 numbers ``[x, y, z, roll,
pitch, yaw]`` (``final_object_pose``, landmarks' ``object_pose``). :func:`replay` carries the object
through a plan: it rests where it lies during a transit; during a transfer it keeps the pose relative to
the tcp it had at the transfer's first waypoint. :func:`validate_plan` checks a plan against a
:class:`~clew_ros.spatial.world.SpatialWorld` as the contract states and returns the problems found
(empty: valid), each naming what is wrong: the file's shape, the start and the joins of segments, each
transfer's grasp (the tcp within ``grasp_tolerance`` and ``grasp_angle_tolerance`` of the grasp's pose),
every configuration along every straight piece at <= 0.002 rad per revolute joint (0.001 m prismatic) with
the object resting (an obstacle to every link but the gripper links) or held (its spheres on the tcp,
touching supports only from above), the object left only at stable placements and clear of the obstacles
there, and the goal (the same face down, the centre within ``goal_tolerance``, the yaw within
``goal_angle_tolerance``) or, for a motion-only query, ``world.robot.goal``.
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
from numpy.typing import NDArray

from clew_ros.core.errors import PlanFileError
from clew_ros.core.plan import Plan, PlanLandmark, PlanSegment
from clew_ros.spatial.checker import Held, SpatialChecker
from clew_ros.spatial.inverse import InverseKinematics
from clew_ros.spatial.placements import object_extent, resting_on
from clew_ros.spatial.robot import RobotModel
from clew_ros.spatial.scene import Obstacle, make_obstacle
from clew_ros.spatial.tier import object_touches
from clew_ros.spatial.transforms import matrix_pose, pose_matrix
from clew_ros.spatial.turns import joint_gaps
from clew_ros.spatial.validate import ValidationSettings, validate_transit, validation_samples
from clew_ros.spatial.world import SpatialWorld

__all__ = [
    "WORLD_KIND",
    "SpatialMotion",
    "make_plan",
    "object_obstacle",
    "path_problems",
    "replay",
    "resting_problems",
    "rotation_angle",
    "validate_plan",
    "yaw_error",
]

WORLD_KIND = "spatial"

Matrix = NDArray[np.float64]


@dataclass(frozen=True, eq=False)
class SpatialMotion:
    """One segment replayed: ``configurations`` (M, n) and the object's 4x4 pose at each,
    ``object_matrices`` (M, 4, 4; ``None`` in a world without an object). ``grasp_rel`` is the tcp's pose in
    the object's frame during a transfer (``None`` during a transit, when the object rests)."""

    index: int
    kind: str
    grasp: int | None
    configurations: NDArray[np.float64]
    object_matrices: NDArray[np.float64] | None
    grasp_rel: Matrix | None

    @property
    def object_poses(self) -> NDArray[np.float64] | None:
        """The object's poses as the plan file writes them, ``[x, y, z, roll, pitch, yaw]`` each (M, 6)."""
        if self.object_matrices is None:
            return None
        return np.array([matrix_pose(m) for m in self.object_matrices]).reshape(-1, 6)


def rotation_angle(a: Matrix, b: Matrix) -> float:
    """The angle (rad) of the rotation between two orientations (3x3, or the rotation blocks of 4x4 poses)."""
    relative = np.asarray(a)[:3, :3].T @ np.asarray(b)[:3, :3]
    return math.acos(max(-1.0, min(1.0, (float(np.trace(relative)) - 1.0) / 2.0)))


def yaw_error(goal: Matrix, final: Matrix) -> float:
    """The angle (rad, in [0, pi]) of the rotation about world z that takes the goal's orientation to the
    final one (section 1b's yaw error; both rest on the same face, so that rotation is about z)."""
    turn = np.asarray(final)[:3, :3] @ np.asarray(goal)[:3, :3].T
    return abs(math.atan2(float(turn[1, 0]), float(turn[0, 0])))


def object_obstacle(world: SpatialWorld, pose: Matrix) -> Obstacle:
    """The world's object at ``pose`` (4x4) as an obstacle named ``object`` (what the arm meets in transit)."""
    if world.object is None:
        raise ValueError("world: a motion-only world has no object")
    shape = world.object.shape
    return make_obstacle("object", shape.shape, shape.size, pose, "world.object")


def _samples(waypoints: NDArray[np.float64], steps: NDArray[np.float64], robot: RobotModel) -> NDArray[np.float64]:
    """Every configuration checked along the straight pieces through ``waypoints`` (no repeats at joins)."""
    if len(waypoints) == 1:
        return np.array(waypoints, dtype=np.float64)
    pieces = [
        validation_samples(waypoints[i], waypoints[i + 1], steps, robot.continuous, robot.lower)[1:]
        for i in range(len(waypoints) - 1)
    ]
    return np.concatenate([waypoints[:1], *pieces])


def replay(
    world: SpatialWorld, plan: Plan, settings: ValidationSettings | None = None, *, waypoints_only: bool = False
) -> Iterator[SpatialMotion]:
    """The plan's segments with the object carried along from ``world.object.initial``: the configurations
    along each straight piece (no joint moving more than ``settings``' step between two; ``waypoints_only``:
    the waypoints themselves) and the object's pose at each."""
    settings = settings or ValidationSettings()
    robot = world.robot
    steps = np.where(robot.prismatic, settings.step_m, settings.step_rad)
    kinematics = InverseKinematics(robot)
    pose = None if world.object is None else pose_matrix(world.object.initial)
    for index, segment in enumerate(plan.segments):
        waypoints = np.asarray(segment.waypoints, dtype=np.float64)
        configurations = waypoints if waypoints_only else _samples(waypoints, steps, robot)
        grasp_rel = None
        if pose is None:
            matrices = None
        elif segment.kind == "transfer":
            grasp_rel = np.linalg.inv(pose) @ kinematics.tcp_poses(waypoints[:1])[0]
            matrices = kinematics.tcp_poses(configurations) @ np.linalg.inv(grasp_rel)
            pose = matrices[-1]
        else:
            matrices = np.broadcast_to(pose, (len(configurations), 4, 4))
        yield SpatialMotion(index, segment.kind, segment.grasp, configurations, matrices, grasp_rel)


def make_plan(
    world: SpatialWorld,
    segments: Sequence[tuple[str, int | None, Any]],
    *,
    message: str = "plan found",
    stats: Mapping[str, Any] | None = None,
    landmarks: Sequence[PlanLandmark] = (),
) -> Plan:
    """A successful spatial plan of ``segments`` (``(kind, grasp, waypoints)`` each) in ``world``, its
    ``final_object_pose`` from :func:`replay` (``None`` for a motion-only query)."""
    built = tuple(PlanSegment(kind, grasp, _frozen(waypoints)) for kind, grasp, waypoints in segments)
    plan = Plan(
        world=world.name,
        joint_names=tuple(world.robot.joint_names),
        success=True,
        message=message,
        code="SUCCEEDED",
        segments=built,
        landmarks=tuple(landmarks),
        stats=dict(stats or {}),
        world_kind=WORLD_KIND,
    )
    final = None
    for motion in replay(world, plan, waypoints_only=True):
        if motion.object_matrices is not None:
            final = _frozen(np.round(matrix_pose(motion.object_matrices[-1]), 9))
    if final is None and world.object is not None:
        final = _frozen(np.round(world.object.initial, 9))
    return replace(plan, final_object_pose=final)


def _frozen(values: Any) -> NDArray[np.float64]:
    array = np.array(values, dtype=np.float64)
    array.setflags(write=False)
    return array


# -- validation ----------------------------------------------------------------------------------------


def resting_problems(world: SpatialWorld, pose: Matrix, where: str) -> list[str]:
    """What is wrong with the object resting at ``pose`` (4x4): not a stable placement, inside the bounds
    no more (its exact corners or rim), or its box or cylinder (exactly) touching an obstacle other than the
    support it rests on. ``where`` starts each problem."""
    assert world.object is not None
    shape = world.object.shape
    found = resting_on(shape, pose, world.supports, world.tolerances["placement_tolerance"])
    if found is None:
        at = np.round(matrix_pose(pose), 6).tolist()
        tolerance = world.tolerances["placement_tolerance"]
        message = (
            f"{where}: the object at {at} is not at a stable placement (no flat face within world.placement_tolerance "
            f"{tolerance} m of a support's top face with its centre above it)"
        )
        return [message]
    problems = []
    if world.bounds is not None:
        low, high = object_extent(shape, pose)
        if np.any(low < world.bounds[:3]) or np.any(high > world.bounds[3:]):
            problems.append(f"{where}: the object leaves the bounds")
    others = [o for o in world.obstacles if o.name != found[0].name]
    problems += [f"{where}: the object touches obstacle {name!r}" for name in object_touches(shape, pose, others)]
    return problems


def _structure_problems(world: SpatialWorld, plan: Plan, settings: ValidationSettings) -> list[str]:
    """What sections 1b and 2 say of the plan's shape, before any configuration is checked."""
    if plan.world_kind != WORLD_KIND:
        return [f"world_kind: expected {WORLD_KIND!r} (the world is spatial), got {plan.world_kind!r}"]
    robot = world.robot
    problems = []
    if plan.world != world.name:
        problems.append(f"world: expected {world.name!r}, got {plan.world!r}")
    if list(plan.joint_names) != list(robot.joint_names):
        problems.append(f"joint_names: expected {list(robot.joint_names)}, got {list(plan.joint_names)}")
    if not plan.success:
        if plan.segments or plan.final_object_pose is not None:
            problems.append("a failed plan must have no segments and a null final_object_pose")
        return problems
    segments = plan.segments
    if not segments:
        problems.append("a successful plan has no segments")
    elif segments[0].kind != "transit":
        problems.append("a plan starts with a transit segment")
    if problems:
        return problems
    problems = _segment_problems(world, segments, settings)
    if world.object is None:
        return problems + _motion_only_problems(world, plan, settings)
    if plan.final_object_pose is None:
        problems.append("a successful plan has a final_object_pose")
    return problems


def _motion_only_problems(world: SpatialWorld, plan: Plan, settings: ValidationSettings) -> list[str]:
    """A motion-only query's plan: one transit segment ending at ``world.robot.goal`` (modulo 2 pi on the
    continuous joints) or with the tcp at ``world.robot.goal_pose``, no final object pose."""
    problems = []
    if len(plan.segments) != 1:
        problems.append(f"a motion-only query's plan is one transit segment, got {len(plan.segments)} segments")
    end = plan.segments[-1].waypoints[-1]
    if world.goal is not None:
        miss = float(np.max(joint_gaps(end, world.goal, world.robot.continuous)))
        if miss > settings.match_rad:
            problems.append(f"the plan ends {miss:.6g} from world.robot.goal (more than {settings.match_rad})")
    elif world.goal_pose is not None:
        tcp = InverseKinematics(world.robot).tcp_poses(np.asarray(end, dtype=np.float64)[None])[0]
        goal = pose_matrix(list(world.goal_pose))
        distance, angle = float(np.linalg.norm(tcp[:3, 3] - goal[:3, 3])), rotation_angle(tcp, goal)
        if distance > settings.goal_pose_m or angle > settings.goal_pose_rad:
            problems.append(
                f"the plan ends with the tcp {distance:.6g} m and {angle:.6g} rad from world.robot.goal_pose "
                f"(more than {settings.goal_pose_m} m or {settings.goal_pose_rad} rad)"
            )
    if plan.final_object_pose is not None:
        problems.append("final_object_pose: expected null in a world without an object")
    return problems


def _segment_problems(world: SpatialWorld, segments: Sequence[PlanSegment], settings: ValidationSettings) -> list[str]:
    """Kinds that alternate, waypoints within the joint limits, grasp indices, and joins within 1e-6."""
    robot = world.robot
    problems = []
    grasps = 0 if world.object is None else len(world.object.grasps)
    previous_end = world.initial
    for index, segment in enumerate(segments):
        waypoints, grasp = segment.waypoints, segment.grasp
        if waypoints.ndim != 2 or waypoints.shape[1] != robot.dof or not len(waypoints):
            problems.append(f"segment {index}: expected waypoints of {robot.dof} joint values each")
            continue
        if index and segment.kind == segments[index - 1].kind:
            problems.append(f"segment {index}: kinds must alternate (two {segment.kind} segments in a row)")
        outside = ((waypoints < robot.lower - 1e-9) | (waypoints > robot.upper + 1e-9)) & ~_continuous(robot)
        if np.any(outside):
            row, joint = (int(v[0]) for v in np.nonzero(outside))
            problems.append(
                f"segment {index}: waypoint {row} puts {robot.joint_names[joint]} at {waypoints[row, joint]:.6g}, "
                f"outside its limits [{robot.lower[joint]:.6g}, {robot.upper[joint]:.6g}]"
            )
        if segment.kind == "transfer" and (grasp is None or not 0 <= grasp < grasps):
            what = "the world has no object" if world.object is None else f"expected a grasp index in [0, {grasps})"
            problems.append(f"segment {index}: transfer with grasp {grasp}: {what}")
        if segment.kind == "transit" and grasp is not None:
            problems.append(f"segment {index}: a transit has grasp null, got {grasp}")
        jump = float(np.max(joint_gaps(waypoints[0], previous_end, robot.continuous)))
        if jump > settings.match_rad:
            what = "world.robot.initial" if index == 0 else "the end of the previous segment"
            problems.append(f"segment {index}: starts {jump:.6g} from {what} (more than {settings.match_rad})")
        previous_end = waypoints[-1]
    return problems


def _continuous(robot: RobotModel) -> NDArray[np.bool_]:
    """The joints any value of which is within limits (a plan may carry a continuous joint unwrapped)."""
    return robot.continuous if len(robot.continuous) else np.zeros(robot.dof, dtype=bool)


def _grasp_problem(world: SpatialWorld, index: int, grasp: int, tcp: Matrix, pose: Matrix) -> str | None:
    assert world.object is not None
    target = pose @ pose_matrix(world.object.grasps[grasp].tolist())
    distance = float(np.linalg.norm(tcp[:3, 3] - target[:3, 3]))
    angle = rotation_angle(tcp, target)
    position_tolerance = world.tolerances["grasp_tolerance"]
    angle_tolerance = world.tolerances["grasp_angle_tolerance"]
    if distance <= position_tolerance and angle <= angle_tolerance:
        return None
    return (
        f"segment {index} (transfer): its first waypoint does not hold grasp {grasp}: the tcp is {distance:.6f} m "
        f"and {angle:.6f} rad from the grasp's pose (world.grasp_tolerance {position_tolerance} m, "
        f"world.grasp_angle_tolerance {angle_tolerance} rad)"
    )


def _goal_problems(world: SpatialWorld, plan: Plan, pose: Matrix, settings: ValidationSettings) -> list[str]:
    assert world.object is not None
    assert plan.final_object_pose is not None
    problems = []
    written = pose_matrix(plan.final_object_pose.tolist())
    if (
        float(np.max(np.abs(written[:3, 3] - pose[:3, 3]))) > settings.pose_match
        or rotation_angle(written, pose) > settings.pose_match
    ):
        problems.append(
            f"final_object_pose {plan.final_object_pose.tolist()} differs from the replayed "
            f"{np.round(matrix_pose(pose), 6).tolist()} (by more than {settings.pose_match})"
        )
    goal = pose_matrix(world.object.goal)
    found = resting_on(world.object.shape, pose, world.supports, world.tolerances["placement_tolerance"])
    face = world.object.goal_on[1]
    if found is None or found[1] != face:
        what = "not at a stable placement" if found is None else f"on face {found[1]}"
        problems.append(f"the object ends {what}; the goal rests it on face {face}")
    distance = float(np.linalg.norm(pose[:3, 3] - goal[:3, 3]))
    if distance > world.tolerances["goal_tolerance"]:
        tolerance = world.tolerances["goal_tolerance"]
        problems.append(f"the object ends {distance:.4f} m from the goal (world.goal_tolerance {tolerance})")
    if found is not None and found[1] == face:
        yaw = yaw_error(goal, pose)
        if yaw > world.tolerances["goal_angle_tolerance"] + 1e-9:
            problems.append(
                f"the object ends {yaw:.4f} rad (yaw about z) from the goal's orientation "
                f"(world.goal_angle_tolerance {world.tolerances['goal_angle_tolerance']})"
            )
    return problems


def validate_plan(
    world: SpatialWorld, plan: Plan | Mapping[str, Any], settings: ValidationSettings | None = None
) -> list[str]:
    """Check a spatial plan against ``world`` as sections 1b and 2 state; the problems found (empty: valid).

    ``plan`` may also be a parsed plan file (a dict): a malformed one gives one problem naming the field at
    fault. Every configuration along every straight piece is checked, no revolute joint moving more than
    ``settings.step_rad`` (0.002 rad) between two checks."""
    settings = settings or ValidationSettings()
    if not isinstance(plan, Plan):
        try:
            plan = Plan.from_dict(plan)
        except PlanFileError as error:
            return [f"malformed plan: {error}"]
    problems = _structure_problems(world, plan, settings)
    if problems or not plan.success:
        return problems
    problems, pose = _motion_problems(world, plan, settings)
    if world.object is not None and pose is not None:
        problems += _goal_problems(world, plan, pose, settings)
    return problems


def path_problems(world: SpatialWorld, plan: Plan, settings: ValidationSettings | None = None) -> list[str]:
    """:func:`validate_plan` but for the goal: the segments' structure, every configuration along them, the
    grasps and the placements the object is let go of at (what a plan's improvement must keep, whatever goal
    its run was given)."""
    settings = settings or ValidationSettings()
    problems = _structure_problems(world, plan, settings)
    if problems or not plan.success:
        return problems
    return _motion_problems(world, plan, settings)[0]


def _motion_problems(
    world: SpatialWorld, plan: Plan, settings: ValidationSettings
) -> tuple[list[str], NDArray[np.float64] | None]:
    """The problems of every segment's motion, and where the object ends (``None``: motion-only)."""
    problems: list[str] = []
    robot, spheres = world.robot, world.spheres
    thing = world.object
    kinematics = InverseKinematics(robot)
    pose = None if thing is None else pose_matrix(thing.initial)
    unstable = False  # the object was let go of off a stable placement (said once)
    for segment_index, segment in enumerate(plan.segments):
        waypoints = np.asarray(segment.waypoints, dtype=np.float64)
        head = f"segment {segment_index} ({segment.kind})"
        if thing is None or pose is None:
            checker = world.checker
        elif segment.kind == "transit":
            if not unstable:
                problems += resting_problems(world, pose, f"{head}: where it rests")
            checker = SpatialChecker(
                robot, spheres, world.obstacles, world.bounds, resting_object=object_obstacle(world, pose)
            )
        else:
            assert segment.grasp is not None
            tcp = kinematics.tcp_poses(waypoints[:1])[0]
            problem = _grasp_problem(world, segment_index, segment.grasp, tcp, pose)
            if problem:
                problems.append(problem)
            grasp_rel = np.linalg.inv(pose) @ tcp
            held = Held(thing.shape, grasp_rel, world.supports, world.tolerances["placement_tolerance"])
            checker = SpatialChecker(robot, spheres, world.obstacles, world.bounds, held=held)
        problems += [f"{head}: {problem}" for problem in validate_transit(checker, waypoints, settings)]
        if thing is not None and pose is not None and segment.kind == "transfer":
            pose = kinematics.tcp_poses(waypoints[-1:])[0] @ np.linalg.inv(grasp_rel)
            unstable = resting_on(thing.shape, pose, world.supports, world.tolerances["placement_tolerance"]) is None
            if unstable:
                problems.append(
                    f"{head}: lets go of the object at {np.round(matrix_pose(pose), 6).tolist()}, not a stable "
                    f"placement (no flat face within world.placement_tolerance "
                    f"{world.tolerances['placement_tolerance']} m of a support's top face with its centre above it)"
                )
    return problems, pose
