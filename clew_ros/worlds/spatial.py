"""Generated spatial worlds (``clew_world spatial_* --robot panda|ur5|random``), solvable by construction.

A world is built around its witness, in this order, from one random stream (a function of the family, the
robot, the seed and the attempt):

1. the arm (the shipped Panda or UR5, or a random serial arm of 4-8 joints from
   :func:`~clew_ros.spatial.random_robot.random_robot_urdf`), the object (a box or a cylinder) and its grasps
   (top-down, and into each side; the tcp :attr:`SpatialGeneration.grasp_depth_m` inside the object);
2. the witness's holds: a configuration that holds the object level (the family's face down) near a point
   drawn in the arm's workspace, found by damped least squares on the tcp's forward kinematics (any arm of
   3 joints or more: only the face's tilt and, where a family shares one table, the height are
   constrained), for the start and for the goal; and the approach above each (the tcp backed off along its
   approach axis);
3. the supports under the two placements (tables, shelf boards), then the family's obstacles (shelf walls
   and boards, clutter, a closed box), each kept only when it is :attr:`SpatialGeneration.margin_m` clear of
   the arm, the held object and the resting object along the whole witness (screened inflated by that
   margin);
4. the witness plan -- transit to the grasp, transfer to the goal (through a via configuration when the
   straight move collides), transit back to the approach -- checked as a user's plan is, by
   :func:`clew_ros.spatial.plan.validate_plan` at 0.002 rad.

An attempt that fails at any step (no level hold near the drawn point, a support or wall that cannot be made
clear, a witness the validator refuses) starts over with the next stream. The unsolvable family puts the
goal inside a closed box (walls, a lid and the support as its floor, the object starting outside it), or
on a table out of every grasp's reach (the arm's reach bounded by its link offsets); the witness is then a
failed plan that says why. The pieces (the arms, grasps, holds, the witness's sweep) are
:mod:`~clew_ros.worlds.spatial_holds`.
"""

from __future__ import annotations

import functools
import math
import os
import zlib
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np
import yaml
from numpy.typing import NDArray

from clew_ros.core.plan import Plan
from clew_ros.spatial.checker import Held, SpatialChecker
from clew_ros.spatial.placements import FACE_RPY
from clew_ros.spatial.plan import WORLD_KIND, make_plan, object_obstacle, resting_problems, validate_plan
from clew_ros.spatial.scene import Obstacle, make_obstacle
from clew_ros.spatial.transforms import matrix_pose, pose_matrix, rpy_matrix
from clew_ros.spatial.validate import validate_transit
from clew_ros.spatial.world import SpatialWorld, spatial_world_from_parameters
from clew_ros.worlds.errors import GenerationError, UnknownFamilyError
from clew_ros.worlds.spatial_flips import TURNED_WORLDS
from clew_ros.worlds.spatial_holds import (
    Hold,
    Solver,
    SpatialGeneration,
    Sweep,
    config_folder,
    draw_object,
    find_hold,
    footprint,
    grasps_of,
    load_arm,
)
from clew_ros.worlds.spatial_regrasp import REGRASP_LAYOUTS, RejectedError, regrasp_world

__all__ = [
    "SPATIAL_FAMILIES",
    "SPATIAL_ROBOTS",
    "SpatialFamily",
    "SpatialGenerated",
    "SpatialGeneration",
    "config_folder",
    "generate_spatial",
    "spatial_world_text",
    "write_spatial_world",
]

Matrix = NDArray[np.float64]

#: The arms a spatial family is generated on: the shipped Panda and UR5, or a random serial arm.
SPATIAL_ROBOTS = ("panda", "ur5", "random")


@dataclass(frozen=True)
class SpatialFamily:
    """A family of spatial worlds: ``layout`` builds the supports and obstacles around the witness's holds;
    ``grasps`` which grasps a witness may use (``top``, ``side``, ``any``); ``reorient``: the goal rests on
    another face than the start; ``one_table``: start and goal on one table (same height)."""

    name: str
    summary: str
    layout: str
    grasps: str = "any"
    reorient: bool = False
    one_table: bool = False
    solvable: bool = True
    angle_tolerances: tuple[float, ...] = (math.pi, 0.3)
    #: the arm starts at the approach of the start's grasp (not at its home, which may reach over a shelf)
    start_at_approach: bool = False
    #: a regrasp family: the key of :data:`~clew_ros.worlds.spatial_regrasp.REGRASP_LAYOUTS` or of
    #: :data:`~clew_ros.worlds.spatial_flips.TURNED_WORLDS` ("": none)
    regrasp: str = ""
    #: the arms it is generated on (a regrasp family's random arm ends in a wrist: without one, a random arm
    #: rarely holds an object both from above and from the side at one placement, 0 worlds in 200 draws)
    robots: tuple[str, ...] = SPATIAL_ROBOTS


