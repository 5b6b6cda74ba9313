"""Frames to draw in a spatial world, from the files ``clew_render`` reads: a spatial world's parameter file,
a spatial plan file (``clew-plan/1`` with ``"world_kind": "spatial"``, interface.md sections 1b and 2)
replayed, or a frames file.

A frames file is JSON: ``{"joints": [[...], ...], "object_poses": [[x, y, z, roll, pitch, yaw], ...],
"held": [false, ...]}`` -- the planned joints per frame (T, n), and optionally the object's pose per frame
(or one pose: at rest there; absent: at rest at its initial pose) and whether the gripper holds it.

A plan is replayed as the contract says: straight joint-space pieces between waypoints (sampled every
``step_rad`` at most); in a transit the object rests where it is, in a transfer with grasp g it rides on
the tool centre point at the inverse of g (g is the tcp's pose in the object's frame).
"""

from __future__ import annotations

import itertools
import json
import math
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from clew_ros.core.errors import ClewError
from clew_ros.core.files import FileRefusedError, read_regular_file
from clew_ros.core.plan import FORMAT, PlanFileLimits
from clew_ros.planar.world import read_parameter_file
from clew_ros.render.errors import RenderError
from clew_ros.spatial import WORLD_KIND
from clew_ros.spatial.transforms import pose_matrix
from clew_ros.spatial.world import SpatialWorld

__all__ = [
    "FrameSampling",
    "SpatialFrames",
    "frames_from_document",
    "frames_from_plan",
    "is_spatial_world_file",
    "load_spatial_world",
    "read_frames",
]

Array = NDArray[np.float64]


@dataclass(frozen=True)
class FrameSampling:
    """How a plan is cut into frames."""

    step_rad: float = 0.04  # the largest joint motion between frames (rad, or m for a prismatic joint): smooth
    max_frames: int = 150  # frames of a long plan thinned to this many (12 s of GIF at 80 ms a frame)


@dataclass(frozen=True, eq=False)
class SpatialFrames:
    """The planned joints per frame (T, n), the object's 4x4 pose per frame (T, 4, 4; ``None`` without an
    object), whether the gripper holds it (T,), and a caption."""

    joints: Array
    object_poses: Array | None
    held: NDArray[np.bool_]
    title: str


def is_spatial_world_file(path: str | Path) -> bool:
    """Whether a world parameter file says ``world.kind: spatial``; a file that cannot be read is refused
    with a :class:`RenderError` naming it."""
    try:
        parameters = read_parameter_file(path)
    except ClewError as error:
        raise RenderError(str(error)) from None
    world = parameters.get("world")
    return isinstance(world, Mapping) and world.get("kind") == WORLD_KIND


def load_spatial_world(path: str | Path) -> SpatialWorld:
    """The spatial world of a parameter file (relative paths inside it read from its folder); every error
    a :class:`RenderError` naming the file and the parameter."""
    from clew_ros.spatial.world import spatial_world_from_parameters

    path = Path(path)
    try:
        return spatial_world_from_parameters(read_parameter_file(path), path.parent)
    except ClewError as error:
        raise RenderError(f"{path}: {error}") from None


def _read_json(path: Path) -> Any:
    limit = PlanFileLimits().max_bytes
    try:
        data = read_regular_file(path, limit, "PlanFileLimits.max_bytes")
    except FileRefusedError as error:
        raise RenderError(f"{path}: cannot read ({error})") from None

    def refuse(name: str) -> Any:
        raise RenderError(f"{path}: {name} is not a number a frame may hold")

    try:
        return json.loads(data.decode("utf-8"), parse_constant=refuse)
    except UnicodeDecodeError as error:
        raise RenderError(f"{path}: expected UTF-8 JSON (byte {error.start})") from None
    except (json.JSONDecodeError, RecursionError) as error:
        raise RenderError(f"{path}: expected JSON ({type(error).__name__}: {error})") from None


def _array(value: Any, shape: tuple[int, ...], where: str, what: str) -> Array:
    try:
        out = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError, OverflowError):
        raise RenderError(f"{where}: expected {what}") from None
    if out.shape != shape or not np.all(np.isfinite(out)):
        raise RenderError(f"{where}: expected {what}, got shape {out.shape}")
    return out


def _thin(count: int, events: set[int], sampling: FrameSampling) -> list[int]:
    """At most ``max_frames`` rows of ``count``, evenly spread, keeping the first, the last and ``events``."""
    if count <= sampling.max_frames:
        return list(range(count))
    keep = {0, count - 1, *events}
    spare = max(2, sampling.max_frames - len(keep))
    keep |= {round(r) for r in np.linspace(0, count - 1, spare)}
    return sorted(keep)


def _check_plan(world: SpatialWorld, plan: Any, source: str) -> list[Any]:
    """The plan's segments, once its header is the world's: format, world kind and name, joint names."""
    if not isinstance(plan, Mapping) or plan.get("format") != FORMAT:
        raise RenderError(f"{source}: expected a JSON object with format {FORMAT!r}")
    if plan.get("world_kind", WORLD_KIND) != WORLD_KIND:
        raise RenderError(f"{source}: world_kind: expected spatial (the world is), got {plan.get('world_kind')!r:.40}")
    if plan.get("world") != world.name:
        raise RenderError(f"{source}: world: the plan is for world {plan.get('world')!r:.80}, not {world.name!r}")
    if plan.get("joint_names") != list(world.robot.joint_names):
        raise RenderError(f"{source}: joint_names: expected the world's planned joints {list(world.robot.joint_names)}")
    segments = plan.get("segments")
    if not isinstance(segments, list):
        raise RenderError(f"{source}: segments: expected a list")
    return segments


