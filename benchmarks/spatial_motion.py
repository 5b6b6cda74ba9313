"""``python -m benchmarks spatial_motion [--families ...] [--robots ...] [--problems N] [--planners ...]``: motion-only
problems of the MotionBenchMaker kind (:mod:`benchmarks.spatial_scenes`) planned by every planner named, on the
same problems in the same run.

Planners are looked up by name in :data:`PLANNERS` (``name -> callable(problem, seed, time_limit_s) ->``
:class:`PlannerResult`), or given as ``module:function`` with that signature, so a planner is added without
touching the harness (``--planners ompl_rrtconnect mypackage.motion:plan``). The shipped ones:

* ``aca``: the project's Ariadne's Clew planner, :func:`clew_ros.spatial.space.plan` on the problem's
  motion-only world (``world.robot.goal``; EXPLORE for transit, SEARCH_TRANSIT, shortcuts checked at
  0.002 rad), default ``planner.*`` but the seed and the time limit, on the same checker (spheres, then the
  exact geometry) as the
  OMPL peer (the checker object itself); its kernels are warmed before the clock, as ``clew_plan`` does.
* ``ompl_rrtconnect``: OMPL 2.x (PyPI ``ompl``, nanobind bindings) ``RRTConnect`` (default range) then its
  ``PathSimplifier`` (``SimpleSetup.simplifySolution`` for what is left of the time limit, at least
  :attr:`OmplSettings.simplify_min_s`), on the project's collision model: the state validity checker is
  :meth:`SpatialChecker.valid` on one configuration, the motion validator checks the straight joint-space move
  at every 0.002 rad per joint (the contract's validator step, :func:`clew_ros.spatial.validate.validation_samples`)
  in batched calls, a coarse pass (every :attr:`OmplSettings.coarse_stride`-th sample) before the rest, so
  a colliding move usually stops early.
* ``roboplan_rrtconnect``: roboplan's C++ RRT-Connect (PyPI ``roboplan-rrt``) then its ``PathShortcutter``, on
  its own exact geometry (pinocchio + coal on the URDF's meshes and the scene's primitives, the SRDF's
  disabled pairs), edges checked every 0.002 rad (configuration distance): the exact-geometry C++ reference.
  Its scene is built once per robot (loading the meshes is not timed); the scene's obstacles are swapped
  per problem.

Per planner (and per family and robot): success within the time limit, median and p90 wall time (a failure
counts at the limit), median CPU time, median joint travel of the successful paths (sum over joints of
|motion|, rad), median configurations checked (where the planner counts them), and the successful paths
valid under the planner's checker (spheres, then the exact geometry) at 0.002 rad per joint
(:func:`~clew_ros.spatial.validate.validate_transit`)
and, with ``--exact`` (roboplan installed), under the exact geometry at 0.002 rad. A planner that is not
installed is reported as such; the others run. Times exclude each planner's one-off setup (building the
sphere model and checker, loading meshes): what a MoveIt user sees per query.
"""

from __future__ import annotations

import argparse
import dataclasses
import functools
import importlib
import itertools
import json
import math
import time
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from benchmarks.spatial_checker import CONFIG, ROBOTS
from benchmarks.spatial_scenes import FAMILIES, MotionProblem, ProblemContext, problems, robot_tree
from benchmarks.spatial_scenes import context as problem_context
from benchmarks.spatial_tight import tighten
from clew_ros.core.settings import PlannerSettings
from clew_ros.spatial.checker import SpatialChecker
from clew_ros.spatial.offline import warm_up
from clew_ros.spatial.scene import Obstacle
from clew_ros.spatial.space import plan as spatial_plan
from clew_ros.spatial.validate import validate_transit, validation_samples
from clew_ros.spatial.world import SpatialWorld, spatial_world_from_parameters

__all__ = [
    "PLANNERS",
    "ExactScene",
    "OmplSettings",
    "PlannerResult",
    "Run",
    "aca",
    "aca_world",
    "cached_context",
    "exact_scene",
    "load_planner",
    "main",
    "register",
    "summary",
]

#: The contract's validator step (rad per revolute joint): every motion check samples at least this finely.
STEP_RAD = 0.002


