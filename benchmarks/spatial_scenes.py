"""Motion-only problems of the MotionBenchMaker kind: a table with clutter, a shelf, a cage, a bookshelf.

:func:`generate` draws one problem: a scene (a ``moveit_msgs/PlanningScene`` as a YAML-ready mapping, the
format :func:`clew_ros.spatial.scene.scene_obstacles` and MoveIt read) for a shipped robot (the Panda or
the UR5 of ``config/robots``), and a start and a goal joint configuration, each found by the tcp inverse
kinematics (:class:`~clew_ros.spatial.inverse.InverseKinematics`, collision-free solutions only) at a tcp
target drawn inside a region of the furniture: between the clutter on the table (from above), in a shelf's
or bookshelf's cell (horizontally through its open front, any roll about the approach), inside a cage
(through its open front) or above it. Start and goal lie in different regions or far apart in one.

Every size, distance and angle is drawn from the ranges of :class:`SceneSettings`, the furniture placed at a
random bearing in front of or beside the robot; a draw that puts furniture on the robot, or whose targets
the robot cannot reach without collision, is drawn again (a problem is never tuned to one scene). With
``SceneSettings.nontrivial`` (the default) the straight joint-space move from start to goal must collide, so
no planner solves a problem by its first connection attempt. The robot stands on a mounting plate (an
obstacle 5 mm under its base's sphere model). Same seed, family and robot: the same problem, byte for byte.

:func:`context` loads a problem for planning: the robot model, its sphere model (cached per robot), the
obstacles read back from the scene mapping (by the same reader as ``world.scene_file``) and the checker.
:meth:`MotionProblem.write` writes the scene file and a ``world.kind: spatial`` parameter file of the
motion-only query (``world.robot.goal``, interface.md section 1b) that ``clew_plan`` and the node read.
"""

from __future__ import annotations

import functools
import math
import re
import zlib
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import yaml
from numpy.typing import NDArray

from benchmarks.spatial_checker import CONFIG, ROBOTS
from clew_ros.spatial.checker import SpatialChecker
from clew_ros.spatial.inverse import IKSettings, InverseKinematics
from clew_ros.spatial.random_robot import BASE_LINK, TIP_LINK, random_robot_urdf
from clew_ros.spatial.robot import RobotModel, robot_from_parameters
from clew_ros.spatial.scene import Obstacle, scene_obstacles
from clew_ros.spatial.spheres import SphereModel, sphere_model
from clew_ros.spatial.transforms import matrix_pose, pose_matrix, rpy_matrix
from clew_ros.spatial.validate import validation_samples

__all__ = [
    "FAMILIES",
    "MotionProblem",
    "ProblemContext",
    "SceneSettings",
    "context",
    "generate",
    "problems",
    "robot_and_spheres",
    "robot_tree",
]

Matrix = NDArray[np.float64]
Range = tuple[float, float]