SPATIAL_FAMILIES: dict[str, SpatialFamily] = {
    family.name: family
    for family in (
        SpatialFamily("spatial_table", "spatial: pick and place from one table to another", "tables"),
        SpatialFamily("spatial_shelf", "spatial: from a table into a shelf (boards, walls, a lid)", "shelf"),
        SpatialFamily(
            "spatial_clutter",
            "spatial: one table, 5-12 boxes and cylinders around the start and the goal",
            "clutter",
            one_table=True,
        ),
        SpatialFamily(
            "spatial_reorient",
            "spatial: the goal rests the object on another face (taken from the side, turned over)",
            "tables",
            grasps="side",
            reorient=True,
            angle_tolerances=(math.pi, 0.3),
        ),
        SpatialFamily(
            "spatial_narrow",
            "spatial: shelf to shelf, lids and walls as close as the witness lets them",
            "narrow",
            grasps="side",
            start_at_approach=True,
        ),
        SpatialFamily(
            "spatial_bin_cubby",
            "spatial: a regrasp is needed: from a bin (grasps from above only) into a cubby (from its open side only)",
            "regrasp",
            regrasp="bin_cubby",
        ),
        SpatialFamily(
            "spatial_cubby_bin",
            "spatial: a regrasp is needed: from a cubby (grasps from its open side only) into a bin (from above only)",
            "regrasp",
            regrasp="cubby_bin",
        ),
        SpatialFamily(
            "spatial_shelf_bin",
            "spatial: a regrasp is needed: from under a shelf's lid (grasps from the side only) into a bin",
            "regrasp",
            regrasp="shelf_bin",
        ),
        SpatialFamily(
            "spatial_bin_shelf",
            "spatial: a regrasp is needed: from a bin (grasps from above only) onto a shelf under its lid",
            "regrasp",
            regrasp="bin_shelf",
        ),
        SpatialFamily(
            "spatial_flip",
            "spatial: a regrasp is needed: a bar turned over (grasps into its top and bottom faces only)",
            "regrasp",
            regrasp="flip",
        ),
        SpatialFamily(
            "spatial_laid_down",
            "spatial: a regrasp is needed: a tall box from a cubby (side grasps) laid down in a low one (its end)",
            "regrasp",
            regrasp="laid_down",
        ),
        SpatialFamily(
            "spatial_unsolvable",
            "spatial: the goal inside a closed box, or on a table out of every grasp's reach",
            "unsolvable",
            solvable=False,
        ),
    )
}


@dataclass(frozen=True, eq=False)
class SpatialGenerated:
    """One generated spatial world: its ``parameters`` (``{"world": ...}``; robot files as absolute paths,
    :func:`write_spatial_world` writes them relative to the file), its ``witness`` (a valid plan, or a failed
    plan saying why none exists) and how it was made."""

    family: str
    robot: str
    seed: int
    parameters: dict[str, Any]
    witness: Plan
    solvable: bool
    notes: tuple[str, ...]
    attempts: int
    stats: dict[str, Any] = field(default_factory=dict)

    @property
    def name(self) -> str:
        return str(self.parameters["world"]["name"])

    def world(self) -> SpatialWorld:
        """The world as a user's file gives it (parsed, its robot and sphere model loaded)."""
        return spatial_world_from_parameters(self.parameters, config_folder())


class _RejectedError(Exception):
    """This stream gave no acceptable world."""


# ------------------------------------------------------------------------------------------- building


def _box(name: str, size: Sequence[float], pose: Sequence[float]) -> dict[str, Any]:
    return {"shape": "box", "size": [round(float(v), 6) for v in size], "pose": [round(float(v), 6) for v in pose]}


def _obstacle(name: str, entry: dict[str, Any]) -> Obstacle:
    return make_obstacle(name, entry["shape"], entry["size"], pose_matrix(entry["pose"]), name)


