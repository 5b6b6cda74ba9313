"""The parameter specification: every parameter of the parameter file and the node, in one place.

One :class:`ParameterSpec` per parameter (name, type, default, unit, limits,
description), one :class:`ParameterTable` per namespace:

- :data:`WORLD_PARAMETERS`: ``world.*`` (interface.md §1), plus the pattern
  :data:`OBSTACLE_PARAMETER` for ``world.obstacles.<name>``;
- :data:`PLANNER_PARAMETERS`: ``planner.*``;
- :data:`PLAYBACK_PARAMETERS`: ``playback.*`` and ``trajectory.*``, the playback's timing (the node's
  and ``clew_plan``'s live view's); the node's own ``record.*``, ``live.*``, ``state.*``, ``markers.*`` and
  ``parameters.*``, and which namespaces it fixes at start, are specified with the node
  (``clew_ros.ros.node_parameters``); a spatial world's ``world.*`` with the spatial world
  (``clew_ros.spatial.parameters``);
- :data:`LIMITS`: the caps on the size of what the parameters describe
  (links, obstacles, vertices, grasps, parameter count and name lengths).

Derived from these tables: the defaults of
:class:`~clew_ros.core.settings.PlannerSettings`,
:class:`~clew_ros.planar.world.World`, :class:`~clew_ros.planar.world.Robot` and
``clew_ros.ros.parameters.NodeSettings``; the defaults and required keys of
the world parser; the checks of scalar parameters (:func:`check_value`); the
ROS 2 parameter descriptors (``clew_ros.ros.parameters.descriptor_for``);
and the parameter tables of docs/parameters.md (``clew_ros.cli.parameter_tables.markdown_tables``)::

    python -m clew_ros.cli.parameter_tables        # print the tables
    python -m clew_ros.cli.parameter_tables --update docs/parameters.md

The ``world.*`` lists, polygons and the rules that tie several keys together
are checked by the world parser (:mod:`clew_ros.planar.world`). Pure data and
checks: no ROS, no numpy.
"""

from __future__ import annotations

import dataclasses
import enum
import math
from collections.abc import Iterable, Iterator, Mapping
from dataclasses import dataclass
from typing import Any

from clew_ros.core.errors import ParameterError, short_repr

__all__ = [
    "KIND_PARAMETER",
    "LIMITS",
    "OBSTACLE_PARAMETER",
    "PLANNER_PARAMETERS",
    "PLAYBACK_PARAMETERS",
    "REQUIRED",
    "RETIRED_PARAMETERS",
    "WORLD_PARAMETERS",
    "Limits",
    "ParameterSpec",
    "ParameterTable",
    "ParameterType",
    "check_joint_count",
    "check_value",
    "retired_message",
]


class _Required:
    """The default of a parameter that has none: it must be given."""

    def __repr__(self) -> str:
        return "REQUIRED"


#: The default of a required parameter.
REQUIRED: Any = _Required()

#: Parameters that no longer do anything, with the reason: a file that sets one still loads (the value
#: is ignored, with a warning), so that older parameter files keep working.
RETIRED_PARAMETERS: dict[str, str] = {
    "planner.max_sweep_steps": "free intervals are computed in closed form, with no sweep",
}


def retired_message(name: str) -> str:
    """What a warning says about retired parameter ``name``."""
    return f"{name} is retired and ignored: {RETIRED_PARAMETERS[name]}"


class ParameterType(enum.Enum):
    """The type of a parameter's value; ``value`` is the name the parameter tables and the descriptors show."""

    BOOL = "bool"
    INTEGER = "integer"
    DOUBLE = "double"
    STRING = "string"
    DOUBLE_ARRAY = "double[]"
    STRING_ARRAY = "string[]"
    #: One number for every joint, or a list with one per joint (a joint limit, as in ``joint_limits.yaml``).
    DOUBLE_PER_JOINT = "double or double[]"

    @property
    def python_type(self) -> type:
        """The Python type of a checked value (of an item, for the arrays and the per-joint values)."""
        return {"bool": bool, "integer": int, "string": str, "string[]": str}.get(self.value, float)


