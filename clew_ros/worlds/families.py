"""The families of generated worlds and :func:`generate`, which builds one world of a family from a seed.

A solvable world is built in this order (each step from one random stream, see :func:`generate`):

1. the arm (:mod:`~clew_ros.worlds.arms`), the object (:mod:`~clew_ros.worlds.shapes`) and the
   bounds (a square around the base, the reach plus the object's size and 0.35 m at least);
2. the witness (:mod:`~clew_ros.worlds.witness`), in the world without obstacles: it fixes the arm's
   start, the object's start and, where it ends, the goal; it must move the object at least 0.3 m;
3. the family's layout (:mod:`~clew_ros.worlds.layouts`) around the witness, every obstacle at least
   the family's margin from the arm and the object along the whole witness;
4. the world checked as a user's would be: parsed by :func:`~clew_ros.planar.world.world_from_parameters`,
   start and goal by :func:`~clew_ros.planar.collision.check_start_and_goal`, and the witness by
   :func:`~clew_ros.planar.plan.validate_plan` at 0.002 rad.

Any step that fails (no valid candidate, a layout not near enough the motion, a witness the validator
refuses) starts over with the next stream, at most :data:`MAX_ATTEMPTS` times. The unsolvable family
puts a ring around a goal the witness reached and keeps the world only when
:func:`~clew_ros.planar.passage.separation` proves that the object cannot get in.
"""

from __future__ import annotations

import math
import zlib
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np
import shapely

from clew_ros.core.errors import WorldError
from clew_ros.core.plan import Plan, PlanSegment
from clew_ros.planar.collision import check_start_and_goal
from clew_ros.planar.kinematics import wrap_angle
from clew_ros.planar.passage import separation
from clew_ros.planar.plan import replay, validate_plan
from clew_ros.planar.world import World, world_from_parameters
from clew_ros.worlds.arms import ArmShape, make_arm
from clew_ros.worlds.errors import GenerationError, UnknownFamilyError
from clew_ros.worlds.layouts import Layout, LayoutError, blocks_near, clutter, pocket, ring, shelves, window
from clew_ros.worlds.regrasp import regrasp_needed
from clew_ros.worlds.shapes import SHAPES, ObjectShape, make_shape
from clew_ros.worlds.snake import (
    SNAKE_JOINTS,
    WALL_MARGIN_M,
    make_bar,
    make_snake_arm,
    simulate_snake,
    snake_layout,
    snake_tree,
    variant_of,
)
from clew_ros.worlds.sweep import Sweep
from clew_ros.worlds.witness import WitnessError, simulate

__all__ = ["FAMILIES", "MAX_ATTEMPTS", "Family", "GeneratedWorld", "family_names", "generate"]

#: Streams tried per world before :class:`GenerationError`.
MAX_ATTEMPTS = 40
#: Shortest distance (m) the witness must carry the object from its start to its goal.
MIN_CARRY_M = 0.3
#: ``world.goal_angle_tolerance`` meaning any orientation (the config worlds' value, just under pi).
ANY_ANGLE = 3.14159

LayoutBuilder = Callable[[World, Sweep, np.random.Generator], Layout]


class _RejectedError(Exception):
    """This stream gave no acceptable world."""


@dataclass(frozen=True)
class Family:
    """A family of worlds: what varies and the layout built around the witness.

    ``joints`` and ``shapes`` are drawn uniformly; ``transfers`` gives the chances of a witness with
    1, 2, 3 transfers; ``angle_tolerances`` the choices of ``world.goal_angle_tolerance`` (rad);
    ``margin_m`` the clearance of every obstacle from the witness (m); ``needs_regrasp``: keep only worlds
    that provably need two transfers or more.
    """

    name: str
    summary: str
    joints: tuple[int, ...]
    shapes: tuple[str, ...]
    layout: LayoutBuilder | None  # None: the unsolvable family's ring (:func:`_unsolvable`)
    margin_m: float = 0.04
    transfers: tuple[float, float, float] = (0.4, 0.4, 0.2)
    angle_tolerances: tuple[float, ...] = (ANY_ANGLE, 0.5, 0.2)
    solvable: bool = True
    needs_regrasp: bool = False  # keep only worlds where :func:`regrasp_needed` proves one transfer too few
    #: streams tried per world before :class:`GenerationError`
    attempts: int = MAX_ATTEMPTS
    #: builds the whole world from (family, seed, stream, attempt) instead of the recipe above (``snake``)
    build: Callable[[Family, int, np.random.Generator, int], GeneratedWorld] | None = None