class _Builder:
    """One attempt: the arm, the object, the holds, the tree and the witness."""

    def __init__(
        self, family: SpatialFamily, robot: str, seed: int, rng: np.random.Generator, settings: SpatialGeneration
    ) -> None:
        self.family, self.seed, self.rng, self.settings = family, seed, rng, settings
        self.robot_name = robot
        self.arm = load_arm(robot, rng, wrist=bool(family.regrasp))
        self.solver = Solver(self.arm, settings)
        self.thing = draw_object(rng)
        self.grasps = grasps_of(self.thing, settings.grasp_depth_m)
        self.obstacles: dict[str, dict[str, Any]] = {}
        self.supports: list[str] = []
        self.notes: list[str] = []

    # -- holds

    def point(self, angle: float) -> NDArray[np.float64]:
        reach, shoulder = self.arm.reach, self.arm.shoulder
        radius = self.rng.uniform(0.35, 0.7) * reach
        return np.array(
            [
                shoulder[0] + radius * math.cos(angle),
                shoulder[1] + radius * math.sin(angle),
                shoulder[2] + self.rng.uniform(-0.45, 0.1) * reach,
            ]
        )

    def holds(self) -> tuple[int, Hold, Hold]:
        kinds = {"any": ("top", "side"), "top": ("top",), "side": ("side",)}[self.family.grasps]
        usable = [i for i, (kind, _) in enumerate(self.grasps) if kind in kinds]
        index = int(self.rng.choice(usable))
        grasp = pose_matrix(self.grasps[index][1])
        face_a = "-z"
        face_b = self._goal_face(grasp) if self.family.reorient else face_a
        angle = self.rng.uniform(-math.pi, math.pi)
        start = find_hold(self.solver, self.arm, grasp, face_a, self.point(angle), height=None, rng=self.rng)
        if start is None:
            raise _RejectedError("no level hold near the start point")
        turn = self.rng.uniform(0.5, 1.2 if self.family.one_table else 2.2) * self.rng.choice([-1.0, 1.0])
        height = None
        if self.family.one_table:
            height = start.pose[2, 3] - self.thing.height(face_a) + self.thing.height(face_b)
        goal = find_hold(
            self.solver, self.arm, grasp, face_b, self.point(angle + turn), height=height, rng=self.rng, near=start.q
        )
        if goal is None:
            raise _RejectedError("no level hold near the goal point")
        if np.linalg.norm(goal.pose[:3, 3] - start.pose[:3, 3]) < self.settings.min_carry_m:
            raise _RejectedError("start and goal too close")
        return index, start, goal

    def _goal_face(self, grasp: Matrix) -> str:
        """A face other than -z on which the grasp's approach points down or sideways."""
        approach = grasp[:3, 2]
        faces = [
            face
            for face in self.thing.faces
            if face != "-z" and float((rpy_matrix(*FACE_RPY[face]) @ approach)[2]) <= 0.1
        ]
        if not faces:
            raise _RejectedError("no other face to turn the object onto with this grasp")
        return str(self.rng.choice(faces))

    # -- supports

    def table(self, name: str, hold: Hold, *, extra: Sequence[Hold] = ()) -> None:
        """A table under ``hold``'s placement (and ``extra``'s: one table for both), facing the arm."""
        poses = [hold.pose, *[h.pose for h in extra]]
        centres = np.array([p[:3, 3] for p in poses])
        top = float(hold.pose[2, 3] - self.thing.height(hold.face))
        thickness = self.settings.table_thickness_m
        if len(poses) > 1:
            chord = centres[1, :2] - centres[0, :2]
            yaw = math.atan2(chord[1], chord[0])
            length = float(np.linalg.norm(chord)) + self.rng.uniform(0.2, 0.35)
            width = self.rng.uniform(0.25, 0.4)
            middle = centres[:, :2].mean(axis=0)
        else:
            offset = centres[0, :2] - self.arm.shoulder[:2]
            yaw = math.atan2(offset[1], offset[0])
            length, width = self.rng.uniform(0.2, 0.4), self.rng.uniform(0.25, 0.45)
            # the object near the edge that faces the arm (a few cm in), the top reaching away from it
            inset = float(np.max(np.abs(footprint(self.thing, hold)))) + self.rng.uniform(0.02, 0.06)
            middle = centres[0, :2] + (length / 2 - inset) * np.array([math.cos(yaw), math.sin(yaw)])
            middle += self.rng.uniform(-0.03, 0.03) * np.array([-math.sin(yaw), math.cos(yaw)])
        for _ in range(2):  # as drawn, else as small as the object's footprint allows
            entry = _box(name, [length, width, thickness], [*middle, top - thickness / 2, 0, 0, yaw])
            table = SpatialChecker(
                self.arm.robot, self.arm.spheres, [_obstacle(name, entry)], self_collision=False, exact=False
            )
            configurations = np.array([q for h in (hold, *extra) for q in (*h.leaving, *h.lift)])
            if table.valid(configurations).all():
                break
            middle = centres[:, :2].mean(axis=0)
            reach = float(np.max(np.linalg.norm(centres[:, :2] - middle, axis=1)))
            length = width = 2 * (reach + float(np.max(np.abs(footprint(self.thing, hold)))) + 0.01)
        else:
            raise _RejectedError(f"the arm holding the object reaches through {name}")
        self.obstacles[name] = entry
        self.supports.append(name)

    # -- the world and its witness

    def tree(self, start: Hold, goal: Hold, initial: NDArray[np.float64]) -> dict[str, Any]:
        reach, shoulder = self.arm.reach, self.arm.shoulder
        span = reach + 0.5
        bounds = [
            shoulder[0] - span,
            shoulder[1] - span,
            shoulder[2] - span,
            shoulder[0] + span,
            shoulder[1] + span,
            shoulder[2] + span,
        ]
        return {
            "kind": "spatial",
            "name": f"{self.family.name}_{self.robot_name}_{self.seed}",
            "bounds": [round(float(v), 3) for v in bounds],
            "robot": {**self.arm.tree, "initial": [round(float(v), 9) for v in initial]},
            "obstacle_names": list(self.obstacles),
            "obstacles": dict(self.obstacles),
            "supports": list(self.supports),
            "object": {
                "shape": self.thing.shape,
                "size": list(self.thing.size),
                "initial": [round(v, 9) for v in matrix_pose(start.pose)],
                "goal": [round(v, 9) for v in matrix_pose(goal.pose)],
                "grasps": [v for _, grasp in self.grasps for v in grasp],
            },
            "goal_angle_tolerance": float(self.rng.choice(self.family.angle_tolerances)),
        }

    def world(self, tree: dict[str, Any]) -> SpatialWorld:
        return spatial_world_from_parameters(
            {"world": tree}, config_folder(), prepared=(self.arm.robot, self.arm.spheres)
        )

    def initial(self, world: SpatialWorld, start: Hold) -> NDArray[np.float64]:
        """The arm's start: its home (or a random configuration) from which the straight move to the approach
        is free, else the approach itself."""
        resting = SpatialChecker(
            world.robot,
            world.spheres,
            world.obstacles,
            world.bounds,
            resting_object=object_obstacle(world, start.pose),
            exact=False,
        )
        if self.family.start_at_approach:
            return start.up
        candidates = [] if self.arm.home is None else [self.arm.home]
        candidates += list(
            self.rng.uniform(world.robot.lower, world.robot.upper, size=(self.settings.via_tries, world.robot.dof))
        )
        for q in candidates:
            if resting.valid(q[None])[0] and not validate_transit(resting, [q, start.up]):
                return np.asarray(q)
        return start.up

    def carry(self, world: SpatialWorld, grasp_rel: Matrix, start: Hold, goal: Hold) -> list[NDArray[np.float64]]:
        """The transfer's waypoints: straight from approach to approach, else through a via configuration."""
        held = Held(self.thing, grasp_rel, world.supports, world.tolerances["placement_tolerance"])
        checker = SpatialChecker(world.robot, world.spheres, world.obstacles, world.bounds, held=held, exact=False)
        direct = [*start.raising, *goal.lowering]
        if not validate_transit(checker, direct):
            return direct
        vias = self.rng.uniform(world.robot.lower, world.robot.upper, size=(self.settings.via_tries, world.robot.dof))
        vias = vias[checker.valid(vias)]
        for via in vias:
            path = [*start.raising, via, *goal.lowering]
            if not validate_transit(checker, path):
                return path
        raise _RejectedError(
            f"no straight or single-via transfer between the approaches: {validate_transit(checker, direct)[0]}"
        )

    def witness(self, tree: dict[str, Any], index: int, start: Hold, goal: Hold) -> tuple[SpatialWorld, Plan]:
        world = self.world(tree)
        initial = self.initial(world, start)
        tree["robot"]["initial"] = [round(float(v), 9) for v in initial]
        world = self.world(tree)
        assert world.object is not None
        tcp = self.solver.kinematics.tcp_poses(start.q[None])[0]
        grasp_rel = np.linalg.inv(pose_matrix(world.object.initial)) @ tcp
        carried = self.carry(world, grasp_rel, start, goal)
        first = [world.initial, *start.coming] if np.any(world.initial != start.up) else start.coming
        plan = make_plan(
            world,
            [("transit", None, first), ("transfer", index, carried), ("transit", None, goal.leaving)],
            message="witness: the manipulation the world was built around",
        )
        problems = validate_plan(world, plan)
        if problems:
            raise _RejectedError(f"the witness does not validate: {problems[0]}")
        return world, plan


