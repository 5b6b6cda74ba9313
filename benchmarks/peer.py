"""Peer comparison on transit sub-problems: OMPL RRTConnect against the project's own planner.

``python -m benchmarks.peer WORLD [--problems N] [--time-limit S] [--seed N] [--step-rad R]``
prints one JSON object.

A sub-problem: move the arm from one valid configuration to another, the
object resting at its initial pose (pairs drawn uniformly within the joint
limits, seeded, kept when both ends are valid and at least 1 rad apart).

* **OMPL** (PyPI ``ompl`` 2.x, nanobind bindings): ``RealVectorStateSpace``
  bounded by the joint limits, ``RRTConnect`` with its default range. The
  validity test is the project's own, :func:`~clew_ros.planar.collision.is_valid`
  (:class:`ProjectValidity`): the state validity checker calls it on one
  configuration, and a Python :class:`ompl.base.MotionValidator` samples each
  straight motion every ``step_rad`` (joint-space L2, so per joint too) and
  tests all the samples in one batched call (OMPL's default discrete motion
  validator would call the state checker once per sample, about 30x slower
  here). ``--checker loop`` uses the per-state shapely loop
  :class:`~benchmarks.throughput.PerStateChecker` for both instead. Success:
  an exact solution within the time limit. No path simplification.
* **Project** (:func:`project_transit`): the Ariadne's Clew algorithm posed
  on the transit problem with the core's own pieces: SEARCH is
  ``clew_ros.core.search.local_search`` minimising the joint-space distance
  to ``q_goal`` over Manhattan paths (the same straight probe from
  ``ManyJoints.straight_transit_joints`` joints, greedy probe, GA, bouncing, free
  intervals and damped least-squares refinement that SEARCH_TRANSIT uses, only the
  objective differs: SEARCH_TRANSIT minimises the tip's distance to a grasp
  point, which any of many configurations satisfies, so it would not pose the
  same problem as OMPL's). The distance is weighted by ``planner.joint_weight``
  (0.1 m/rad, the planner's own conversion in its landmark distance), because
  SEARCH's thresholds are in metres (refinement from 0.15 x reach); when SEARCH from the start fails, EXPLORE adds a
  landmark (GA over landmark x Manhattan genes maximising the distance to the
  other landmarks, as :mod:`clew_ros.core.explore` does) and SEARCH runs from
  it, until success or the time limit. Success: the end is within 1e-3 rad
  (L2) of ``q_goal``.

Both planners' paths are checked afterwards with :func:`~clew_ros.planar.collision.is_valid`
at 0.002 rad per joint (the contract's validator step).
"""

from __future__ import annotations

import argparse
import itertools
import json
import os
import sys
import time

import numpy as np

from benchmarks.throughput import PerStateChecker, random_configurations
from benchmarks.worlds import all_worlds, select
from clew_ros.core.genetic import minimize
from clew_ros.core.search import SearchJob, local_search
from clew_ros.core.settings import PlannerSettings, Termination
from clew_ros.core.space import Mode, PlanningContext
from clew_ros.planar.collision import check_start_and_goal, is_valid
from clew_ros.planar.space import PlanarSpace
from clew_ros.planar.world import World, world_from_parameters

__all__ = ["ompl_unavailable_reason", "path_is_valid", "project_transit", "solve_ompl", "transit_problems"]

GOAL_TOLERANCE_RAD = 1e-3
CHECK_STEP_RAD = 0.002


def transit_problems(world: World, count: int, seed: int, min_distance_rad: float = 1.0) -> list[tuple]:
    """``count`` pairs ``(q_start, q_goal)`` of valid transit configurations, seeded."""
    rng = np.random.default_rng(seed)
    pose = world.object.initial
    problems: list[tuple] = []
    for _ in range(1000):
        q = random_configurations(world, 256, rng)
        q = q[is_valid(world, q, pose[None])]
        for a, b in zip(q[0::2], q[1::2], strict=False):  # an odd count leaves the last one out
            if np.linalg.norm(a - b) >= min_distance_rad:
                problems.append((a, b))
            if len(problems) == count:
                return problems
    return problems


