"""Spatial worlds where a regrasp is necessary, proved by construction, each with a two-transfer witness.

The object starts in one enclosure and must end in another that admits other grasps:

- a **bin** (a floor and four walls a few millimetres from the object, as high as the witness's lift lets
  them be) admits grasps from above only: the hand of a grasp from the side meets a wall;
- a **cubby** (a board, a ceiling 2-3 cm above the object, a back wall and two side walls, open towards
  the arm) admits grasps from its open side only: the hand of a grasp from above meets the ceiling;
- a **shelf** (a board and a lid 2-3 cm above the object, a back wall, open at the front and on both sides,
  running on 8-25 cm beyond the object) admits grasps from the side only, as a cubby does.

A free table on the way carries the regrasp: the witness takes the object out with the first grasp, sets it
down on the table, takes it again with the second and puts it in. The proof that no single transfer exists is
:func:`single_grasp_refutation`: every grasp's hand (the links that ride on the tcp's frame, on the exact
geometry, 2 mm deep) meets an obstacle at the start or at every goal pose within the goal's tolerances
(sampled); a world where one grasp escapes that is not kept.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from clew_ros.core.plan import Plan
from clew_ros.spatial.checker import Held, SpatialChecker
from clew_ros.spatial.handling import drag_problems
from clew_ros.spatial.inverse import InverseKinematics
from clew_ros.spatial.placements import MovableObject
from clew_ros.spatial.plan import make_plan, object_obstacle, validate_plan
from clew_ros.spatial.robot import RobotModel
from clew_ros.spatial.scene import Obstacle, make_obstacle
from clew_ros.spatial.space import straight_samples_clear
from clew_ros.spatial.tier import coal_module, coal_shape, link_shapes, object_touches
from clew_ros.spatial.transforms import pose_matrix, rpy_matrix
from clew_ros.spatial.validate import ValidationSettings, validate_transit
from clew_ros.spatial.world import SpatialWorld
from clew_ros.worlds.spatial_holds import Arm, Hold, Solver, find_hold, footprint, grasps_of, hold_from

__all__ = [
    "REGRASP_LAYOUTS",
    "RegraspLayout",
    "RejectedError",
    "cubby_around",
    "enclosure_clear",
    "hand_blocked",
    "regrasp_world",
    "single_grasp_refutation",
    "witness_holds",
    "witness_world",
]

Matrix = NDArray[np.float64]


class RejectedError(Exception):
    """This stream gave no acceptable regrasp world."""


@dataclass(frozen=True)
class RegraspLayout:
    """Where the object starts and ends (``bin``, ``cubby`` or ``shelf``) and the grasp kind each admits."""

    start: str
    goal: str

    @staticmethod
    def grasp_kind(enclosure: str) -> str:
        return {"bin": "top", "cubby": "side", "shelf": "side"}[enclosure]


REGRASP_LAYOUTS = {
    "bin_cubby": RegraspLayout("bin", "cubby"),
    "cubby_bin": RegraspLayout("cubby", "bin"),
    "shelf_bin": RegraspLayout("shelf", "bin"),
    "bin_shelf": RegraspLayout("bin", "shelf"),
}

#: A wall or lid this close (m) to the object, drawn per world.
GAP_RANGE_M = (0.004, 0.015)
#: A shelf's board and lid run on this far (m) beyond the object on either side (it has no side walls).
SHELF_SIDE_M = (0.08, 0.25)
#: The cubby's (and shelf's) ceiling this far above the object's top (m).
CEILING_RANGE_M = (0.02, 0.03)
#: A bin's walls are this thick (m): a wrist without fingers (the UR5's) still meets them from the side.
BIN_WALL_M = 0.04
#: In a cubby the object is lifted this much (m) before it slides out (its ceiling is 2-3 cm above it).
CUBBY_LIFT_M = 0.01
#: A bin is widened by these (m, all four gaps) until the witness's hand clears its walls.
WIDEN_M = (0.0, 0.003, 0.006, 0.01)
#: A witness's transfer or transit that is not free straight goes by way of its ends raised this much (m).
RAISE_M = 0.2
#: A path is first checked at every this many of the validator's samples (cheap refusals), then at all.
COARSE_EVERY = 16
#: The goal lies this far (rad, either way) round the arm's first joint from the start, the table half-way.
TURN_RAD = (1.2, 2.2)
#: Objects stand at most this tall (m) in these worlds: a bin's walls must reach above a side grasp's
#: fingers and stay below the object's lift.
MAX_HEIGHT_M = 0.11
#: The table lies these fractions of the way round from the start to the goal, tried in turn.
TABLE_FRACTIONS = (0.5, 0.3, 0.7)
#: A hand counts as blocked when it goes this deep (m) into an obstacle at every pose sampled.
BLOCK_DEPTH_M = 0.002


# ----------------------------------------------------------------------------------------- the proof


def _hand(robot: RobotModel) -> list[tuple[Any, Matrix]]:
    """The hand's coal shapes (links riding on the tcp's frame), each with its pose in the tcp's frame."""
    to_tcp = np.linalg.inv(robot.tcp)
    return [
        (shape, to_tcp @ local)
        for link, shapes in zip(robot.links, link_shapes(robot), strict=True)
        if link.frame == robot.tcp_frame
        for shape, local in shapes
    ]