@dataclass(frozen=True, eq=False)
class GeneratedWorld:
    """One generated world: its ``parameters`` (``{"world": ...}``, the parameter file's tree), its
    ``witness`` (a valid plan, or for an unsolvable world a failed plan saying why none exists), and how
    it was made."""

    family: str
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

    def world(self) -> World:
        """The parsed world."""
        return world_from_parameters(self.parameters)


# --------------------------------------------------------------------------- the layouts of the families


def _with_blocks(
    world: World, sweep: Sweep, rng: np.random.Generator, layout: Layout, *, near_start: int, near_goal: int
) -> Layout:
    taken = list(layout.obstacles.values())
    for pose, count, what in ((world.object.initial, near_start, "start"), (world.object.goal, near_goal, "goal")):
        if count:
            extra = blocks_near(world, sweep, rng, pose, count=count, what=what, taken=taken)
            layout.obstacles.update(extra.obstacles)
            layout.notes += extra.notes
            taken += list(extra.obstacles.values())
    return layout


def _blocks_layout(world: World, sweep: Sweep, rng: np.random.Generator) -> Layout:
    near_start, near_goal = int(rng.integers(1, 3)), int(rng.integers(2, 4))
    layout = _with_blocks(world, sweep, rng, Layout({}, []), near_start=near_start, near_goal=near_goal)
    if len(layout.obstacles) < 2:
        raise LayoutError("fewer than two blocks found a place near the placements")
    return layout


def _pocket_layout(world: World, sweep: Sweep, rng: np.random.Generator) -> Layout:
    layout = pocket(world, sweep, rng, world.object.goal)
    return _with_blocks(world, sweep, rng, layout, near_start=int(rng.integers(0, 3)), near_goal=0)


def _shelves_layout(world: World, sweep: Sweep, rng: np.random.Generator) -> Layout:
    return shelves(world, sweep, rng)


def _window_layout(world: World, sweep: Sweep, rng: np.random.Generator) -> Layout:
    layout = window(world, sweep, rng)
    return _with_blocks(world, sweep, rng, layout, near_start=0, near_goal=int(rng.integers(0, 3)))


def _clutter_layout(world: World, sweep: Sweep, rng: np.random.Generator) -> Layout:
    layout = clutter(world, sweep, rng, int(rng.integers(8, 17)))
    return _with_blocks(world, sweep, rng, layout, near_start=0, near_goal=int(rng.integers(1, 3)))


def _mixed_layout(world: World, sweep: Sweep, rng: np.random.Generator) -> Layout:
    layout = clutter(world, sweep, rng, int(rng.integers(4, 9)))
    return _with_blocks(world, sweep, rng, layout, near_start=1, near_goal=2)


ALL_SHAPES = tuple(SHAPES)

#: Every family by name, in the order ``clew_world --list`` prints them.
FAMILIES: dict[str, Family] = {
    family.name: family
    for family in (
        Family(
            "shapes2",
            "2-joint arm, every object shape, blocks close to the start and the goal (the plan-quality reference)",
            (2,),
            ALL_SHAPES,
            _blocks_layout,
        ),
        Family(
            "regrasp2",
            "2-joint arm, every object shape, a tight goal orientation that provably needs a regrasp (as figure1)",
            (2,),
            ALL_SHAPES,
            _blocks_layout,
            transfers=(0.0, 0.6, 0.4),
            angle_tolerances=(0.1, 0.2),
            needs_regrasp=True,
        ),
        Family(
            "pocket",
            "3-joint arm; the goal in a pocket open on the side the witness enters from",
            (3,),
            ("triangle", "box", "L", "convex", "nonconvex"),
            _pocket_layout,
            margin_m=0.035,
        ),
        Family(
            "shelves",
            "4-5 joints; a box or bar taken from between shelf boards to between other boards",
            (4, 5),
            ("box", "bar", "convex"),
            _shelves_layout,
            margin_m=0.035,
        ),
        Family(
            "window",
            "3-5 joints; a wall from bound to bound between start and goal, with the windows the witness used",
            (3, 4, 5),
            ALL_SHAPES,
            _window_layout,
        ),
        Family(
            "clutter",
            "4-joint arm; 8-16 boxes scattered along the motion, blocks near the goal",
            (4,),
            ALL_SHAPES,
            _clutter_layout,
        ),
        Family(
            "arm7",
            "7-joint arm; a box, bar or convex object from one shelf rack to another",
            (7,),
            ("box", "bar", "convex"),
            _shelves_layout,
            margin_m=0.035,
        ),
        Family(
            "arm10",
            "10-joint arm, every object shape; 4-8 boxes along the motion and blocks near start and goal",
            (10,),
            ALL_SHAPES,
            _mixed_layout,
        ),
        Family(
            "snake",
            "15-40 joints (equal, decreasing, random lengths; loose, tight limits); a bar from a shelf into a slot",
            SNAKE_JOINTS,
            ("bar",),
            None,
            transfers=(0.0, 1.0, 0.0),
            angle_tolerances=(0.3,),
            margin_m=WALL_MARGIN_M,
            attempts=100,  # a witness of many joints is refused more often (a wall too near it, mostly)
            build=lambda family, seed, rng, attempt: _snake(family, seed, rng, attempt),  # noqa: PLW0108 (defined below)
        ),
        Family(
            "unsolvable",
            "2-4 joints; the goal inside a closed ring, or one whose opening is narrower than the object",
            (2, 3, 4),
            ALL_SHAPES,
            None,
            transfers=(1.0, 0.0, 0.0),
            solvable=False,
        ),
    )
}