def path_is_valid(world: World, waypoints: np.ndarray, step_rad: float = CHECK_STEP_RAD) -> bool:
    """Every configuration along the straight pieces, at most ``step_rad`` apart per joint, is valid."""
    pieces = [waypoints[:1]]
    for a, b in itertools.pairwise(waypoints):
        count = max(1, int(np.ceil(np.max(np.abs(b - a)) / step_rad)))
        pieces.append(a + (np.arange(1, count + 1)[:, None] / count) * (b - a))
    configurations = np.concatenate(pieces)
    valid = np.concatenate(
        [
            is_valid(world, configurations[i : i + 20_000], world.object.initial[None])
            for i in range(0, len(configurations), 20_000)
        ]
    )
    return bool(valid.all())


def ompl_unavailable_reason() -> str | None:
    try:
        from ompl import base, geometric  # noqa: F401
    except ImportError as error:
        return f"ompl not importable ({error}); install the bench extra: pip install -e '.[bench]'"
    return None


class ProjectValidity:
    """The project's validity test (:func:`clew_ros.planar.collision.is_valid`) as OMPL's checkers see it.

    ``state(q)``: one configuration (a batch of 1). ``motion(a, b)``: the
    straight segment sampled every ``step_rad`` (joint-space L2, both ends
    included), all samples tested in one batched ``is_valid`` call; this is
    how the project's test is meant to be used, and what OMPL's default
    discrete motion validator would do one state at a time. With
    ``checker="loop"`` both use :class:`~benchmarks.throughput.PerStateChecker`
    (a plain shapely loop, same answers) one state at a time instead.
    """

    def __init__(self, world: World, step_rad: float, checker: str = "is_valid") -> None:
        self.world = world
        self.pose = np.asarray(world.object.initial, float)[None]
        self.step = step_rad
        self.loop = PerStateChecker(world, world.object.initial) if checker == "loop" else None
        self.states = 0  # configurations tested
        self.calls = 0  # calls into the validity test

    def state(self, q: np.ndarray) -> bool:
        self.states += 1
        self.calls += 1
        if self.loop is not None:
            return self.loop(q)
        return bool(is_valid(self.world, q[None], self.pose)[0])

    def motion(self, a: np.ndarray, b: np.ndarray) -> bool:
        count = max(1, int(np.ceil(np.linalg.norm(b - a) / self.step)))
        samples = a + (np.arange(count + 1)[:, None] / count) * (b - a)
        if self.loop is not None:
            for q in samples:
                self.states += 1
                self.calls += 1
                if not self.loop(q):
                    return False
            return True
        self.states += len(samples)
        self.calls += 1
        return bool(is_valid(self.world, samples, self.pose).all())


