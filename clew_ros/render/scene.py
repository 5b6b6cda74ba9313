"""What a picture shows: the world, optionally a plan and a landmark tree.

A :class:`Scene` is built from a world alone, a world and a plan, or a
recording (which holds the world YAML, the trajectory and the events, the
``landmark`` events among them). :meth:`Scene.motion` replays the plan with
the core (:func:`clew_ros.core.plan.replay`).
"""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from clew_ros.core.errors import ClewError, PlanFileError
from clew_ros.core.plan import Plan, PlanLandmark, replay
from clew_ros.core.world import World, load_world, world_from_parameters
from clew_ros.render.errors import RenderError

__all__ = [
    "LandmarkGraph",
    "Motion",
    "Scene",
    "landmarks_from_events",
    "load_world_file",
    "read_plan_file",
    "root_landmark",
    "scene_from_plan",
    "scene_from_recording",
    "scene_from_world",
    "world_from_yaml_text",
]


@dataclass(frozen=True)
class LandmarkGraph:
    """The landmark tree as drawn: node positions (K, 2) and edges (E, 2, 2), in metres."""

    nodes: np.ndarray
    edges: np.ndarray
    root: int | None = 0

    @classmethod
    def from_landmarks(cls, landmarks: Sequence[PlanLandmark]) -> LandmarkGraph | None:
        """Nodes where the object rests at each landmark (as the node's markers draw them), parent -> child edges;
        ``None`` without landmarks."""
        if not landmarks:
            return None
        tips = np.array([lm.object_pose[:2] for lm in landmarks], dtype=float)
        index = {lm.id: i for i, lm in enumerate(landmarks)}
        edges = [
            (tips[index[lm.parent]], tips[i])
            for i, lm in enumerate(landmarks)
            if lm.parent is not None and lm.parent in index
        ]
        root = next((i for i, lm in enumerate(landmarks) if lm.parent is None), None)
        return cls(tips, np.array(edges, dtype=float).reshape(-1, 2, 2), root)


@dataclass(frozen=True)
class Motion:
    """A plan replayed: one row per configuration along it.

    ``held[i]`` is the grasp index held at row ``i`` (-1: none);
    ``events`` lists ``(row, "grasp" | "ungrasp", grasp)`` where the gripper changes.
    """

    configurations: np.ndarray  # (M, n) rad
    object_poses: np.ndarray  # (M, 3)
    held: np.ndarray  # (M,) int
    segment: np.ndarray  # (M,) int
    events: list[tuple[int, str, int]]

    def __len__(self) -> int:
        return len(self.configurations)

    def sample(self, count: int, *, before_events: bool = True) -> list[int]:
        """About ``count`` rows evenly spaced along the joint-space path, always with the ends and events.

        With ``before_events`` the row just before each event is included too
        (an animation shows the gripper arrive, then change).
        """
        steps = np.max(np.abs(np.diff(self.configurations, axis=0)), axis=1) if len(self) > 1 else np.zeros(0)
        distance = np.concatenate([[0.0], np.cumsum(steps)])
        if distance[-1] <= 0 or count <= 1:
            rows = {0, len(self) - 1}
        else:
            targets = np.linspace(0.0, distance[-1], max(2, count))
            rows = set(np.searchsorted(distance, targets).clip(0, len(self) - 1).tolist())
        for row, _kind, _grasp in self.events:
            rows.update({max(0, row - 1), row} if before_events else {row})
        return sorted(rows)

    def rest_poses(self) -> list[np.ndarray]:
        """Where the object is put down (after each ungrasp), in order."""
        return [self.object_poses[row] for row, kind, _grasp in self.events if kind == "ungrasp"]


@dataclass
class Scene:
    """What one picture shows: a world, a plan to draw along (``None``: the arm at its start), the landmark tree,
    a title and notes for the caption."""

    world: World
    plan: Plan | None = None
    landmarks: LandmarkGraph | None = None
    title: str = ""
    notes: list[str] = field(default_factory=list)

    def motion(self, step_rad: float = 0.01) -> Motion | None:
        """The plan replayed at ``step_rad`` (rad per joint between rows), or ``None`` without a plan."""
        if self.plan is None or not self.plan.segments:
            return None
        configurations, poses, held, segment, events = [], [], [], [], []
        row = 0
        previous_grasp = -1
        try:
            for step in replay(self.world, self.plan, step_rad):
                index, q, p = step.index, step.configurations, step.object_poses
                grasp_now = int(step.grasp) if step.kind == "transfer" and step.grasp is not None else -1
                if grasp_now != previous_grasp:
                    if previous_grasp >= 0:
                        events.append((row, "ungrasp", previous_grasp))
                    if grasp_now >= 0:
                        events.append((row, "grasp", grasp_now))
                previous_grasp = grasp_now
                configurations.append(q)
                poses.append(np.asarray(p))
                held.append(np.full(len(q), grasp_now))
                segment.append(np.full(len(q), index))
                row += len(q)
        except (KeyError, TypeError, ValueError, IndexError) as error:
            raise RenderError(f"the plan cannot be replayed in world {self.world.name!r}: {error!r}") from None
        return Motion(
            np.concatenate(configurations), np.concatenate(poses), np.concatenate(held), np.concatenate(segment), events
        )

    @property
    def grasp_count(self) -> int:
        return 0 if self.plan is None else self.plan.grasp_count


# --------------------------------------------------------------------------- builders