def family_names() -> list[str]:
    """The families' names, in :data:`FAMILIES`' order."""
    return list(FAMILIES)


# --------------------------------------------------------------------------- building one world


def _stream(family: str, seed: int, attempt: int) -> np.random.Generator:
    """The random stream of one attempt: a function of the family's name, the seed and the attempt only."""
    return np.random.default_rng([zlib.crc32(family.encode()), seed, attempt])


def _pose(values: np.ndarray) -> list[float]:
    """A pose for the parameter file: angle wrapped into [-pi, pi), every value rounded to 1e-6."""
    return [round(float(values[0]), 6), round(float(values[1]), 6), round(float(wrap_angle(values[2])), 6)]


def _travel(plan: Plan) -> float:
    """Sum over joints of the absolute motion (rad), as the planner's ``joint_travel_rad``."""
    return float(sum(np.abs(np.diff(s.waypoints, axis=0)).sum() for s in plan.segments))


def _parsed(tree: dict[str, Any]) -> World:
    """The world of ``tree`` as a user's file gets it: parsed, start and goal checked."""
    try:
        return check_start_and_goal(world_from_parameters({"world": tree}))
    except WorldError as error:
        raise _RejectedError(str(error)) from None


@dataclass
class _Draft:
    """A world before its layout: the ``world`` tree (arm, object, start, goal), the witness plan that
    ends at the goal, and what the notes and stats say of them."""

    tree: dict[str, Any]
    witness: Plan
    kind: str
    angle_tolerance: float
    stats: dict[str, Any]

    @property
    def world(self) -> World:
        return world_from_parameters({"world": self.tree})

    def with_layout(self, layout: Layout) -> dict[str, Any]:
        """The tree with the layout's obstacles and the tolerances, keys in the contract's order."""
        tree = dict(self.tree)
        if layout.obstacles:
            tree["obstacle_names"] = list(layout.obstacles)
            tree["obstacles"] = {name: vertices.ravel().tolist() for name, vertices in layout.obstacles.items()}
        tree["grasp_tolerance"] = 0.005
        tree["goal_tolerance"] = 0.02
        tree["goal_angle_tolerance"] = self.angle_tolerance
        return tree


def _robot_tree(arm: ArmShape, initial: np.ndarray) -> dict[str, Any]:
    return {
        "base": [0.0, 0.0],
        "link_lengths": arm.link_lengths.tolist(),
        "link_width": arm.link_width,
        "joint_lower": arm.joint_lower.tolist(),
        "joint_upper": arm.joint_upper.tolist(),
        "initial": [round(float(v), 6) for v in initial],
        "self_collision": True,
    }


def _object_tree(shape: ObjectShape, start: list[float], goal: list[float]) -> dict[str, Any]:
    return {
        "polygon": shape.vertices.ravel().tolist(),
        "initial": start,
        "goal": goal,
        "grasps": shape.grasps.ravel().tolist(),
    }