# ------------------------------------------------------------------------------------------- layouts


def _bisect(fits: Callable[[float], bool], low: float, high: float, steps: int) -> float | None:
    """The smallest value in [low, high] (to ``steps`` halvings) for which ``fits`` holds, assuming it holds
    from some value on; ``None`` when it does not hold at ``high``."""
    if not fits(high):
        return None
    if fits(low):
        return low
    for _ in range(steps):
        middle = (low + high) / 2
        low, high = (low, middle) if fits(middle) else (middle, high)
    return high


def _shelf(builder: _Builder, sweep: Sweep, name: str, hold: Hold, *, narrow: bool) -> None:
    """A shelf around a placement: its board (the support, already in), a lid and two side walls, as near
    as the witness allows (``narrow``) or a few cm farther."""
    rng, settings = builder.rng, builder.settings
    board = builder.obstacles[name]
    length, width, thickness = board["size"]
    x, y, z, _, _, yaw = board["pose"]
    top = z + thickness / 2
    frame = rpy_matrix(0.0, 0.0, yaw)
    slack = 0.0 if narrow else float(rng.uniform(0.04, 0.12))
    height = builder.thing.size[2] if builder.thing.shape == "box" else builder.thing.size[0]

    def lid(gap: float) -> dict[str, Any]:
        return _box(
            f"{name}_lid",
            [length, width, settings.board_thickness_m],
            [x, y, top + gap + settings.board_thickness_m / 2, 0, 0, yaw],
        )

    gap = _bisect(lambda g: sweep.clear(_obstacle("lid", lid(g))), 1.2 * height, 1.2, settings.bisection_steps)
    if gap is None or (narrow and gap > height + 0.3):
        raise _RejectedError("no lid clear of the witness near the shelf")
    gap += slack + settings.margin_m
    builder.obstacles[f"{name}_lid"] = lid(gap)
    wall_height = gap + thickness + settings.board_thickness_m

    def wall(side: float, offset: float) -> dict[str, Any]:
        centre = np.array([x, y, 0.0]) + frame @ np.array([0.0, side * (offset + settings.board_thickness_m / 2), 0.0])
        return _box(
            f"{name}_wall",
            [length, settings.board_thickness_m, wall_height],
            [centre[0], centre[1], z - thickness / 2 + wall_height / 2, 0, 0, yaw],
        )

    for side, label in ((1.0, "left"), (-1.0, "right")):
        offset = _bisect(
            functools.partial(_wall_clear, sweep, wall, side),
            width / 2,
            width / 2 + 0.5,
            settings.bisection_steps,
        )
        if offset is None:
            raise _RejectedError(f"no {label} wall clear of the witness")
        builder.obstacles[f"{name}_{label}"] = wall(side, offset + slack + settings.margin_m)
    builder.notes.append(f"{name}: lid {gap:.3f} m above the board ({'narrow' if narrow else 'with room'})")


