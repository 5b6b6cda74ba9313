"""The node's parameters: names, defaults, descriptors and validation.

Three families, all with descriptors (``ros2 param describe`` shows them):

- ``world.*``: the world of interface.md §1; ``world.obstacles.<name>`` for
  each name in ``world.obstacle_names``. Validated by the core
  (:func:`~clew_ros.core.world.world_from_parameters`, then
  :func:`~clew_ros.core.collision.check_start_and_goal`), so every refusal
  names the parameter at fault.
- ``planner.*``: :data:`~clew_ros.core.settings.PLANNER_PARAMETERS`,
  validated by :func:`~clew_ros.core.settings.check_planner_parameter`.
- the node's own: :data:`NODE_PARAMETERS` (``record.*``, ``playback.*``,
  ``trajectory.*``).

Every parameter is declared with ``dynamic_typing`` so that a YAML ``30``
is as good as ``30.0``; the value is checked here instead, with a message of
the form ``<parameter>: <what was expected>``.

When no ``world.*`` parameter is given at all, the node serves the embedded
default world file (``config/figure1.yaml``): its ``world.*`` and
``planner.*`` become the defaults. When any ``world.*`` parameter is given,
the world comes from the given parameters alone (the optional keys of
interface.md §1 take their documented defaults).
"""

from __future__ import annotations

import array
import math
import os
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from rcl_interfaces.msg import FloatingPointRange, IntegerRange, ParameterDescriptor

from clew_ros.core.collision import check_start_and_goal
from clew_ros.core.errors import ParameterError, WorldError
from clew_ros.core.settings import PLANNER_PARAMETERS, PlannerSettings
from clew_ros.core.world import World, read_parameter_file, world_from_parameters

__all__ = [
    "DEFAULT_WORLD_FILE",
    "NODE_PARAMETERS",
    "OWN_PREFIXES",
    "WORLD_PARAMETERS",
    "Configuration",
    "NodeSettings",
    "configuration_from_values",
    "default_world_file",
    "descriptor_for",
    "flatten",
    "initial_values",
    "nest",
    "plain_value",
]

DEFAULT_WORLD_FILE = "figure1.yaml"
REQUIRED = object()  # marks a world.* parameter without a default

#: world.<key> -> (type, default or REQUIRED / None for "absent", description)
WORLD_PARAMETERS: dict[str, tuple[str, Any, str]] = {
    "name": ("string", "world", "Name of the world; plans and recordings carry it."),
    "bounds": ("double[]", REQUIRED, "The workspace box [xmin, ymin, xmax, ymax] (m); touching its edge is inside."),
    "robot.base": ("double[]", REQUIRED, "Position [x, y] of joint 1 (m)."),
    "robot.link_lengths": ("double[]", REQUIRED, "Length of each link (m); n >= 2 links."),
    "robot.link_width": ("double", 0.0, "Links are capsules of radius link_width / 2 (m); 0: segments."),
    "robot.joint_lower": ("double[]", REQUIRED, "Lower joint limits (rad), one per link."),
    "robot.joint_upper": ("double[]", REQUIRED, "Upper joint limits (rad), one per link."),
    "robot.initial": ("double[]", REQUIRED, "Joint angles at the start (rad), one per link."),
    "robot.self_collision": ("bool", True, "Check non-adjacent links against each other."),
    "obstacle_names": ("string[]", None, ("Names of the obstacles; each needs world.obstacles.<name>. "
                                          "Omit it for a world without obstacles.")),
    "object.polygon": ("double[]", REQUIRED, "The object as a flat x0, y0, x1, y1, ... list in its own frame (m)."),
    "object.initial": ("double[]", REQUIRED, "Start placement [x, y, theta] of the object (m, rad)."),
    "object.goal": ("double[]", REQUIRED, "Goal placement [x, y, theta] of the object (m, rad); ~/plan plans to it."),
    "object.grasps": ("double[]", REQUIRED, "Grasp points on the object's boundary, flat x0, y0, ... in its frame (m)."),
    "grasp_tolerance": ("double", 0.005, "The tip holds a grasp when it is this close to it (m)."),
    "goal_tolerance": ("double", 0.02, "Largest distance of the final object position from the goal (m)."),
    "goal_angle_tolerance": ("double", math.pi, "Largest orientation error at the goal (rad); pi: any."),
}
OBSTACLE_DESCRIPTION = "Obstacle polygon as a flat x0, y0, x1, y1, ... list (m)."