@dataclass(frozen=True)
class SceneSettings:
    """The ranges every scene is drawn from (m, rad) and how hard the generator tries."""

    #: Bearing of the furniture about the base's z axis (rad): in front of the robot or to either side.
    bearing_rad: Range = (-1.6, 1.6)
    #: Table: distance from the base's axis to the table's near edge (m), the table's depth and width (m),
    #: its top's height relative to the base (m: a work table at or a little above the mount), the clutter's
    #: count and the clutter's footprint and height (m; tall enough to be in the way of a straight move).
    table_distance_m: Range = (0.2, 0.35)
    table_depth_m: Range = (0.5, 0.8)
    table_width_m: Range = (0.8, 1.4)
    table_height_m: Range = (-0.05, 0.15)
    table_clutter: tuple[int, int] = (3, 8)
    clutter_size_m: Range = (0.04, 0.12)
    clutter_height_m: Range = (0.08, 0.3)
    #: Height of a top-down tcp target above the table (m): clear of the table for the fingers and the model's
    #: 2-5 cm over-approximation, low enough to be among the clutter.
    table_target_height_m: Range = (0.08, 0.2)
    #: Least distance between the start's and the goal's tcp targets on the table (m).
    table_target_gap_m: float = 0.3
    #: Shelf: distance to its open front (m), depth, width, the lowest board's height relative to the base,
    #: the cells' heights (m: room for a hand turned any way about its approach) and their count.
    shelf_distance_m: Range = (0.45, 0.7)
    shelf_depth_m: Range = (0.3, 0.45)
    shelf_width_m: Range = (0.6, 1.0)
    shelf_bottom_m: Range = (-0.1, 0.3)
    shelf_cell_m: Range = (0.26, 0.36)
    shelf_cells: tuple[int, int] = (2, 3)
    #: Boards' and panels' thickness (m).
    board_m: float = 0.02
    #: Cage: distance to its open front (m), depth, width, height, its floor's height relative to the base
    #: (m), the bars' radius and spacing (m) on its back and sides.
    cage_distance_m: Range = (0.4, 0.6)
    cage_depth_m: Range = (0.25, 0.4)
    cage_width_m: Range = (0.35, 0.55)
    cage_height_m: Range = (0.3, 0.42)
    cage_floor_m: Range = (0.0, 0.3)
    bar_radius_m: Range = (0.008, 0.015)
    bar_spacing_m: Range = (0.06, 0.1)
    #: Height of the start's top-down tcp target above the cage's roof (m).
    above_cage_m: Range = (0.12, 0.3)
    #: Bookshelf: distance to its front (m), depth, width, the lowest board's height relative to the base,
    #: the levels' heights (m) and count, the books per level and their thickness, depth and height (m).
    bookshelf_distance_m: Range = (0.45, 0.65)
    bookshelf_depth_m: Range = (0.25, 0.35)
    bookshelf_width_m: Range = (0.8, 1.2)
    bookshelf_bottom_m: Range = (-0.3, 0.0)
    bookshelf_level_m: Range = (0.26, 0.34)
    bookshelf_levels: tuple[int, int] = (3, 4)
    books: tuple[int, int] = (2, 6)
    book_thickness_m: Range = (0.02, 0.06)
    book_depth_m: Range = (0.15, 0.25)
    book_height_m: Range = (0.15, 0.24)
    #: How deep a horizontal tcp target lies inside a cell, as a fraction of the cell's depth (past the front).
    cell_depth_fraction: Range = (0.1, 0.5)
    #: Clearance (m) a target keeps from a cell's boards and sides (its centre; the IK's checker judges the hand).
    cell_margin_m: float = 0.06
    #: The tcp inverse kinematics (collision-free solutions only); 32 seeds find most reachable targets.
    ik: IKSettings = field(default_factory=IKSettings)
    #: Targets drawn per region before the scene is drawn again; scenes drawn before giving up.
    target_tries: int = 12
    scene_tries: int = 200
    #: The straight joint-space move from start to goal must collide (checked every 0.002 rad).
    nontrivial: bool = True
    #: Least joint-space distance (rad, L2) between start and goal.
    min_distance_rad: float = 0.5


