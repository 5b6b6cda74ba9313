"""A recorded spatial run (interface.md sections 1b, 3 and 4) as frames to draw: its world and its plan.

- The world is drawn from what the recording holds, and no path named inside the recording is ever opened
  (a recording is a file people share; its paths may name anything on the machine that reads it): the
  last ``~/world_yaml`` gives the ``world.*`` parameters the run planned in (the run's goal), its robot is
  the recording's ``~/robot_description`` with each mesh taken from the arm's ``robot_links`` markers of
  ``~/world_markers`` (as the node simplified them), and the obstacles of a ``world.scene_file`` are the
  ``~/world_markers`` obstacles past those ``world.obstacle_names`` lists. A recording without them is
  refused, saying to pass ``--world``; ``--world`` (a spatial world file the user names) replaces the
  recorded world altogether.
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
from clew_ros.core.parameters import LIMITS
from clew_ros.render.errors import RenderError
from clew_ros.render.spatial.frames import FrameSampling, SpatialFrames, frames_from_plan
from clew_ros.spatial import WORLD_KIND
from clew_ros.spatial.transforms import matrix_pose, pose_matrix, quaternion_matrix
from clew_ros.spatial.world import SpatialWorld

__all__ = ["RecordedSpatialRun", "is_spatial_recording", "recorded_parameters", "spatial_recording"]

_OUTCOMES = ("succeeded", "aborted", "canceled")
#: ``visualization_msgs/Marker`` types: the solids an obstacle is drawn as, and a triangle list.
_SHAPES = {1: "box", 3: "cylinder", 2: "sphere"}
_TRIANGLE_LIST = 11


@dataclass(frozen=True, eq=False)
class RecordedSpatialRun:
    """A spatial recording read: its world, the frames of its plan (the start alone without one), and what
    the world was read from (``world_yaml + robot_description + world_markers`` or ``--world``)."""

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
    if not isinstance(world, Mapping) or world.get("kind") != WORLD_KIND:
        return None
    return dict(parameters)  # type: ignore[arg-type]


def _world(parameters: dict[str, Any], recording: Any, source: str) -> tuple[SpatialWorld, str]:
    """The recorded world, drawn from what the recording holds and nothing else: no path named inside it is
    opened (a recording is a file people share). The robot is ``~/robot_description`` with its meshes taken
    from the ``robot_links`` of ``~/world_markers``; the obstacles of a ``world.scene_file`` are the
    ``~/world_markers`` obstacles past those ``world.obstacle_names`` lists."""
    from clew_ros.spatial.robot import robot_from_parameters
    from clew_ros.spatial.spheres import sphere_model
    from clew_ros.spatial.world import spatial_world_from_parameters

    world_tree = dict(parameters["world"])
    robot = world_tree.get("robot")
    if not isinstance(robot, Mapping):
        raise RenderError(f"{source} (~/world_yaml): world.robot is not a mapping; pass the world with --world")
    topic = _topic(recording, "robot_description")
    description = recording.last(topic) if topic else None
    if description is None:
        raise RenderError(
            f"{source}: the recording holds no ~/robot_description to draw the robot from; pass the world with "
            "--world WORLD.yaml"
        )
    topic = _topic(recording, "world_markers")
    markers = list(getattr(recording.last(topic), "markers", [])) if topic else []
    robot_tree = {k: v for k, v in robot.items() if k not in ("urdf", "srdf", "description")}
    robot_tree["description"] = description.data
    world_tree["robot"] = robot_tree
    origin = "world_yaml + robot_description + world_markers"
    if "scene_file" in world_tree:
        _inline_scene(world_tree, markers, source)
    folder = Path(source).resolve().parent
    try:
        model = robot_from_parameters(robot_tree, folder, meshes=_link_meshes(markers, source))
        prepared = (model, sphere_model(model))
        return spatial_world_from_parameters({**parameters, "world": world_tree}, folder, prepared=prepared), origin
    except ClewError as error:
        raise RenderError(f"{source} (~/world_yaml): {error}; pass the world with --world WORLD.yaml") from None


def _link_meshes(markers: list[Any], source: str) -> dict[str, list[np.ndarray]]:
    """The arm's meshes ``~/world_markers`` draws (``robot_links`` TRIANGLE_LISTs in their link's frame), by
    link, in marker order (the order of the link's collisions)."""
    out: dict[str, list[np.ndarray]] = {}
    total = 0
    for marker in sorted(markers, key=lambda m: int(getattr(m, "id", 0))):
        if getattr(marker, "ns", "") == "robot_links" and getattr(marker, "type", None) == _TRIANGLE_LIST:
            total += len(marker.points)
            if total > 3 * LIMITS.max_total_triangles:  # checked before the points are read
                raise RenderError(
                    f"{source}: the ~/world_markers meshes hold more than Limits.max_total_triangles "
                    f"({LIMITS.max_total_triangles}) triangles"
                )
            corners = np.array([(p.x, p.y, p.z) for p in marker.points], dtype=np.float64).reshape(-1, 3)
            out.setdefault(str(marker.header.frame_id), []).append(corners)
    return out


def _inline_scene(world_tree: dict[str, Any], markers: list[Any], source: str) -> None:
    """Replace ``world.scene_file`` (never opened) by the obstacles ``~/world_markers`` draws past those of
    ``world.obstacle_names`` (ids are indices in the world's obstacles), named ``scene_<id>``; the supports
    become the ``supports`` markers."""
    names = world_tree.get("obstacle_names") or []
    names = list(names) if isinstance(names, list) else []
    solids = {
        int(m.id): m
        for m in markers
        if getattr(m, "ns", "") in ("obstacles", "supports") and getattr(m, "type", None) in _SHAPES
    }
    if len(solids) > LIMITS.max_obstacles:  # checked before any is read
        raise RenderError(
            f"{source}: ~/world_markers hold more than Limits.max_obstacles ({LIMITS.max_obstacles}) obstacles"
        )
    if not solids:
        raise RenderError(
            f"{source}: ~/world_yaml names a scene file and the recording's ~/world_markers hold no obstacles; "
            "pass the world with --world WORLD.yaml"
        )
    table = dict(world_tree.get("obstacles") or {})
    supports = []
    for index in sorted(solids):
        marker = solids[index]
        name = names[index] if index < len(names) else f"scene_{index}"
        if index >= len(names):
            names.append(name)
            table[name] = _marker_obstacle(marker)
        if marker.ns == "supports":
            supports.append(name)
    world_tree.pop("scene_file")
    world_tree["obstacle_names"], world_tree["obstacles"], world_tree["supports"] = names, table, supports


def _marker_obstacle(marker: Any) -> dict[str, Any]:
    """A CUBE / CYLINDER / SPHERE marker as an obstacle's parameters (``scale`` as RViz draws it)."""
    shape = _SHAPES[marker.type]
    scale = (float(marker.scale.x), float(marker.scale.y), float(marker.scale.z))
    size = {"box": list(scale), "cylinder": [scale[2], scale[0] / 2], "sphere": [scale[0] / 2]}[shape]
    p, q = marker.pose.position, marker.pose.orientation
    pose = matrix_pose(quaternion_matrix([p.x, p.y, p.z], [q.x, q.y, q.z, q.w]))
    return {"shape": shape, "size": size, "pose": pose}


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
