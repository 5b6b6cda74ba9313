"""What a picture shows: the world, optionally a plan and a landmark tree.

A :class:`Scene` is built from a world alone, a world and a plan, or a
recording (which holds the world YAML, the trajectory, the events and the
landmark markers). :meth:`Scene.motion` replays the plan with the core.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from clew_ros.core.errors import ClewError
from clew_ros.core.plan import replay
from clew_ros.core.world import World, load_world, world_from_parameters
from clew_ros.render.errors import RenderError

__all__ = ["LandmarkGraph", "Motion", "Scene", "world_from_yaml_text", "scene_from_world", "scene_from_plan",
           "scene_from_recording"]


@dataclass(frozen=True)
class LandmarkGraph:
    """The landmark tree as drawn: node positions (K, 2) and edges (E, 2, 2), in metres."""

    nodes: np.ndarray
    edges: np.ndarray
    root: int | None = 0

    @classmethod
    def from_plan(cls, world: World, landmarks: list[dict]) -> "LandmarkGraph | None":
        """Nodes where the object rests at each landmark (as the node's markers draw them); parent -> child edges."""
        del world  # the positions are in the landmarks themselves
        if not landmarks:
            return None
        tips = np.array([lm["object_pose"][:2] for lm in landmarks], dtype=float)
        index = {lm["id"]: i for i, lm in enumerate(landmarks)}
        edges = [(tips[index[lm["parent"]]], tips[i]) for i, lm in enumerate(landmarks)
                 if lm.get("parent") is not None and lm["parent"] in index]
        root = next((i for i, lm in enumerate(landmarks) if lm.get("parent") is None), None)
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


@dataclass
class Scene:
    world: World
    plan: dict | None = None
    landmarks: LandmarkGraph | None = None
    title: str = ""
    notes: list[str] = field(default_factory=list)

    def motion(self, step_rad: float = 0.01) -> Motion | None:
        """The plan replayed at ``step_rad`` (rad per joint between rows), or ``None`` without a plan."""
        if not self.plan or not self.plan.get("segments"):
            return None
        configurations, poses, held, segment, events = [], [], [], [], []
        row = 0
        previous_grasp = -1
        try:
            for index, (kind, grasp, q, p) in enumerate(replay(self.world, self.plan, step_rad)):
                grasp_now = int(grasp) if kind == "transfer" and grasp is not None else -1
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
        return Motion(np.concatenate(configurations), np.concatenate(poses), np.concatenate(held),
                      np.concatenate(segment), events)

    @property
    def grasp_count(self) -> int:
        if not self.plan:
            return 0
        return sum(s.get("kind") == "transfer" for s in self.plan.get("segments", []))


# --------------------------------------------------------------------------- builders


def world_from_yaml_text(text: str, *, source: str = "world YAML") -> World:
    """A world from the text of a ROS 2 parameter file (as recorded on ``~/world_yaml``).

    Collisions are not checked: a picture of a faulty world helps to see the fault.
    """
    try:
        document = yaml.safe_load(text)
    except yaml.YAMLError as error:
        raise RenderError(f"{source}: not valid YAML ({error})") from None
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


def scene_from_plan(world: World, plan: dict) -> Scene:
    if plan.get("world") not in (None, world.name):
        raise RenderError(f"the plan is for world {plan.get('world')!r}, not {world.name!r}")
    outcome = "plan found" if plan.get("success") else f"no plan: {plan.get('message', '')}"
    return Scene(world, plan if plan.get("success") else None, LandmarkGraph.from_plan(world, plan.get("landmarks", [])),
                 title=f"{world.name}: {outcome}")


def read_plan_file(path: str | Path) -> dict:
    try:
        plan = json.loads(Path(path).read_text())
    except (OSError, json.JSONDecodeError) as error:
        raise RenderError(f"{path}: cannot read the plan ({error})") from None
    if not isinstance(plan, dict) or plan.get("format") != "clew-plan/1":
        raise RenderError(f"{path}: expected a JSON object with format 'clew-plan/1'")
    return plan


def _topic(recording: Any, suffix: str) -> str | None:
    names = [t for t in recording.topics if t.rstrip("/").endswith("/" + suffix)]
    return names[0] if names else None


def _marker_points(marker: Any) -> tuple[list[np.ndarray], list[tuple[np.ndarray, np.ndarray]]]:
    """Nodes and edges that one marker draws, in the world frame (x, y)."""
    position = marker.pose.position
    q = marker.pose.orientation
    yaw = math.atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z))
    c, s = math.cos(yaw), math.sin(yaw)

    def world(point: Any) -> np.ndarray:
        return np.array([position.x + c * point.x - s * point.y, position.y + s * point.x + c * point.y])

    points = [world(p) for p in marker.points]
    kind = marker.type
    if kind in (6, 7, 8):  # CUBE_LIST, SPHERE_LIST, POINTS
        return points, []
    if kind in (1, 2, 3):  # CUBE, SPHERE, CYLINDER
        return [np.array([position.x, position.y])], []
    if kind == 5:  # LINE_LIST
        return [], [(points[i], points[i + 1]) for i in range(0, len(points) - 1, 2)]
    if kind == 4:  # LINE_STRIP
        return [], list(zip(points[:-1], points[1:]))
    return [], []