def _shrunk(obstacle: Obstacle, depth: float) -> tuple[float, ...]:
    """The obstacle's size shrunk by ``depth`` on every side (what a shape ``depth`` deep into it meets)."""
    size = np.asarray(obstacle.size, dtype=np.float64)
    if obstacle.shape == "box":
        return tuple(np.maximum(size - 2 * depth, 1e-6))
    if obstacle.shape == "cylinder":
        return (max(size[0] - 2 * depth, 1e-6), max(size[1] - depth, 1e-6))
    return (max(size[0] - depth, 1e-6),)


def hand_blocked(robot: RobotModel, tcp: Matrix, obstacles: Sequence[Obstacle], depth: float = BLOCK_DEPTH_M) -> bool:
    """Whether the hand (every link riding on the tcp's frame) at tcp pose ``tcp`` goes ``depth`` deep into one
    of ``obstacles``, on the exact geometry. Such a grasp is held by no configuration of the arm."""
    coal = coal_module()
    request = coal.CollisionRequest()
    hand = _hand(robot)
    for obstacle in obstacles:
        other = coal_shape(coal, obstacle.shape, _shrunk(obstacle, depth))
        where = coal.Transform3s(
            np.ascontiguousarray(obstacle.pose[:3, :3]), np.ascontiguousarray(obstacle.pose[:3, 3])
        )
        for shape, local in hand:
            placed = tcp @ local
            result = coal.CollisionResult()
            if coal.collide(shape, coal.Transform3s(placed[:3, :3], placed[:3, 3]), other, where, request, result):
                return True
    return False


def goal_poses(world: SpatialWorld, yaw_steps: int = 24, grid: int = 3) -> list[Matrix]:
    """Object poses within the goal's tolerances where the object itself is free: the goal turned about z
    (``yaw_steps`` within ``goal_angle_tolerance``) and moved on a ``grid`` x ``grid`` of horizontal offsets
    within ``goal_tolerance``."""
    assert world.object is not None
    goal = pose_matrix(world.object.goal)
    tolerance = world.tolerances["goal_angle_tolerance"]
    reach = world.tolerances["goal_tolerance"] / math.sqrt(2)
    out = []
    for yaw in np.linspace(-tolerance, tolerance, yaw_steps, endpoint=tolerance < math.pi):
        for dx in np.linspace(-reach, reach, grid):
            for dy in np.linspace(-reach, reach, grid):
                pose = goal.copy()
                pose[:3, :3] = rpy_matrix(0.0, 0.0, float(yaw)) @ goal[:3, :3]
                pose[:2, 3] += (dx, dy)
                others = [o for o in world.obstacles if o.name != world.object.goal_on[0]]
                if not object_touches(world.object.shape, pose, others):
                    out.append(pose)
    return out


