"""Obstacles and bounds of a spatial world, from parameters and MoveIt planning scene YAML (interface.md
section 1b).

An obstacle is a ``shape_msgs/SolidPrimitive``: ``box`` (``size`` = full extents ``[x, y, z]``),
``cylinder`` (``[height, radius]`` along its own z) or ``sphere`` (``[radius]``), at a ``pose``
``[x, y, z, roll, pitch, yaw]`` in ``world`` (m, rad). A planning scene file (``world.scene_file``) is a
``moveit_msgs/PlanningScene`` written as YAML, as MoveIt and MotionBenchMaker write it: each of
``world.collision_objects`` has an ``id``, an optional ``pose`` and its ``primitives`` (``type``: box,
sphere or cylinder, by name or by SolidPrimitive's number; ``dimensions``) with ``primitive_poses``
(``position`` ``[x, y, z]``, ``orientation`` a quaternion ``[x, y, z, w]``), in the frame its
``header.frame_id`` names.
"""

from __future__ import annotations

import math
from collections import Counter
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from clew_ros.core.errors import WorldError, short_repr
from clew_ros.core.files import FileRefusedError, read_regular_file, yaml_error_place
from clew_ros.core.parameters import LIMITS, Limits
from clew_ros.spatial.parameters import checked_value, world_value
from clew_ros.spatial.transforms import pose_matrix, quaternion_matrix

__all__ = [
    "SHAPES",
    "Obstacle",
    "bounds_from_parameters",
    "kind_of",
    "make_obstacle",
    "obstacle_arrays",
    "obstacles_from_parameters",
    "read_scene_file",
    "scene_obstacles",
    "world_obstacles",
]

#: Each shape and the number of its ``size`` values.
SHAPES = {"box": 3, "cylinder": 2, "sphere": 1}


@dataclass(frozen=True, eq=False)
class Obstacle:
    """A primitive obstacle: ``shape``, ``size`` (SolidPrimitive dimensions, m) and its 4x4 ``pose`` in
    ``world``."""

    name: str
    shape: str
    size: tuple[float, ...]
    pose: NDArray[np.float64]


def kind_of(value: Any) -> str:
    """What a value read from a file is, without quoting it (an error never repeats what a file holds)."""
    if isinstance(value, list | tuple | Mapping | str):
        return f"a {type(value).__name__} of {len(value)}"
    return f"a {type(value).__name__}"


def _numbers(
    value: Any, parameter: str, count: int, what: str, quote: Callable[[Any], str] = short_repr
) -> list[float]:
    try:
        out = [float(v) for v in value]
    except (TypeError, ValueError, OverflowError):
        raise WorldError(parameter, f"expected {what}, got {quote(value)}") from None
    if len(out) != count or not all(math.isfinite(v) for v in out):
        raise WorldError(parameter, f"expected {what} ({count} finite numbers), got {quote(value)}")
    return out


def make_obstacle(
    name: str,
    shape: Any,
    size: Any,
    pose: NDArray[np.float64],
    parameter: str,
    *,
    quote: Callable[[Any], str] = short_repr,
) -> Obstacle:
    """An obstacle, checked; ``parameter`` (``world.obstacles.<name>``) names it in errors, which show a wrong
    value as ``quote`` says (:func:`kind_of` for a value from a file)."""
    if shape not in SHAPES:
        raise WorldError(f"{parameter}.shape", f"expected one of {', '.join(SHAPES)}, got {quote(shape)}")
    dims = {"box": "[x, y, z] full extents", "cylinder": "[height, radius]", "sphere": "[radius]"}[shape]
    values = _numbers(size, f"{parameter}.size", SHAPES[shape], f"a {shape} size {dims}", quote)
    if not all(v > 0.0 for v in values):
        raise WorldError(f"{parameter}.size", f"expected positive sizes {dims}, got {quote(values)}")
    return Obstacle(name, shape, tuple(values), pose)


def obstacles_from_parameters(world: Mapping[str, Any]) -> tuple[Obstacle, ...]:
    """The obstacles ``world.obstacle_names`` lists, each from ``world.obstacles.<name>.shape / .size /
    .pose``."""
    names = world_value(world, "world.obstacle_names") or []
    if isinstance(names, str) or not all(isinstance(n, str) for n in names):
        raise WorldError("world.obstacle_names", f"expected a list of names, got {short_repr(names)}")
    if len(names) > LIMITS.max_obstacles:
        raise WorldError(
            "world.obstacle_names", f"{len(names)} names, more than Limits.max_obstacles ({LIMITS.max_obstacles})"
        )
    if len(set(names)) != len(names):
        raise WorldError("world.obstacle_names", "expected distinct names")
    table = world.get("obstacles", {}) or {}
    if not isinstance(table, Mapping):
        raise WorldError("world.obstacles", f"expected a mapping of obstacles, got {short_repr(table)}")
    out = []
    for name in names:
        parameter = f"world.obstacles.{name}"
        entry = table.get(name)
        if not isinstance(entry, Mapping):
            raise WorldError(parameter, "expected shape, size and pose (world.obstacle_names lists it)")
        shape, size, pose = (world_value(entry, f"{parameter}.{key}") for key in ("shape", "size", "pose"))
        matrix = pose_matrix(_numbers(pose, f"{parameter}.pose", 6, "a pose [x, y, z, roll, pitch, yaw]"))
        out.append(make_obstacle(name, shape, size, matrix, parameter))
    return tuple(out)