@dataclass(frozen=True)
class PlannerResult:
    """What a planner returns: ``success``, the path's ``waypoints`` ((k, n), from the start to the goal,
    straight joint-space pieces between them), its own wall and CPU time for the query (s, setup excluded),
    the configurations it checked (``None``: not counted) and a ``message`` (why it failed, or empty)."""

    success: bool
    waypoints: NDArray[np.float64] | None
    time_s: float
    cpu_s: float
    checks: int | None = None
    message: str = ""


Planner = Callable[[MotionProblem, int, float], PlannerResult]

#: The planners by name (:func:`register` adds one).
PLANNERS: dict[str, Planner] = {}


def register(name: str) -> Callable[[Planner], Planner]:
    """Add a planner to :data:`PLANNERS` under ``name`` (a decorator)."""

    def add(planner: Planner) -> Planner:
        PLANNERS[name] = planner
        return planner

    return add


def load_planner(name: str) -> Planner:
    """A planner of :data:`PLANNERS`, or ``module:function``; ``ValueError`` naming what is expected."""
    if name in PLANNERS:
        return PLANNERS[name]
    if ":" in name:
        module, _, attribute = name.partition(":")
        try:
            found = getattr(importlib.import_module(module), attribute)
        except (ImportError, AttributeError) as error:
            raise ValueError(f"--planners: cannot load {name!r} ({error})") from None
        if not callable(found):
            raise ValueError(f"--planners: {name!r} is not callable")
        planner: Planner = found
        return planner
    raise ValueError(f"--planners: unknown planner {name!r}; expected one of {', '.join(PLANNERS)} or module:function")


@functools.cache
def cached_context(problem: MotionProblem) -> ProblemContext:
    """The problem loaded (:func:`benchmarks.spatial_scenes.context`) once per process: every planner's checker."""
    return problem_context(problem)


def _missing(module: str, extra: str) -> str | None:
    try:
        importlib.import_module(module)
    except ImportError as error:
        return f"{module} not importable ({error}); pip install -e '.[{extra}]'"
    return None


# ------------------------------------------------------------------------------------------------ OMPL


@dataclass(frozen=True)
class OmplSettings:
    """How the OMPL peer runs."""

    #: The simplifier gets what is left of the time limit, and at least this (s): MoveIt simplifies every
    #: solution, and a path found at the limit would otherwise go out raw.
    simplify_min_s: float = 0.05
    #: A motion is checked first at every this-many-th sample (all at 0.002 rad), then at all of them: a
    #: colliding move is usually rejected by the coarse pass at a fraction of the cost.
    coarse_stride: int = 16


class _Validity:
    """The project's checker (spheres, then the exact geometry) as OMPL's state and motion validators see it;
    counts the configurations checked."""

    def __init__(self, problem_context: ProblemContext, settings: OmplSettings) -> None:
        self.checker = problem_context.checker
        self.steps = np.full(problem_context.robot.dof, STEP_RAD)
        self.stride = settings.coarse_stride
        self.checks = 0

    def state(self, q: NDArray[np.float64]) -> bool:
        self.checks += 1
        return bool(self.checker.valid(q[None])[0])

    def motion(self, a: NDArray[np.float64], b: NDArray[np.float64]) -> bool:
        samples = validation_samples(a, b, self.steps)[1:]  # the start was checked when it was added
        coarse = samples[self.stride - 1 :: self.stride]
        self.checks += len(coarse)
        if len(coarse) and not self.checker.valid(coarse).all():
            return False
        rest = np.delete(samples, np.s_[self.stride - 1 :: self.stride], axis=0)
        self.checks += len(rest)
        return bool(self.checker.valid(rest).all())


