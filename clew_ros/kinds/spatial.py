"""The spatial world (interface.md section 1b) as a :class:`~clew_ros.kinds.base.WorldKind`."""

from __future__ import annotations

import copy
import threading
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

import numpy as np

from clew_ros.core.clew import PlanResult, Progress
from clew_ros.core.plan import Plan
from clew_ros.core.settings import PlannerSettings, Termination
from clew_ros.core.tree import LandmarkTree
from clew_ros.kinds.base import WorldKind
from clew_ros.motion.spatial import spatial_track
from clew_ros.recording.trajectory import spatial_trajectory_plan
from clew_ros.ros import spatial as spatial_messages
from clew_ros.ros.events import spatial_plan_fields
from clew_ros.spatial import WORLD_KIND, offline
from clew_ros.spatial.transforms import matrix_pose, quaternion_matrix
from clew_ros.spatial.world import SpatialWorld

__all__ = ["SpatialKind"]


class SpatialKind(WorldKind):
    """An arm of a URDF in a 3-D scene (:class:`~clew_ros.spatial.world.SpatialWorld`); its setup is a
    :class:`~clew_ros.ros.spatial.SpatialSetup`."""

    name = WORLD_KIND
    world_type = SpatialWorld
    problem_type = offline.SpatialProblem
    live_in_3d = True

    def problem_from_parameters(
        self,
        parameters: Mapping[str, Any],
        folder: Path,
        *,
        seed: int | None = None,
        time_limit: float | None = None,
        improve_time: float | None = None,
    ) -> offline.SpatialProblem:
        return offline.problem_from_parameters(
            parameters, folder, seed=seed, time_limit=time_limit, improve_time=improve_time
        )

    def warm_up(self, problem: offline.SpatialProblem) -> float:
        return offline.warm_up(problem.world)

    def warm_up_worker(self, problem: offline.SpatialProblem) -> None:
        offline.warm_up(problem.world)  # the spatial kernels, compiled once per process

    def plan_problem(
        self,
        problem: offline.SpatialProblem,
        *,
        cancel: threading.Event | None = None,
        progress: Callable[[Progress], None] | None = None,
    ) -> Plan:
        return offline.plan_problem(problem, cancel=cancel, progress=progress)

    def failed_plan(self, problem: offline.SpatialProblem, message: str, elapsed_s: float) -> Plan:
        return offline.failed_plan(problem.world, problem.settings, message, elapsed_s)

    def plan(
        self,
        world: SpatialWorld,
        settings: PlannerSettings,
        *,
        goal: np.ndarray | None,
        termination: Termination,
        progress: Callable[[Progress], None] | None,
    ) -> PlanResult:
        del goal  # the world holds its goal (with_goal): clew_plan's planner, same settings, same plan
        from clew_ros.spatial.space import plan

        return plan(world, settings, termination=termination, progress=progress)

    def checked_plan(self, world: SpatialWorld, result: PlanResult) -> Plan:
        return offline.checked_plan(world, result)

    def start_collision_detail(self, world: SpatialWorld) -> str | None:
        from clew_ros.spatial.snapshot import start_contacts

        return start_contacts(world)

    def root_tree(self, world: SpatialWorld) -> LandmarkTree:
        pose = np.zeros(6) if world.object is None else np.asarray(world.object.initial, dtype=float)
        return LandmarkTree(world.initial, pose)

    def default_goal(self, world: SpatialWorld) -> np.ndarray:
        """The object's goal placement, or a motion-only query's ``world.robot.goal`` (joints) or
        ``world.robot.goal_pose`` (the tcp's pose)."""
        if world.object is not None:
            return np.asarray(world.object.goal, dtype=float)
        return np.asarray(world.goal if world.goal is not None else world.goal_pose, dtype=float)

    def with_goal(self, world: SpatialWorld, goal: np.ndarray) -> SpatialWorld:
        return spatial_messages.with_goal(world, goal)

    def goal_from_pose_stamped(self, msg: Any, world: SpatialWorld) -> np.ndarray:
        return spatial_messages.goal_from_pose_stamped(msg, world)  # a full orientation, a stable placement

    def goal_message(self, world: SpatialWorld, goal: np.ndarray, time_ns: int) -> Any | None:
        if world.object is None and world.goal is not None:  # a joint goal: no pose to record
            return None
        return spatial_messages.pose_stamped(goal, time_ns)

    def landmark_markers(self, world: SpatialWorld, landmarks: Any, time_ns: int) -> Any:
        return spatial_messages.landmark_markers(world, landmarks, time_ns)

    def track(self, world: SpatialWorld, plan: Plan, setup: Any, timing: Any) -> Any:
        return spatial_track(world, plan, setup.joints, timing)

    def plan_fields(self, world: SpatialWorld, track: Any) -> dict[str, Any]:
        return spatial_plan_fields(track, has_object=world.object is not None)

    def end_state(self, plan: Plan) -> tuple[np.ndarray, tuple[float, ...] | None] | None:
        final = plan.final_object_pose
        return np.array(plan.segments[-1].waypoints[-1], dtype=float), None if final is None else tuple(final)

    def setup_of(self, parameters: Mapping[str, Any], folder: Path) -> Any:
        """The setup (:func:`~clew_ros.ros.spatial.load_spatial`), the world's paths made absolute from
        ``folder`` (a recording's ``~/world_yaml`` names them absolute, as the node's launch file hands them)."""
        tree = copy.deepcopy(dict(parameters))
        if isinstance(tree.get("world"), dict):
            spatial_messages.absolute_paths(tree["world"], folder.resolve())
        _, setup = spatial_messages.load_spatial(tree, folder)
        return setup

    def announce_world(
        self, out: Any, world: SpatialWorld, planner: PlannerSettings, recording: Any, setup: Any
    ) -> None:
        if setup is None:
            raise ValueError("a spatial world is put out with its setup (clew_ros.ros.spatial.load_spatial)")
        out.spatial_world(world, setup, planner, recording)

    def publish_sample(
        self, out: Any, world: SpatialWorld, state: Any, *, setup: Any, track: Any, time_ns: int, recording: Any
    ) -> None:
        del track
        out.spatial_sample(world, setup, state, time_ns=time_ns, recording=recording)

    def pose_goal(self, msg: Any) -> tuple[float, ...]:
        p, q = msg.pose.position, msg.pose.orientation
        return tuple(matrix_pose(quaternion_matrix([p.x, p.y, p.z], [q.x, q.y, q.z, q.w])))

    def plan_from_trajectory(
        self, parameters: Mapping[str, Any], trajectory: Any, outcome_fields: Mapping[str, Any], message: str
    ) -> Plan | None:
        world = parameters.get("world")
        name = world.get("name", WORLD_KIND) if isinstance(world, Mapping) else WORLD_KIND
        return spatial_trajectory_plan(trajectory, dict(outcome_fields), message, str(name or WORLD_KIND))

    def record_run(
        self,
        run: Any,
        world: SpatialWorld,
        plan: Plan,
        *,
        planner: PlannerSettings,
        node: Any,
        recording_text: str,
        setup: Any,
    ) -> None:
        if setup is None:
            raise ValueError("a spatial world is recorded with its setup (clew_ros.ros.spatial.load_spatial)")
        run.record_spatial(world, setup, plan, planner=planner, node=node, recording_text=recording_text)