def single_grasp_refutation(world: SpatialWorld) -> list[str]:
    """Why no single transfer takes the object from its start to its goal: per grasp, where its hand is
    blocked (``grasp i: blocked at the start`` / ``at every goal pose sampled``). A grasp that is blocked at
    neither raises :class:`RejectedError` (the world may not need a regrasp)."""
    assert world.object is not None
    start = pose_matrix(world.object.initial)
    goals = goal_poses(world)
    if not goals:
        raise RejectedError("no goal pose within tolerance leaves the object free")
    reasons = []
    for index, grasp in enumerate(world.object.grasps):
        rel = pose_matrix(grasp)
        if hand_blocked(world.robot, start @ rel, world.obstacles):
            reasons.append(f"grasp {index}: its hand meets an obstacle at the start")
        elif all(hand_blocked(world.robot, pose @ rel, world.obstacles) for pose in goals):
            reasons.append(f"grasp {index}: its hand meets an obstacle at each of {len(goals)} goal poses sampled")
        else:
            raise RejectedError(f"grasp {index} is blocked neither at the start nor at the goal")
    return reasons


# ---------------------------------------------------------------------------------------- enclosures


def _entry(shape: str, size: Sequence[float], pose: Sequence[float]) -> dict[str, Any]:
    return {"shape": shape, "size": [round(float(v), 6) for v in size], "pose": [round(float(v), 6) for v in pose]}


def _frame_entry(name: str, frame: Matrix, centre: Sequence[float], size: Sequence[float]) -> dict[str, Any]:
    """A box ``size`` centred at ``centre`` in ``frame`` (a level frame: its yaw only)."""
    del name
    position = frame[:3, :3] @ np.asarray(centre) + frame[:3, 3]
    yaw = math.atan2(frame[1, 0], frame[0, 0])
    return _entry("box", size, [*position, 0.0, 0.0, yaw])


def _half_extent(thing: MovableObject, hold: Hold, frame: Matrix) -> NDArray[np.float64]:
    """The object's half extents along ``frame``'s x and y (its footprint turned into the frame)."""
    corners = footprint(thing, hold) @ frame[:2, :2]
    return np.asarray(np.abs(corners).max(axis=0))


def bin_around(
    thing: MovableObject, hold: Hold, gaps: NDArray[np.float64], wall_height: float, thickness: float
) -> dict[str, dict[str, Any]]:
    """A bin around ``hold``'s placement: its floor (the support) and four walls ``wall_height`` above the
    floor, ``gaps`` (m: +x, -x, +y, -y in the object's frame) from the object."""
    centre = hold.pose[:3, 3]
    bottom = float(centre[2] - thing.height(hold.face))
    yaw = math.atan2(hold.pose[1, 0], hold.pose[0, 0])
    frame = np.eye(4)
    frame[:3, :3] = rpy_matrix(0.0, 0.0, yaw)
    frame[:3, 3] = (centre[0], centre[1], bottom)
    half = _half_extent(thing, hold, frame)
    inner = half + np.array([(gaps[0] + gaps[1]) / 2, (gaps[2] + gaps[3]) / 2])
    shift = np.array([(gaps[0] - gaps[1]) / 2, (gaps[2] - gaps[3]) / 2])
    outer = inner + thickness
    out = {
        "bin_floor": _frame_entry("bin_floor", frame, [*shift, -thickness / 2], [2 * outer[0], 2 * outer[1], thickness])
    }
    z = wall_height / 2
    out["bin_wall_px"] = _frame_entry(
        "", frame, [shift[0] + inner[0] + thickness / 2, shift[1], z], [thickness, 2 * outer[1], wall_height]
    )
    out["bin_wall_nx"] = _frame_entry(
        "", frame, [shift[0] - inner[0] - thickness / 2, shift[1], z], [thickness, 2 * outer[1], wall_height]
    )
    out["bin_wall_py"] = _frame_entry(
        "", frame, [shift[0], shift[1] + inner[1] + thickness / 2, z], [2 * inner[0], thickness, wall_height]
    )
    out["bin_wall_ny"] = _frame_entry(
        "", frame, [shift[0], shift[1] - inner[1] - thickness / 2, z], [2 * inner[0], thickness, wall_height]
    )
    return out


