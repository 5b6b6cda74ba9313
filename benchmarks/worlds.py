"""The benchmark worlds: every ``config/*.yaml`` plus two scaling series (not ``clew_world``'s generated families).

* ``joints_N`` (N = 2, 3, 5, 7, 10): figure1's task (its bounds, blocks, bar,
  start and goal placements, read from ``config/figure1.yaml``) with the
  1.7 m arm split into N links of decreasing length (``linspace(1.0, 0.7, N)``
  scaled to 1.7 m; N = 2 gives figure1's own 1.0 + 0.7). Start ``q = (0,
  pi/2/(N-1), ..., pi/2/(N-1))``: the arm curls up by a quarter turn, as
  figure1's ``(0, pi/2)`` does. Limits: joint 1 +-3.14159, the others +-2.8.
* ``obstacles_M`` (M = 2, 8, 32): ``joints_3`` with M - 2 small square boxes
  (8 cm) added to figure1's two blocks. Boxes come from one fixed random
  sequence, each kept only when it is 15 cm clear of the start arm, 30 cm
  clear of the object at its start and goal placements, 10 cm clear of the
  other obstacles and of the base's 0.45 m disc; so the boxes of a smaller
  world are the first boxes of a larger one. Start and goal validity is
  checked by :func:`clew_ros.planar.collision.check_start_and_goal`; that a world
  is solvable is not proven, the success rate shows it.

Worlds are built in memory; :func:`write_world` writes one as a ROS 2
parameter file (never into ``config/``).
"""

from __future__ import annotations

import copy
import fnmatch
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import shapely
import yaml

from clew_ros.planar.collision import check_start_and_goal
from clew_ros.planar.world import read_parameter_file, world_from_parameters

__all__ = [
    "CONFIG_DIR",
    "JOINT_COUNTS",
    "OBSTACLE_COUNTS",
    "BenchWorld",
    "all_worlds",
    "config_worlds",
    "generated_worlds",
    "joints_world",
    "obstacles_world",
    "select",
    "write_world",
]

CONFIG_DIR = Path(__file__).absolute().parents[1] / "config"  # the checkout this file is in
JOINT_COUNTS = (2, 3, 5, 7, 10)
OBSTACLE_COUNTS = (2, 8, 32)
#: Time limit (s) of generated worlds: the 7-joint criterion is 30 s.
GENERATED_TIME_LIMIT_S = 30.0
#: Time limit (s) of a config world without planner.time_limit (the planner's default).
DEFAULT_TIME_LIMIT_S = 30.0
REACH_M = 1.7
BOX_SIZE_M = 0.08
_BOX_SEED = 20240607


@dataclass(frozen=True)
class BenchWorld:
    """One benchmark world: its parameter tree and what the tables group it by."""

    name: str
    series: str  # "config", "joints" or "obstacles" (the scaling series, or a file of config/)
    parameters: dict  # ros__parameters tree: world (+ planner)
    time_limit_s: float  # default per-run limit
    joints: int
    obstacles: int


def _bench_world(name: str, series: str, parameters: dict, time_limit_s: float) -> BenchWorld:
    world = check_start_and_goal(world_from_parameters(parameters))  # raises WorldError: start or goal invalid
    return BenchWorld(name, series, parameters, time_limit_s, world.robot.dof, len(world.obstacles))


def config_worlds(directory: Path = CONFIG_DIR) -> list[BenchWorld]:
    """Every world of ``directory/*.yaml``, with its own ``planner.time_limit``."""
    worlds = []
    for path in sorted(directory.glob("*.yaml")):
        parameters = read_parameter_file(path)
        limit = float((parameters.get("planner") or {}).get("time_limit", DEFAULT_TIME_LIMIT_S))
        worlds.append(_bench_world(parameters["world"]["name"], "config", parameters, limit))
    return worlds


def link_lengths(joints: int) -> list[float]:
    """Decreasing link lengths summing to 1.7 m (``[1.0, 0.7]`` for 2 joints)."""
    weights = np.linspace(1.0, 0.7, joints)
    return [round(float(v), 6) for v in REACH_M * weights / weights.sum()]


def _figure1_tree() -> dict:
    return copy.deepcopy(read_parameter_file(CONFIG_DIR / "figure1.yaml")["world"])


