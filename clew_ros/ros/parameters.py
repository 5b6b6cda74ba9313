"""The node's parameters: start values, descriptors and validation.

The parameters are specified in :mod:`clew_ros.core.parameters` (name, type,
default, unit, range, description); this module turns that specification
into ROS 2 descriptors (``ros2 param describe`` shows them) and checks the
values. Three families:

- ``world.*``: :data:`~clew_ros.core.parameters.WORLD_PARAMETERS`, the world
  of interface.md §1; ``world.obstacles.<name>`` for each name in
  ``world.obstacle_names``. Checked by the core
  (:func:`~clew_ros.planar.world.world_from_parameters`, then
  :func:`~clew_ros.planar.collision.check_start_and_goal`), so every refusal
  names the parameter at fault. A spatial world's (``world.kind: spatial``,
  §1b): :data:`~clew_ros.spatial.parameters.SPATIAL_WORLD_PARAMETERS` and
  ``world.obstacles.<name>.shape / .size / .pose``, checked by the spatial
  world parser (:func:`~clew_ros.ros.spatial.load_spatial`); a name neither
  specifies is refused.
- ``planner.*``: :data:`~clew_ros.core.parameters.PLANNER_PARAMETERS`,
  checked by :class:`~clew_ros.core.settings.PlannerSettings`.
- the node's own: :data:`~clew_ros.ros.node_parameters.NODE_PARAMETERS`
  (``record.*``, ``playback.*``, ``trajectory.*``, ``live.*``,
  ``parameters.*``, ``markers.*``, ``state.*``), checked here into :class:`NodeSettings`.

The parameters that matter for safety (``world.*``, ``record.*``,
``trajectory.*``, ``live.*``: :data:`~clew_ros.ros.node_parameters.LOCKED_PREFIXES`)
are declared read-only, so that rclpy refuses a change from any peer with a
reason naming the parameter, unless the node is started with
``parameters.allow_runtime_changes: true`` (itself read-only).
:func:`check_parameter_names` holds a node to the parameter count and name
length of :data:`~clew_ros.core.parameters.LIMITS`.

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
import dataclasses
from collections.abc import Collection, Mapping
from dataclasses import dataclass, fields
from pathlib import Path
from typing import TYPE_CHECKING, Any

from rcl_interfaces.msg import FloatingPointRange, IntegerRange, ParameterDescriptor

from clew_ros.core.errors import ParameterError, WorldError, short_repr
from clew_ros.core.parameters import (
    KIND_PARAMETER,
    LIMITS,
    OBSTACLE_PARAMETER,
    PLANNER_PARAMETERS,
    RETIRED_PARAMETERS,
    WORLD_PARAMETERS,
    Limits,
    ParameterSpec,
    ParameterType,
    check_joint_count,
    check_value,
)
from clew_ros.core.settings import PlannerSettings
from clew_ros.planar.collision import check_start_and_goal
from clew_ros.planar.world import WORLD_KIND as PLANAR_WORLD_KIND
from clew_ros.planar.world import World, read_parameter_file, world_from_parameters
from clew_ros.ros.node_parameters import NODE_PARAMETERS, PLANNER_LOCK, RUNTIME_CHANGES, SIM_TIME_CHANGES
from clew_ros.spatial import WORLD_KIND as SPATIAL_WORLD_KIND
from clew_ros.spatial.parameters import (
    OBSTACLE_PREFIX,
    SPATIAL_OBSTACLE_PARAMETERS,
    SPATIAL_WORLD_PARAMETERS,
    spatial_spec,
)

if TYPE_CHECKING:
    from clew_ros.ros.spatial import SpatialSetup
    from clew_ros.spatial.world import SpatialWorld

__all__ = [
    "DEFAULT_WORLD_FILE",
    "NODE_PARAMETERS",
    "OWN_PREFIXES",
    "WORLD_PARAMETERS",
    "Configuration",
    "NodeSettings",
    "check_parameter_names",
    "configuration_from_values",
    "default_world_file",
    "descriptor_for",
    "flatten",
    "initial_values",
    "is_spatial",
    "nest",
    "node_settings",
    "plain_value",
    "resolve_record_directory",
    "runtime_changes_allowed",
]

DEFAULT_WORLD_FILE = "figure1.yaml"

#: The parameter prefixes the node owns and checks (others, e.g. use_sim_time, are rclpy's).
OWN_PREFIXES = (
    "world.",
    "planner.",
    "record.",
    "markers.",
    "playback.",
    "trajectory.",
    "live.",
    "parameters.",
    "state.",
)


@dataclass(frozen=True)
class NodeSettings:
    """The node's own parameters, checked (defaults from :data:`~clew_ros.ros.node_parameters.NODE_PARAMETERS`)."""

    record_enabled: bool = NODE_PARAMETERS.default("record.enabled")
    record_directory: str = NODE_PARAMETERS.default("record.directory")
    #: Most run folders kept (0: no limit) and most bytes of complete runs kept (0: no limit).
    record_max_runs: int = NODE_PARAMETERS.default("record.max_runs")
    record_max_bytes: int = NODE_PARAMETERS.default("record.max_bytes")
    playback_rate_hz: float = NODE_PARAMETERS.default("playback.rate")
    #: Triangles per link mesh in ~/world_markers (0: every one).
    marker_link_faces: int = NODE_PARAMETERS.default("markers.link_faces")
    #: The joint limits: one number for every joint, or one per joint (checked against the world's joints).
    max_velocity_rad_s: float | tuple[float, ...] = NODE_PARAMETERS.default("trajectory.max_velocity")
    max_acceleration_rad_s2: float | tuple[float, ...] = NODE_PARAMETERS.default("trajectory.max_acceleration")
    joint_speed_rad_s: float | tuple[float, ...] | None = NODE_PARAMETERS.default("trajectory.joint_speed")
    grasp_dwell_s: float = NODE_PARAMETERS.default("trajectory.grasp_dwell")
    foxglove_port: int = NODE_PARAMETERS.default("live.foxglove_port")
    allow_runtime_changes: bool = NODE_PARAMETERS.default(RUNTIME_CHANGES)
    #: The world as it is now (interface.md section 3c): which inputs are on, and their tuning.
    state_joint_states: bool = NODE_PARAMETERS.default("state.joint_states")
    state_max_age_s: float = NODE_PARAMETERS.default("state.max_age")
    state_object_pose: bool = NODE_PARAMETERS.default("state.object_pose")
    state_snap_m: float = NODE_PARAMETERS.default("state.snap_m")
    state_snap_rad: float = NODE_PARAMETERS.default("state.snap_rad")
    state_obstacles: bool = NODE_PARAMETERS.default("state.obstacles")
    state_points: bool = NODE_PARAMETERS.default("state.points")
    state_voxel_m: float = NODE_PARAMETERS.default("state.voxel_m")
    state_self_filter_m: float = NODE_PARAMETERS.default("state.self_filter_m")
    state_max_points: int = NODE_PARAMETERS.default("state.max_points")
    state_advance: bool = NODE_PARAMETERS.default("state.advance")
    #: ``use_sim_time`` may change while the node runs; ``planner.*`` is fixed at start.
    allow_sim_time_changes: bool = NODE_PARAMETERS.default(SIM_TIME_CHANGES)
    lock_planner: bool = NODE_PARAMETERS.default(PLANNER_LOCK)
    #: ``record_directory`` resolved when these settings are made (at start): absolute, ``~`` expanded,
    #: symbolic links and ``..`` resolved; every run folder is made inside it.
    record_path: Path = dataclasses.field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "record_path", resolve_record_directory(self.record_directory))

    @property
    def velocity_limit_rad_s(self) -> float | tuple[float, ...]:
        """The joints' velocity limit (one for all, or one per joint): ``trajectory.joint_speed`` (deprecated
        alias) when set, else ``max_velocity``."""
        return self.max_velocity_rad_s if self.joint_speed_rad_s is None else self.joint_speed_rad_s