def landmarks_from_markers(arrays: list[Any]) -> LandmarkGraph | None:
    """The landmark tree drawn by a sequence of ``MarkerArray`` messages (later markers replace earlier ones)."""
    current: dict[tuple[str, int], Any] = {}
    for array in arrays:
        for marker in array.markers:
            if marker.action == 3:  # DELETEALL: every marker so far, whatever its namespace
                current = {}
            elif marker.action == 2:  # DELETE
                current.pop((marker.ns, marker.id), None)
            else:
                current[(marker.ns, marker.id)] = marker
    nodes: list[np.ndarray] = []
    edges: list[tuple[np.ndarray, np.ndarray]] = []
    for marker in current.values():
        more_nodes, more_edges = _marker_points(marker)
        nodes += more_nodes
        edges += more_edges
    if not nodes and not edges:
        return None
    return LandmarkGraph(np.array(nodes, dtype=float).reshape(-1, 2), np.array(edges, dtype=float).reshape(-1, 2, 2),
                         0 if nodes else None)


def scene_from_recording(path: str | Path, world: World | None = None) -> Scene:
    """The scene of a recorded run: world, plan rebuilt from the trajectory, landmark markers."""
    from clew_ros.recording import Recording, RecordingError, trajectory_to_plan

    try:
        recording = Recording(path)
    except RecordingError as error:
        raise RenderError(str(error)) from None
    notes = [] if recording.complete else ["recording cut short: read up to its last complete chunk"]
    if world is None:
        topic = _topic(recording, "world_yaml")
        message = recording.last(topic) if topic else None
        if message is None:
            raise RenderError(f"{path}: the recording holds no ~/world_yaml message; pass --world WORLD.yaml")
        world = world_from_yaml_text(message.data, source=f"{path} ({topic})")
    events = []
    topic = _topic(recording, "events")
    for message in recording.decoded(topic) if topic else []:
        try:
            event = json.loads(message.data)
        except (ValueError, TypeError):
            continue
        if isinstance(event, dict):
            events.append(event)
    grasps = [int(e["grasp"]) for e in events if e.get("event") == "grasp" and isinstance(e.get("grasp"), int)]
    outcome = next((e for e in reversed(events) if e.get("event") in ("succeeded", "aborted", "canceled")), None)
    plan = None
    topic = _topic(recording, "trajectory")
    trajectory = recording.last(topic) if topic else None
    if trajectory is not None and len(trajectory.points):
        plan = trajectory_to_plan(world, trajectory, grasps=grasps or None)
    topic = _topic(recording, "landmarks")
    landmarks = landmarks_from_markers(recording.decoded(topic)) if topic else None
    run = Path(path).name
    state = outcome["event"] if outcome else ("plan recorded" if plan else "no plan recorded")
    return Scene(world, plan, landmarks, title=f"{world.name}: run {run[:8]} {state}", notes=notes)
