"""The world: robot, obstacles and movable object, parsed from the parameter file.

The parameter file is the ROS 2 parameter YAML of ``interface.md`` section 1;
:data:`~clew_ros.core.parameters.WORLD_PARAMETERS` specifies its keys and
defaults. Parsing checks every value and the rules that tie keys together,
and returns immutable objects; any fault raises
:class:`~clew_ros.core.errors.WorldError` naming the parameter at fault.

Parsing is pure: it does no collision check. Whether the start and the goal
are valid placements (section 1's validity test) is checked by
:func:`clew_ros.planar.collision.check_start_and_goal`.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path
from typing import Any

import numpy as np
import shapely
import yaml

from clew_ros.core.errors import WorldError, short_repr
from clew_ros.core.files import FileRefusedError, read_regular_file, yaml_error_place
from clew_ros.core.parameters import LIMITS, REQUIRED, WORLD_PARAMETERS, Limits

__all__ = [
    "MAX_LINKS",
    "MAX_PARAMETER_FILE_BYTES",
    "WORLD_CHECKS",
    "WORLD_KIND",
    "MovableObject",
    "Obstacle",
    "Robot",
    "World",
    "WorldChecks",
    "load_world",
    "read_parameter_file",
    "world_from_parameters",
    "world_to_parameters",
]

#: ``world.kind`` of a planar world (the default) and a plan file's ``world_kind`` for it.
WORLD_KIND = "planar"


@dataclass(frozen=True)
class WorldChecks:
    """What a planar world's numbers are checked against when it is read."""

    #: A grasp point lies on the object's boundary when it is this close to it (m).
    grasp_on_boundary_tolerance_m: float = 1e-6
    #: Largest magnitude of any number of the world (m or rad). Beyond it the geometry loses its precision
    #: (and squares overflow); no planar arm needs it.
    max_abs_value: float = 1e6


#: The checks :func:`world_from_parameters` makes.
WORLD_CHECKS = WorldChecks()
#: Most links a robot may have (:attr:`Limits.max_links <clew_ros.core.parameters.Limits.max_links>`).
MAX_LINKS = LIMITS.max_links
#: Largest parameter file read (bytes); ``/dev/zero`` is not a world.
MAX_PARAMETER_FILE_BYTES = LIMITS.max_parameter_file_bytes
#: The safe YAML loader, libyaml's where PyYAML has it (four times faster on a large parameter file; the same
#: values: the same resolver and constructor).
_YAML_LOADER = getattr(yaml, "CSafeLoader", yaml.SafeLoader)


def _frozen(values: Any, dtype: type = float) -> np.ndarray:
    array: np.ndarray = np.array(values, dtype=dtype)
    array.setflags(write=False)
    return array


@dataclass(frozen=True, eq=False)
class Robot:
    """Planar chain of revolute joints (angles in rad, lengths in m)."""

    base: np.ndarray  # (2,)
    link_lengths: np.ndarray  # (n,)
    joint_lower: np.ndarray  # (n,)
    joint_upper: np.ndarray  # (n,)
    initial: np.ndarray  # (n,)
    link_width: float = WORLD_PARAMETERS.default("robot.link_width")
    self_collision: bool = WORLD_PARAMETERS.default("robot.self_collision")

    @property
    def dof(self) -> int:
        return len(self.link_lengths)

    @property
    def reach(self) -> float:
        """Sum of the link lengths (m)."""
        return float(self.link_lengths.sum())

    @property
    def joint_names(self) -> list[str]:
        return [f"joint_{i + 1}" for i in range(self.dof)]


@dataclass(frozen=True, eq=False)
class Obstacle:
    name: str
    vertices: np.ndarray  # (V, 2), counter-clockwise


@dataclass(frozen=True, eq=False)
class MovableObject:
    """The object: polygon and grasps in its own frame, poses as (x, y, theta)."""

    polygon: np.ndarray  # (V, 2), counter-clockwise
    initial: np.ndarray  # (3,)
    goal: np.ndarray  # (3,)
    grasps: np.ndarray  # (G, 2)

    @cached_property
    def radius(self) -> float:
        """Largest distance from the object's origin to one of its vertices (m)."""
        return float(np.linalg.norm(self.polygon, axis=1).max())