def resolve_record_directory(text: str) -> Path:
    """``record.directory`` as the absolute path runs are recorded in; :class:`ParameterError` says why not.

    ``~`` (and ``~user``) is expanded; environment variables are not: a ``$``
    is refused, so that no value names another variable's content. The path
    is made absolute (relative to the working directory) and resolved
    (symbolic links and ``..``), once: a link changed later cannot move the
    recordings (:class:`~clew_ros.node.run_recording.Recordings` checks it).
    """
    name = "record.directory"
    if "$" in text:
        raise ParameterError(
            name,
            f"expected a path without '$': environment variables are not expanded (write the path out, or let "
            f"the launch file or shell substitute it), got {text!r}",
        )
    if "\0" in text:
        raise ParameterError(name, "expected a path without NUL characters")
    try:
        expanded = Path(text).expanduser()
    except RuntimeError:  # no home directory for '~' or '~user'
        raise ParameterError(name, f"expected '~' to name a home directory, got {text!r}") from None
    try:
        return expanded.resolve()
    except (OSError, RuntimeError) as error:  # a symbolic link loop, an unreadable parent
        raise ParameterError(name, f"expected a path that resolves, got {text!r} ({error})") from None


#: The parameter behind each field of :class:`NodeSettings` (every node parameter, once).
SETTINGS_FIELDS = {
    "record_enabled": "record.enabled",
    "record_directory": "record.directory",
    "record_max_runs": "record.max_runs",
    "record_max_bytes": "record.max_bytes",
    "playback_rate_hz": "playback.rate",
    "marker_link_faces": "markers.link_faces",
    "max_velocity_rad_s": "trajectory.max_velocity",
    "max_acceleration_rad_s2": "trajectory.max_acceleration",
    "joint_speed_rad_s": "trajectory.joint_speed",
    "grasp_dwell_s": "trajectory.grasp_dwell",
    "foxglove_port": "live.foxglove_port",
    "allow_runtime_changes": RUNTIME_CHANGES,
    "state_joint_states": "state.joint_states",
    "state_max_age_s": "state.max_age",
    "state_object_pose": "state.object_pose",
    "state_snap_m": "state.snap_m",
    "state_snap_rad": "state.snap_rad",
    "state_obstacles": "state.obstacles",
    "state_points": "state.points",
    "state_voxel_m": "state.voxel_m",
    "state_self_filter_m": "state.self_filter_m",
    "state_max_points": "state.max_points",
    "state_advance": "state.advance",
    "allow_sim_time_changes": SIM_TIME_CHANGES,
    "lock_planner": PLANNER_LOCK,
}
assert [f.name for f in fields(NodeSettings) if f.init] == list(SETTINGS_FIELDS)
assert sorted(SETTINGS_FIELDS.values()) == sorted(NODE_PARAMETERS)