@register("ompl_rrtconnect")
def ompl_rrtconnect(
    problem: MotionProblem, seed: int, time_limit_s: float, settings: OmplSettings | None = None
) -> PlannerResult:
    """OMPL's RRTConnect and path simplifier on the project's checker (see the module docstring)."""
    from ompl import base as ob
    from ompl import geometric as og
    from ompl import util as ou

    settings = settings or OmplSettings()
    ou.setLogLevel(ou.LOG_NONE)
    # OMPL seeds every planner's sampler from one process-wide generator, seeded once (a later setSeed is
    # ignored): the same command gives the same runs, and a run depends on the runs before it in the process
    ou.RNG.setSeed(seed + 1)  # OMPL's seed must be positive
    loaded = cached_context(problem)
    n = loaded.robot.dof
    test = _Validity(loaded, settings)

    def vector(state: Any) -> NDArray[np.float64]:
        return np.fromiter((state[i] for i in range(n)), dtype=float, count=n)

    class MotionValidator(ob.MotionValidator):
        def checkMotion(self, s1: Any, s2: Any) -> bool:  # noqa: N802 - OMPL's name
            return test.motion(vector(s1), vector(s2))

    space = ob.RealVectorStateSpace(n)
    bounds = ob.RealVectorBounds(n)
    for i in range(n):
        bounds.setLow(i, float(loaded.robot.lower[i]))
        bounds.setHigh(i, float(loaded.robot.upper[i]))
    space.setBounds(bounds)
    setup = og.SimpleSetup(space)
    setup.setStateValidityChecker(lambda state: test.state(vector(state)))
    information = setup.getSpaceInformation()
    information.setStateValidityCheckingResolution(STEP_RAD / space.getMaximumExtent())
    validator = MotionValidator(information)
    information.setMotionValidator(validator)
    start, goal = space.allocState(), space.allocState()
    for i in range(n):
        start[i] = float(problem.start[i])
        goal[i] = float(problem.goal[i])
    setup.setStartAndGoalStates(start, goal)
    setup.setPlanner(og.RRTConnect(information))
    started, cpu_started = time.perf_counter(), time.process_time()
    setup.solve(time_limit_s)
    success = bool(setup.haveExactSolutionPath())
    waypoints = None
    if success:
        left = time_limit_s - (time.perf_counter() - started)
        setup.simplifySolution(max(left, settings.simplify_min_s))
        path = setup.getSolutionPath()
        waypoints = np.array([vector(s) for s in path.getStates()])
    wall, cpu = time.perf_counter() - started, time.process_time() - cpu_started
    return PlannerResult(success, waypoints, wall, cpu, test.checks, "" if success else "no exact solution")


# --------------------------------------------------------------------------------------------- roboplan


class ExactScene:
    """A roboplan scene of one shipped robot (meshes loaded once), its obstacles swapped per problem."""

    def __init__(self, robot: str) -> None:
        core = importlib.import_module("roboplan.core")
        self.core = core
        tree = ROBOTS[robot]
        urdf = (CONFIG / tree["urdf"]).resolve()
        # the shipped URDFs name meshes relative to their folder: roboplan resolves absolute paths
        text = urdf.read_text(encoding="utf-8").replace('filename="meshes/', f'filename="{urdf.parent}/meshes/')
        self.scene = core.Scene(robot, core.loadUrdfSceneDescriptionFromXml(text))
        self.scene.importSrdf((CONFIG / tree["srdf"]).read_text(encoding="utf-8"))
        self.group = "clew_chain"
        self.scene.addGroupFromChain(self.group, tree["base_link"], tree["tip_link"])
        self.joint_names = list(self.scene.getJointGroupInfo(self.group).joint_names)
        self.obstacles: list[str] = []
        self.problem = ""

    def load(self, problem: MotionProblem, obstacles: Sequence[Obstacle], fixed: dict[str, float]) -> None:
        """The scene's obstacles replaced by ``obstacles``; the joints not planned at ``fixed``."""
        if self.problem == problem.name:
            return
        for name in self.obstacles:
            self.scene.removeGeometry(name)
        colour = np.array([0.5, 0.5, 0.5, 1.0])
        core = self.core
        for o in obstacles:
            name = f"obstacle_{o.name}"
            pose = np.asfortranarray(o.pose)
            if o.shape == "box":
                self.scene.addBoxGeometry(name, "universe", core.Box(*o.size), pose, colour)
            elif o.shape == "cylinder":
                self.scene.addCylinderGeometry(name, "universe", core.Cylinder(o.size[1], o.size[0]), pose, colour)
            else:
                self.scene.addSphereGeometry(name, "universe", core.Sphere(o.size[0]), pose, colour)
        self.obstacles = [f"obstacle_{o.name}" for o in obstacles]
        pairs = [(a, b) for i, a in enumerate(self.obstacles) for b in self.obstacles[i + 1 :]]
        if pairs:
            self.scene.setCollisions(pairs, False)  # obstacles touching one another are not a collision
        full = self.scene.getCurrentJointPositions()
        names = self.scene.getJointNames()
        for joint, value in fixed.items():
            if joint in names:
                full[names.index(joint)] = value
        self.scene.setJointPositions(full)
        self.problem = problem.name

    def full(self, q: NDArray[np.float64]) -> NDArray[np.float64]:
        out: NDArray[np.float64] = self.scene.toFullJointPositions(self.group, np.asarray(q, dtype=np.float64))
        return out

    def collides(self, q: NDArray[np.float64]) -> bool:
        return bool(self.scene.hasCollisions(self.full(q)))

    def path_collides(self, waypoints: NDArray[np.float64]) -> bool:
        """Whether a configuration along the straight pieces collides, checked every 0.002 rad (exact)."""
        if len(waypoints) == 1:
            return self.collides(waypoints[0])
        return any(
            self.core.hasCollisionsAlongPath(self.scene, self.full(a), self.full(b), STEP_RAD)
            for a, b in itertools.pairwise(waypoints)
        )