def cubby_around(
    thing: MovableObject,
    hold: Hold,
    approach: Matrix,
    rng: np.random.Generator,
    thickness: float,
    *,
    shelf: bool = False,
    recess: float = 0.0,
) -> dict[str, dict[str, Any]]:
    """A cubby around ``hold``'s placement, open against ``approach`` (the hand's horizontal approach
    direction): a board (the support), a ceiling 2-3 cm above the object, a back wall and two side walls a few
    mm from it; the board and ceiling end at the object's front face (``recess`` m behind it). A ``shelf`` has no
    side walls: its board and lid run on 8-25 cm beyond the object on either side."""
    centre = hold.pose[:3, 3]
    bottom = float(centre[2] - thing.height(hold.face))
    height = 2 * thing.height(hold.face)
    frame = np.eye(4)
    frame[:3, :3] = rpy_matrix(0.0, 0.0, math.atan2(approach[1], approach[0]))  # x: into the cubby
    frame[:3, 3] = (centre[0], centre[1], bottom)
    half = _half_extent(thing, hold, frame)
    back, left, right = rng.uniform(*GAP_RANGE_M, size=3)
    if shelf:
        left, right = rng.uniform(*SHELF_SIDE_M, size=2)
    ceiling = float(rng.uniform(*CEILING_RANGE_M))
    front = -half[0] + recess
    rear = half[0] + back
    width_lo, width_hi = -half[1] - right, half[1] + left
    inside = height + ceiling
    depth = rear - front
    mid_x, mid_y = (rear + front) / 2, (width_hi + width_lo) / 2
    span = width_hi - width_lo + (0.0 if shelf else 2 * thickness)
    name = "shelf" if shelf else "cubby"
    out = {
        f"{name}_board": _frame_entry(
            "", frame, [mid_x + thickness / 2, mid_y, -thickness / 2], [depth + thickness, span, thickness]
        ),
        f"{name}_ceiling": _frame_entry(
            "", frame, [mid_x + thickness / 2, mid_y, inside + thickness / 2], [depth + thickness, span, thickness]
        ),
        f"{name}_back": _frame_entry("", frame, [rear + thickness / 2, mid_y, inside / 2], [thickness, span, inside]),
    }
    if not shelf:
        out["cubby_left"] = _frame_entry(
            "", frame, [mid_x, width_hi + thickness / 2, inside / 2], [depth, thickness, inside]
        )
        out["cubby_right"] = _frame_entry(
            "", frame, [mid_x, width_lo - thickness / 2, inside / 2], [depth, thickness, inside]
        )
    return out


# ------------------------------------------------------------------------------------------ the witness


def _clear(arm: Arm, configurations: Sequence[NDArray[np.float64]], items: dict[str, dict[str, Any]]) -> bool:
    """Whether the arm at ``configurations`` clears the obstacles ``items`` (exact geometry, no object)."""
    obstacles = [
        make_obstacle(name, entry["shape"], entry["size"], pose_matrix(entry["pose"]), name)
        for name, entry in items.items()
    ]
    checker = SpatialChecker(arm.robot, arm.spheres, obstacles, self_collision=False)
    return bool(checker.valid(np.asarray(configurations)).all())


def enclosure_clear(arm: Arm, holds: Sequence[Hold], items: dict[str, dict[str, Any]]) -> bool:
    """Whether the arm clears the obstacles ``items`` at every hold's configurations (leaving and lifting)."""
    return _clear(arm, [q for hold in holds for q in (*hold.leaving, *hold.raising)], items)


def hold_at(
    solver: Solver,
    arm: Arm,
    grasp: Matrix,
    pose: Matrix,
    *,
    rng: np.random.Generator,
    near: NDArray[np.float64],
    face: str = "-z",
) -> Hold | None:
    """A hold of the object at exactly ``pose`` (resting on ``face``) by ``grasp`` (inverse kinematics of the
    whole tcp pose, arms of 6 joints or more), with its approach and lift; ``None`` when no valid solution is
    found."""
    if arm.robot.dof < 6:
        return None
    target = pose @ grasp
    found = solver.kinematics.solve(target, rng, seeds=near[None])
    if not len(found):
        return None
    valid = found[solver.alone.valid(found)]
    if not len(valid):
        return None
    q = valid[np.argmin(np.abs(valid - near).sum(axis=1))]
    return hold_from(solver, arm, q, pose, face, rng=rng)