def _wall_clear(sweep: Sweep, wall: Callable[[float, float], dict[str, Any]], side: float, offset: float) -> bool:
    return sweep.clear(_obstacle("wall", wall(side, offset)))


def _clutter(builder: _Builder, sweep: Sweep, table: str) -> None:
    rng = builder.rng
    entry = builder.obstacles[table]
    length, width, thickness = entry["size"]
    x, y, z, _, _, yaw = entry["pose"]
    top = z + thickness / 2
    frame = rpy_matrix(0.0, 0.0, yaw)
    wanted, placed, tries = int(rng.integers(5, 13)), 0, 0
    while placed < wanted and tries < 6 * wanted:
        tries += 1
        local = np.array([rng.uniform(-0.5, 0.5) * length, rng.uniform(-0.5, 0.5) * width, 0.0])
        centre = np.array([x, y, 0.0]) + frame @ local
        height = rng.uniform(0.04, 0.16)
        name = f"clutter_{placed}"
        if rng.random() < 0.6:
            side = rng.uniform(0.03, 0.07, size=2)
            entry_ = _box(
                name, [*side, height], [centre[0], centre[1], top + height / 2, 0, 0, rng.uniform(-math.pi, math.pi)]
            )
        else:
            radius = rng.uniform(0.015, 0.04)
            entry_ = {
                "shape": "cylinder",
                "size": [round(height, 6), round(radius, 6)],
                "pose": [round(float(v), 6) for v in (centre[0], centre[1], top + height / 2, 0, 0, 0)],
            }
        obstacle = _obstacle(name, entry_)
        if sweep.clear(obstacle) and all(
            _apart(obstacle, _obstacle(other, builder.obstacles[other]))
            for other in builder.obstacles
            if other.startswith("clutter")
        ):
            builder.obstacles[name] = entry_
            placed += 1
    if placed < 3:
        raise _RejectedError(f"only {placed} clutter items found room")
    builder.notes.append(f"{placed} clutter items on {table}")