def _draft(family: Family, seed: int, rng: np.random.Generator, attempt: int) -> _Draft:
    """Arm, object, bounds and witness (steps 1 and 2 of the module's recipe)."""
    name = f"{family.name}_{seed}"
    arm = make_arm(rng, int(rng.choice(family.joints)))
    shape = make_shape(str(rng.choice(family.shapes)), rng, arm.reach * float(rng.uniform(0.15, 0.3)))
    half = round(arm.reach + max(0.35, shape.radius + 0.1), 2)
    tree: dict[str, Any] = {
        "name": name,
        "bounds": [-half, -half, half, half],
        "robot": _robot_tree(arm, np.zeros(len(arm.link_lengths))),
        "object": _object_tree(shape, [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]),
    }
    transfers = int(rng.choice([1, 2, 3], p=family.transfers))
    try:
        witness = simulate(world_from_parameters({"world": tree}), shape, rng, transfers=transfers)
    except WitnessError as error:
        raise _RejectedError(str(error)) from None
    start = _pose(witness.object_initial)
    tree["robot"] = _robot_tree(arm, witness.initial)
    tree["object"] = _object_tree(shape, start, start)
    joint_names = tuple(f"joint_{i + 1}" for i in range(len(arm.link_lengths)))
    plan = Plan(name, joint_names, True, "", None, witness.segments, None)
    goal = _pose(list(replay(world_from_parameters({"world": tree}), plan, None))[-1].object_poses[-1])
    if math.hypot(goal[0] - start[0], goal[1] - start[1]) < MIN_CARRY_M:
        raise _RejectedError("the witness leaves the object too close to its start")
    tree["object"]["goal"] = goal
    stats = {
        "generator": "clew_world",
        "family": family.name,
        "world_seed": seed,
        "attempts": attempt + 1,
        "expected": "solvable" if family.solvable else "unsolvable",
    }
    if family.solvable:
        stats.update(transfers=transfers, joint_travel_rad=round(_travel(plan), 6))
    message = f"witness of {name}: a random manipulation simulated from the start; its end is the goal"
    plan = Plan(name, joint_names, True, message, None, witness.segments, np.array(goal), (), stats)
    return _Draft(tree, plan, shape.kind, float(rng.choice(family.angle_tolerances)), stats)


def _solvable(family: Family, seed: int, draft: _Draft, rng: np.random.Generator) -> GeneratedWorld:
    """The family's layout around the witness, then the checks (steps 3 and 4)."""
    world = draft.world
    assert family.layout is not None  # a solvable family has a layout
    regrasp = None
    if family.needs_regrasp:
        regrasp = regrasp_needed(world_from_parameters({"world": draft.with_layout(Layout({}, []))}))
        if regrasp is None:
            raise _RejectedError("one transfer might do")
    try:
        layout = family.layout(world, Sweep(world, draft.witness, family.margin_m), rng)
    except LayoutError as error:
        raise _RejectedError(str(error)) from None
    tree = draft.with_layout(layout)
    problems = validate_plan(_parsed(tree), draft.witness)
    if problems:
        raise _RejectedError("the witness fails validation: " + "; ".join(problems[:2]))
    notes = (
        (
            f"{world.robot.dof}-joint arm, {draft.kind} object, {len(layout.obstacles)} obstacles, "
            f"goal_angle_tolerance {draft.angle_tolerance:g} rad"
        ),
        *layout.notes,
        *([f"A regrasp is needed: {regrasp}."] if regrasp else []),
        (
            f"Witness: {draft.stats['transfers']} transfer(s), joint travel {draft.stats['joint_travel_rad']:.2f} "
            f"rad; obstacles keep {family.margin_m:g} m from it."
        ),
    )
    return GeneratedWorld(
        family.name, seed, {"world": tree}, draft.witness, True, notes, draft.stats["attempts"], draft.stats
    )


def _unsolvable(family: Family, seed: int, draft: _Draft, rng: np.random.Generator) -> GeneratedWorld:
    """A ring around the goal the witness reached (closed, or with an opening narrower than the object's
    inscribed disc), kept only when :func:`separation` proves the goal out of the object's way."""
    world, witness = draft.world, draft.witness
    at_start = Plan(
        witness.world,
        witness.joint_names,
        True,
        "",
        None,
        (PlanSegment("transit", None, world.robot.initial[None]),),
        None,
    )
    diameter = 2 * float(shapely.maximum_inscribed_circle(shapely.Polygon(world.object.polygon), 1e-5).length)
    opening = None if rng.random() < 0.5 else round(diameter * float(rng.uniform(0.3, 0.7)), 4)
    try:
        layout = ring(world, Sweep(world, at_start, family.margin_m), rng, opening=opening)
    except LayoutError as error:
        raise _RejectedError(str(error)) from None
    tree = draft.with_layout(layout)
    why = separation(_parsed(tree))
    if why is None:
        raise _RejectedError("the ring does not separate the goal from the start")
    failed = Plan(witness.world, witness.joint_names, False, f"no plan exists (unsolvable by construction): {why}")
    failed = replace(failed, stats=draft.stats)
    notes = (
        (
            f"{world.robot.dof}-joint arm, {draft.kind} object (inscribed disc {diameter:.3f} m across), "
            f"goal_angle_tolerance {draft.angle_tolerance:g} rad"
        ),
        *layout.notes,
        f"No plan exists: {why}.",
    )
    return GeneratedWorld(
        family.name, seed, {"world": tree}, failed, False, notes, draft.stats["attempts"], draft.stats
    )