def _exact_free(problem: MotionProblem, path: NDArray[np.float64]) -> bool:
    """Whether ``path`` is free on the exact geometry at 0.002 rad: roboplan's for the shipped robots, pinocchio +
    coal's of :mod:`clew_ros.spatial.exact` for a random arm (no SRDF for roboplan to exempt its neighbours)."""
    if problem.robot in ROBOTS:
        return not exact_scene(problem).path_collides(path)
    from clew_ros.spatial.exact import ExactChecker

    return not ExactChecker(aca_world(problem)).path_problems(path)


@functools.cache
def _roboplan(robot: str) -> ExactScene:
    return ExactScene(robot)


def exact_scene(problem: MotionProblem) -> ExactScene:
    """The exact geometry (roboplan: pinocchio + coal on the URDF's meshes) of the problem's robot and scene."""
    loaded = cached_context(problem)
    scene = _roboplan(problem.robot)
    scene.load(problem, loaded.obstacles, dict(loaded.robot.fixed_positions))
    return scene


@register("roboplan_rrtconnect")
def roboplan_rrtconnect(problem: MotionProblem, seed: int, time_limit_s: float) -> PlannerResult:
    """roboplan's RRT-Connect and path shortcutter on its exact geometry (see the module docstring)."""
    rrt = importlib.import_module("roboplan.rrt")
    scene = exact_scene(problem)
    core = scene.core
    options = rrt.RRTOptions(
        group_name=scene.group,
        max_nodes=1_000_000,  # the time limit ends the search, not a node count
        collision_check_step_size=STEP_RAD,
        rrt_connect=True,
        max_planning_time=time_limit_s,
    )
    planner = rrt.RRT(scene.scene, options)
    planner.setRngSeed(seed)
    started, cpu_started = time.perf_counter(), time.process_time()
    try:
        path = planner.plan(
            core.JointConfiguration(scene.joint_names, np.asarray(problem.start, dtype=np.float64)),
            core.JointConfiguration(scene.joint_names, np.asarray(problem.goal, dtype=np.float64)),
        )
    except RuntimeError as error:  # roboplan raises when it times out (or the start or goal collides)
        wall, cpu = time.perf_counter() - started, time.process_time() - cpu_started
        return PlannerResult(False, None, wall, cpu, None, str(error))
    success = path is not None and len(path.positions) > 0
    waypoints = None
    if success:
        shortcut = core.PathShortcutter(
            scene.scene, core.PathShortcuttingOptions(group_name=scene.group, max_step_size=STEP_RAD, seed=seed)
        )
        waypoints = np.array(shortcut.shortcut(path).positions)
        success = time.perf_counter() - started <= time_limit_s
    wall, cpu = time.perf_counter() - started, time.process_time() - cpu_started
    return PlannerResult(success, waypoints, wall, cpu, None, "" if success else "no path within the time limit")


# ----------------------------------------------------------------------------------------------- the ACA


@functools.cache
def aca_world(problem: MotionProblem) -> SpatialWorld:
    """The problem's motion-only world (its parameters, read as ``clew_plan`` reads them), planned on the
    problem's own checker (spheres, then the exact geometry): the peers' collision model, object for object."""
    loaded = cached_context(problem)
    built = spatial_world_from_parameters(problem.world_parameters(), CONFIG, prepared=(loaded.robot, loaded.spheres))
    return dataclasses.replace(built, checker=loaded.checker)