@dataclass(frozen=True)
class Configuration:
    """Everything the parameters describe, checked: the world, the planner and the node settings.

    A spatial world (``world.kind: spatial``, interface.md section 1b) comes with its ``spatial`` setup
    (:class:`~clew_ros.ros.spatial.SpatialSetup`); a planar one has none.
    """

    world: World | SpatialWorld
    planner: PlannerSettings
    node: NodeSettings
    spatial: SpatialSetup | None = None


#: The value of ``world.kind`` that selects a spatial world (section 1b); ``planar`` is the default.
SPATIAL_KIND = SPATIAL_WORLD_KIND


def is_spatial(values: Mapping[str, Any]) -> bool:
    """Whether parameter values (full name -> value) describe a spatial world (``world.kind: spatial``)."""
    return plain_value(values.get("world.kind")) == SPATIAL_KIND


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
    except Exception:  # noqa: BLE001 - no ament index (not installed by colcon): use the source tree
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
    tables = (
        (PLANNER_PARAMETERS, NODE_PARAMETERS)
        if is_spatial(overrides)
        else (WORLD_PARAMETERS, PLANNER_PARAMETERS, NODE_PARAMETERS)
    )
    embedded: dict[str, Any] = {}
    if not has_world:
        path = default_world_file() if default_file is None else default_file
        tree = read_parameter_file(path)
        embedded = {k: v for k, v in flatten(tree).items() if k.startswith(("world.", "planner."))}
    for table in tables:
        for spec in table.values():
            values[spec.name] = None if spec.required else spec.default
    values.update(embedded)
    values.update(overrides)
    return values