@dataclass(frozen=True, eq=False)
class World:
    name: str
    bounds: np.ndarray  # (4,) xmin, ymin, xmax, ymax
    robot: Robot
    obstacles: tuple[Obstacle, ...]
    object: MovableObject
    grasp_tolerance: float = WORLD_PARAMETERS.default("grasp_tolerance")
    goal_tolerance: float = WORLD_PARAMETERS.default("goal_tolerance")
    goal_angle_tolerance: float = WORLD_PARAMETERS.default("goal_angle_tolerance")
    parameters: Mapping[str, Any] = field(default_factory=dict, repr=False)
    """The ``world`` parameter tree it was loaded from (for recordings)."""


# --------------------------------------------------------------------------- parsing


def read_parameter_file(path: str | Path) -> dict[str, Any]:
    """Read a ROS 2 parameter YAML and return its ``ros__parameters`` tree.

    The node key may be ``clew_planner`` (with or without a leading slash or
    namespace) or the wildcard ``/**``.
    """
    path = Path(path)
    try:
        data = read_regular_file(path, MAX_PARAMETER_FILE_BYTES, "Limits.max_parameter_file_bytes")
    except FileRefusedError as error:
        raise WorldError(str(path), f"cannot read the parameter file: {error}") from None
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as error:
        raise WorldError(str(path), f"expected UTF-8 text ({error.reason} at byte {error.start})") from None
    try:
        document = yaml.load(text, Loader=_YAML_LOADER)  # a safe loader: plain data only
    except yaml.YAMLError as error:
        raise WorldError(str(path), f"expected valid YAML ({yaml_error_place(error)})") from None
    except (RecursionError, MemoryError, ValueError) as error:  # absurd nesting, or numbers YAML cannot hold
        raise WorldError(str(path), f"expected a parameter file YAML can read ({type(error).__name__})") from None
    if not isinstance(document, dict):
        raise WorldError(str(path), "expected a mapping with a 'clew_planner' or '/**' key")
    for key, value in document.items():
        node = str(key).rsplit("/", 1)[-1]
        if node in ("clew_planner", "**") and isinstance(value, dict):
            parameters = value.get("ros__parameters")
            if not isinstance(parameters, dict):
                raise WorldError(f"{key}.ros__parameters", "expected a mapping of parameters")
            return parameters
    raise WorldError(str(path), "expected a top-level 'clew_planner' or '/**' key with 'ros__parameters'")


def _is_number(value: Any) -> bool:
    return isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, bool)


def _as_float(value: Any) -> float:
    """``float(value)``; an integer too large for a float becomes ``inf`` (refused as not finite)."""
    try:
        return float(value)
    except OverflowError:
        return math.inf if value > 0 else -math.inf


def _check_magnitude(name: str, values: np.ndarray) -> None:
    if values.size and float(np.max(np.abs(values))) > WORLD_CHECKS.max_abs_value:
        raise WorldError(
            name,
            f"expected numbers within +-{WORLD_CHECKS.max_abs_value:g} (m or rad), got "
            f"{float(values.flat[np.argmax(np.abs(values))]):.6g}",
        )


def _default(name: str) -> Any:
    """What an absent ``world.*`` parameter ``name`` stands for: its default, or ``None`` when it is required
    (or, like ``world.obstacle_names``, simply absent)."""
    spec = WORLD_PARAMETERS.get(name.removeprefix("world."))
    return None if spec is None or spec.default is REQUIRED else spec.default


def _number(
    tree: Mapping[str, Any], key: str, prefix: str, *, positive: bool = False, non_negative: bool = False
) -> float:
    name = f"{prefix}.{key}"
    value = tree.get(key, _default(name))
    if value is None:
        raise WorldError(name, "is required (a number)")
    if not _is_number(value):
        raise WorldError(name, f"expected a number, got {short_repr(value)}")
    value = _as_float(value)
    if not math.isfinite(value):
        raise WorldError(name, f"expected a finite number, got {value}")
    _check_magnitude(name, np.array([value]))
    if positive and value <= 0:
        raise WorldError(name, f"expected a number > 0, got {value}")
    if non_negative and value < 0:
        raise WorldError(name, f"expected a number >= 0, got {value}")
    return value