@dataclass(frozen=True)
class ParameterSpec:
    """One parameter.

    ``default`` is :data:`REQUIRED` when the parameter must be given, ``None``
    when it is simply absent unless given (``world.obstacle_names``).
    ``limits`` is the closed range ``(low, high)`` of a number, or ``None``.
    ``unit`` is the unit of a number (``m``, ``rad``, ``s``, ...), ``""`` if it
    has none. ``read_only``: taken when the node starts, never changed while it runs.
    ``locked``: it matters for safety (what the robot may hit, how fast it may move,
    where runs are recorded), so the node fixes it at start too, unless it is started
    with its development switch (``parameters.allow_runtime_changes``, :mod:`clew_ros.ros.node_parameters`).
    """

    name: str
    type: ParameterType
    default: Any
    description: str
    unit: str = ""
    limits: tuple[float, float] | None = None
    read_only: bool = False
    locked: bool = False

    @property
    def required(self) -> bool:
        return self.default is REQUIRED

    def fixed(self, *, allow_runtime_changes: bool) -> bool:
        """Whether the node refuses a change of this parameter while it runs (a ``read_only`` descriptor)."""
        return self.read_only or (self.locked and not allow_runtime_changes)

    @property
    def at_run_time(self) -> str:
        """What the parameter tables say about a change while the node runs."""
        if self.read_only:
            return "fixed"
        return "fixed (dev switch)" if self.locked else "settable"


class ParameterTable(Mapping[str, ParameterSpec]):
    """The specs of one namespace, keyed by name without the ``prefix`` (``planner.`` -> ``seed``), in order."""

    def __init__(self, prefix: str, specs: Iterable[ParameterSpec]) -> None:
        self.prefix = prefix
        self._specs: dict[str, ParameterSpec] = {}
        for spec in specs:
            if not spec.name.startswith(prefix):
                raise ValueError(f"{spec.name} is not under {prefix!r}")
            self._specs[spec.name[len(prefix) :]] = spec

    def __getitem__(self, key: str) -> ParameterSpec:
        return self._specs[key]

    def __iter__(self) -> Iterator[str]:
        return iter(self._specs)

    def __len__(self) -> int:
        return len(self._specs)

    def __repr__(self) -> str:
        return f"ParameterTable({self.prefix!r}, {list(self._specs.values())!r})"

    def default(self, key: str) -> Any:
        """The default of ``key``; :class:`KeyError` for a required parameter (it has none)."""
        spec = self._specs[key]
        if spec.required:
            raise KeyError(f"{spec.name} is required: it has no default")
        return spec.default


_B, _I, _D, _S = ParameterType.BOOL, ParameterType.INTEGER, ParameterType.DOUBLE, ParameterType.STRING
_DA, _SA, _DJ = ParameterType.DOUBLE_ARRAY, ParameterType.STRING_ARRAY, ParameterType.DOUBLE_PER_JOINT