# --------------------------------------------------------------------------- checks


def _check_known(name: str, *, spatial: bool = False) -> None:
    if name in RETIRED_PARAMETERS or name == KIND_PARAMETER.name:
        return  # a retired one is accepted and ignored (the node warns at start: retired_names)
    if spatial and name.startswith("world."):
        if spatial_spec(name) is None:
            raise WorldError(
                name,
                "unknown parameter of a spatial world; known: "
                + ", ".join(spec.name for spec in SPATIAL_WORLD_PARAMETERS.values())
                + ", "
                + ", ".join(spec.name for spec in SPATIAL_OBSTACLE_PARAMETERS.values()),
            )
        return  # checked with the whole world by the spatial world parser, naming the parameter at fault
    if name.startswith("world."):
        key = name[len("world.") :]
        if key in WORLD_PARAMETERS:
            return
        parts = key.split(".")
        if parts[0] == "obstacles" and len(parts) == 2:
            return
        raise WorldError(
            name,
            "unknown parameter; known: "
            + ", ".join(f"world.{k}" for k in WORLD_PARAMETERS)
            + ", world.obstacles.<name>",
        )
    if name.startswith("planner."):
        if name[len("planner.") :] not in PLANNER_PARAMETERS:
            raise ParameterError(
                name, "unknown parameter; known: " + ", ".join(f"planner.{k}" for k in PLANNER_PARAMETERS)
            )
        return
    if name not in NODE_PARAMETERS:
        raise ParameterError(name, "unknown parameter; known: " + ", ".join(NODE_PARAMETERS))


def _world_tree(values: Mapping[str, Any], *, listed_obstacles_only: bool) -> dict:
    world = {k: v for k, v in values.items() if k.startswith("world.")}
    if listed_obstacles_only:
        names = plain_value(world.get("world.obstacle_names")) or []
        names = names if isinstance(names, list) else []
        world = {
            k: v
            for k, v in world.items()
            if not k.startswith("world.obstacles.") or k[len("world.obstacles.") :].split(".")[0] in names
        }
    return nest(world)


def configuration_from_values(
    values: Mapping[str, Any], *, listed_obstacles_only: bool = False, previous: Configuration | None = None
) -> Configuration:
    """Check every value (full name -> value) and build the configuration.

    Raises :class:`~clew_ros.core.errors.ParameterError` (or its subclass
    ``WorldError``) naming the first parameter at fault. With
    ``listed_obstacles_only``, ``world.obstacles.<name>`` parameters whose
    name is not in ``world.obstacle_names`` are ignored (a parameter cannot
    be undeclared by ``ros2 param set``, so removing a name from the list
    retires its polygon); without it they are an error (at start). A spatial world
    (``world.kind: spatial``) is read by :func:`clew_ros.ros.spatial.load_spatial`; ``previous``'s is
    reused when its ``world.*`` values are the same.
    """
    values = {k: plain_value(v) for k, v in values.items() if k.startswith(OWN_PREFIXES)}
    spatial = is_spatial(values)
    for name in values:
        _check_known(name, spatial=spatial)
    world_tree = _world_tree(values, listed_obstacles_only=listed_obstacles_only)
    setup = None
    world: World | SpatialWorld
    if spatial:
        world, setup = _spatial_world(world_tree, previous)
    else:
        kind = values.get(KIND_PARAMETER.name)
        if kind is not None and kind != PLANAR_WORLD_KIND:
            raise WorldError(
                KIND_PARAMETER.name, f"expected {PLANAR_WORLD_KIND} or {SPATIAL_KIND}, got {short_repr(kind, 40)}"
            )
        world = check_start_and_goal(world_from_parameters(world_tree))
        for name in ("state.joint_states", "state.object_pose", "state.obstacles", "state.points", "state.advance"):
            if values.get(name) is True:
                raise ParameterError(name, "expected false: the world as it is now needs a spatial world (world.kind)")
    planner_tree = {
        k[len("planner.") :]: v
        for k, v in values.items()
        if k.startswith("planner.") and v is not None and k not in RETIRED_PARAMETERS
    }
    planner = PlannerSettings.from_parameters({"planner": planner_tree})
    return Configuration(world, planner, node_settings(values, world.robot.dof), setup)