def _numbers(
    tree: Mapping[str, Any],
    key: str,
    prefix: str,
    *,
    length: int | None = None,
    min_length: int = 1,
    even: bool = False,
) -> np.ndarray:
    name = f"{prefix}.{key}"
    value = tree.get(key, _default(name))
    if value is None:
        raise WorldError(name, "is required (a list of numbers)")
    if not isinstance(value, (list, tuple)):
        raise WorldError(name, f"expected a list of numbers, got {short_repr(value)}")
    for item in value:
        if not _is_number(item):
            raise WorldError(name, f"expected a list of numbers, got the item {short_repr(item)}")
    array = np.array([_as_float(item) for item in value], dtype=float)
    if not np.all(np.isfinite(array)):
        raise WorldError(name, "expected finite numbers, got NaN or inf")
    _check_magnitude(name, array)
    if length is not None and len(array) != length:
        raise WorldError(name, f"expected {length} numbers, got {len(array)}")
    if len(array) < min_length:
        raise WorldError(name, f"expected at least {min_length} numbers, got {len(array)}")
    if even and len(array) % 2:
        raise WorldError(name, f"expected an even number of values (x, y pairs), got {len(array)}")
    return array


def _check_count(name: str, value: Any, *, per_item: int, cap: int, cap_name: str, items: str) -> None:
    """Refuse a list ``value`` of more than ``cap`` ``items`` (``per_item`` numbers each), before reading it."""
    if isinstance(value, (list, tuple)) and len(value) > cap * per_item:
        raise WorldError(
            name, f"expected at most {cap} {items} (Limits.{cap_name}), got {math.ceil(len(value) / per_item)}"
        )


def _check_name(name: str, text: str, limits: Limits) -> None:
    if len(text) > limits.max_name_chars:
        raise WorldError(
            name,
            f"expected a name of at most {limits.max_name_chars} characters (Limits.max_name_chars), "
            f"got {len(text)}: {short_repr(text, 40)}",
        )