@dataclass(frozen=True)
class Limits:
    """Caps on the size of what the parameters describe; a value beyond one is refused, naming the cap.

    They keep one parameter file or one ``ros2 param set`` from taking a node's memory or time: every
    cost below grows with these counts. The world parser checks the world's (links, obstacles, vertices,
    grasps, names); the node checks the parameter count and name lengths at start and on every change.
    """

    #: Links of the robot: self-collision checks and planning grow with the square of the link count; at
    #: least 64 (the longest generated arms have 40).
    max_links: int = 100
    #: Obstacles (``world.obstacle_names``): every collision check visits each (5,000 plan within the time
    #: limit on a 2-core machine).
    max_obstacles: int = 5000
    #: Vertices of one polygon (an obstacle or the object): its edges are tested one by one.
    max_polygon_vertices: int = 1000
    #: Vertices of all the world's polygons together: the packed collision arrays hold them all.
    max_world_vertices: int = 50_000
    #: Grasps of the object (``world.object.grasps``): EXPLORE and the regrasp search try them in turn.
    max_grasps: int = 256
    #: Parameters one node holds (its own and those of ROS 2): each obstacle is one, so it exceeds max_obstacles.
    max_parameters: int = 6000
    #: Characters of a parameter name, an obstacle name or ``world.name`` (they go into logs, markers
    #: and recordings).
    max_name_chars: int = 256
    #: Characters of a string parameter's value (``record.directory``: a path, PATH_MAX on Linux).
    max_string_chars: int = 4096
    #: Characters of a ``~/goal_pose`` ``header.frame_id`` quoted in a log line or an event (printable
    #: characters only; the rest is cut).
    max_quoted_chars: int = 64
    #: Bytes of a parameter file (``--params-file``, ``clew_plan``'s world, ``clew_render --world``), read
    #: before YAML parses it (YAML reads a dense file at a third of a megabyte a second; 5,000 spatial
    #: obstacles written by ``yaml.safe_dump`` take about a megabyte).
    max_parameter_file_bytes: int = 2 * 2**20
    # ------------------------------------------------------------------ spatial worlds (interface.md 1b)
    #: Bytes of a URDF or SRDF (a file, or the ``world.robot.description`` text), checked before it is parsed.
    max_urdf_bytes: int = 8 * 2**20
    #: Bytes of one mesh file a URDF names, checked before it is read (parsing grows with the file).
    max_mesh_file_bytes: int = 10 * 2**20
    #: Triangles of one mesh (after reading it, before anything else is done with it).
    max_mesh_triangles: int = 200_000
    #: Triangles of all the robot's meshes together: each is kept in memory and drawn in the markers.
    max_total_triangles: int = 1_000_000
    #: Scale factor of a URDF ``<mesh scale>`` (each axis): the sphere model's work grows as its cube.
    max_mesh_scale: float = 10.0
    #: Links (and joints) of a URDF: the tree walk and the self-collision pairs grow with them.
    max_urdf_links: int = 256
    #: XML elements of a URDF (links, joints, collisions, visuals, ...), counted before the URDF parser, whose
    #: work grows with them, reads it (the Panda's: about 300).
    max_urdf_elements: int = 10_000
    #: Cells of one mesh's voxel grid at the sphere model's cell size (``SphereSettings.cell_m``), from the
    #: mesh's extent before voxelising: the grid and its flood fill grow with it (the shipped arms: 15,000).
    max_mesh_cells: int = 500_000
    #: Triangles of one mesh once split to the voxel size (estimated before splitting): the surface
    #: sampling and the split itself grow with it (the shipped arms: at most 90,000).
    max_split_triangles: int = 300_000
    #: Cells of one mesh's solid (surface and inside) the sphere cover chooses among: its candidate matrix
    #: grows as their square (the shipped arms: at most 7,200).
    max_solid_cells: int = 30_000
    #: Spheres of the robot's sphere model: every collision check visits each (the Panda: 213).
    max_spheres: int = 10_000
    #: Bytes of a planning scene file (``world.scene_file``), checked before it is parsed (as the parameter
    #: file's; a MotionBenchMaker scene takes a few kilobytes).
    max_scene_file_bytes: int = 2**20
    #: Primitives of a planning scene's collision objects (an object without any counts one), counted after
    #: YAML expands its aliases and before any is read (with ``world.obstacle_names``: ``max_obstacles``).
    max_scene_objects: int = 5000
    #: Points of one ``~/points`` cloud (section 3c): the highest ``state.max_points`` may be, and its default.
    max_points: int = 1_000_000
    #: Refused requests (``~/plan``, ``~/goal_pose``) recorded in the current run's recording: past it they are
    #: still published and logged, not recorded (a flood of bad goals would otherwise grow one recording).
    max_recorded_refusals: int = 100


#: The caps in force (:class:`Limits`' defaults).
LIMITS = Limits()


def _locked(specs: Iterable[ParameterSpec]) -> list[ParameterSpec]:
    return [dataclasses.replace(spec, locked=True) for spec in specs]


