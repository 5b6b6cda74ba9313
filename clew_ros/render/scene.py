"""What a picture shows: the world, optionally a plan and a landmark tree.

A :class:`Scene` is built from a world alone, a world and a plan, or a
recording (which holds the world YAML, the trajectory and the events, the
``landmark`` events among them). What it holds is drawn from the scene
description (:mod:`clew_ros.scene`): :meth:`Scene.motion` is
:func:`clew_ros.scene.path.plan_motion`, the tree :class:`~clew_ros.scene.items.TreeItems`.
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
from clew_ros.core.plan import Plan, PlanLandmark
from clew_ros.planar.world import World, load_world, world_from_parameters
from clew_ros.render.errors import RenderError
from clew_ros.scene.items import TreeItems
from clew_ros.scene.path import Motion, plan_motion

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


#: The landmark tree as a picture draws it: the scene's :class:`~clew_ros.scene.items.TreeItems`.
LandmarkGraph = TreeItems


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
        if self.plan is None:
            return None
        try:
            return plan_motion(self.world, self.plan, step_rad)
        except (KeyError, TypeError, ValueError, IndexError) as error:
            raise RenderError(f"the plan cannot be replayed in world {self.world.name!r}: {error!r}") from None

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