@dataclass(frozen=True, eq=False)
class MotionProblem:
    """A motion-only query: ``scene`` (a ``moveit_msgs/PlanningScene`` as a YAML-ready mapping, frame
    ``world`` = the robot's ``base_link``), ``start`` and ``goal`` (the planned joints, chain order) and the tcp
    targets (4x4 in ``world``) they were solved for."""

    name: str
    family: str
    robot: str
    seed: int
    scene: dict[str, Any]
    start: Matrix
    goal: Matrix
    start_tcp: Matrix
    goal_tcp: Matrix

    def scene_yaml(self) -> str:
        """The planning scene as YAML text (what MoveIt and MotionBenchMaker write)."""
        return str(yaml.safe_dump(self.scene, sort_keys=False, default_flow_style=None))

    def world_parameters(self, scene_file: str | None = None) -> dict[str, Any]:
        """The ``world.kind: spatial`` parameter tree of this query: the scene read from ``scene_file``, or
        (``None``) its obstacles inline as ``world.obstacle_names`` / ``world.obstacles`` (a planner called
        in-process needs no file)."""
        robot = robot_tree(self.robot)
        world: dict[str, Any] = {
            "kind": "spatial",
            "name": self.name,
            "robot": {**robot, "initial": _rounded(self.start), "goal": _rounded(self.goal)},
        }
        if scene_file is not None:
            world["scene_file"] = scene_file
        else:
            obstacles = scene_obstacles(self.scene, {"world": np.eye(4)}, f"{self.name}.scene")
            world["obstacle_names"] = [o.name for o in obstacles]
            world["obstacles"] = {
                o.name: {"shape": o.shape, "size": list(o.size), "pose": matrix_pose(o.pose)} for o in obstacles
            }
        return {"world": world}

    def write(self, folder: Path) -> Path:
        """``<name>.scene.yaml`` and ``<name>.yaml`` (the parameter file, node ``clew_planner``) in ``folder``;
        the parameter file's path. Refuses to overwrite."""
        folder.mkdir(parents=True, exist_ok=True)
        scene_path, world_path = folder / f"{self.name}.scene.yaml", folder / f"{self.name}.yaml"
        for path in (scene_path, world_path):
            if path.exists():
                raise FileExistsError(f"{path} exists already, not overwriting.")
        scene_path.write_text(self.scene_yaml(), encoding="utf-8")
        parameters = {"clew_planner": {"ros__parameters": self.world_parameters(scene_path.name)}}
        world_path.write_text(yaml.safe_dump(parameters, sort_keys=False, default_flow_style=None), encoding="utf-8")
        return world_path


def _rounded(q: Matrix) -> list[float]:
    return [float(v) for v in q]


@dataclass(frozen=True, eq=False)
class ProblemContext:
    """What planning a problem needs: the robot, its sphere model, the scene's obstacles and the checker."""

    robot: RobotModel
    spheres: SphereModel
    obstacles: tuple[Obstacle, ...]
    checker: SpatialChecker


def robot_tree(name: str) -> dict[str, Any]:
    """The ``world.robot`` parameters of a robot by name: a shipped one (``spatial_checker.ROBOTS``, its paths
    absolute), or ``random-K``: the random arm drawn from seed K (:func:`clew_ros.spatial.random_robot`), its
    URDF inline. ``ValueError`` for another name."""
    if name in ROBOTS:
        tree = ROBOTS[name]
        return {key: str((CONFIG / tree[key]).resolve()) if key in ("urdf", "srdf") else tree[key] for key in tree}
    found = re.fullmatch(r"random-(\d+)", name)
    if found is None:
        raise ValueError(f"robot: expected one of {', '.join(ROBOTS)} or random-K (K a seed), got {name!r}")
    text = random_robot_urdf(np.random.default_rng(int(found[1])), name=name)
    return {"description": text, "base_link": BASE_LINK, "tip_link": TIP_LINK}


@functools.cache
def robot_and_spheres(name: str) -> tuple[RobotModel, SphereModel]:
    """A robot by name (:func:`robot_tree`) and its sphere model, built once per process."""
    robot = robot_from_parameters(robot_tree(name), CONFIG)
    return robot, sphere_model(robot)


def context(problem: MotionProblem) -> ProblemContext:
    """The problem loaded: its scene's obstacles read back from the mapping as ``world.scene_file`` is read."""
    robot, spheres = robot_and_spheres(problem.robot)
    obstacles = tuple(scene_obstacles(problem.scene, {"world": np.eye(4)}, f"{problem.name}.scene"))
    return ProblemContext(robot, spheres, obstacles, SpatialChecker(robot, spheres, obstacles))


# ------------------------------------------------------------------------------------------ the scenes