#: ``shape_msgs/SolidPrimitive`` type numbers that are obstacles here (a cone, 4, is not).
_PRIMITIVE_TYPES = {1: "box", 2: "sphere", 3: "cylinder"}


def _scene_pose(value: Any, parameter: str) -> NDArray[np.float64]:
    """A ``geometry_msgs/Pose`` as MoveIt's YAML writes it: ``position`` [x, y, z] and ``orientation``
    [x, y, z, w] (lists, or mappings with those keys)."""
    if not isinstance(value, Mapping):
        raise WorldError(parameter, f"expected a pose with position and orientation, got {kind_of(value)}")

    def vector(key: str, names: str, default: list[float]) -> list[float]:
        item = value.get(key, default)
        if isinstance(item, Mapping):
            item = [item.get(name, 0.0) for name in names]
        return _numbers(item, f"{parameter}.{key}", len(names), f"[{', '.join(names)}]", kind_of)

    position = vector("position", "xyz", [0.0, 0.0, 0.0])
    orientation = vector("orientation", "xyzw", [0.0, 0.0, 0.0, 1.0])
    if math.sqrt(sum(v * v for v in orientation)) < 1e-9:
        raise WorldError(f"{parameter}.orientation", "expected a non-zero quaternion [x, y, z, w]")
    return quaternion_matrix(position, orientation)


def _collision_object(item: Any, parameter: str, frames: Mapping[str, NDArray[np.float64]]) -> list[Obstacle]:
    if not isinstance(item, Mapping) or not isinstance(item.get("id"), str) or not item["id"]:
        raise WorldError(parameter, "expected a collision object with an id")
    header = item.get("header") or {}
    frame_id = header.get("frame_id", "") if isinstance(header, Mapping) else None
    frame_id = (frame_id or "world").lstrip("/") if isinstance(frame_id, str | None) else kind_of(frame_id)
    if frame_id not in frames:
        raise WorldError(
            f"{parameter}.header.frame_id", f"unknown frame {short_repr(frame_id)}; known: {sorted(frames)}"
        )
    base = frames[frame_id] @ (_scene_pose(item["pose"], f"{parameter}.pose") if "pose" in item else np.eye(4))
    primitives = item.get("primitives") or []
    poses = item.get("primitive_poses") or []
    if not isinstance(primitives, list) or not isinstance(poses, list) or len(primitives) != len(poses):
        raise WorldError(parameter, "expected primitives and primitive_poses, one pose per primitive")
    out = []
    for k, (primitive, pose) in enumerate(zip(primitives, poses, strict=True)):
        where = f"{parameter}.primitives[{k}]"
        kind = primitive.get("type") if isinstance(primitive, Mapping) else None
        shape = _PRIMITIVE_TYPES.get(kind) if isinstance(kind, int) else str(kind).lower()
        if shape not in SHAPES:
            raise WorldError(f"{where}.type", f"expected box, sphere or cylinder, got {kind_of(kind)}")
        name = item["id"] if len(primitives) == 1 else f"{item['id']}_{k}"
        placed = base @ _scene_pose(pose, f"{parameter}.primitive_poses[{k}]")
        out.append(make_obstacle(name, shape, primitive.get("dimensions"), placed, where, quote=kind_of))
    return out


def scene_obstacles(
    scene: Any, frames: Mapping[str, NDArray[np.float64]], parameter: str, limits: Limits = LIMITS
) -> list[Obstacle]:
    """The obstacles of a planning scene (the parsed YAML): each collision object's primitives, named
    ``<id>`` (``<id>_<k>`` for the k-th of several). ``frames`` maps the frame names a ``header.frame_id``
    may give to their 4x4 poses in ``world``; ``parameter`` names the file in errors, which never quote its
    values. Its objects and primitives are counted against ``Limits.max_scene_objects`` before any is read."""
    if not isinstance(scene, Mapping):
        raise WorldError(parameter, "expected a moveit_msgs/PlanningScene as YAML (a mapping with world:)")
    part = scene.get("world") if scene.get("world") is not None else {}
    if not isinstance(part, Mapping):
        raise WorldError(f"{parameter}: world", f"expected a mapping holding collision_objects, got {kind_of(part)}")
    objects = part.get("collision_objects") or []
    if not isinstance(objects, list):
        raise WorldError(f"{parameter}: world.collision_objects", "expected a list of collision objects")
    _check_scene_size(objects, parameter, limits)
    out = []
    for i, item in enumerate(objects):
        out.extend(_collision_object(item, f"{parameter}: world.collision_objects[{i}]", frames))
    return out