@register("aca_spheres")
def aca_spheres(problem: MotionProblem, seed: int, time_limit_s: float) -> PlannerResult:
    """:func:`aca` deciding on the sphere model alone (``SpatialChecker(exact=False)``): the planner before
    validity was decided on the exact geometry, for a before/after in one run."""
    world = aca_world(problem)
    loaded = cached_context(problem)
    alone = SpatialChecker(loaded.robot, loaded.spheres, loaded.obstacles, exact=False)
    return _aca_on(dataclasses.replace(world, checker=alone), seed, time_limit_s)


@register("aca")
def aca(problem: MotionProblem, seed: int, time_limit_s: float) -> PlannerResult:
    """The project's planner: :func:`clew_ros.spatial.space.plan` on the problem's motion-only world
    (EXPLORE and SEARCH_TRANSIT, then its shortcuts), default ``planner.*`` but ``seed`` and ``time_limit``,
    on the checker the peers use; the kernels warmed (:func:`clew_ros.spatial.offline.warm_up`)
    before the clock, as ``clew_plan`` does."""
    return _aca_on(aca_world(problem), seed, time_limit_s)


def _aca_on(world: SpatialWorld, seed: int, time_limit_s: float) -> PlannerResult:
    warm_up(world)
    started, cpu_started = time.perf_counter(), time.process_time()
    result = spatial_plan(world, PlannerSettings(seed=seed, time_limit=time_limit_s))
    wall, cpu = time.perf_counter() - started, time.process_time() - cpu_started
    waypoints = np.array(result.segments[0].waypoints, dtype=np.float64) if result.success else None
    # its collision_checks stat counts free intervals (one per configuration and joint move), not
    # configurations: not the peers' figure, so not reported
    return PlannerResult(result.success, waypoints, wall, cpu, None, result.message)


# --------------------------------------------------------------------------------------------- the runs


@dataclass(frozen=True)
class Run:
    """One planner on one problem with one seed, as the table counts it."""

    planner: str
    problem: str
    family: str
    robot: str
    seed: int
    success: bool
    time_s: float
    cpu_s: float
    travel_rad: float | None
    checks: int | None
    waypoints: int
    valid: bool | None  # under the planner's checker at 0.002 rad (None: no path)
    exact_valid: bool | None  # under the exact geometry at 0.002 rad (None: not checked)
    message: str = ""
    path: list[list[float]] = field(default_factory=list)


def _travel(waypoints: NDArray[np.float64]) -> float:
    return float(np.abs(np.diff(waypoints, axis=0)).sum())


def _run(
    name: str, planner: Planner, problem: MotionProblem, seed: int, time_limit_s: float, *, exact: bool, keep: bool
) -> Run:
    result = planner(problem, seed, time_limit_s)
    path = None if result.waypoints is None else np.asarray(result.waypoints, dtype=np.float64)
    success = result.success and path is not None and len(path) > 0 and result.time_s <= time_limit_s
    valid = exact_valid = None
    message = result.message
    if success and path is not None:
        ends = max(float(np.max(np.abs(path[0] - problem.start))), float(np.max(np.abs(path[-1] - problem.goal))))
        if ends > 1e-6:
            success, message = False, f"the path's ends are {ends:.2g} rad from the start or goal"
        else:
            valid = not validate_transit(cached_context(problem).checker, path)
            if exact:
                exact_valid = _exact_free(problem, path)
    ok = success and path is not None
    return Run(
        planner=name,
        problem=problem.name,
        family=problem.family,
        robot=problem.robot,
        seed=seed,
        success=success,
        time_s=result.time_s,
        cpu_s=result.cpu_s,
        travel_rad=_travel(path) if ok and path is not None else None,
        checks=result.checks,
        waypoints=0 if path is None else len(path),
        valid=valid,
        exact_valid=exact_valid,
        message=message,
        path=path.tolist() if keep and ok and path is not None else [],
    )


def _median(values: Sequence[float]) -> float:
    return float(np.median(values)) if len(values) else math.nan