def world_from_yaml_text(text: str, *, source: str = "world YAML") -> World:
    """A world from the text of a ROS 2 parameter file (as recorded on ``~/world_yaml``).

    Collisions are not checked: a picture of a faulty world helps to see the fault.
    """
    try:
        document = yaml.safe_load(text)
    except yaml.YAMLError as error:
        raise RenderError(f"{source}: not valid YAML ({error})") from None
    except (RecursionError, ValueError) as error:  # absurd nesting, numbers YAML cannot hold
        raise RenderError(f"{source}: not a parameter file YAML can read ({type(error).__name__})") from None
    if not isinstance(document, dict):
        raise RenderError(f"{source}: expected a parameter file mapping")
    parameters = None
    if "world" in document:
        parameters = document
    else:
        for key, value in document.items():
            if str(key).rsplit("/", 1)[-1] in ("clew_planner", "**") and isinstance(value, dict):
                parameters = value.get("ros__parameters")
                break
    if not isinstance(parameters, dict):
        raise RenderError(f"{source}: expected a 'clew_planner' or '/**' key with 'ros__parameters'")
    try:
        return world_from_parameters(parameters)
    except ClewError as error:
        raise RenderError(f"{source}: {error}") from None


def load_world_file(path: str | Path) -> World:
    try:
        return load_world(path)
    except ClewError as error:
        raise RenderError(str(error)) from None


def scene_from_world(world: World) -> Scene:
    return Scene(world, title=f"world {world.name}")


def scene_from_plan(world: World, plan: Plan) -> Scene:
    if plan.world != world.name:
        raise RenderError(f"the plan is for world {plan.world!r}, not {world.name!r}")
    outcome = "plan found" if plan.success else f"no plan: {plan.message}"
    return Scene(
        world,
        plan if plan.success else None,
        LandmarkGraph.from_landmarks(plan.landmarks),
        title=f"{world.name}: {outcome}",
    )


def read_plan_file(path: str | Path) -> Plan:
    """:meth:`Plan.read`, its error as a :class:`RenderError`."""
    try:
        return Plan.read(path)
    except PlanFileError as error:
        raise RenderError(str(error)) from None


def _topic(recording: Any, suffix: str) -> str | None:
    names = [t for t in recording.topics if t.rstrip("/").endswith("/" + suffix)]
    return names[0] if names else None


ROOT_ID = 0
"""Id of the root landmark of every run (:class:`clew_ros.core.tree.LandmarkTree`)."""


def root_landmark(world: World) -> PlanLandmark:
    """The landmark every run starts from: the arm at ``robot.initial``, the object at ``object.initial``."""
    return PlanLandmark(
        ROOT_ID, None, np.array(world.robot.initial, dtype=float), np.array(world.object.initial, dtype=float), None
    )


def landmarks_from_events(events: Sequence[Mapping[str, Any]], world: World) -> tuple[PlanLandmark, ...]:
    """The landmark tree of a run in ``world`` from its ``landmark`` events (``id``, ``parent``, ``grasp``,
    ``object_pose``, ``joints``), in the order first announced; a later event for the same id replaces the earlier.

    The node announces every landmark but the root, which it publishes only as a
    marker: when the events name no root, :func:`root_landmark` comes first.
    Events that lack those fields (or are not ``landmark`` events) are passed
    over; without any landmark event there is no tree (an empty tuple).
    """
    found: dict[int, PlanLandmark] = {}
    for event in events:
        if event.get("event") != "landmark":
            continue
        try:
            landmark = PlanLandmark.from_dict(event, "landmark event")
        except PlanFileError:
            continue
        found[landmark.id] = landmark
    if not found or any(landmark.parent is None for landmark in found.values()) or ROOT_ID in found:
        return tuple(found.values())
    return (root_landmark(world), *found.values())


def _events(recording: Any) -> list[dict[str, Any]]:
    """The JSON objects recorded on ``~/events``, in order (messages that are not one are passed over)."""
    topic = _topic(recording, "events")
    events = []
    for message in recording.decoded(topic) if topic else []:
        try:
            event = json.loads(message.data)
        except (ValueError, TypeError, RecursionError):
            continue
        if isinstance(event, dict):
            events.append(event)
    return events


def scene_from_recording(path: str | Path, world: World | None = None) -> Scene:
    """The scene of a recorded run: its world, the plan rebuilt from ``~/trajectory`` and the landmark tree of its
    ``landmark`` events (none without such events)."""
    from clew_ros.recording import Recording, RecordingError, trajectory_to_plan

    try:
        recording = Recording(path)
        notes = [] if recording.complete else ["recording cut short: read up to its last complete chunk"]
        if recording.problem:
            notes.append(f"stopped at: {recording.problem}")
        if world is None:
            topic = _topic(recording, "world_yaml")
            message = recording.last(topic) if topic else None
            if message is None:
                raise RenderError(f"{path}: the recording holds no ~/world_yaml message; pass --world WORLD.yaml")
            world = world_from_yaml_text(message.data, source=f"{path} ({topic})")
        events = _events(recording)
        grasps = [int(e["grasp"]) for e in events if e.get("event") == "grasp" and isinstance(e.get("grasp"), int)]
        outcome = next((e for e in reversed(events) if e.get("event") in ("succeeded", "aborted", "canceled")), None)
        plan = None
        topic = _topic(recording, "trajectory")
        trajectory = recording.last(topic) if topic else None
        if trajectory is not None and len(trajectory.points):
            plan = trajectory_to_plan(world, trajectory, grasps=grasps or None, source=f"{path} ({topic})")
    except RecordingError as error:
        raise RenderError(str(error)) from None
    landmarks = LandmarkGraph.from_landmarks(landmarks_from_events(events, world))
    run = Path(path).name
    state = outcome["event"] if outcome else ("plan recorded" if plan else "no plan recorded")
    return Scene(world, plan, landmarks, title=f"{world.name}: run {run[:8]} {state}", notes=notes)