def _snake(family: Family, seed: int, rng: np.random.Generator, attempt: int) -> GeneratedWorld:
    """A world of the ``snake`` family (:mod:`~clew_ros.worlds.snake`): arm, witness, shelf and slot, checks."""
    name = f"{family.name}_{seed}"
    variant = variant_of(seed)
    arm = make_snake_arm(rng, int(rng.choice(family.joints)), variant)
    shape = make_bar()
    tree = snake_tree(name, arm, shape)
    try:
        witness, goal_pose = simulate_snake(world_from_parameters({"world": tree}), shape, rng)
    except WitnessError as error:
        raise _RejectedError(str(error)) from None
    start, goal = _pose(witness.object_initial), _pose(goal_pose)
    tree["robot"]["initial"] = [round(float(v), 6) for v in witness.initial]
    tree["object"]["initial"] = start
    tree["object"]["goal"] = goal
    joint_names = tuple(f"joint_{i + 1}" for i in range(len(arm.link_lengths)))
    stats = {
        "generator": "clew_world",
        "family": family.name,
        "world_seed": seed,
        "attempts": attempt + 1,
        "expected": "solvable",
        "transfers": 2,
        "joint_travel_rad": round(_travel(Plan(name, joint_names, True, "", None, witness.segments, None)), 6),
    }
    message = "witness of " + name + ": the arm bent in three groups of joints, a regrasp aside (clew_world snake)"
    plan = Plan(name, joint_names, True, message, None, witness.segments, np.array(goal), (), stats)
    draft = _Draft(tree, plan, "bar", family.angle_tolerances[0], stats)
    world = draft.world
    try:
        layout = snake_layout(world, Sweep(world, plan, WALL_MARGIN_M), rng, np.array(goal))
    except LayoutError as error:
        raise _RejectedError(str(error)) from None
    final = draft.with_layout(layout)
    problems = validate_plan(_parsed(final), plan)
    if problems:
        raise _RejectedError("the witness fails validation: " + "; ".join(problems[:2]))
    notes = (
        (
            f"{arm.link_lengths.size}-joint arm ({variant.name}), bar, {len(layout.obstacles)} obstacles, "
            f"goal_angle_tolerance {draft.angle_tolerance:g} rad"
        ),
        *layout.notes,
        f"Witness: 2 transfers, joint travel {stats['joint_travel_rad']:.2f} rad; the arm bent in groups of joints.",
    )
    return GeneratedWorld(family.name, seed, {"world": final}, plan, True, notes, attempt + 1, stats)


def generate(family: str, seed: int) -> GeneratedWorld:
    """The world of ``family`` (a name of :data:`FAMILIES`) for ``seed`` (an integer >= 0).

    Deterministic: the same family and seed give the same world and witness, byte for byte once
    written (:func:`clew_ros.worlds.files.write_world`). Raises :class:`UnknownFamilyError` for an
    unknown family, ``ValueError`` for a negative seed, and :class:`GenerationError` when
    :data:`MAX_ATTEMPTS` streams gave no acceptable world.
    """
    if family not in FAMILIES:
        raise UnknownFamilyError(family, family_names())
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise ValueError(f"seed: expected an integer >= 0, got {seed!r}")
    chosen = FAMILIES[family]
    build = _solvable if chosen.solvable else _unsolvable
    reasons: list[str] = []
    for attempt in range(chosen.attempts):
        rng = _stream(family, int(seed), attempt)
        try:
            if chosen.build is not None:
                return chosen.build(chosen, int(seed), rng, attempt)
            return build(chosen, int(seed), _draft(chosen, int(seed), rng, attempt), rng)
        except _RejectedError as rejected:
            reasons.append(str(rejected))
    raise GenerationError(f"family {family}, seed {seed}: no world in {chosen.attempts} attempts (last: {reasons[-1]})")