def world_obstacles(
    world: Mapping[str, Any], folder: Path, frames: Mapping[str, NDArray[np.float64]] | None = None
) -> tuple[Obstacle, ...]:
    """Every obstacle of a spatial world: ``world.obstacle_names`` and, when ``world.scene_file`` names one,
    the planning scene's (read relative to ``folder``, the parameter file's). ``frames`` adds the frames a
    scene's ``frame_id`` may name besides ``world`` (the robot's ``base_link``)."""
    out = list(obstacles_from_parameters(world))
    if "scene_file" in world:
        known = {"world": np.eye(4), **(frames or {})}
        scene = read_scene_file(checked_value(world, "world.scene_file"), folder)
        out.extend(scene_obstacles(scene, known, "world.scene_file"))
    if len(out) > LIMITS.max_obstacles:
        raise WorldError(
            "world.scene_file",
            f"{len(out)} obstacles (world.obstacle_names and the scene file's), more than Limits.max_obstacles "
            f"({LIMITS.max_obstacles})",
        )
    twice = sorted(name for name, count in Counter(o.name for o in out).items() if count > 1)
    if twice:
        raise WorldError("world.scene_file", f"obstacle names must be distinct; given twice: {short_repr(twice)}")
    return tuple(out)


def read_scene_file(name: Any, folder: Path, limits: Limits = LIMITS) -> Any:
    """The parsed YAML of ``world.scene_file`` (relative to ``folder``): a regular file of at most
    ``Limits.max_scene_file_bytes``; an error says where the YAML fails, never what the file holds."""
    import yaml

    if not isinstance(name, str) or not name:
        raise WorldError("world.scene_file", f"expected a path, got {short_repr(name)}")
    path = Path(name)
    path = path if path.is_absolute() else folder / path
    try:
        data = read_regular_file(path, limits.max_scene_file_bytes, "Limits.max_scene_file_bytes")
        return yaml.load(data.decode("utf-8"), Loader=getattr(yaml, "CSafeLoader", yaml.SafeLoader))
    except FileRefusedError as error:
        raise WorldError("world.scene_file", f"cannot read {str(path)!r}: {error}") from None
    except UnicodeDecodeError as error:
        raise WorldError(
            "world.scene_file", f"{str(path)!r}: expected UTF-8 text ({error.reason} at byte {error.start})"
        ) from None
    except yaml.YAMLError as error:
        raise WorldError("world.scene_file", f"cannot read {str(path)!r} as YAML ({yaml_error_place(error)})") from None
    except (RecursionError, ValueError, OverflowError) as error:
        raise WorldError(
            "world.scene_file", f"{str(path)!r}: expected YAML it can read ({type(error).__name__})"
        ) from None


def _check_scene_size(objects: list[Any], parameter: str, limits: Limits) -> None:
    """The primitives of the collision objects (an object without any counts one), as YAML aliases expanded
    them, counted against ``Limits.max_scene_objects`` before any is read: a short file may name one list
    many times."""
    count = 0
    for item in objects:
        primitives = item.get("primitives") if isinstance(item, Mapping) else None
        count += max(len(primitives), 1) if isinstance(primitives, list) else 1
        if count > limits.max_scene_objects:
            raise WorldError(
                f"{parameter}: world.collision_objects",
                f"more than Limits.max_scene_objects ({limits.max_scene_objects}) objects and primitives",
            )


def bounds_from_parameters(world: Mapping[str, Any]) -> NDArray[np.float64] | None:
    """``world.bounds`` ``[xmin, ymin, zmin, xmax, ymax, zmax]`` (m), or ``None`` when absent."""
    if "bounds" not in world:
        return None
    values = np.array(_numbers(world["bounds"], "world.bounds", 6, "[xmin, ymin, zmin, xmax, ymax, zmax]"))
    if np.any(values[:3] >= values[3:]):
        raise WorldError("world.bounds", f"expected each minimum below its maximum, got {values.tolist()}")
    return values


def obstacle_arrays(obstacles: Sequence[Obstacle]) -> dict[str, NDArray[Any]]:
    """The obstacles packed for the kernels: kind (0 box, 1 cylinder, 2 sphere), rotation (local to world),
    position, dims (box half extents; cylinder radius, half height; sphere radius) and bounding radius."""
    kind = np.array([list(SHAPES).index(o.shape) for o in obstacles], dtype=np.int64)
    dims = np.zeros((len(obstacles), 3))
    bound = np.zeros(len(obstacles))
    for i, o in enumerate(obstacles):
        if o.shape == "box":
            dims[i] = np.asarray(o.size) / 2
        elif o.shape == "cylinder":
            dims[i, :2] = o.size[1], o.size[0] / 2
        else:
            dims[i, 0] = o.size[0]
        bound[i] = float(np.linalg.norm(dims[i])) if o.shape != "sphere" else o.size[0]
    rot = np.array([o.pose[:3, :3] for o in obstacles]).reshape(-1, 3, 3)
    pos = np.array([o.pose[:3, 3] for o in obstacles]).reshape(-1, 3)
    return {"obs_kind": kind, "obs_r": rot, "obs_t": pos, "obs_dims": dims, "obs_bound": bound}