#: name -> (type, default, description, (min, max) or None)
NODE_PARAMETERS: dict[str, tuple[str, Any, str, tuple | None]] = {
    "record.enabled": ("bool", True, "Record every run as a rosbag2 directory <record.directory>/<run id>/.", None),
    "record.directory": ("string", "~/.ros/clew_recordings",
                         "Where runs are recorded; '~' and environment variables are expanded.", None),
    "playback.rate": ("double", 20.0, "Rate (Hz) of ~/joint_states and ~/object_pose while a plan plays back.",
                      (1.0, 1000.0)),
    "trajectory.joint_speed": ("double", 1.0, ("Joint speed (rad/s) that times ~/trajectory: a move lasts "
                                               "max |dq| / joint_speed."), (0.001, 1000.0)),
    "trajectory.grasp_dwell": ("double", 0.2, "Time (s) a grasp or ungrasp takes in ~/trajectory.", (0.001, 60.0)),
}

#: The parameter prefixes the node owns and checks (others, e.g. use_sim_time, are rclpy's).
OWN_PREFIXES = ("world.", "planner.", "record.", "playback.", "trajectory.")


@dataclass(frozen=True)
class NodeSettings:
    """The node's own parameters, checked."""

    record_enabled: bool = True
    record_directory: str = "~/.ros/clew_recordings"
    playback_rate_hz: float = 20.0
    joint_speed_rad_s: float = 1.0
    grasp_dwell_s: float = 0.2

    @property
    def record_path(self) -> Path:
        return Path(os.path.expandvars(os.path.expanduser(self.record_directory)))


@dataclass(frozen=True)
class Configuration:
    """Everything the parameters describe, checked: the world, the planner and the node settings."""

    world: World
    planner: PlannerSettings
    node: NodeSettings


# --------------------------------------------------------------------------- trees and values


def plain_value(value: Any) -> Any:
    """A parameter value as plain Python (``array.array`` -> ``list``)."""
    if isinstance(value, array.array):
        return value.tolist()
    if isinstance(value, tuple):
        return list(value)
    return value


def flatten(tree: Mapping[str, Any], prefix: str = "") -> dict[str, Any]:
    """Nested parameter tree -> ``{'world.robot.base': [...], ...}``."""
    flat: dict[str, Any] = {}
    for key, value in tree.items():
        name = f"{prefix}{key}"
        if isinstance(value, Mapping):
            flat.update(flatten(value, name + "."))
        else:
            flat[name] = value
    return flat


def nest(flat: Mapping[str, Any]) -> dict[str, Any]:
    """``{'a.b': 1}`` -> ``{'a': {'b': 1}}``; ``None`` values (unset parameters) are left out."""
    tree: dict[str, Any] = {}
    for name, value in flat.items():
        if value is None:
            continue
        *parents, leaf = name.split(".")
        node = tree
        for part in parents:
            node = node.setdefault(part, {})
        node[leaf] = plain_value(value)
    return tree


def default_world_file() -> Path:
    """The embedded default world: the installed share directory, else the source tree's ``config/``."""
    try:
        from ament_index_python.packages import get_package_share_directory

        path = Path(get_package_share_directory("clew_ros")) / "config" / DEFAULT_WORLD_FILE
        if path.is_file():
            return path
    except Exception:  # noqa: BLE001, S110 - no ament index (not installed by colcon): use the source tree
        pass
    return Path(__file__).resolve().parents[2] / "config" / DEFAULT_WORLD_FILE


def initial_values(overrides: Mapping[str, Any], default_file: Path | None = None) -> dict[str, Any]:
    """The value of every parameter the node declares at start, from its overrides.

    ``overrides`` holds the ``--params-file`` / ``-p`` values by full name.
    Returns full name -> value (``None`` for a parameter left unset). Only
    the node's own prefixes are returned; the embedded default world is read
    when no ``world.*`` override exists.
    """
    overrides = {k: plain_value(v) for k, v in overrides.items() if k.startswith(OWN_PREFIXES)}
    values: dict[str, Any] = {}
    has_world = any(name.startswith("world.") for name in overrides)
    embedded: dict[str, Any] = {}
    if not has_world:
        path = default_world_file() if default_file is None else default_file
        tree = read_parameter_file(path)
        embedded = {k: v for k, v in flatten(tree).items() if k.startswith(("world.", "planner."))}
    for key, (_kind, default, _description) in WORLD_PARAMETERS.items():
        values[f"world.{key}"] = None if default is REQUIRED else default
    for name, (_kind, default, _description, _limits) in PLANNER_PARAMETERS.items():
        values[f"planner.{name}"] = default
    for name, (_kind, default, _description, _limits) in NODE_PARAMETERS.items():
        values[name] = default
    values.update(embedded)
    values.update(overrides)
    return values


# --------------------------------------------------------------------------- checks


def _check_known(name: str) -> None:
    if name.startswith("world."):
        key = name[len("world."):]
        if key in WORLD_PARAMETERS:
            return
        parts = key.split(".")
        if parts[0] == "obstacles" and len(parts) == 2:
            return
        raise WorldError(name, "unknown parameter; known: " + ", ".join(f"world.{k}" for k in WORLD_PARAMETERS)
                         + ", world.obstacles.<name>")
    if name.startswith("planner."):
        if name[len("planner."):] not in PLANNER_PARAMETERS:
            raise ParameterError(name, "unknown parameter; known: "
                                 + ", ".join(f"planner.{k}" for k in PLANNER_PARAMETERS))
        return
    if name not in NODE_PARAMETERS:
        raise ParameterError(name, "unknown parameter; known: " + ", ".join(NODE_PARAMETERS))