def _apart(a: Obstacle, b: Obstacle) -> bool:
    """Bounding spheres apart (clutter items do not overlap)."""

    def radius(o: Obstacle) -> float:
        if o.shape == "box":
            return float(np.linalg.norm(o.size)) / 2
        return math.hypot(o.size[0] / 2, o.size[1])

    return float(np.linalg.norm(a.pose[:3, 3] - b.pose[:3, 3])) > radius(a) + radius(b)


# ------------------------------------------------------------------------------------------- families


def _solvable(builder: _Builder) -> SpatialGenerated:
    family = builder.family
    index, start, goal = builder.holds()
    if family.one_table:
        builder.table("table", start, extra=[goal])
    else:
        builder.table("table_a", start)
        builder.table("shelf" if family.layout in ("shelf", "narrow") else "table_b", goal)
        if family.layout == "narrow":
            builder.obstacles["shelf_a"] = builder.obstacles.pop("table_a")
            builder.supports[0] = "shelf_a"
    tree = builder.tree(start, goal, start.up)
    world, plan = builder.witness(tree, index, start, goal)
    sweep = Sweep(world, plan, builder.settings.margin_m)
    if family.layout == "shelf":
        _shelf(builder, sweep, "shelf", goal, narrow=False)
    elif family.layout == "narrow":
        _shelf(builder, sweep, "shelf_a", start, narrow=True)
        _shelf(builder, sweep, "shelf", goal, narrow=True)
    elif family.layout == "clutter":
        _clutter(builder, sweep, "table")
    final = {**tree, "obstacle_names": list(builder.obstacles), "obstacles": dict(builder.obstacles)}
    world = builder.world(final)
    problems = validate_plan(world, plan)
    if problems:
        raise _RejectedError(f"the witness does not validate among the obstacles: {problems[0]}")
    travel, stats = _witness_stats(builder, plan)
    plan = replace(plan, stats=stats)
    what = (
        f"{builder.robot_name} ({world.robot.dof} joints), a {builder.thing.shape} {list(builder.thing.size)} m, "
        f"from face {start.face} to face {goal.face}, grasp {index} ({builder.grasps[index][0]})"
    )
    notes = (
        what,
        *builder.notes,
        f"Witness: {plan.grasp_count} transfer, joint travel {travel:.2f} rad, validated at 0.002 rad.",
    )
    return SpatialGenerated(
        family.name, builder.robot_name, builder.seed, {"world": final}, plan, True, notes, 0, stats
    )


def _witness_stats(builder: _Builder, plan: Plan) -> tuple[float, dict[str, Any]]:
    """A solvable world's witness: its joint travel (rad) and the stats the file records."""
    travel = float(sum(np.abs(np.diff(s.waypoints, axis=0)).sum() for s in plan.segments))
    stats = {
        "expected": "solvable",
        "family": builder.family.name,
        "robot": builder.robot_name,
        "seed": builder.seed,
        "transfers": plan.grasp_count,
        "joint_travel_rad": round(travel, 6),
    }
    return travel, stats


def _regrasp(builder: _Builder) -> SpatialGenerated:
    """A world where a regrasp is needed (:mod:`clew_ros.worlds.spatial_regrasp`)."""
    family = builder.family
    if family.regrasp in TURNED_WORLDS:
        tree, plan, notes = TURNED_WORLDS[family.regrasp](builder)
    else:
        tree, plan, notes = regrasp_world(builder, REGRASP_LAYOUTS[family.regrasp])
    world = builder.world(tree)
    travel, stats = _witness_stats(builder, plan)
    what = f"{builder.robot_name} ({world.robot.dof} joints), a {builder.thing.shape} {list(builder.thing.size)} m"
    notes = [
        what,
        *notes,
        f"Witness: {plan.grasp_count} transfers, joint travel {travel:.2f} rad, validated at 0.002 rad.",
    ]
    return SpatialGenerated(
        family.name,
        builder.robot_name,
        builder.seed,
        {"world": tree},
        replace(plan, stats=stats),
        True,
        tuple(notes),
        0,
        stats,
    )