def _check_world_vertices(tree: Mapping[str, Any], limits: Limits) -> None:
    """Refuse a world whose polygons hold more than ``limits.max_world_vertices`` vertices, before parsing them."""
    polygons = [
        tree.get("obstacles").values() if isinstance(tree.get("obstacles"), Mapping) else [],  # type: ignore[union-attr]
        [tree["object"].get("polygon")] if isinstance(tree.get("object"), Mapping) else [],
    ]
    vertices = sum(len(flat) // 2 for group in polygons for flat in group if isinstance(flat, (list, tuple)))
    if vertices > limits.max_world_vertices:
        raise WorldError(
            "world.obstacles",
            f"expected at most {limits.max_world_vertices} vertices in all the world's polygons "
            f"(Limits.max_world_vertices), got {vertices}",
        )


def _polygon(tree: Mapping[str, Any], key: str, prefix: str, limits: Limits = LIMITS) -> np.ndarray:
    """A flat x0, y0, x1, y1, ... list as a valid, counter-clockwise polygon."""
    name = f"{prefix}.{key}"
    _check_count(
        name,
        tree.get(key),
        per_item=2,
        cap=limits.max_polygon_vertices,
        cap_name="max_polygon_vertices",
        items="vertices",
    )
    flat = _numbers(tree, key, prefix, min_length=6, even=True)
    vertices = flat.reshape(-1, 2)
    if len(vertices) > 1 and np.allclose(vertices[0], vertices[-1]):
        vertices = vertices[:-1]  # tolerate an explicitly closed ring
    if len(vertices) < 3:
        raise WorldError(name, "expected at least 3 distinct vertices")
    polygon = shapely.Polygon(vertices)
    if polygon.area <= 1e-12:
        raise WorldError(name, "expected a polygon with non-zero area")
    if not polygon.is_valid:
        reason = shapely.is_valid_reason(polygon)
        raise WorldError(name, f"expected a simple polygon (no self-intersection), got: {reason}")
    if not polygon.exterior.is_ccw:
        vertices = vertices[::-1]
    return vertices.copy()


def _mapping(tree: Mapping[str, Any], key: str, prefix: str, *, required: bool = True) -> Mapping[str, Any]:
    value = tree.get(key)
    if value is None and not required:
        return {}
    if not isinstance(value, Mapping):
        raise WorldError(f"{prefix}.{key}", f"expected a mapping, got {short_repr(value)}")
    return value


def _bool(tree: Mapping[str, Any], key: str, prefix: str) -> bool:
    value = tree.get(key, _default(f"{prefix}.{key}"))
    if not isinstance(value, bool):
        raise WorldError(f"{prefix}.{key}", f"expected true or false, got {short_repr(value)}")
    return value


def world_from_parameters(parameters: Mapping[str, Any], limits: Limits = LIMITS) -> World:
    """Parse a :class:`World` from a ``ros__parameters`` tree, checking every value.

    ``parameters`` holds a ``world`` key (other keys are ignored). Raises
    :class:`~clew_ros.core.errors.WorldError` naming the parameter at fault;
    a world beyond one of ``limits`` (links, obstacles, vertices, grasps,
    name lengths) is refused naming the parameter and the limit.
    The start and goal placements are not checked for collisions here: see
    :func:`clew_ros.planar.collision.check_start_and_goal`.
    """
    if not isinstance(parameters, Mapping):
        raise WorldError("ros__parameters", f"expected a mapping, got {short_repr(parameters)}")
    tree = parameters.get("world")
    if not isinstance(tree, Mapping):
        raise WorldError("world", f"expected a mapping of world parameters, got {short_repr(tree)}")
    name = tree.get("name", _default("world.name"))
    if not isinstance(name, str) or not name:
        raise WorldError("world.name", f"expected a non-empty string, got {short_repr(name)}")
    _check_name("world.name", name, limits)
    bounds = _numbers(tree, "bounds", "world", length=4)
    if not (bounds[0] < bounds[2] and bounds[1] < bounds[3]):
        raise WorldError("world.bounds", f"expected xmin < xmax and ymin < ymax, got {bounds.tolist()}")
    robot = _robot(_mapping(tree, "robot", "world"), limits)
    _check_world_vertices(tree, limits)
    obstacles = _obstacles(tree, limits)
    movable = _movable_object(_mapping(tree, "object", "world"), limits)
    return World(
        name=name,
        bounds=_frozen(bounds),
        robot=robot,
        obstacles=obstacles,
        object=movable,
        grasp_tolerance=_number(tree, "grasp_tolerance", "world", positive=True),
        goal_tolerance=_number(tree, "goal_tolerance", "world", positive=True),
        goal_angle_tolerance=_number(tree, "goal_angle_tolerance", "world", non_negative=True),
        parameters=_plain(tree),
    )


def _robot(tree: Mapping[str, Any], limits: Limits) -> Robot:
    """``world.robot``: the chain, its joint limits and its start within them."""
    rp = "world.robot"
    _check_count(
        f"{rp}.link_lengths",
        tree.get("link_lengths"),
        per_item=1,
        cap=limits.max_links,
        cap_name="max_links",
        items="links",
    )
    lengths = _numbers(tree, "link_lengths", rp, min_length=2)
    n = len(lengths)
    if np.any(lengths <= 0):
        raise WorldError(f"{rp}.link_lengths", f"expected lengths > 0, got {lengths.tolist()}")
    lower = _numbers(tree, "joint_lower", rp)
    upper = _numbers(tree, "joint_upper", rp)
    initial = _numbers(tree, "initial", rp)
    for key, array in (("joint_lower", lower), ("joint_upper", upper), ("initial", initial)):
        if len(array) != n:
            raise WorldError(f"{rp}.{key}", f"expected {n} values (one per link in link_lengths), got {len(array)}")
    for i in range(n):
        if lower[i] > upper[i]:
            raise WorldError(
                f"{rp}.joint_lower",
                f"expected joint_lower <= joint_upper, but joint_{i + 1} has {lower[i]} > {upper[i]}",
            )
        if not lower[i] <= initial[i] <= upper[i]:
            raise WorldError(
                f"{rp}.initial", f"expected joint_{i + 1} within [{lower[i]}, {upper[i]}], got {initial[i]}"
            )
    return Robot(
        base=_frozen(_numbers(tree, "base", rp, length=2)),
        link_lengths=_frozen(lengths),
        joint_lower=_frozen(lower),
        joint_upper=_frozen(upper),
        initial=_frozen(initial),
        link_width=_number(tree, "link_width", rp, non_negative=True),
        self_collision=_bool(tree, "self_collision", rp),
    )


def _obstacles(tree: Mapping[str, Any], limits: Limits) -> tuple[Obstacle, ...]:
    """``world.obstacles.<name>`` for each name of ``world.obstacle_names``, in that order."""
    names = tree.get("obstacle_names", _default("world.obstacle_names"))
    obstacle_tree = tree.get("obstacles") or {}
    if not isinstance(obstacle_tree, Mapping):
        raise WorldError(
            "world.obstacles", f"expected a mapping of name: [x0, y0, ...], got {short_repr(obstacle_tree)}"
        )
    if names is None:
        names = []
    _check_count(
        "world.obstacle_names", names, per_item=1, cap=limits.max_obstacles, cap_name="max_obstacles", items="obstacles"
    )
    if isinstance(obstacle_tree, Mapping) and len(obstacle_tree) > limits.max_obstacles:
        raise WorldError(
            "world.obstacles",
            f"expected at most {limits.max_obstacles} obstacles (Limits.max_obstacles), got {len(obstacle_tree)}",
        )
    if not isinstance(names, (list, tuple)) or not all(isinstance(s, str) and s for s in names):
        raise WorldError("world.obstacle_names", f"expected a list of non-empty strings, got {short_repr(names)}")
    for obstacle_name in names:
        _check_name("world.obstacle_names", obstacle_name, limits)
    if len(set(names)) != len(names):
        raise WorldError("world.obstacle_names", "expected unique names")
    for key in obstacle_tree:
        if key not in names:
            raise WorldError(
                f"world.obstacles.{key}",
                f"unknown obstacle: not listed in world.obstacle_names {short_repr(names, 200)}",
            )
    obstacles = []
    for obstacle_name in names:
        if obstacle_name not in obstacle_tree:
            raise WorldError(f"world.obstacles.{obstacle_name}", "is required: it is listed in world.obstacle_names")
        polygon = _polygon(obstacle_tree, obstacle_name, "world.obstacles", limits)
        obstacles.append(Obstacle(obstacle_name, _frozen(polygon)))
    return tuple(obstacles)


def _movable_object(tree: Mapping[str, Any], limits: Limits) -> MovableObject:
    """``world.object``: its polygon, its grasps on the polygon's boundary, its start and goal poses."""
    op = "world.object"
    polygon = _polygon(tree, "polygon", op, limits)
    _check_count(
        f"{op}.grasps", tree.get("grasps"), per_item=2, cap=limits.max_grasps, cap_name="max_grasps", items="grasps"
    )
    grasps = _numbers(tree, "grasps", op, min_length=2, even=True).reshape(-1, 2)
    boundary = shapely.Polygon(polygon).exterior
    distances = np.atleast_1d(shapely.distance(boundary, shapely.points(grasps)))
    for index, distance in enumerate(distances):
        if distance > WORLD_CHECKS.grasp_on_boundary_tolerance_m:
            raise WorldError(
                f"{op}.grasps",
                f"expected every grasp on the object's boundary (within "
                f"{WORLD_CHECKS.grasp_on_boundary_tolerance_m} m), but grasp {index} "
                f"{grasps[index].tolist()} is {distance:.6g} m away",
            )
    return MovableObject(
        polygon=_frozen(polygon),
        initial=_frozen(_numbers(tree, "initial", op, length=3)),
        goal=_frozen(_numbers(tree, "goal", op, length=3)),
        grasps=_frozen(grasps),
    )


def _plain(value: Any) -> Any:
    if isinstance(value, Mapping):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    return value


def load_world(path: str | Path) -> World:
    """Read, parse and check the world of a parameter file (no collision check: see
    :func:`clew_ros.planar.collision.check_start_and_goal`)."""
    return world_from_parameters(read_parameter_file(path))


def world_to_parameters(world: World) -> dict[str, Any]:
    """The world as a ``{'world': {...}}`` parameter tree (ROS 2 YAML-ready)."""
    tree: dict[str, Any] = {
        "name": world.name,
        "bounds": world.bounds.tolist(),
        "robot": {
            "base": world.robot.base.tolist(),
            "link_lengths": world.robot.link_lengths.tolist(),
            "link_width": world.robot.link_width,
            "joint_lower": world.robot.joint_lower.tolist(),
            "joint_upper": world.robot.joint_upper.tolist(),
            "initial": world.robot.initial.tolist(),
            "self_collision": world.robot.self_collision,
        },
        "object": {
            "polygon": world.object.polygon.ravel().tolist(),
            "initial": world.object.initial.tolist(),
            "goal": world.object.goal.tolist(),
            "grasps": world.object.grasps.ravel().tolist(),
        },
        "grasp_tolerance": world.grasp_tolerance,
        "goal_tolerance": world.goal_tolerance,
        "goal_angle_tolerance": world.goal_angle_tolerance,
    }
    if world.obstacles:
        tree["obstacle_names"] = [o.name for o in world.obstacles]
        tree["obstacles"] = {o.name: o.vertices.ravel().tolist() for o in world.obstacles}
    return {"world": tree}