def _check_node_parameter(name: str, value: Any) -> Any:
    kind, _default, _description, limits = NODE_PARAMETERS[name]
    if kind == "bool":
        if not isinstance(value, bool):
            raise ParameterError(name, f"expected true or false, got {value!r}")
        return value
    if kind == "string":
        if not isinstance(value, str) or not value:
            raise ParameterError(name, f"expected a non-empty string, got {value!r}")
        return value
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise ParameterError(name, f"expected a number, got {value!r}")
    if limits and not limits[0] <= value <= limits[1]:
        raise ParameterError(name, f"expected a value in [{limits[0]}, {limits[1]}], got {value}")
    return float(value)


def _world_tree(values: Mapping[str, Any], *, listed_obstacles_only: bool) -> dict:
    world = {k: v for k, v in values.items() if k.startswith("world.")}
    if listed_obstacles_only:
        names = plain_value(world.get("world.obstacle_names")) or []
        names = names if isinstance(names, list) else []
        world = {k: v for k, v in world.items()
                 if not k.startswith("world.obstacles.") or k[len("world.obstacles."):] in names}
    return nest(world)


def configuration_from_values(values: Mapping[str, Any], *, listed_obstacles_only: bool = False) -> Configuration:
    """Check every value (full name -> value) and build the configuration.

    Raises :class:`~clew_ros.core.errors.ParameterError` (or its subclass
    ``WorldError``) naming the first parameter at fault. With
    ``listed_obstacles_only``, ``world.obstacles.<name>`` parameters whose
    name is not in ``world.obstacle_names`` are ignored (a parameter cannot
    be undeclared by ``ros2 param set``, so removing a name from the list
    retires its polygon); without it they are an error (at start).
    """
    values = {k: plain_value(v) for k, v in values.items() if k.startswith(OWN_PREFIXES)}
    for name in values:
        _check_known(name)
    world_tree = _world_tree(values, listed_obstacles_only=listed_obstacles_only)
    world = check_start_and_goal(world_from_parameters(world_tree))
    planner_tree = {k[len("planner."):]: v for k, v in values.items() if k.startswith("planner.") and v is not None}
    planner = PlannerSettings.from_parameters({"planner": planner_tree})
    node = {name: _check_node_parameter(name, values.get(name, default))
            for name, (_kind, default, _d, _l) in NODE_PARAMETERS.items()}
    return Configuration(world, planner, NodeSettings(
        record_enabled=node["record.enabled"],
        record_directory=node["record.directory"],
        playback_rate_hz=node["playback.rate"],
        joint_speed_rad_s=node["trajectory.joint_speed"],
        grasp_dwell_s=node["trajectory.grasp_dwell"],
    ))


# --------------------------------------------------------------------------- descriptors


def descriptor_for(name: str) -> ParameterDescriptor:
    """The descriptor a parameter is declared with: description, expected type, range."""
    descriptor = ParameterDescriptor(name=name, dynamic_typing=True)
    if name.startswith("world.obstacles."):
        descriptor.description = OBSTACLE_DESCRIPTION
        descriptor.additional_constraints = "list of numbers (an even count, at least 3 points)"
    elif name.startswith("world."):
        kind, default, description = WORLD_PARAMETERS[name[len("world."):]]
        descriptor.description = description
        required = "required" if default is REQUIRED else f"default {default!r}" if default is not None else "optional"
        descriptor.additional_constraints = f"{kind}; {required}; a change is refused while a plan runs"
    elif name.startswith("planner."):
        kind, default, description, limits = PLANNER_PARAMETERS[name[len("planner."):]]
        descriptor.description = description
        descriptor.additional_constraints = f"{kind.__name__} in [{limits[0]}, {limits[1]}]; default {default}"
        if kind is int:
            descriptor.integer_range = [IntegerRange(from_value=int(limits[0]), to_value=int(limits[1]), step=1)]
        else:
            descriptor.floating_point_range = [FloatingPointRange(from_value=float(limits[0]),
                                                                  to_value=float(limits[1]), step=0.0)]
    else:
        kind, default, description, limits = NODE_PARAMETERS[name]
        descriptor.description = description
        descriptor.additional_constraints = f"{kind}; default {default!r}"
        if limits:
            descriptor.additional_constraints += f"; in [{limits[0]}, {limits[1]}]"
            descriptor.floating_point_range = [FloatingPointRange(from_value=float(limits[0]),
                                                                  to_value=float(limits[1]), step=0.0)]
    return descriptor