WORLD_PARAMETERS = ParameterTable(
    "world.",
    _locked(
        [
            ParameterSpec(
                "world.name",
                _S,
                "world",
                f"Name of the world; plans and recordings carry it. At most {LIMITS.max_name_chars} characters.",
            ),
            ParameterSpec(
                "world.bounds",
                _DA,
                REQUIRED,
                "The workspace box [xmin, ymin, xmax, ymax] (m); touching its edge is inside.",
                "m",
            ),
            ParameterSpec("world.robot.base", _DA, REQUIRED, "Position [x, y] of joint 1 (m).", "m"),
            ParameterSpec(
                "world.robot.link_lengths",
                _DA,
                REQUIRED,
                f"Length of each link (m); n >= 2 links, at most {LIMITS.max_links}.",
                "m",
            ),
            ParameterSpec(
                "world.robot.link_width", _D, 0.0, "Links are capsules of radius link_width / 2 (m); 0: segments.", "m"
            ),
            ParameterSpec("world.robot.joint_lower", _DA, REQUIRED, "Lower joint limits (rad), one per link.", "rad"),
            ParameterSpec("world.robot.joint_upper", _DA, REQUIRED, "Upper joint limits (rad), one per link.", "rad"),
            ParameterSpec(
                "world.robot.initial", _DA, REQUIRED, "Joint angles at the start (rad), one per link.", "rad"
            ),
            ParameterSpec("world.robot.self_collision", _B, True, "Check non-adjacent links against each other."),
            ParameterSpec(
                "world.obstacle_names",
                _SA,
                None,
                "Names of the obstacles; each needs world.obstacles.<name>. Omit it for a world without obstacles. "
                f"At most {LIMITS.max_obstacles} names of at most {LIMITS.max_name_chars} characters.",
            ),
            ParameterSpec(
                "world.object.polygon",
                _DA,
                REQUIRED,
                f"The object as a flat x0, y0, x1, y1, ... list in its own frame (m); at most "
                f"{LIMITS.max_polygon_vertices} vertices.",
                "m",
            ),
            ParameterSpec(
                "world.object.initial", _DA, REQUIRED, "Start placement [x, y, theta] of the object (m, rad).", "m, rad"
            ),
            ParameterSpec(
                "world.object.goal",
                _DA,
                REQUIRED,
                "Goal placement [x, y, theta] of the object (m, rad); ~/plan plans to it.",
                "m, rad",
            ),
            ParameterSpec(
                "world.object.grasps",
                _DA,
                REQUIRED,
                "Grasp points on the object's boundary, flat x0, y0, ... in its frame (m); "
                f"at most {LIMITS.max_grasps}.",
                "m",
            ),
            ParameterSpec(
                "world.grasp_tolerance", _D, 0.005, "The tip holds a grasp when it is this close to it (m).", "m"
            ),
            ParameterSpec(
                "world.goal_tolerance",
                _D,
                0.02,
                "Largest distance of the final object position from the goal (m).",
                "m",
            ),
            ParameterSpec(
                "world.goal_angle_tolerance",
                _D,
                math.pi,
                "Largest orientation error at the goal (rad); pi: any.",
                "rad",
            ),
        ]
    ),
)

#: ``world.obstacles.<name>``, one per name in ``world.obstacle_names`` (not a key of :data:`WORLD_PARAMETERS`).
OBSTACLE_PARAMETER = ParameterSpec(
    "world.obstacles.<name>",
    _DA,
    REQUIRED,
    f"Obstacle polygon as a flat x0, y0, x1, y1, ... list (m); at most {LIMITS.max_polygon_vertices} vertices "
    f"(and {LIMITS.max_world_vertices} in all the world's polygons).",
    "m",
    locked=True,
)

#: ``world.kind``: the kind of world the ``world.*`` parameters describe; absent, a planar world's (this module's
#: tables). Not a key of :data:`WORLD_PARAMETERS`: a planar world need not name its kind.
KIND_PARAMETER = ParameterSpec(
    "world.kind",
    _S,
    None,
    "The kind of world: planar (these parameters; the default when absent) or spatial (interface.md section 1b: "
    "the spatial world's parameters).",
    locked=True,
)