def _raised(robot: RobotModel, q: NDArray[np.float64], rng: np.random.Generator) -> NDArray[np.float64] | None:
    """The configuration nearest ``q`` with the tcp ``RAISE_M`` higher, its orientation kept (``None``: out of
    reach)."""
    target = robot.tcp_pose(q.tolist())
    target[2, 3] += RAISE_M
    found = InverseKinematics(robot).solve(target, rng, seeds=q[None])
    return found[np.argmin(np.abs(found - q).sum(axis=1))] if len(found) else None


def _clear_path(checker: SpatialChecker, path: Sequence[NDArray[np.float64]]) -> bool:
    """Whether every straight piece of ``path`` is valid at the validator's samples (no explanation sought)."""
    points = np.asarray(path)
    return bool(
        straight_samples_clear(
            checker, points[:-1], points[1:], coarse_every=COARSE_EVERY, settings=ValidationSettings()
        ).all()
    )


def connect(
    what: str,
    checker: SpatialChecker,
    a: Sequence[NDArray[np.float64]],
    b: Sequence[NDArray[np.float64]],
    *,
    rng: np.random.Generator,
    tries: int,
) -> list[NDArray[np.float64]]:
    """``a`` then ``b`` (paths), joined straight, by way of their ends raised, or through one random via
    configuration under ``checker``."""
    direct = [*a, *b]
    tries_ = [direct]
    robot = checker.robot
    high_a, high_b = _raised(robot, a[-1], rng), _raised(robot, b[0], rng)
    if high_a is not None and high_b is not None:
        tries_.append([*a, high_a, high_b, *b])
    for path in tries_:
        if _clear_path(checker, path):
            return path
    vias = rng.uniform(robot.lower, robot.upper, size=(tries, robot.dof))
    for via in vias[checker.valid(vias)]:
        path = [*a, via, *b]
        if _clear_path(checker, path):
            return path
    raise RejectedError(f"{what}: no straight or single-via path: {validate_transit(checker, direct)[0]}")


def regrasp_segments(
    world: SpatialWorld,
    grasps: tuple[int, int],
    holds: tuple[Hold, Hold, Hold, Hold],
    *,
    rng: np.random.Generator,
    tries: int,
) -> list[tuple[str, int | None, list[NDArray[np.float64]]]]:
    """The witness's five segments: to the start, the first transfer to the table, the transit between the
    grasps, the second transfer into the goal, away from it. ``holds``: the start, the table's first and
    second holds, the goal."""
    assert world.object is not None
    start, first, second, goal = holds
    free = SpatialChecker(
        world.robot, world.spheres, world.obstacles, world.bounds, resting_object=object_obstacle(world, start.pose)
    )
    at_table = SpatialChecker(
        world.robot, world.spheres, world.obstacles, world.bounds, resting_object=object_obstacle(world, first.pose)
    )
    at_goal = SpatialChecker(
        world.robot, world.spheres, world.obstacles, world.bounds, resting_object=object_obstacle(world, goal.pose)
    )
    carried = []
    for index, (a, b) in zip(grasps, ((start, first), (second, goal)), strict=True):
        rel = np.linalg.inv(a.pose) @ world.robot.tcp_pose(a.q.tolist())
        held = Held(world.object.shape, rel, world.supports, world.tolerances["placement_tolerance"])
        checker = SpatialChecker(world.robot, world.spheres, world.obstacles, world.bounds, held=held)
        carried.append(connect(f"transfer {index}", checker, a.raising, b.lowering, rng=rng, tries=tries))
    to_start = connect("to the start", free, [world.initial], start.coming, rng=rng, tries=tries)
    between = connect("at the table", at_table, first.leaving, second.coming, rng=rng, tries=tries)
    away = goal.leaving
    if not at_goal.valid(np.asarray(away)).all():
        raise RejectedError("the hand cannot leave the goal")
    return [
        ("transit", None, to_start),
        ("transfer", grasps[0], carried[0]),
        ("transit", None, between),
        ("transfer", grasps[1], carried[1]),
        ("transit", None, away),
    ]