@dataclass
class _Scene:
    """A scene being drawn: collision objects (id -> boxes / cylinders in ``world``) and target regions."""

    objects: dict[str, list[tuple[str, tuple[float, ...], Matrix]]] = field(default_factory=dict)
    #: name -> a sampler of tcp targets (4x4 in ``world``)
    regions: dict[str, Callable[[np.random.Generator], Matrix]] = field(default_factory=dict)

    def add(self, object_id: str, shape: str, size: Sequence[float], pose: Matrix) -> None:
        self.objects.setdefault(object_id, []).append((shape, tuple(float(v) for v in size), pose))

    def box(self, object_id: str, frame: Matrix, center: Sequence[float], size: Sequence[float]) -> None:
        """A box of full extents ``size`` centred at ``center`` in ``frame``, aligned with it."""
        self.add(object_id, "box", size, frame @ _translation(center))

    def planning_scene(self, name: str, robot: str) -> dict[str, Any]:
        objects = []
        for object_id, parts in self.objects.items():
            objects.append(
                {
                    "header": {"frame_id": "world"},
                    "id": object_id,
                    "primitives": [
                        {"type": {"box": 1, "sphere": 2, "cylinder": 3}[shape], "dimensions": _numbers(size)}
                        for shape, size, _ in parts
                    ],
                    "primitive_poses": [_pose_message(pose) for _, _, pose in parts],
                    "operation": 0,  # moveit_msgs/CollisionObject ADD
                }
            )
        return {
            "name": name,
            "robot_model_name": robot,
            "world": {"collision_objects": objects},
            "is_diff": True,
        }


def _numbers(values: Sequence[float] | Matrix) -> list[float]:
    return [round(float(v), 6) for v in values]


def _pose_message(pose: Matrix) -> dict[str, dict[str, float]]:
    """A ``geometry_msgs/Pose`` as MoveIt's YAML writes it (mappings x, y, z and x, y, z, w)."""
    x, y, z, w = _quaternion(pose[:3, :3])
    px, py, pz = _numbers(pose[:3, 3])
    return {
        "position": {"x": px, "y": py, "z": pz},
        "orientation": {"x": round(x, 9), "y": round(y, 9), "z": round(z, 9), "w": round(w, 9)},
    }


def _quaternion(r: Matrix) -> tuple[float, float, float, float]:
    """The unit quaternion (x, y, z, w) of a rotation matrix (Shepperd's method), w >= 0."""
    trace = float(np.trace(r))
    if trace > 0:
        s = 2.0 * math.sqrt(trace + 1.0)
        q = ((r[2, 1] - r[1, 2]) / s, (r[0, 2] - r[2, 0]) / s, (r[1, 0] - r[0, 1]) / s, s / 4)
    elif r[0, 0] > r[1, 1] and r[0, 0] > r[2, 2]:
        s = 2.0 * math.sqrt(1.0 + r[0, 0] - r[1, 1] - r[2, 2])
        q = (s / 4, (r[0, 1] + r[1, 0]) / s, (r[0, 2] + r[2, 0]) / s, (r[2, 1] - r[1, 2]) / s)
    elif r[1, 1] > r[2, 2]:
        s = 2.0 * math.sqrt(1.0 + r[1, 1] - r[0, 0] - r[2, 2])
        q = ((r[0, 1] + r[1, 0]) / s, s / 4, (r[1, 2] + r[2, 1]) / s, (r[0, 2] - r[2, 0]) / s)
    else:
        s = 2.0 * math.sqrt(1.0 + r[2, 2] - r[0, 0] - r[1, 1])
        q = ((r[0, 2] + r[2, 0]) / s, (r[1, 2] + r[2, 1]) / s, s / 4, (r[1, 0] - r[0, 1]) / s)
    sign = -1.0 if q[3] < 0 else 1.0
    return (sign * float(q[0]), sign * float(q[1]), sign * float(q[2]), sign * float(q[3]))


def _translation(xyz: Sequence[float]) -> Matrix:
    out = np.eye(4)
    out[:3, 3] = xyz
    return out


def _uniform(rng: np.random.Generator, bounds: Range) -> float:
    return float(rng.uniform(bounds[0], bounds[1]))


def _count(rng: np.random.Generator, bounds: tuple[int, int]) -> int:
    return int(rng.integers(bounds[0], bounds[1] + 1))