def _spatial_world(tree: dict[str, Any], previous: Configuration | None) -> tuple[SpatialWorld, SpatialSetup]:
    """The spatial world of a ``world`` tree, relative paths read from the working directory; the previous
    configuration's world when its tree is the same (loading the robot and its sphere model takes seconds).
    A new world's kernels are compiled (or loaded from numba's cache) here, as ``clew_plan`` does before its
    clock starts, so that a run's ``planner.time_limit`` never pays for them."""
    if previous is not None and previous.spatial is not None and previous.spatial.tree == tree:
        return previous.world, previous.spatial  # type: ignore[return-value]  # a spatial setup: a spatial world
    from clew_ros.ros.spatial import load_spatial

    try:
        world, setup = load_spatial(tree, Path.cwd())
    except ImportError as error:
        raise WorldError(
            "world.kind", f"spatial worlds need the spatial extra (pip install 'clew_ros[spatial]'): {error}"
        ) from None
    from clew_ros.spatial.offline import warm_up

    warm_up(world)
    return world, setup


def node_settings(values: Mapping[str, Any], dof: int) -> NodeSettings:
    """The node's own parameters among ``values`` (full name -> value; others ignored), checked for an arm
    of ``dof`` joints; :class:`~clew_ros.core.errors.ParameterError` names the first one at fault."""
    node = {field: _node_value(NODE_PARAMETERS[name], values.get(name)) for field, name in SETTINGS_FIELDS.items()}
    for field, name in SETTINGS_FIELDS.items():  # a per-joint list holds one value per joint of this world
        if NODE_PARAMETERS[name].type is ParameterType.DOUBLE_PER_JOINT:
            check_joint_count(NODE_PARAMETERS[name], node[field], dof)
    return NodeSettings(**node)


def _node_value(spec: ParameterSpec, value: Any) -> Any:
    """A node parameter's value checked; unset (``None``) is its default, ``None`` for one absent unless given."""
    if value is None:
        return spec.default
    return check_value(spec, value)


# --------------------------------------------------------------------------- descriptors


def descriptor_for(
    name: str, *, spatial: bool = False, allow_runtime_changes: bool = False, lock_planner: bool = False
) -> ParameterDescriptor:
    """The descriptor a parameter is declared with: its spec's description, type and default, and range;
    ``spatial``: a ``world.*`` name is a spatial world's (:mod:`clew_ros.spatial.parameters`).

    Every parameter is declared with ``dynamic_typing`` (a ``30`` is as good
    as ``30.0``: the value is checked by this module, not by rclpy). It is
    ``read_only`` when its spec is, and when it is locked (``world.*``,
    ``record.*``, ``trajectory.*``, ``live.*``) unless ``allow_runtime_changes``; ``planner.*`` too with
    ``lock_planner``.
    """
    spec = _spec_of(name, spatial=spatial)
    descriptor = ParameterDescriptor(
        name=name,
        dynamic_typing=True,
        description=spec.description,
        additional_constraints=_constraints(spec),
        read_only=spec.fixed(allow_runtime_changes=allow_runtime_changes)
        or (lock_planner and name.startswith("planner.")),
    )
    if spec.limits is not None:
        low, high = spec.limits
        if spec.type is ParameterType.INTEGER:
            descriptor.integer_range = [IntegerRange(from_value=int(low), to_value=int(high), step=1)]
        else:
            descriptor.floating_point_range = [
                FloatingPointRange(from_value=float(low), to_value=float(high), step=0.0)
            ]
    return descriptor