def _joints_parameters(joints: int) -> dict:
    tree = _figure1_tree()
    bend = round(math.pi / 2 / (joints - 1), 6)
    lengths = link_lengths(joints)
    lengths[-1] = round(REACH_M - sum(lengths[:-1]), 6)
    tree["name"] = f"joints_{joints}"
    tree["robot"].update(
        link_lengths=lengths,
        joint_lower=[-3.14159] + [-2.8] * (joints - 1),
        joint_upper=[3.14159] + [2.8] * (joints - 1),
        initial=[0.0] + [bend] * (joints - 1),
    )
    return {"world": tree, "planner": {"time_limit": GENERATED_TIME_LIMIT_S}}


def joints_world(joints: int) -> BenchWorld:
    """figure1's task with a ``joints``-link arm of the same 1.7 m reach."""
    return _bench_world(f"joints_{joints}", "joints", _joints_parameters(joints), GENERATED_TIME_LIMIT_S)


def _box(x: float, y: float) -> list[float]:
    h = BOX_SIZE_M / 2
    return [round(v, 4) for v in (x - h, y - h, x + h, y - h, x + h, y + h, x - h, y + h)]


def _scattered_boxes(parameters: dict, count: int) -> list[list[float]]:
    """``count`` boxes, the first ones of one fixed sequence (see the module docstring)."""
    world = check_start_and_goal(world_from_parameters(parameters))
    from clew_ros.planar.kinematics import joint_positions, transform_points

    arm = shapely.LineString(joint_positions(world.robot, world.robot.initial[None])[0])
    placements = [
        shapely.Polygon(transform_points(pose, world.object.polygon))
        for pose in (world.object.initial, world.object.goal)
    ]
    taken = [shapely.Polygon(o.vertices) for o in world.obstacles]
    base = shapely.Point(world.robot.base).buffer(0.45)
    xmin, ymin, xmax, ymax = world.bounds
    rng = np.random.default_rng(_BOX_SEED)
    boxes: list[list[float]] = []
    for _ in range(100_000):
        if len(boxes) == count:
            return boxes
        x, y = rng.uniform([xmin + 0.15, ymin + 0.15], [xmax - 0.15, ymax - 0.15])
        flat = _box(float(x), float(y))
        box = shapely.Polygon(np.reshape(flat, (-1, 2)))
        if (
            box.distance(arm) < 0.15
            or box.distance(base) < 0.1
            or min(box.distance(p) for p in placements) < 0.3
            or min(box.distance(t) for t in taken) < 0.1
        ):
            continue
        boxes.append(flat)
        taken.append(box)
    raise RuntimeError(f"could not place {count} boxes")


def obstacles_world(count: int) -> BenchWorld:
    """``joints_3`` with ``count`` obstacles in all (figure1's two blocks and ``count - 2`` boxes)."""
    parameters = _joints_parameters(3)
    tree = parameters["world"]
    tree["name"] = f"obstacles_{count}"
    for index, flat in enumerate(_scattered_boxes(parameters, count - len(tree["obstacle_names"]))):
        name = f"box_{index:02d}"
        tree["obstacle_names"].append(name)
        tree["obstacles"][name] = flat
    return _bench_world(tree["name"], "obstacles", parameters, GENERATED_TIME_LIMIT_S)


def generated_worlds() -> list[BenchWorld]:
    return [joints_world(n) for n in JOINT_COUNTS] + [obstacles_world(m) for m in OBSTACLE_COUNTS]


def all_worlds() -> list[BenchWorld]:
    return config_worlds() + generated_worlds()


def select(worlds: list[BenchWorld], pattern: str | None) -> list[BenchWorld]:
    """Worlds whose name matches ``pattern``: a glob (``joints_*``) or a comma-separated list of them."""
    if not pattern:
        return list(worlds)
    patterns = [p.strip() for p in pattern.split(",") if p.strip()]
    return [w for w in worlds if any(fnmatch.fnmatchcase(w.name, p) or p == w.name for p in patterns)]


def write_world(world: BenchWorld, directory: Path) -> Path:
    """Write ``world`` as ``directory/<name>.yaml`` (a ROS 2 parameter file) and return its path."""
    directory = Path(directory).resolve()
    if directory == CONFIG_DIR.resolve():
        raise ValueError("benchmark worlds are never written into config/")
    directory.mkdir(parents=True, exist_ok=True)
    path = directory / f"{world.name}.yaml"
    path.write_text(yaml.safe_dump({"clew_planner": {"ros__parameters": world.parameters}}, sort_keys=False))
    return path