def _unsolvable(builder: _Builder) -> SpatialGenerated:
    """The goal inside a closed box (its support the floor, four walls and a lid), or on a table out of
    reach."""
    family, rng, settings = builder.family, builder.rng, builder.settings
    index, start, goal = builder.holds()
    builder.table("table_a", start)
    boxed = rng.random() < 0.5
    thing = builder.thing
    assert builder.grasps
    if not boxed:  # move the goal out of reach, along the same direction
        grasp_reach = max(float(np.linalg.norm(g[:3])) for _, g in builder.grasps)
        bound = builder.arm.reach + grasp_reach + 0.005 + 0.02  # + grasp_tolerance + goal_tolerance
        direction = goal.pose[:2, 3] - builder.arm.shoulder[:2]
        direction /= np.linalg.norm(direction)
        far = builder.arm.shoulder[:2] + direction * (bound + rng.uniform(0.1, 0.3))
        goal.pose[:2, 3] = far
        goal.pose[2, 3] = builder.arm.shoulder[2] + (goal.pose[2, 3] - builder.arm.shoulder[2]) * 0.5
    builder.table("table_b", goal)
    tree = builder.tree(start, goal, start.up)
    world = builder.world(tree)
    initial = builder.initial(world, start)
    tree["robot"]["initial"] = [round(float(v), 9) for v in initial]
    if boxed:
        _closed_box(builder, goal)
        why = (
            "the goal lies inside a closed box (table_b its floor, four walls and a lid) and the object starts "
            "outside it: it cannot get in"
        )
    else:
        distance = float(np.linalg.norm(goal.pose[:3, 3] - builder.arm.shoulder))
        why = (
            f"the goal's centre is {distance:.3f} m from the first joint; the tcp never gets farther than "
            f"{builder.arm.reach:.3f} m from it, nor a grasp's tcp nearer the object's centre than its offset "
            "allows: no grasp holds the object within the goal tolerance"
        )
    final = {**tree, "obstacle_names": list(builder.obstacles), "obstacles": dict(builder.obstacles)}
    world = builder.world(final)
    checker = SpatialChecker(
        world.robot,
        world.spheres,
        world.obstacles,
        world.bounds,
        resting_object=object_obstacle(world, start.pose),
        exact=False,
    )
    if not checker.valid(world.initial[None])[0] or resting_problems(world, start.pose, "start"):
        raise _RejectedError("the start is not free")
    if boxed and resting_problems(world, goal.pose, "goal"):
        raise _RejectedError("the object does not fit in the closed box")
    stats = {"expected": "unsolvable", "family": family.name, "robot": builder.robot_name, "seed": builder.seed}
    failed = Plan(
        world.name,
        tuple(world.robot.joint_names),
        False,
        f"no plan exists (unsolvable by construction): {why}",
        stats=stats,
        world_kind=WORLD_KIND,
    )
    notes = (
        f"{builder.robot_name} ({world.robot.dof} joints), a {thing.shape} {list(thing.size)} m",
        f"No plan exists: {why}.",
    )
    del index, settings
    return SpatialGenerated(
        family.name, builder.robot_name, builder.seed, {"world": final}, failed, False, notes, 0, stats
    )


def _closed_box(builder: _Builder, goal: Hold) -> None:
    """Walls and a lid around the goal placement, on ``table_b`` (which then reaches under the walls)."""
    rng, settings = builder.rng, builder.settings
    thing = builder.thing
    corners = footprint(thing, goal)
    gap = float(rng.uniform(0.02, 0.04))
    half = np.abs(corners).max(axis=0) + gap
    centre = goal.pose[:3, 3]
    top = float(goal.pose[2, 3] - thing.height(goal.face))
    height = 2 * thing.height(goal.face) + gap
    t = settings.board_thickness_m
    floor = builder.obstacles["table_b"]
    floor["size"] = [
        round(float(max(floor["size"][0], 2 * (half[0] + t) + 0.02)), 6),
        round(float(max(floor["size"][1], 2 * (half[1] + t) + 0.02)), 6),
        floor["size"][2],
    ]
    floor["pose"][3:] = [0, 0, 0]
    floor["pose"][:2] = [round(float(centre[0]), 6), round(float(centre[1]), 6)]
    for name, size, offset in (
        ("box_north", [2 * (half[0] + t), t, height], [0, half[1] + t / 2]),
        ("box_south", [2 * (half[0] + t), t, height], [0, -half[1] - t / 2]),
        ("box_east", [t, 2 * half[1], height], [half[0] + t / 2, 0]),
        ("box_west", [t, 2 * half[1], height], [-half[0] - t / 2, 0]),
    ):
        builder.obstacles[name] = _box(
            name, size, [centre[0] + offset[0], centre[1] + offset[1], top + height / 2, 0, 0, 0]
        )
    builder.obstacles["box_lid"] = _box(
        "box_lid", [2 * (half[0] + t), 2 * (half[1] + t), t], [centre[0], centre[1], top + height + t / 2, 0, 0, 0]
    )