def _furniture_frame(rng: np.random.Generator, distance: float, settings: SceneSettings) -> Matrix:
    """A frame at ``distance`` from the base's axis at a random bearing: x away from the robot, z up."""
    bearing = _uniform(rng, settings.bearing_rad)
    out: Matrix = pose_matrix([distance * math.cos(bearing), distance * math.sin(bearing), 0.0, 0.0, 0.0, bearing])
    return out


def _horizontal_target(frame: Matrix, point: Sequence[float], roll: float) -> Matrix:
    """A tcp pose at ``point`` (in ``frame``) approaching along ``frame``'s x (the tcp's z axis), turned by
    ``roll`` about it."""
    approach = rpy_matrix(0.0, math.pi / 2, 0.0) @ rpy_matrix(0.0, 0.0, roll)  # tcp z along the frame's x
    out = np.eye(4)
    out[:3, :3] = approach
    out[:3, 3] = point
    result: Matrix = frame @ out
    return result


def _top_down_target(point: Sequence[float], yaw: float) -> Matrix:
    """A tcp pose at ``point`` (in ``world``) pointing down (the tcp's z along -z), turned by ``yaw``."""
    out = np.eye(4)
    out[:3, :3] = rpy_matrix(math.pi, 0.0, 0.0) @ rpy_matrix(0.0, 0.0, yaw)
    out[:3, 3] = point
    return out


def _cell_sampler(
    frame: Matrix, x: Range, y: Range, z: Range, settings: SceneSettings
) -> Callable[[np.random.Generator], Matrix]:
    """Horizontal targets in a cell of ``frame``: ``x`` its depth (front, back), ``y`` and ``z`` its extents."""
    margin = settings.cell_margin_m

    def sample(rng: np.random.Generator) -> Matrix:
        depth = x[0] + _uniform(rng, settings.cell_depth_fraction) * (x[1] - x[0])
        lateral = _uniform(rng, (y[0] + margin, y[1] - margin))
        height = _uniform(rng, (z[0] + margin, z[1] - margin)) if z[1] - z[0] > 2 * margin else (z[0] + z[1]) / 2
        return _horizontal_target(frame, [depth, lateral, height], _uniform(rng, (-math.pi, math.pi)))

    return sample


def _table(rng: np.random.Generator, settings: SceneSettings) -> _Scene:
    scene = _Scene()
    near = _uniform(rng, settings.table_distance_m)
    depth, width = _uniform(rng, settings.table_depth_m), _uniform(rng, settings.table_width_m)
    top = _uniform(rng, settings.table_height_m)
    frame = _furniture_frame(rng, near, settings)
    thickness = 0.04
    scene.box("table", frame, [depth / 2, 0.0, top - thickness / 2], [depth, width, thickness])
    for sx in (0.05, depth - 0.05):
        for sy in (-width / 2 + 0.05, width / 2 - 0.05):
            scene.box("table", frame, [sx, sy, top - thickness - 0.35], [0.05, 0.05, 0.7])
    for k in range(_count(rng, settings.table_clutter)):
        size = _uniform(rng, settings.clutter_size_m)
        height = _uniform(rng, settings.clutter_height_m)
        where = [_uniform(rng, (0.08, depth - 0.08)), _uniform(rng, (-width / 2 + 0.08, width / 2 - 0.08))]
        if rng.uniform() < 0.5:
            pose = frame @ _translation([*where, top + height / 2]) @ _yaw(_uniform(rng, (-math.pi, math.pi)))
            scene.add(f"clutter_{k}", "box", [size, _uniform(rng, settings.clutter_size_m), height], pose)
        else:
            scene.add(f"clutter_{k}", "cylinder", [height, size / 2], frame @ _translation([*where, top + height / 2]))

    def on_table(rng: np.random.Generator) -> Matrix:
        point = frame @ np.array(
            [
                _uniform(rng, (0.08, depth - 0.08)),
                _uniform(rng, (-width / 2 + 0.08, width / 2 - 0.08)),
                top + _uniform(rng, settings.table_target_height_m),
                1.0,
            ]
        )
        return _top_down_target(point[:3], _uniform(rng, (-math.pi, math.pi)))

    scene.regions["table"] = on_table
    return scene