def solve_ompl(
    world: World, problems: list[tuple], time_limit_s: float, step_rad: float, checker: str = "is_valid"
) -> list[dict]:
    """RRTConnect (OMPL 2.x nanobind bindings) on each problem; one record per problem."""
    from ompl import base as ob
    from ompl import geometric as og
    from ompl import util as ou

    ou.setLogLevel(ou.LOG_NONE)
    n = world.robot.dof
    test = ProjectValidity(world, step_rad, checker)

    def vector(state) -> np.ndarray:
        return np.fromiter((state[i] for i in range(n)), dtype=float, count=n)

    class MotionValidator(ob.MotionValidator):
        """Straight joint-space segments checked by one batched call (see :class:`ProjectValidity`)."""

        def checkMotion(self, s1, s2) -> bool:  # noqa: N802 - OMPL's name; RRTConnect uses this overload only
            return test.motion(vector(s1), vector(s2))

    records = []
    for q_start, q_goal in problems:
        space = ob.RealVectorStateSpace(n)
        bounds = ob.RealVectorBounds(n)
        for i in range(n):
            bounds.setLow(i, float(world.robot.joint_lower[i]))
            bounds.setHigh(i, float(world.robot.joint_upper[i]))
        space.setBounds(bounds)
        setup = og.SimpleSetup(space)
        setup.setStateValidityChecker(lambda state: test.state(vector(state)))
        information = setup.getSpaceInformation()
        # used by the default motion validator (not installed) and by path interpolation
        information.setStateValidityCheckingResolution(step_rad / space.getMaximumExtent())
        validator = MotionValidator(information)
        information.setMotionValidator(validator)
        start, goal = space.allocState(), space.allocState()
        for i in range(n):
            start[i] = float(q_start[i])
            goal[i] = float(q_goal[i])
        setup.setStartAndGoalStates(start, goal)
        setup.setPlanner(og.RRTConnect(information))
        test.states = test.calls = 0
        started, cpu_started = time.perf_counter(), time.process_time()
        setup.solve(time_limit_s)
        wall, cpu = time.perf_counter() - started, time.process_time() - cpu_started
        success = bool(setup.haveExactSolutionPath())
        record = {
            "success": success,
            "wall_s": wall,
            "cpu_s": cpu,
            "checks": test.states,
            "calls": test.calls,
            "valid": None,
            "waypoints": 0,
        }
        if success:
            path = setup.getSolutionPath()
            waypoints = np.array([vector(s) for s in path.getStates()])
            record.update(valid=path_is_valid(world, waypoints), waypoints=len(waypoints))
        records.append(record)
    return records


def project_transit(
    world: World,
    q_start: np.ndarray,
    q_goal: np.ndarray,
    time_limit_s: float,
    seed: int,
    *,
    settings: PlannerSettings | None = None,
) -> dict:
    """The Ariadne's Clew algorithm on one transit problem (see the module docstring)."""
    settings = settings or PlannerSettings(seed=seed, time_limit=time_limit_s, threads=1)  # one core, as OMPL
    termination = Termination(time_limit_s)
    ctx = PlanningContext(PlanarSpace(world), settings, np.random.default_rng(seed), termination)
    mode = Mode.resting(np.asarray(world.object.initial, float)[None])
    n = world.robot.dof
    k = settings.manhattan_order
    goal = np.asarray(q_goal, float)

    weight = settings.joint_weight  # m/rad: SEARCH's thresholds are in metres (0.15 x reach)

    def objective(q: np.ndarray, _poses: np.ndarray) -> np.ndarray:
        return weight * np.linalg.norm(q - goal, axis=1)

    def error(q: np.ndarray) -> np.ndarray:
        return weight * (q - goal)

    landmarks = [np.asarray(q_start, float)]
    parents: list[int | None] = [None]
    arrivals: list[np.ndarray] = [landmarks[0][None]]  # waypoints from the parent to each landmark
    started, cpu_started = time.perf_counter(), time.process_time()
    success = False
    searched_from_start = None
    waypoints = landmarks[0][None]
    # as SEARCH_TRANSIT from ManyJoints.straight_transit_joints: a straight move to the goal first
    straight = goal[None] if n >= ctx.many.straight_transit_joints else None
    while True:
        job = SearchJob(
            landmarks[-1], objective, error, 0.1 * weight * GOAL_TOLERANCE_RAD, mode, toward=goal, straight=straight
        )
        [(tail, distance)] = local_search(ctx, [job])
        distance /= weight  # rad
        if searched_from_start is None:
            searched_from_start = bool(distance <= GOAL_TOLERANCE_RAD)
        if distance <= GOAL_TOLERANCE_RAD:
            waypoints = np.concatenate([*_lineage(arrivals, parents, len(landmarks) - 1), tail[1:]])
            success = True
            break
        if termination():
            break
        # EXPLORE: a landmark as far as possible from the others
        starts = np.array(landmarks)

        def decode(population: np.ndarray, starts: np.ndarray = starts):
            index = np.clip(population[:, 0].astype(int), 0, len(landmarks) - 1)
            return index, ctx.manhattan(starts[index], population[:, 1:].reshape(-1, k, n), mode)

        def evaluate(population: np.ndarray, starts: np.ndarray = starts) -> np.ndarray:
            _, paths = decode(population)
            ctx.counters.evaluations += len(population)
            return -np.min(np.linalg.norm(paths.final[:, None] - starts[None], axis=2), axis=1)

        initial = np.empty((settings.population, 1 + k * n))
        initial[:, 0] = ctx.rng.integers(0, len(landmarks), size=settings.population)
        initial[:, 1:] = ctx.initial_genes(settings.population).reshape(settings.population, -1)
        result = minimize(
            evaluate, initial, ctx.rng, settings.genetic, categories=len(landmarks), should_stop=termination
        )
        index, path = decode(result.genes[None])
        landmarks.append(path.final[0].copy())
        parents.append(int(index[0]))
        arrivals.append(path.waypoints[0, 1:])
        if termination():
            break
    wall, cpu = time.perf_counter() - started, time.process_time() - cpu_started
    return {
        "success": success,
        "wall_s": wall,
        "cpu_s": cpu,
        "search_only": searched_from_start,
        "landmarks": len(landmarks),
        "intervals": ctx.counters.clearance_checks,
        "evaluations": ctx.counters.evaluations,
        "valid": path_is_valid(world, waypoints) if success else None,
        "waypoints": len(waypoints),
    }