def _spec_of(name: str, *, spatial: bool = False) -> ParameterSpec:
    """The spec of parameter ``name`` (``spatial``: of a spatial world); :class:`KeyError` for one the node
    does not take."""
    if name == KIND_PARAMETER.name:
        return SPATIAL_WORLD_PARAMETERS["kind"] if spatial else KIND_PARAMETER
    if spatial and name.startswith("world."):
        spec = spatial_spec(name)
        if spec is None:
            raise KeyError(f"{name} is not a parameter of a spatial world")
        return spec
    if name.startswith("world.obstacles.") and name.count(".") == 2:
        return OBSTACLE_PARAMETER
    if name.startswith("world."):
        return WORLD_PARAMETERS[name[len("world.") :]]
    if name.startswith("planner."):
        return PLANNER_PARAMETERS[name[len("planner.") :]]
    return NODE_PARAMETERS[name]


def _constraints(spec: ParameterSpec) -> str:
    """The descriptor's ``additional_constraints``: type, default and range in words (one wording per family)."""
    if spec is OBSTACLE_PARAMETER:
        return (
            f"list of numbers (an even count, at least 3 points, at most {LIMITS.max_polygon_vertices}); "
            f"fixed at start (unless {RUNTIME_CHANGES})"
        )
    if spec.name.startswith("world."):
        given = "required" if spec.required else "optional" if spec.default is None else f"default {spec.default!r}"
        text = f"{spec.type.value}; {given}; fixed at start (unless {RUNTIME_CHANGES}: then not while a plan runs)"
        if spec.name.startswith(OBSTACLE_PREFIX):
            return f"{text}; one per name in world.obstacle_names"
        return text if spec.limits is None else f"{text}; in [{spec.limits[0]}, {spec.limits[1]}]"
    if spec.name.startswith("planner."):
        assert spec.limits is not None
        return f"{spec.type.python_type.__name__} in [{spec.limits[0]}, {spec.limits[1]}]; default {spec.default}"
    kind = spec.type.value
    if spec.type is ParameterType.DOUBLE_PER_JOINT:
        kind = "double (every joint) or double[] (one per joint)"
    text = f"{kind}; " + ("unset by default" if spec.default is None else f"default {spec.default!r}")
    if spec.limits is None:
        return text
    each = "each " if spec.type is ParameterType.DOUBLE_PER_JOINT else ""
    return f"{text}; {each}in [{spec.limits[0]}, {spec.limits[1]}]"


# --------------------------------------------------------------------------- the switch and the caps


def runtime_changes_allowed(overrides: Mapping[str, Any]) -> bool:
    """The development switch ``parameters.allow_runtime_changes`` among a node's start values (default off).

    Read before any descriptor is given, since it decides which are read-only.
    Raises :class:`ParameterError` when it is not a bool.
    """
    value = overrides.get(RUNTIME_CHANGES)
    return False if value is None else bool(check_value(NODE_PARAMETERS[RUNTIME_CHANGES], plain_value(value)))


def check_parameter_names(names: Collection[str], limits: Limits = LIMITS) -> None:
    """Hold the names of one node's parameters to ``limits``: how many, and how long each.

    Raises :class:`ParameterError` naming the first name at fault and the limit (``Limits.<field>``).
    """
    if len(names) > limits.max_parameters:
        raise ParameterError(
            "parameters",
            f"expected at most {limits.max_parameters} parameters (Limits.max_parameters), got {len(names)}",
        )
    for name in names:
        if len(name) > limits.max_name_chars:
            raise ParameterError(
                name[:40] + "...",
                f"expected a parameter name of at most {limits.max_name_chars} characters (Limits.max_name_chars), "
                f"got {len(name)}",
            )