def _yaw(angle: float) -> Matrix:
    """A 4x4 rotation about z by ``angle`` (rad)."""
    out: Matrix = pose_matrix([0.0, 0.0, 0.0, 0.0, 0.0, angle])
    return out


def _cabinet(
    scene: _Scene,
    object_id: str,
    frame: Matrix,
    *,
    depth: float,
    width: float,
    boards: Sequence[float],
    thickness: float,
) -> None:
    """An open-fronted cabinet in ``frame`` (front at x = 0): boards (top faces at ``boards``, bottom to top),
    two sides and a back from the lowest board's bottom to the highest board's top."""
    low, high = boards[0] - thickness, boards[-1]
    for level in boards:
        scene.box(object_id, frame, [depth / 2, 0.0, level - thickness / 2], [depth, width, thickness])
    for side in (-1, 1):
        scene.box(
            object_id,
            frame,
            [depth / 2, side * (width / 2 + thickness / 2), (low + high) / 2],
            [depth, thickness, high - low],
        )
    scene.box(
        object_id, frame, [depth + thickness / 2, 0.0, (low + high) / 2], [thickness, width + 2 * thickness, high - low]
    )


def _shelf(rng: np.random.Generator, settings: SceneSettings) -> _Scene:
    scene = _Scene()
    distance, depth = _uniform(rng, settings.shelf_distance_m), _uniform(rng, settings.shelf_depth_m)
    width = _uniform(rng, settings.shelf_width_m)
    frame = _furniture_frame(rng, distance, settings)
    boards = [_uniform(rng, settings.shelf_bottom_m)]
    for _ in range(_count(rng, settings.shelf_cells)):
        boards.append(boards[-1] + _uniform(rng, settings.shelf_cell_m))
    t = settings.board_m
    _cabinet(scene, "shelf", frame, depth=depth, width=width, boards=boards, thickness=t)
    for k in range(len(boards) - 1):
        z = (boards[k], boards[k + 1] - t)
        scene.regions[f"cell_{k}"] = _cell_sampler(frame, (0.0, depth), (-width / 2, width / 2), z, settings)
    return scene


def _cage(rng: np.random.Generator, settings: SceneSettings) -> _Scene:
    scene = _Scene()
    distance, depth = _uniform(rng, settings.cage_distance_m), _uniform(rng, settings.cage_depth_m)
    width, height = _uniform(rng, settings.cage_width_m), _uniform(rng, settings.cage_height_m)
    floor = _uniform(rng, settings.cage_floor_m)
    frame = _furniture_frame(rng, distance, settings)
    t = settings.board_m
    scene.box("cage", frame, [depth / 2, 0.0, floor - t / 2], [depth, width, t])
    scene.box("cage", frame, [depth / 2, 0.0, floor + height + t / 2], [depth, width, t])
    radius, spacing = _uniform(rng, settings.bar_radius_m), _uniform(rng, settings.bar_spacing_m)
    middle = frame @ _translation([0.0, 0.0, floor + height / 2])
    for side in (-1, 1):  # the sides' bars, front to back
        for x in np.arange(0.0, depth + 1e-9, depth / max(1, round(depth / spacing))):
            scene.add("cage", "cylinder", [height, radius], middle @ _translation([x, side * width / 2, 0.0]))
    for y in np.arange(-width / 2, width / 2 + 1e-9, width / max(1, round(width / spacing)))[1:-1]:  # the back's
        scene.add("cage", "cylinder", [height, radius], middle @ _translation([depth, y, 0.0]))
    inner = (-width / 2 + radius, width / 2 - radius)
    scene.regions["inside"] = _cell_sampler(frame, (0.0, depth), inner, (floor, floor + height), settings)

    def above(rng: np.random.Generator) -> Matrix:
        point = frame @ np.array(
            [
                _uniform(rng, (0.0, depth)),
                _uniform(rng, (-width / 2, width / 2)),
                floor + height + t + _uniform(rng, settings.above_cage_m),
                1.0,
            ]
        )
        return _top_down_target(point[:3], _uniform(rng, (-math.pi, math.pi)))

    scene.regions["above"] = above
    return scene