def _lineage(arrivals: list[np.ndarray], parents: list[int | None], last: int) -> list[np.ndarray]:
    """The waypoints from the start to landmark ``last``: each landmark's arrival from its parent, in order."""
    chain = []
    index: int | None = last
    while index is not None:
        chain.append(arrivals[index])
        index = parents[index]
    return chain[::-1]


def run_peer(
    name: str,
    count: int,
    time_limit_s: float,
    seed: int,
    step_rad: float,
    *,
    with_ompl: bool = True,
    checker: str = "is_valid",
) -> dict:
    matches = select(all_worlds(), name)
    if len(matches) != 1:
        raise SystemExit(f"peer: expected one world named {name!r}, found {len(matches)}")
    world = check_start_and_goal(world_from_parameters(matches[0].parameters))
    problems = transit_problems(world, count, seed)
    reason = ompl_unavailable_reason() if with_ompl else "skipped (--no-ompl)"
    out = {
        "world": world.name,
        "problems": len(problems),
        "time_limit_s": time_limit_s,
        "step_rad": step_rad,
        "ompl_available": reason is None,
        "ompl_reason": reason,
        "ompl_checker": checker,
    }
    out["project"] = [project_transit(world, a, b, time_limit_s, seed + i) for i, (a, b) in enumerate(problems)]
    out["ompl"] = solve_ompl(world, problems, time_limit_s, step_rad, checker) if reason is None else None
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m benchmarks.peer", description=__doc__.split("\n\n")[0])
    parser.add_argument("world")
    parser.add_argument("--problems", type=int, default=20)
    parser.add_argument("--time-limit", type=float, default=10.0, help="per problem and planner (s)")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument(
        "--step-rad",
        type=float,
        default=0.002,
        help="OMPL motion-check step, joint-space L2 (rad); default the contract's 0.002",
    )
    parser.add_argument(
        "--checker",
        choices=("is_valid", "loop"),
        default="is_valid",
        help="OMPL's validity test: the project's is_valid (states one by one, motions batched; "
        "default) or the per-state shapely loop of benchmarks.throughput",
    )
    parser.add_argument("--no-ompl", action="store_true")
    args = parser.parse_args(argv)
    result = run_peer(
        args.world,
        args.problems,
        args.time_limit,
        args.seed,
        args.step_rad,
        with_ompl=not args.no_ompl,
        checker=args.checker,
    )
    sys.stdout.write(json.dumps(result) + "\n")
    sys.stdout.flush()
    os._exit(0)  # skip interpreter teardown: nanobind (ompl 2.x) prints leak warnings at exit


if __name__ == "__main__":
    main()