def summary(runs: Sequence[Run], time_limit_s: float) -> dict[str, Any]:
    """The table's figures of ``runs`` (one planner's): failures count at the time limit."""
    times = [r.time_s if r.success else time_limit_s for r in runs]
    good = [r for r in runs if r.success]
    checks = [float(r.checks) for r in runs if r.checks is not None]
    return {
        "runs": len(runs),
        "success": len(good) / len(runs) if runs else math.nan,
        "median_s": _median(times),
        "p90_s": float(np.percentile(times, 90)) if times else math.nan,
        "median_cpu_s": _median([r.cpu_s for r in runs]),
        "travel_rad": _median([r.travel_rad for r in good if r.travel_rad is not None]),
        "checks": _median(checks) if checks else None,
        "valid": sum(bool(r.valid) for r in good),
        "exact_valid": sum(bool(r.exact_valid) for r in good) if any(r.exact_valid is not None for r in good) else None,
        "solved": len(good),
    }


def _row(label: str, planner: str, figures: dict[str, Any]) -> str:
    checks = "-" if figures["checks"] is None else f"{figures['checks']:,.0f}"
    exact = "-" if figures["exact_valid"] is None else f"{figures['exact_valid']}/{figures['solved']}"
    return (
        f"| {label} | {planner} | {figures['runs']} | {figures['success']:.0%} | {figures['median_s']:.3f} | "
        f"{figures['p90_s']:.3f} | {figures['median_cpu_s']:.3f} | {figures['travel_rad']:.2f} | {checks} | "
        f"{figures['valid']}/{figures['solved']} | {exact} |"
    )


def table(runs: Sequence[Run], planners: Sequence[str], time_limit_s: float) -> list[str]:
    """The markdown table: every family and robot, then all problems, one row per planner."""
    lines = [
        (
            "| problems | planner | runs | success | median s | p90 s | median CPU s | travel rad | checks | "
            "valid (checker) | valid (exact) |"
        ),
        "|---|---|--:|--:|--:|--:|--:|--:|--:|--:|--:|",
    ]
    groups = sorted({(r.family, r.robot) for r in runs}, key=lambda g: (list(FAMILIES).index(g[0]), g[1]))
    for family, robot in [*groups, ("all", "")]:
        for planner in planners:
            chosen = [
                r for r in runs if r.planner == planner and (family == "all" or (r.family, r.robot) == (family, robot))
            ]
            if chosen:
                label = "all" if family == "all" else f"{family} {robot}"
                lines.append(_row(label, planner, summary(chosen, time_limit_s)))
    return lines


def ratios(runs: Sequence[Run], planners: Sequence[str], time_limit_s: float) -> list[str]:
    """Each planner's median time and travel over the first planner's (OMPL's when it leads), all problems."""
    if len(planners) < 2:
        return []
    base = summary([r for r in runs if r.planner == planners[0]], time_limit_s)
    out = []
    for planner in planners[1:]:
        figures = summary([r for r in runs if r.planner == planner], time_limit_s)
        out.append(
            f"{planner} / {planners[0]}: median time {figures['median_s'] / base['median_s']:.2f}, "
            f"median travel {figures['travel_rad'] / base['travel_rad']:.2f}"
        )
    return out