# ------------------------------------------------------------------------------------------- entry points


def _stream(family: str, robot: str, seed: int, attempt: int) -> np.random.Generator:
    return np.random.default_rng([zlib.crc32(family.encode()), zlib.crc32(robot.encode()), seed, attempt])


def generate_spatial(
    family: str, seed: int, robot: str = "panda", settings: SpatialGeneration | None = None
) -> SpatialGenerated:
    """The world of spatial ``family`` on ``robot`` (``panda``, ``ur5`` or ``random``) for ``seed``; the same
    arguments give the same world and witness. :class:`UnknownFamilyError` for an unknown family,
    ``ValueError`` for a bad robot or seed, :class:`GenerationError` when no attempt gave a world."""
    if family not in SPATIAL_FAMILIES:
        raise UnknownFamilyError(family, list(SPATIAL_FAMILIES))
    if robot not in SPATIAL_ROBOTS:
        raise ValueError(f"robot: expected one of {', '.join(SPATIAL_ROBOTS)}, got {robot!r}")
    if isinstance(seed, bool) or not isinstance(seed, int | np.integer) or seed < 0:
        raise ValueError(f"seed: expected an integer >= 0, got {seed!r}")
    settings = settings or SpatialGeneration()
    chosen = SPATIAL_FAMILIES[family]
    if robot not in chosen.robots:
        raise ValueError(f"robot: family {family} is generated on {', '.join(chosen.robots)}, got {robot!r}")
    reasons: list[str] = []
    attempts = settings.random_attempts if robot == "random" else settings.attempts
    for attempt in range(attempts):
        builder = _Builder(chosen, robot, int(seed), _stream(family, robot, int(seed), attempt), settings)
        try:
            if chosen.regrasp:
                made = _regrasp(builder)
            else:
                made = _solvable(builder) if chosen.solvable else _unsolvable(builder)
        except (_RejectedError, RejectedError) as rejected:
            reasons.append(str(rejected))
            continue
        return replace(made, attempts=attempt + 1, stats={**made.stats, "attempts": attempt + 1})
    raise GenerationError(
        f"family {family} on {robot}, seed {seed}: no world in {attempts} attempts (last: {reasons[-1]})"
    )


def _relative(parameters: dict[str, Any], folder: Path) -> dict[str, Any]:
    """The parameters with the robot's files written relative to ``folder`` (where the file goes)."""
    world = dict(parameters["world"])
    robot = dict(world["robot"])
    for key in ("urdf", "srdf"):
        if key in robot:
            robot[key] = os.path.relpath(robot[key], folder.resolve())
    world["robot"] = robot
    return {"world": world}


def spatial_world_text(generated: SpatialGenerated, folder: Path) -> str:
    """The parameter file's text for a file in ``folder``: a comment header, then the tree."""
    header = [
        f"# Generated by `clew_world {generated.family} --robot {generated.robot} --seed {generated.seed}`.",
        f"# expected: {'solvable' if generated.solvable else 'unsolvable'}",
        *(f"# {line}" for line in generated.notes),
    ]
    if generated.solvable:
        header.append(
            "# Solvable by construction: its witness plan (clew-plan/1) is written next to it as *.witness.json."
        )
    body = yaml.safe_dump(
        {"clew_planner": {"ros__parameters": _relative(generated.parameters, folder)}},
        sort_keys=False,
        default_flow_style=None,
        width=1 << 16,
    )
    return "\n".join(header) + "\n" + body


def write_spatial_world(generated: SpatialGenerated, path: str | Path, *, witness: bool = True) -> list[Path]:
    """Write the parameter file at ``path`` (robot files relative to it) and, unless ``witness`` is false,
    the witness next to it (``WORLD.witness.json``); returns the paths written."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(spatial_world_text(generated, path.parent), encoding="utf-8")
    written = [path]
    if witness:
        written.append(generated.witness.write(path.with_name(path.stem + ".witness.json")))
    return written