def witness_holds(
    builder: Any,
    layout: RegraspLayout,
    firsts: list[int],
    second: int,
    faces: tuple[str, str, str] = ("-z", "-z", "-z"),
) -> tuple[int, tuple[Hold, Hold, Hold, Hold]]:
    """The first grasp (the first of ``firsts`` that serves) and the witness's four holds: the start (first
    grasp), the table (first grasp, then ``second``, one pose), the goal (``second``); ``faces``: the face the
    object rests on at the start, on the table and at the goal."""
    arm, solver, rng, settings = builder.arm, builder.solver, builder.rng, builder.settings
    g2 = pose_matrix(builder.grasps[second][1])
    angle = rng.uniform(-math.pi, math.pi)
    turn = rng.uniform(*TURN_RAD) * rng.choice([-1.0, 1.0])
    lifts = {"bin": None, "table": None, "cubby": CUBBY_LIFT_M, "shelf": CUBBY_LIFT_M}
    point = builder.point
    goal = find_hold(solver, arm, g2, faces[2], point(angle + turn), height=None, rng=rng, lift_m=lifts[layout.goal])
    if goal is None:
        raise RejectedError("no hold near the goal point")
    where = point(angle)
    starts: dict[int, Hold | None] = {}
    for fraction in TABLE_FRACTIONS:  # the table half-way round, else nearer either end
        table_second = find_hold(
            solver, arm, g2, faces[1], point(angle + fraction * turn), height=None, rng=rng, near=goal.q
        )
        if table_second is None:
            continue
        for first in firsts:
            if first not in starts:
                g1 = pose_matrix(builder.grasps[first][1])
                starts[first] = find_hold(
                    solver, arm, g1, faces[0], where, height=None, rng=rng, near=goal.q, lift_m=lifts[layout.start]
                )
            start = starts[first]
            if start is None:
                continue
            found = _table_holds(builder, (pose_matrix(builder.grasps[first][1]), g2), table_second, (start, goal))
            if found is not None:
                table_first, table_second = found
                break
        else:
            continue
        break
    else:
        raise RejectedError("no first grasp holds the object both at the start and at a table")
    for a, b in ((start, goal), (start, table_first), (table_first, goal)):
        if np.linalg.norm(a.pose[:3, 3] - b.pose[:3, 3]) < settings.min_carry_m:
            raise RejectedError("placements too close")
    return first, (start, table_first, table_second, goal)


def _table_holds(
    builder: Any, grasps: tuple[Matrix, Matrix], second: Hold, ends: tuple[Hold, Hold]
) -> tuple[Hold, Hold] | None:
    """The table's two holds at one pose: the first grasp at ``second``'s pose; else the other way round (the
    first grasp's own level hold there, the second grasp at its pose). ``ends``: the start and goal holds."""
    arm, solver, rng = builder.arm, builder.solver, builder.rng
    face = second.face
    first = hold_at(solver, arm, grasps[0], second.pose, rng=rng, near=ends[0].q, face=face)
    if first is not None:
        return first, second
    other = find_hold(solver, arm, grasps[0], face, second.pose[:3, 3], height=None, rng=rng, near=ends[0].q)
    there = None if other is None else hold_at(solver, arm, grasps[1], other.pose, rng=rng, near=ends[1].q, face=face)
    return None if other is None or there is None else (other, there)


def _enclosure(builder: Any, kind: str, hold: Hold) -> dict[str, dict[str, Any]]:
    """A bin, a cubby or a shelf around ``hold``'s placement (its support first)."""
    arm, solver, rng, thing, settings = builder.arm, builder.solver, builder.rng, builder.thing, builder.settings
    if kind in ("cubby", "shelf"):
        approach = solver.kinematics.tcp_poses(hold.q[None])[0][:3, 2]
        return cubby_around(thing, hold, approach, rng, settings.board_thickness_m, shelf=kind == "shelf")
    # above a side grasp's fingers, below the palm of one from above and the object's lift
    tall = 2 * thing.height(hold.face)
    low, high = 0.75 * tall + 0.012, min(tall + 0.025, settings.lift_m + settings.approach_m - 0.012)
    if low > high:
        raise RejectedError("the object is too tall for a bin its lift leaves")
    wall, gaps = float(rng.uniform(low, high)), rng.uniform(*GAP_RANGE_M, size=4)
    for widen in WIDEN_M:  # a few mm wider where the hand holding the object needs it
        items = bin_around(thing, hold, gaps + widen, wall, BIN_WALL_M)
        if _clear(arm, [*hold.leaving, *hold.raising], items):
            break
    return items