def _bookshelf(rng: np.random.Generator, settings: SceneSettings) -> _Scene:
    scene = _Scene()
    distance, depth = _uniform(rng, settings.bookshelf_distance_m), _uniform(rng, settings.bookshelf_depth_m)
    width = _uniform(rng, settings.bookshelf_width_m)
    frame = _furniture_frame(rng, distance, settings)
    boards = [_uniform(rng, settings.bookshelf_bottom_m)]
    for _ in range(_count(rng, settings.bookshelf_levels)):
        boards.append(boards[-1] + _uniform(rng, settings.bookshelf_level_m))
    t = settings.board_m
    _cabinet(scene, "bookshelf", frame, depth=depth, width=width, boards=boards, thickness=t)
    book = 0
    for k in range(len(boards) - 1):
        room = boards[k + 1] - t - boards[k]
        count = _count(rng, settings.books)
        thick = [_uniform(rng, settings.book_thickness_m) for _ in range(count)]
        cuts = np.sort(rng.uniform(0.0, max(0.0, width - sum(thick)), count))  # the free room left of each book
        for i in range(count):  # side by side, none overlapping, in random gaps
            deep = _uniform(rng, settings.book_depth_m)
            tall = min(_uniform(rng, settings.book_height_m), room - 0.01)
            y = -width / 2 + float(cuts[i]) + sum(thick[:i]) + thick[i] / 2
            scene.box(f"book_{book}", frame, [depth - deep / 2, y, boards[k] + tall / 2], [deep, thick[i], tall])
            book += 1
        z = (boards[k], boards[k + 1] - t)
        scene.regions[f"level_{k}"] = _cell_sampler(frame, (0.0, depth), (-width / 2, width / 2), z, settings)
    return scene


#: Each family's scene drawer, in the order the benchmark lists them.
FAMILIES: dict[str, Callable[[np.random.Generator, SceneSettings], _Scene]] = {
    "table": _table,
    "shelf": _shelf,
    "cage": _cage,
    "bookshelf": _bookshelf,
}


def _mount(scene: _Scene, spheres: SphereModel) -> None:
    """The plate the robot stands on: 5 mm under the lowest sphere of its base (links no joint moves)."""
    static = spheres.frames == 0
    top = float(np.min(spheres.centers[static, 2] - spheres.radii[static])) - 0.005 if static.any() else -0.005
    scene.add("mount", "box", [0.4, 0.4, 0.04], _translation([0.0, 0.0, top - 0.02]))


# ----------------------------------------------------------------------------------------- the problems


def _straight_collides(checker: SpatialChecker, a: Matrix, b: Matrix) -> bool:
    steps = np.full(len(a), 0.002)
    return not bool(checker.valid(validation_samples(a, b, steps)).all())


def generate(family: str, robot: str, seed: int, settings: SceneSettings | None = None) -> MotionProblem:
    """One problem of ``family`` (:data:`FAMILIES`) for ``robot`` (``panda`` or ``ur5``), drawn from ``seed``.

    Raises ``ValueError`` for an unknown family or robot, and ``RuntimeError`` when
    ``SceneSettings.scene_tries`` scenes give no problem (ranges the robot cannot reach)."""
    if family not in FAMILIES:
        raise ValueError(f"family: expected one of {', '.join(FAMILIES)}, got {family!r}")
    robot_tree(robot)  # a known name, else ValueError
    settings = settings or SceneSettings()
    model, spheres = robot_and_spheres(robot)
    solver = InverseKinematics(model, settings.ik)
    rng = np.random.default_rng([seed, zlib.crc32(family.encode()), zlib.crc32(robot.encode())])
    name = f"{family}_{robot}_{seed}"
    for _ in range(settings.scene_tries):
        scene = FAMILIES[family](rng, settings)
        _mount(scene, spheres)
        message = scene.planning_scene(name, robot)
        obstacles = scene_obstacles(message, {"world": np.eye(4)}, name)
        checker = SpatialChecker(model, spheres, obstacles, exact=False)  # drawn with room to spare
        if checker.static_collision:
            continue
        found = _query(scene, checker, solver, rng, settings)
        if found is None:
            continue
        (start, start_tcp), (goal, goal_tcp) = found
        return MotionProblem(name, family, robot, seed, message, start, goal, start_tcp, goal_tcp)
    raise RuntimeError(f"{name}: no problem in {settings.scene_tries} scenes (the robot reaches none of the targets)")


