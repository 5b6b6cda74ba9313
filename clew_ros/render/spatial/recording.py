"""A recorded spatial run (interface.md sections 1b, 3 and 4) as frames to draw: its world and its plan.

- The world is the recording's last ``~/world_yaml``: the ``world.*`` parameters the run planned in (the
  run's goal, the files it names as absolute paths). When the URDF file it names is not on this machine
  (a recording carried elsewhere), the robot is the recording's ``~/robot_description`` instead (the same
  URDF, its meshes as URIs a viewer opens); a scene file that is missing is an error that says to pass
  ``--world``. ``--world`` (a spatial world file) replaces the recorded world altogether.
- The plan is rebuilt as :class:`~clew_ros.client.PlannerClient` rebuilds it: the last ``~/trajectory``
  (the planned joints' URDF names and positions) cut into segments by the ``succeeded`` event's
  ``segments`` (:func:`~clew_ros.recording.trajectory.spatial_trajectory_plan`), then replayed into frames
  (:func:`~clew_ros.render.spatial.frames.frames_from_plan`). A run without a plan (aborted, canceled, cut
  short) is the world at its start, the outcome in the caption.
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from clew_ros.core.errors import ClewError
from clew_ros.render.errors import RenderError
from clew_ros.render.spatial.frames import FrameSampling, SpatialFrames, frames_from_plan
from clew_ros.spatial.transforms import pose_matrix
from clew_ros.spatial.world import SpatialWorld

__all__ = ["RecordedSpatialRun", "is_spatial_recording", "recorded_parameters", "spatial_recording"]

_OUTCOMES = ("succeeded", "aborted", "canceled")


@dataclass(frozen=True, eq=False)
class RecordedSpatialRun:
    """A spatial recording read: its world, the frames of its plan (the start alone without one), and what
    the world was read from (``world_yaml``, ``world_yaml + robot_description`` or ``--world``)."""

    world: SpatialWorld
    frames: SpatialFrames
    world_source: str


def _topic(recording: Any, suffix: str) -> str | None:
    names = [t for t in recording.topics if t.rstrip("/").endswith("/" + suffix)]
    return names[0] if names else None


def recorded_parameters(text: str, source: str) -> dict[str, Any] | None:
    """The ``ros__parameters`` of a recorded ``~/world_yaml`` when its world is spatial, else ``None``."""
    try:
        document = yaml.safe_load(text)
    except (yaml.YAMLError, RecursionError, ValueError) as error:
        raise RenderError(f"{source}: not a parameter file YAML can read ({type(error).__name__})") from None
    if not isinstance(document, Mapping) or not document:
        return None
    entry = next(iter(document.values()))
    parameters = entry.get("ros__parameters") if isinstance(entry, Mapping) else None
    world = parameters.get("world") if isinstance(parameters, Mapping) else None
    if not isinstance(world, Mapping) or world.get("kind") != "spatial":
        return None
    return dict(parameters)  # type: ignore[arg-type]


def _world(parameters: dict[str, Any], recording: Any, source: str) -> tuple[SpatialWorld, str]:
    """The recorded world; its robot from ``~/robot_description`` when the URDF file it names is gone."""
    from clew_ros.spatial.world import spatial_world_from_parameters

    folder = Path(source).resolve().parent
    robot = parameters["world"].get("robot")
    urdf = robot.get("urdf") if isinstance(robot, Mapping) else None
    origin = "world_yaml"
    if isinstance(urdf, str) and not urdf.startswith("package://") and not Path(urdf.removeprefix("file://")).is_file():
        topic = _topic(recording, "robot_description")
        message = recording.last(topic) if topic else None
        if message is None:
            raise RenderError(
                f"{source}: the URDF {urdf!r:.200} that ~/world_yaml names is not here and the recording holds no "
                "~/robot_description; pass the world with --world WORLD.yaml"
            )
        world_tree = dict(parameters["world"])
        world_tree["robot"] = {k: v for k, v in robot.items() if k != "urdf"} | {"description": message.data}
        parameters = {**parameters, "world": world_tree}
        origin = "world_yaml + robot_description"
    try:
        return spatial_world_from_parameters(parameters, folder), origin
    except ClewError as error:
        raise RenderError(f"{source} (~/world_yaml): {error}; pass the world with --world WORLD.yaml") from None


def _events(recording: Any) -> list[dict[str, Any]]:
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


def _start(world: SpatialWorld, title: str) -> SpatialFrames:
    rest = None if world.object is None else pose_matrix(world.object.initial)[None]
    return SpatialFrames(world.initial[None], rest, np.zeros(1, dtype=bool), title)


def is_spatial_recording(path: str | Path) -> bool:
    """Whether the recording at ``path`` is of a spatial run (its last ``~/world_yaml`` says so)."""
    from clew_ros.recording import Recording, RecordingError

    try:
        recording = Recording(path)
        topic = _topic(recording, "world_yaml")
        message = recording.last(topic) if topic else None
    except RecordingError as error:
        raise RenderError(str(error)) from None
    return message is not None and recorded_parameters(message.data, f"{path} ({topic})") is not None


def spatial_recording(
    path: str | Path, world: SpatialWorld | None = None, sampling: FrameSampling | None = None
) -> RecordedSpatialRun | None:
    """The recorded spatial run at ``path`` (a run directory or ``.mcap``), or ``None`` when the recording's
    world is not spatial (a planar run; also one without ``~/world_yaml`` when no ``world`` is given).
    ``world`` replaces the recorded world. Every error a :class:`RenderError` naming the file."""
    from clew_ros.recording import Recording, RecordingError, spatial_trajectory_plan

    source = str(path)
    try:
        recording = Recording(path)
        origin = "--world"
        if world is None:
            topic = _topic(recording, "world_yaml")
            message = recording.last(topic) if topic else None
            parameters = None if message is None else recorded_parameters(message.data, f"{source} ({topic})")
            if parameters is None:
                return None
            world, origin = _world(parameters, recording, source)
        events = _events(recording)
        topic = _topic(recording, "trajectory")
        trajectory = recording.last(topic) if topic else None
    except RecordingError as error:
        raise RenderError(str(error)) from None
    run = Path(path).name[:8]
    outcome = next((e for e in reversed(events) if e.get("event") in _OUTCOMES), None)
    if outcome is None or outcome.get("event") != "succeeded" or trajectory is None or not len(trajectory.points):
        state = "no outcome recorded" if outcome is None else f"{outcome['event']}: {outcome.get('message', '')!s:.100}"
        return RecordedSpatialRun(world, _start(world, f"{world.name}: run {run} {state}"), origin)
    if "segments" not in outcome:
        raise RenderError(f"{source}: the succeeded event has no segments (recorded by an older node)")
    try:
        plan = spatial_trajectory_plan(trajectory, outcome, str(outcome.get("message", "")), world.name)
    except (ValueError, TypeError, KeyError, IndexError) as error:
        raise RenderError(f"{source}: the plan cannot be rebuilt from ~/trajectory and the events: {error}") from None
    if list(plan.joint_names) != list(world.robot.joint_names):
        raise RenderError(
            f"{source}: ~/trajectory names the joints {list(plan.joint_names)}, the world plans "
            f"{list(world.robot.joint_names)}"
        )
    frames = frames_from_plan(world, plan.to_dict(), source, sampling)
    transfers = sum(1 for s in plan.segments if s.kind == "transfer")
    title = f"{world.name}: run {run} succeeded, {len(plan.segments)} segments, {transfers} transfer(s)"
    return RecordedSpatialRun(world, SpatialFrames(frames.joints, frames.object_poses, frames.held, title), origin)
