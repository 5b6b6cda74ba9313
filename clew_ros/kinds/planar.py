"""The planar world (interface.md section 1) as a :class:`~clew_ros.kinds.base.WorldKind`."""

from __future__ import annotations

import dataclasses
import math
import threading
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

import numpy as np

from clew_ros.core.clew import PlanResult, Progress
from clew_ros.core.errors import ClewError
from clew_ros.core.plan import Plan
from clew_ros.core.settings import PlannerSettings, Termination
from clew_ros.core.tree import LandmarkTree
from clew_ros.kinds.base import WorldKind
from clew_ros.motion.playback import node_track
from clew_ros.planar import offline
from clew_ros.planar.kernel import warm_up
from clew_ros.planar.plan import checked_plan
from clew_ros.planar.space import plan
from clew_ros.planar.world import WORLD_KIND, World, world_from_parameters
from clew_ros.recording.trajectory import trajectory_to_plan
from clew_ros.ros import messages

__all__ = ["PlanarKind"]


class PlanarKind(WorldKind):
    """A planar arm moving a polygon on a table (:class:`~clew_ros.planar.world.World`)."""

    name = WORLD_KIND
    world_type = World
    problem_type = offline.Problem

    def problem_from_parameters(
        self,
        parameters: Mapping[str, Any],
        folder: Path,
        *,
        seed: int | None = None,
        time_limit: float | None = None,
        improve_time: float | None = None,
    ) -> offline.Problem:
        del folder  # a planar world names no file
        return offline.problem_from_parameters(parameters, seed=seed, time_limit=time_limit, improve_time=improve_time)

    def warm_up(self, problem: offline.Problem) -> float:
        del problem
        return warm_up()

    def plan_problem(
        self,
        problem: offline.Problem,
        *,
        cancel: threading.Event | None = None,
        progress: Callable[[Progress], None] | None = None,
    ) -> Plan:
        return offline.plan_problem(problem, cancel=cancel, progress=progress)

    def failed_plan(self, problem: offline.Problem, message: str, elapsed_s: float) -> Plan:
        return offline.failed_plan(problem.world, problem.settings, message, elapsed_s)

    def plan(
        self,
        world: World,
        settings: PlannerSettings,
        *,
        goal: np.ndarray | None,
        termination: Termination,
        progress: Callable[[Progress], None] | None,
    ) -> PlanResult:
        return plan(world, settings, goal=goal, termination=termination, progress=progress)

    def checked_plan(self, world: World, result: PlanResult) -> Plan:
        return checked_plan(world, result)

    def root_tree(self, world: World) -> LandmarkTree:
        return LandmarkTree(world.robot.initial, world.object.initial)

    def default_goal(self, world: World) -> np.ndarray:
        return np.asarray(world.object.goal, dtype=float)

    def with_goal(self, world: World, goal: np.ndarray) -> World:
        return dataclasses.replace(world, object=dataclasses.replace(world.object, goal=goal))

    def goal_from_pose_stamped(self, msg: Any, world: World) -> np.ndarray:
        return messages.goal_from_pose_stamped(msg, world)

    def goal_message(self, world: World, goal: np.ndarray, time_ns: int) -> Any:
        del world
        return messages.goal_pose_stamped(goal, time_ns)

    def landmark_markers(self, world: World, landmarks: Any, time_ns: int) -> Any:
        return messages.landmark_markers(landmarks, time_ns, world.object.polygon)

    def track(self, world: World, plan: Plan, setup: Any, timing: Any) -> Any:
        del setup
        return node_track(world, plan, timing)

    def setup_of(self, parameters: Mapping[str, Any], folder: Path) -> None:
        del parameters, folder

    def announce_world(self, out: Any, world: World, planner: PlannerSettings, recording: Any, setup: Any) -> None:
        del setup
        out.planar_world(world, planner, recording)

    def publish_sample(
        self, out: Any, world: World, state: Any, *, setup: Any, track: Any, time_ns: int, recording: Any
    ) -> None:
        del setup
        out.planar_sample(world, track, state, time_ns=time_ns, recording=recording)

    def pose_goal(self, msg: Any) -> tuple[float, ...]:
        p, q = msg.pose.position, msg.pose.orientation
        return (p.x, p.y, 2.0 * math.atan2(q.z, q.w))

    def plan_from_trajectory(
        self, parameters: Mapping[str, Any], trajectory: Any, outcome_fields: Mapping[str, Any], message: str
    ) -> Plan | None:
        del outcome_fields
        try:
            world = world_from_parameters(parameters)
        except ClewError:
            return None
        return trajectory_to_plan(world, trajectory, message=message, strict=True)

    def record_run(
        self,
        run: Any,
        world: World,
        plan: Plan,
        *,
        planner: PlannerSettings,
        node: Any,
        recording_text: str,
        setup: Any,
    ) -> None:
        del setup
        run.record_planar(world, plan, planner=planner, node=node, recording_text=recording_text)