def regrasp_world(builder: Any, layout: RegraspLayout) -> tuple[dict[str, Any], Plan, list[str]]:
    """Build one regrasp world on ``builder`` (a :class:`clew_ros.worlds.spatial._Builder`): its parameter
    tree, its witness plan (two transfers, checked on the exact geometry) and notes. Raises
    :class:`RejectedError` when this stream gives none."""
    arm, rng, settings = builder.arm, builder.rng, builder.settings
    if arm.robot.dof < 6:
        raise RejectedError("the regrasp at the table needs an arm of 6 joints or more")
    thing = builder.thing
    if 2 * thing.height("-z") > MAX_HEIGHT_M:  # standing in a bin its lift leaves: as tall as the draw allows
        tall = round(float(rng.uniform(0.06, MAX_HEIGHT_M)), 3)
        size = (*thing.size[:2], tall) if thing.shape == "box" else (tall, thing.size[1])
        builder.thing = MovableObject(thing.shape, size)
        builder.grasps = grasps_of(builder.thing, settings.grasp_depth_m)
    kinds = [kind for kind, _ in builder.grasps]
    first_kind, second_kind = layout.grasp_kind(layout.start), layout.grasp_kind(layout.goal)
    firsts = [int(i) for i in rng.permutation([i for i, k in enumerate(kinds) if k == first_kind])]
    second = int(rng.choice([i for i, k in enumerate(kinds) if k == second_kind]))
    first, holds = witness_holds(builder, layout, firsts, second)
    start, goal = holds[0], holds[3]
    enclosures = {}
    for kind, hold in ((layout.start, start), (layout.goal, goal)):
        items = _enclosure(builder, kind, hold)
        enclosures[kind] = next(iter(items))
        builder.obstacles.update(items)
    builder.table("table", holds[2])
    if not enclosure_clear(arm, holds, builder.obstacles):
        raise RejectedError("an enclosure or the table is in the way of the witness's holds")
    builder.supports[:] = [enclosures[layout.start], "table", enclosures[layout.goal]]
    tree, plan, refutation = witness_world(
        builder,
        (first, second),
        holds,
        "witness: out of the first enclosure, regrasped on the table, into the second",
    )
    notes = [
        (
            f"{layout.start} to {layout.goal}: grasp {first} ({first_kind}) out of the {layout.start}, set down "
            f"on the table, grasp {second} ({second_kind}) into the {layout.goal}"
        ),
        "No single transfer: " + "; ".join(refutation),
    ]
    return tree, plan, notes


def witness_world(
    builder: Any, grasps: tuple[int, int], holds: tuple[Hold, Hold, Hold, Hold], message: str
) -> tuple[dict[str, Any], Plan, list[str]]:
    """The world's parameter tree (its obstacles and supports already on ``builder``), the witness through
    ``holds`` by ``grasps`` (checked on the exact geometry, not dragging the object) and the refutation of a
    single transfer; :class:`RejectedError` when either fails."""
    rng = builder.rng
    start, goal = holds[0], holds[3]
    tree = builder.tree(start, goal, start.up)
    tree["goal_angle_tolerance"] = float(rng.choice([0.3, math.pi]))
    world = builder.world(tree)
    tree["robot"]["initial"] = [round(float(v), 9) for v in builder.initial(world, start)]
    world = builder.world(tree)
    segments = regrasp_segments(world, grasps, holds, rng=rng, tries=builder.settings.via_tries)
    plan = make_plan(world, segments, message=message)
    problems = validate_plan(world, plan) or drag_problems(world, plan)
    if problems:
        raise RejectedError(f"the witness does not validate: {problems[0]}")
    return tree, plan, single_grasp_refutation(world)