PLANNER_PARAMETERS = ParameterTable(
    "planner.",
    [
        ParameterSpec(
            "planner.seed", _I, 0, "Seed of the random generator; same seed, same plan.", limits=(0, 2**31 - 1)
        ),
        ParameterSpec(
            "planner.time_limit",
            _D,
            30.0,
            "Seconds before the planner stops and reports TIME_LIMIT.",
            "s",
            (0.01, 3600.0),
        ),
        ParameterSpec(
            "planner.resolution",
            _D,
            0.01,
            "EXPLORE stops with NO_PATH_AT_RESOLUTION when a new landmark is closer than this to the others "
            "(landmark-distance units, m).",
            "m",
            (1e-6, 10.0),
        ),
        ParameterSpec(
            "planner.clearance",
            _D,
            0.001,
            "Clearance (m) every planned configuration keeps from what it could hit; bounds the motion "
            "between checks so plans stay valid at any finer check.",
            "m",
            (1e-6, 0.1),
        ),
        ParameterSpec(
            "planner.manhattan_order",
            _I,
            2,
            "Order k of the Manhattan paths optimised (k single paths of n moves).",
            limits=(1, 8),
        ),
        ParameterSpec("planner.population", _I, 24, "Genetic algorithm population size.", limits=(4, 1000)),
        ParameterSpec(
            "planner.generations", _I, 12, "Genetic algorithm generations per optimisation.", limits=(1, 1000)
        ),
        ParameterSpec(
            "planner.explore_candidates", _I, 4, "Landmark/grasp pairs (m1) tried per EXPLORE step.", limits=(1, 1000)
        ),
        ParameterSpec(
            "planner.search_rounds", _I, 3, "Rounds of SEARCH's do-while loop before it gives up.", limits=(1, 100)
        ),
        ParameterSpec(
            "planner.joint_weight",
            _D,
            0.1,
            "Weight (m/rad) of the joint angles in the landmark distance.",
            "m/rad",
            (0.0, 10.0),
        ),
        ParameterSpec(
            "planner.threads",
            _I,
            0,
            "Threads that decode a population's Manhattan paths (0: all cores; never more than the cores); the "
            "plan does not depend on it.",
            limits=(0, 256),
        ),
        ParameterSpec(
            "planner.improve_time",
            _D,
            0.5,
            "Budget (s) for improving a found plan (other grasps, elbows and regrasp placements, fewer "
            "transfers, shortcuts); counted in work, not wall time, so the plan does not depend on the machine; "
            "stops early at time_limit or cancel; 0: off.",
            "s",
            (0.0, 3600.0),
        ),
    ],
)

#: The world as it is now (interface.md section 3c; spatial worlds): inputs the node reads while it runs. Each is
#: off unless turned on; all read only (taken when the node starts).
#: The playback's timing: what the node times ``~/trajectory`` and its playback with, and ``clew_plan``'s live
#: view too (the node's own parameters, :data:`clew_ros.ros.parameters.NODE_PARAMETERS`, include these).
PLAYBACK_PARAMETERS = ParameterTable(
    "",
    [
        ParameterSpec(
            "playback.rate",
            _D,
            20.0,
            "Rate (Hz) of ~/joint_states and ~/object_pose while a plan plays back.",
            "Hz",
            (1.0, 1000.0),
        ),
        ParameterSpec(
            "trajectory.max_velocity",
            _DJ,
            1.0,
            "Velocity limit (rad/s) of the joints in ~/trajectory and the playback: one value for every joint, "
            "or a list with one per joint, joint_1 first (the per-joint limits of a joint_limits.yaml).",
            "rad/s",
            (0.001, 1000.0),
            locked=True,
        ),
        ParameterSpec(
            "trajectory.max_acceleration",
            _DJ,
            2.0,
            "Acceleration limit (rad/s^2) of the joints in ~/trajectory and the playback: one value for every "
            "joint, or a list with one per joint.",
            "rad/s^2",
            (0.001, 100000.0),
            locked=True,
        ),
        ParameterSpec(
            "trajectory.joint_speed",
            _DJ,
            None,
            "Deprecated alias of trajectory.max_velocity, kept so that parameter files that set it still load; "
            "when set, it is the velocity limit and trajectory.max_velocity is ignored.",
            "rad/s",
            (0.001, 1000.0),
            locked=True,
        ),
        ParameterSpec(
            "trajectory.grasp_dwell",
            _D,
            0.2,
            "Time (s) a grasp or ungrasp takes in ~/trajectory.",
            "s",
            (0.001, 60.0),
            locked=True,
        ),
    ],
)