def _arguments(argv: list[str] | None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(prog="python -m benchmarks spatial_motion", description=__doc__.split("\n\n")[0])
    parser.add_argument("--families", nargs="+", default=list(FAMILIES), choices=list(FAMILIES))
    parser.add_argument(
        "--robots", nargs="+", default=list(ROBOTS), help=f"{', '.join(ROBOTS)} or random-K (a random arm, seed K)"
    )
    parser.add_argument("--problems", type=int, default=3, help="problems per family and robot (default 3)")
    parser.add_argument("--seed", type=int, default=0, help="the first problem's seed (default 0)")
    parser.add_argument("--seeds", type=int, default=1, help="planner seeds per problem (default 1)")
    parser.add_argument(
        "--planners",
        nargs="+",
        default=["ompl_rrtconnect", "roboplan_rrtconnect"],
        help=f"names ({', '.join(PLANNERS)}) or module:function; the first is the ratios' reference",
    )
    parser.add_argument("--time-limit", type=float, default=5.0, help="per run (s; default 5)")
    parser.add_argument("--exact", action="store_true", help="check every path on the exact geometry (roboplan)")
    parser.add_argument("--json", type=Path, help="write every run (and its path) to this file")
    parser.add_argument("--write-scenes", type=Path, help="write each problem's scene and parameter file here")
    parser.add_argument(
        "--tight",
        action="store_true",
        help="goals millimetres from an object and a wall (benchmarks.spatial_tight), as MotionBenchMaker's grasps",
    )
    args = parser.parse_args(argv)
    if args.problems < 1 or args.seeds < 1 or not args.time_limit > 0:
        parser.error("--problems and --seeds: expected at least 1; --time-limit: expected a positive number")
    try:
        for robot in args.robots:
            robot_tree(robot)
        args.chosen = {name: load_planner(name) for name in args.planners}
    except ValueError as error:
        parser.error(str(error))
    return args


#: What the shipped planners and ``--exact`` import, and the extra that installs it.
_NEEDS = {
    "ompl_rrtconnect": ("ompl", "bench"),
    "roboplan_rrtconnect": ("roboplan.rrt", "bench"),
    "--exact": ("roboplan.core", "bench"),
}


def _available(names: Sequence[str], exact: bool) -> tuple[list[str], bool]:
    """The planners that can run (a missing one is said and left out), and whether ``--exact`` can."""
    missing = {name: _missing(*_NEEDS[name]) for name in [*names, *(["--exact"] if exact else [])] if name in _NEEDS}
    for name, reason in missing.items():
        if reason is not None:
            print(f"{name}: not run, {reason}")
    return [name for name in names if missing.get(name) is None], exact and missing.get("--exact") is None


def _tightened(queries: Sequence[MotionProblem]) -> list[MotionProblem]:
    """The problems made tight (:func:`benchmarks.spatial_tight.tighten`; one that cannot be is named and left
    out), and how many of their starts and goals, all valid on the exact geometry, each checker refuses."""
    out = []
    for query in queries:
        tight = tighten(query)
        if tight is None:
            print(f"{query.name}: no tight goal kept its start valid and a straight way out; left out")
        else:
            out.append(tight)
    ends = 0
    refused = {"spheres alone": 0, "spheres + exact": 0}
    for query in out:
        loaded = cached_context(query)
        rows = np.stack([query.start, query.goal])
        ends += len(rows)
        alone = SpatialChecker(loaded.robot, loaded.spheres, loaded.obstacles, exact=False)
        refused["spheres alone"] += int((~alone.valid(rows)).sum())
        refused["spheres + exact"] += int((~loaded.checker.valid(rows)).sum())
    figures = ", ".join(f"{name} {count}" for name, count in refused.items())
    print(f"tight problems: {len(out)}; of their {ends} starts and goals (valid on the meshes) refused by: {figures}")
    return out


def main(argv: list[str] | None = None) -> int:
    args = _arguments(argv)
    planners, exact = _available(list(args.chosen), args.exact)
    started = time.perf_counter()
    queries = []
    for family, robot, k in itertools.product(args.families, args.robots, range(args.problems)):
        try:
            queries += problems([family], [robot], 1, args.seed + k)
        except RuntimeError as error:  # an arm that reaches no target of the family (a random arm): said, skipped
            print(f"not generated: {error}")
    if args.tight:
        queries = _tightened(queries)
    print(
        f"{len(queries)} problems ({', '.join(args.families)}; {', '.join(args.robots)}; seeds {args.seed}-"
        f"{args.seed + args.problems - 1}) generated in {time.perf_counter() - started:.1f} s; "
        f"time limit {args.time_limit:g} s a run, {args.seeds} seed(s) a problem"
    )
    if args.write_scenes:
        for query in queries:
            query.write(args.write_scenes)
        print(f"scenes and parameter files written to {args.write_scenes}")
    for query in queries:  # one-off setup, not timed: sphere model, checker, meshes, compiled kernels
        cached_context(query).checker.valid(query.start[None])
        if ("roboplan_rrtconnect" in planners or exact) and query.robot in ROBOTS:
            _roboplan(query.robot)
    runs = [
        _run(name, args.chosen[name], query, seed, args.time_limit, exact=exact, keep=args.json is not None)
        for query in queries
        for name in planners
        for seed in range(args.seeds)
    ]
    print()
    print("\n".join(table(runs, planners, args.time_limit)))
    for line in ratios(runs, planners, args.time_limit):
        print(line)
    for r in runs:
        if not r.success:
            print(f"failed: {r.planner} on {r.problem} (seed {r.seed}): {r.message}")
    if args.json:
        args.json.write_text(json.dumps([asdict(r) for r in runs]) + "\n", encoding="utf-8")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