def _turned_towards(solutions: Matrix, near: Matrix, robot: RobotModel) -> Matrix:
    """Each revolute joint of ``solutions`` (k, n) moved by whole turns as near ``near`` as its limits allow:
    the same tcp pose, the same collisions (a turn brings every link back), and no needless turn to plan
    (a UR5's joints span +-2 pi: a solution found a turn away from the start is the same posture)."""
    turn = 2.0 * math.pi
    turns = np.round((near - solutions) / turn)
    turns[:, robot.prismatic] = 0.0
    moved = solutions + turns * turn
    # a whole turn that would leave the limits is taken back one turn at a time (at most one is ever needed)
    moved = np.where(moved > robot.upper, moved - turn, moved)
    moved = np.where(moved < robot.lower, moved + turn, moved)
    out: Matrix = np.where((moved >= robot.lower) & (moved <= robot.upper), moved, solutions)
    return out


def _solve(
    sampler: Callable[[np.random.Generator], Matrix],
    checker: SpatialChecker,
    solver: InverseKinematics,
    rng: np.random.Generator,
    tries: int,
    *,
    near: Matrix | None = None,
    away_from: Matrix | None = None,
    gap_m: float = 0.0,
) -> tuple[Matrix, Matrix] | None:
    """A collision-free configuration at a target of ``sampler`` (the solution nearest ``near`` when given,
    else the first), the target at least ``gap_m`` from ``away_from``'s position; ``None`` after ``tries``."""
    for _ in range(tries):
        target = sampler(rng)
        if away_from is not None and float(np.linalg.norm(target[:3, 3] - away_from[:3, 3])) < gap_m:
            continue
        solutions = solver.solve(target, rng, checker=checker)
        if len(solutions) == 0:
            continue
        if near is None:
            return solutions[0], target
        solutions = _turned_towards(solutions, near, checker.robot)
        best = int(np.argmin(np.linalg.norm(solutions - near, axis=1)))
        return solutions[best], target
    return None


def _query(
    scene: _Scene,
    checker: SpatialChecker,
    solver: InverseKinematics,
    rng: np.random.Generator,
    settings: SceneSettings,
) -> tuple[tuple[Matrix, Matrix], tuple[Matrix, Matrix]] | None:
    """Start and goal in two regions drawn from the scene's (or twice in its only one, targets apart)."""
    names = list(scene.regions)
    if len(names) > 1:
        first, second = (names[int(i)] for i in rng.permutation(len(names))[:2])
    else:
        first = second = names[0]
    gap = settings.table_target_gap_m if first == second else 0.0
    middle = (checker.robot.lower + checker.robot.upper) / 2  # the start: the solution nearest mid-range
    start = _solve(scene.regions[first], checker, solver, rng, settings.target_tries, near=middle)
    if start is None:
        return None
    for _ in range(settings.target_tries):
        goal = _solve(scene.regions[second], checker, solver, rng, 1, near=start[0], away_from=start[1], gap_m=gap)
        if goal is None:
            continue
        if float(np.linalg.norm(goal[0] - start[0])) < settings.min_distance_rad:
            continue
        if settings.nontrivial and not _straight_collides(checker, start[0], goal[0]):
            continue
        return start, goal
    return None


def problems(
    families: Sequence[str], robots: Sequence[str], count: int, seed: int = 0, settings: SceneSettings | None = None
) -> list[MotionProblem]:
    """``count`` problems per family and robot (seeds ``seed``, ``seed + 1``, ...), family by family."""
    return [
        generate(family, robot, seed + k, settings) for family in families for robot in robots for k in range(count)
    ]