# --------------------------------------------------------------------------- checks


def check_value(spec: ParameterSpec, value: Any) -> Any:
    """``value`` checked against ``spec`` and converted; raises :class:`ParameterError` naming ``spec.name``.

    For the scalar types: a bool is ``true`` or ``false``; a string is
    non-empty; an integer is an ``int`` or an integral ``float`` (``5.0``),
    returned as ``int``; a double is an ``int`` or a ``float``, returned as
    ``float``; a number lies within ``spec.limits`` (NaN never does). A
    per-joint value is a double, or a non-empty list of doubles (each within
    the limits) returned as a tuple of floats; how many joints it must cover
    is :func:`check_joint_count`'s to check. Arrays (``world.*`` lists) are
    checked by the world parser, not here.
    """
    kind = spec.type
    if kind is ParameterType.BOOL:
        if not isinstance(value, bool):
            raise ParameterError(spec.name, f"expected true or false, got {short_repr(value)}")
        return value
    if kind is ParameterType.STRING:
        if not isinstance(value, str) or not value:
            raise ParameterError(spec.name, f"expected a non-empty string, got {short_repr(value)}")
        if len(value) > LIMITS.max_string_chars:
            raise ParameterError(
                spec.name,
                f"expected at most {LIMITS.max_string_chars} characters (Limits.max_string_chars), got {len(value)}",
            )
        return value
    if kind is ParameterType.DOUBLE_PER_JOINT:
        return _check_per_joint(spec, value)
    if kind not in (ParameterType.INTEGER, ParameterType.DOUBLE):
        raise TypeError(f"{spec.name}: {kind.value} values are checked by the world parser")
    return _check_number(spec, value, kind)


def _check_number(spec: ParameterSpec, value: Any, kind: ParameterType, joint: str = "") -> Any:
    """One number of ``spec`` (``joint``: the item of a per-joint list it is, named in the message)."""
    of = f" for {joint}" if joint else ""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        expected = "an integer" if kind is ParameterType.INTEGER else "a number"
        raise ParameterError(spec.name, f"expected {expected}{of}, got {short_repr(value)}")
    if kind is ParameterType.INTEGER and isinstance(value, float) and not value.is_integer():
        raise ParameterError(spec.name, f"expected an integer, got {value!r}")
    try:
        converted = kind.python_type(value)
    except OverflowError:  # an integer too large for a float
        converted = None
    limits = spec.limits
    if limits is None:
        if converted is None or not math.isfinite(converted):
            raise ParameterError(spec.name, f"expected a finite number{of}, got {short_repr(value)}")
    elif converted is None or math.isnan(converted) or not limits[0] <= converted <= limits[1]:
        raise ParameterError(spec.name, f"expected a value in [{limits[0]}, {limits[1]}]{of}, got {short_repr(value)}")
    return converted


def _check_per_joint(spec: ParameterSpec, value: Any) -> float | tuple[float, ...]:
    if isinstance(value, (list, tuple)):
        if not value:
            raise ParameterError(
                spec.name, "expected a number for every joint or a list with one per joint, got an empty list"
            )
        return tuple(
            _check_number(spec, item, ParameterType.DOUBLE, f"joint_{index + 1}") for index, item in enumerate(value)
        )
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ParameterError(
            spec.name,
            f"expected a number for every joint or a list with one per joint, got {short_repr(value)}",
        )
    return float(_check_number(spec, value, ParameterType.DOUBLE))


def check_joint_count(spec: ParameterSpec, value: float | tuple[float, ...] | None, joints: int) -> None:
    """Check that a per-joint value (checked by :func:`check_value`) covers ``joints`` joints: a number covers
    them all, a list must hold one per joint. Raises :class:`ParameterError` naming ``spec.name``."""
    if not isinstance(value, tuple) or len(value) == joints:
        return
    names = ", ".join(f"joint_{i + 1}" for i in range(joints))
    raise ParameterError(
        spec.name,
        f"expected a number for every joint or a list with one per joint ({joints}: {names}), "
        f"got a list of {len(value)}",
    )