def _segment(world: SpatialWorld, segment: Any, where: str, step: float) -> tuple[list[Array], Array | None]:
    """A segment's configurations, each straight piece sampled every ``step`` at most, and the inverse of
    its grasp's 4x4 pose (``None`` in a transit)."""
    robot = world.robot
    if not isinstance(segment, Mapping) or segment.get("kind") not in ("transit", "transfer"):
        raise RenderError(f"{where}: expected kind transit or transfer, grasp and waypoints")
    waypoints = segment.get("waypoints")
    if not isinstance(waypoints, list) or not waypoints:
        raise RenderError(f"{where}.waypoints: expected a list of configurations")
    points = _array(waypoints, (len(waypoints), robot.dof), f"{where}.waypoints", f"{robot.dof} numbers each")
    inverse_grasp: Array | None = None
    if segment["kind"] == "transfer":
        if world.object is None:
            raise RenderError(f"{where}: a transfer, but the world has no object")
        grasp, count = segment.get("grasp"), len(world.object.grasps)
        if isinstance(grasp, bool) or not isinstance(grasp, int) or not 0 <= grasp < count:
            raise RenderError(f"{where}.grasp: expected a grasp index 0 to {count - 1}, got {grasp!r:.40}")
        inverse_grasp = np.asarray(np.linalg.inv(pose_matrix(world.object.grasps[grasp])), dtype=np.float64)
    rows: list[Array] = [points[0]]
    for a, b in itertools.pairwise(points):
        count = max(1, math.ceil(float(np.abs(b - a).max()) / step))
        rows += [a + (b - a) * (k / count) for k in range(1, count + 1)]
    return rows, inverse_grasp


def frames_from_plan(
    world: SpatialWorld, plan: Any, source: str = "plan", sampling: FrameSampling | None = None
) -> SpatialFrames:
    """The frames of a spatial plan (the parsed plan file): every straight piece sampled at ``step_rad``,
    the object resting or riding on the tcp; a failed plan gives the start alone."""
    sampling = sampling or FrameSampling()
    segments = _check_plan(world, plan, source)
    rest = pose_matrix(world.object.initial) if world.object is not None else None
    if plan.get("success") is not True or not segments:
        start = None if rest is None else rest[None]
        title = f"{world.name}: no plan: {plan.get('message')!s:.120}"
        return SpatialFrames(world.initial[None], start, np.zeros(1, dtype=bool), title)
    joints: list[Array] = []
    poses: list[Array] = []
    held: list[bool] = []
    events: set[int] = set()
    for i, segment in enumerate(segments):
        rows, inverse_grasp = _segment(world, segment, f"{source}: segments[{i}]", max(sampling.step_rad, 1e-6))
        transfer = inverse_grasp is not None
        if joints and transfer != held[-1]:
            events.add(len(joints))
        for q in rows:
            joints.append(q)
            held.append(transfer)
            if rest is not None:
                poses.append(world.robot.tcp_pose(q.tolist()) @ inverse_grasp if inverse_grasp is not None else rest)
        if transfer:
            rest = poses[-1]
    keep = _thin(len(joints), events, sampling)
    transfers = sum(1 for s in segments if s.get("kind") == "transfer")
    return SpatialFrames(
        np.asarray(joints)[keep],
        np.asarray(poses)[keep] if rest is not None else None,
        np.asarray(held, dtype=bool)[keep],
        f"{world.name}: plan of {len(segments)} segments, {transfers} transfer(s)",
    )


def frames_from_document(world: SpatialWorld, data: Any, source: str = "frames") -> SpatialFrames:
    """The frames of a frames file (the parsed JSON; see the module docstring)."""
    if not isinstance(data, Mapping) or "joints" not in data:
        raise RenderError(f"{source}: expected a plan file ({FORMAT}) or an object with joints (T, n)")
    raw = data["joints"]
    count = len(raw) if isinstance(raw, list) else 0
    if count == 0:
        raise RenderError(f"{source}: joints: expected a non-empty list of configurations")
    joints = _array(raw, (count, world.robot.dof), f"{source}: joints", f"{world.robot.dof} numbers per frame")
    poses = None
    if world.object is not None:
        value = data.get("object_poses", list(world.object.initial))
        if isinstance(value, list) and value and not isinstance(value[0], list):
            value = [value]
        items = value if isinstance(value, list) else []
        six = _array(
            items, (len(items), 6), f"{source}: object_poses", "poses of 6 numbers [x, y, z, roll, pitch, yaw]"
        )
        if len(six) not in (1, count):
            raise RenderError(f"{source}: object_poses: expected one pose or one per frame ({count}), got {len(six)}")
        poses = np.array([pose_matrix(p) for p in np.repeat(six, count // len(six), axis=0)])
    elif data.get("object_poses") is not None:
        raise RenderError(f"{source}: object_poses: the world has no object")
    flags = data.get("held", [False] * count)
    if not isinstance(flags, list) or len(flags) != count or not all(isinstance(f, bool) for f in flags):
        raise RenderError(f"{source}: held: expected {count} true/false values, one per frame")
    return SpatialFrames(joints, poses, np.asarray(flags, dtype=bool), f"{world.name}: {count} frames")


def read_frames(path: str | Path, world: SpatialWorld, sampling: FrameSampling | None = None) -> SpatialFrames:
    """A plan file or a frames file, by its content (a plan says ``"format": "clew-plan/1"``)."""
    path = Path(path)
    data = _read_json(path)
    if isinstance(data, Mapping) and "format" in data:
        return frames_from_plan(world, data, str(path), sampling)
    return frames_from_document(world, data, str(path))
