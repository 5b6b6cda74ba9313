"""SEARCH_TRANSIT and SEARCH_TRANSFER: local planners as optimisation (paper 1.3.2, 1.3.4).

Both minimise a distance over Manhattan paths of order k coded with bouncing
(so every candidate is collision-free), with the genetic algorithm, repeating
from the best end point while it improves (the paper's do-while loop). A short
numeric refinement then closes the last millimetres: damped least squares on a
finite-difference Jacobian, applied as single-joint moves clamped to their
free intervals. Inverse kinematics never builds a Manhattan path, so redundant
arms work alike; configurations that hold a grasp (closed form for two joints,
sampled for more: :mod:`clew_ros.core.reach`) refuse hopeless transits, for two
joints steer the elbow, and give SEARCH_TRANSIT's greedy probe a configuration to
head for before the GA (:func:`_greedy_probe`: one Manhattan path, bounced into
the free intervals like any other, kept when it gets closer); SEARCH_TRANSFER's
probe heads for the nearest configuration holding the object at the goal
(:func:`transfer_probe_target`).

A SEARCH_TRANSFER that stalls near the goal (:data:`JOIN_RADIUS`) is joined to
it (:func:`join_stalled`): configurations that hold the object within the
goal's tolerances are found by inverse kinematics
(:func:`goal_configurations`) and reached by RRT-Connect in the same mode,
every move checked continuously (:func:`clew_ros.core.connect.join`), drawing
from a generator of its own. This departs from the paper (docs/algorithm.md).
"""

from __future__ import annotations

import dataclasses
import itertools
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from clew_ros.core.collision import is_valid, packed_world
from clew_ros.core.connect import join
from clew_ros.core.continuous import MIN_MARGIN_FACTOR, StopOnly, path_valid, straight_move_clear
from clew_ros.core.genetic import minimize_islands
from clew_ros.core.inverse import solve_point
from clew_ros.core.kernel import clearly_valid
from clew_ros.core.kinematics import compose, relative, tip_poses, transform_points, wrap_angle
from clew_ros.core.manhattan import Counters, ManhattanPaths, run_manhattan, single_moves
from clew_ros.core.reach import (
    HOLD_SAMPLES,
    approach_cell,
    approach_excess,
    goal_within_reach,
    holding_configurations,
    holding_configurations_aimed,
    holding_configurations_near,
    two_link_grasps,
    within_reach,
)
from clew_ros.core.settings import ManyJoints, PlannerSettings, Termination
from clew_ros.core.world import World

__all__ = [
    "PathResult",
    "PlanningContext",
    "SearchJob",
    "TransitRequest",
    "goal_configurations",
    "goal_error",
    "join_stalled",
    "local_search",
    "search_transfer",
    "search_transit",
    "search_transits",
    "transfer_probe_target",
]

#: One SEARCH_TRANSIT request: start joints ``(n,)``, the resting object's pose ``(3,)``, the grasp's index
#: and the allowed approach cells (or ``None``), see :func:`search_transit`.
TransitRequest = tuple[np.ndarray, np.ndarray, int, np.ndarray | None]

#: A SEARCH_TRANSFER that stalls closer to the goal than this fraction of the arm's reach (m / m) is joined
#: to it by RRT-Connect when it can be (:func:`join_stalled`).
JOIN_RADIUS = 0.3
#: Rounds of that RRT-Connect at most (each extends one tree a step, and the other as far as it is clear).
JOIN_ROUNDS = 30
#: Seeds of the inverse kinematics for SEARCH_TRANSFER's goal configurations: the stalled one and random ones.
GOAL_SEEDS = 8
#: A join's generator is seeded with (planner.seed, this, where the search stalled): its own stream.
JOIN_STREAM = 13


@dataclass
class PlanningContext:
    """Everything one planning run shares: world, settings, randomness, stop test, counters."""

    world: World
    settings: PlannerSettings
    rng: np.random.Generator
    termination: Termination = field(default_factory=Termination)
    counters: Counters = field(default_factory=Counters)
    #: Random starts of the holding configurations that decide whether a transit is hopeless (more of them
    #: after an EXPLORE round that found no transit at all: :func:`clew_ros.core.reach.holding_configurations`
    #: answers the same request with the same sample, so a retry must draw a larger one).
    hold_samples: int = HOLD_SAMPLES
    #: Whether a stalled SEARCH_TRANSIT is joined to its holding configurations (:func:`join_stalled`): only
    #: from an EXPLORE round that found no transit at all to the next that finds one (elsewhere joins cost
    #: more than they save).
    transit_joins: bool = False
    #: how the search adapts to arms of many joints
    many: ManyJoints = field(default_factory=ManyJoints)

    def manhattan(self, q0: np.ndarray, genes: np.ndarray, **mode: np.ndarray) -> ManhattanPaths:
        return run_manhattan(
            self.world,
            q0,
            genes,
            margin_m=self.settings.clearance,
            counters=self.counters,
            should_stop=self.termination,
            threads=self.settings.threads,
            **mode,
        )

    def initial_genes(self, count: int, islands: int | None = None) -> np.ndarray:
        """Random Manhattan genes ``(count, k, n)`` (``(islands, count, k, n)``); the first individual
        (of each island) stays put."""
        n = self.world.robot.dof
        shape = (count, self.settings.manhattan_order, n)
        genes = self.rng.normal(0.0, 1.2, size=shape if islands is None else (islands, *shape))
        genes[..., 0, :, :] = 0.0
        return genes


@dataclass
class PathResult:
    success: bool
    waypoints: np.ndarray  # (m, n), starting at the start configuration
    distance: float  # final value of the objective (m)
    grasp_rel: np.ndarray | None = None  # transit: object pose in the end-effector frame at the grasp
    object_pose: np.ndarray | None = None  # transfer: where the object ends


@dataclass
class SearchJob:
    """One local search: from ``q0``, minimise ``objective(final_q, object_poses)``; refinement drives
    ``error(q)`` ``(B, m)`` below ``accept``. ``pose``: the resting object's pose (transit) or its
    pose in the end-effector frame (transfer), as ``mode`` says."""

    q0: np.ndarray
    objective: Callable[[np.ndarray, np.ndarray], np.ndarray]
    error: Callable[[np.ndarray], np.ndarray]
    accept: float
    mode: dict[str, np.ndarray]  # {"object_poses": (1, 3)} (transit) or {"grasp_rel": (1, 3)} (transfer)
    #: The configurations ``(m, n)`` a search that stalled at ``q`` may be joined to, drawn from a generator
    #: (:func:`join_stalled`), or ``None``.
    targets: Callable[[np.ndarray, np.random.Generator], np.ndarray] | None = None
    join_within: float = 0.0  # m: a search stalled farther than this from its target is not joined
    #: A configuration ``(n,)`` that meets the target, which the greedy probe heads for (:func:`_greedy_probe`);
    #: ``None``: no probe.
    toward: np.ndarray | None = None
    #: Configurations ``(m, n)`` meeting the target, nearest first, that a straight joint-space move
    #: from ``q0`` may reach (:func:`_straight_probe`, arms of many joints); ``None``: no such probe.
    straight: np.ndarray | None = None

    @property
    def pose(self) -> np.ndarray:
        pose: np.ndarray = next(iter(self.mode.values()))[0]
        return pose


#: Whether SEARCH_TRANSIT first tries one Manhattan path straight to the nearest holding configuration
#: (:func:`_greedy_probe`) before the GA rounds; ``False`` is the search as the paper has it.
GREEDY_PROBE = True
#: Whether SEARCH_TRANSFER's greedy probe heads for the nearest of its goal configurations
#: (:func:`goal_configurations`); ``False``: transfers start with the GA (as with ``GREEDY_PROBE`` off).
TRANSFER_PROBE = True
#: The transfer probe's inverse kinematics draws from a generator seeded with (planner.seed, this, where
#: the transfer starts): its own stream, as a join's.
PROBE_STREAM = 17


def local_search(ctx: PlanningContext, jobs: list[SearchJob]) -> list[tuple[np.ndarray, float]]:
    """SEARCH's do-while loop for independent jobs at once: a greedy probe (:func:`_greedy_probe`), GA
    rounds from each job's best end point (the jobs' populations are islands of one batch,
    :func:`minimize_islands`), then refinement.

    All jobs are transits or all are transfers. Returns each job's waypoints and final objective.
    """
    n = ctx.world.robot.dof
    k = ctx.settings.manhattan_order
    size = ctx.settings.population
    key = next(iter(jobs[0].mode))  # "object_poses" (transit) or "grasp_rel" (transfer)
    poses = np.array([job.pose for job in jobs])
    q = np.array([np.asarray(job.q0, dtype=float) for job in jobs])
    waypoints: list[list[np.ndarray]] = [[row[None].copy()] for row in q]
    best = np.array(
        [float(job.objective(q[i][None], _object_at(ctx, q[i][None], job.mode))[0]) for i, job in enumerate(jobs)]
    )
    refine_radius = 0.15 * ctx.world.robot.reach
    _straight_probe(ctx, jobs, q, best, waypoints)
    if GREEDY_PROBE:
        _greedy_probe(ctx, jobs, q, best, waypoints, key=key, poses=poses, target=refine_radius * 0.2)
    searching = np.arange(len(jobs))
    if not ctx.many.transit_ga:  # arms of many joints: a transit is the straight probe's, or none
        searching = np.array([i for i, job in enumerate(jobs) if job.straight is None], dtype=int)
    for _ in range(ctx.settings.search_rounds):
        searching = searching[best[searching] > refine_radius * 0.2]
        if not len(searching) or ctx.termination():
            break
        starts = q[searching]

        def evaluate(
            population: np.ndarray,
            islands: np.ndarray,
            *,
            starts: np.ndarray = starts,
            searching: np.ndarray = searching,
        ) -> np.ndarray:  # this round's starts and jobs
            count, children = population.shape[:2]
            paths = ctx.manhattan(
                np.repeat(starts[islands], children, axis=0),
                population.reshape(-1, k, n),
                **{key: np.repeat(poses[searching[islands]], children, axis=0)},
            )
            ctx.counters.evaluations += count * children
            finals = paths.final.reshape(count, children, n)
            ends = paths.object_poses.reshape(count, children, 3)
            return np.array([jobs[searching[island]].objective(finals[a], ends[a]) for a, island in enumerate(islands)])

        initial = ctx.initial_genes(size, islands=len(searching)).reshape(len(searching), size, k * n)
        results = minimize_islands(
            evaluate,
            initial,
            ctx.rng,
            ctx.settings.genetic,
            targets=np.full(len(searching), refine_radius * 0.2),
            should_stop=ctx.termination,
        )
        moved = np.array(
            [result.fitness < best[i] - 1e-4 for i, result in zip(searching, results, strict=True)], dtype=bool
        )  # else a local minimum: the end point did not move closer
        if not moved.any():
            break
        genes = np.array([result.genes for result in results])[moved].reshape(-1, k, n)
        searching = searching[moved]
        paths = ctx.manhattan(q[searching], genes, **{key: poses[searching]})
        for row, i in enumerate(searching):
            waypoints[i].append(paths.waypoints[row, 1:])
            q[i] = paths.final[row]
            best[i] = float(jobs[i].objective(q[i][None], _object_at(ctx, q[i][None], jobs[i].mode))[0])
    answers = []
    for i, job in enumerate(jobs):
        if best[i] <= refine_radius:
            refined = _refine(ctx, q[i], job.error, job.accept, job.mode)
            waypoints[i].append(refined[1:])
            q[i] = refined[-1]
            best[i] = float(job.objective(q[i][None], _object_at(ctx, q[i][None], job.mode))[0])
        answers.append((np.concatenate(waypoints[i]), float(best[i])))
    return answers


def _greedy_probe(
    ctx: PlanningContext,
    jobs: list[SearchJob],
    q: np.ndarray,
    best: np.ndarray,
    waypoints: list[list[np.ndarray]],
    *,
    key: str,
    poses: np.ndarray,
    target: float,
) -> None:
    """Before the GA, every job with a configuration to head for (``toward``) and not yet within
    ``target`` tries one Manhattan path: each joint in turn moved by what separates it from ``toward``,
    bounced into its free interval as a GA individual's gene would be (RRT-Connect's greedy connection
    to its goal, one joint at a time), the object at the jobs' ``poses`` under mode ``key`` (as
    :func:`local_search` has them). Kept, in ``q``, ``best`` and ``waypoints``, where it gets closer.
    One decoded path per job, cheap next to a generation; where the way is open the GA has nothing
    left to do."""
    probe = [i for i in np.flatnonzero(best > target) if jobs[i].toward is not None]
    if not probe:
        return
    genes = np.zeros((len(probe), ctx.settings.manhattan_order, ctx.world.robot.dof))
    for a, i in enumerate(probe):
        genes[a, 0] = np.asarray(jobs[i].toward) - q[i]
    paths = ctx.manhattan(q[probe], genes, **{key: poses[probe]})
    ctx.counters.evaluations += len(probe)
    for a, i in enumerate(probe):
        value = float(jobs[i].objective(paths.final[a][None], paths.object_poses[a][None])[0])
        if value < best[i] - 1e-4:
            waypoints[i].append(paths.waypoints[a, 1:])
            q[i] = paths.final[a]
            best[i] = value


def _straight_probe(
    ctx: PlanningContext, jobs: list[SearchJob], q: np.ndarray, best: np.ndarray, waypoints: list[list[np.ndarray]]
) -> None:
    """Jobs with ``straight`` configurations (transits of arms of many joints, :class:`ManyJoints`) try a
    straight joint-space move from their start to each, nearest first, checked continuously with
    :data:`~clew_ros.core.continuous.MIN_MARGIN_FACTOR` x the clearance as the improvement's moves are
    (valid at any checking step); the first clear one ends the search there. Draws nothing at random."""
    world = ctx.world
    for i, job in enumerate(jobs):
        if job.straight is None or not len(job.straight) or ctx.termination():
            continue
        targets = job.straight
        pose = job.pose if "object_poses" in job.mode else None
        rel = job.pose if "grasp_rel" in job.mode else None
        starts = np.broadcast_to(q[i], targets.shape)
        clear = _sampled_clear(world, starts, targets, object_pose=pose, grasp_rel=rel)
        if clear.any():
            clear[clear] = _moves_clear_stopping(
                ctx, starts[clear], targets[clear], object_pose=pose, grasp_rel=rel, until=True
            )
        way = targets[int(np.argmax(clear))][None] if clear.any() else None
        if way is None:  # by way of a retreat along the tip's heading and an approach along the target's
            back = ctx.many.approach_radii * world.object.radius / 2
            retreat = _backed_line(world, q[i], back, ctx.many.approach_steps // 2) or []
            for target in targets if retreat else []:
                if ctx.termination():
                    break
                approach = _backed_line(world, target, back, ctx.many.approach_steps // 2)
                if approach is None:
                    continue
                path = np.array([q[i], *retreat, *approach[::-1], target])
                if not _sampled_clear(world, path[:-1], path[1:], object_pose=pose, grasp_rel=rel).all():
                    continue
                if _moves_clear_stopping(ctx, path[:-1], path[1:], object_pose=pose, grasp_rel=rel, until=False).all():
                    way = path[1:]
                    break
        if way is not None:
            reached = way[-1]
            value = float(job.objective(reached[None], _object_at(ctx, reached[None], job.mode))[0])
            if value < best[i]:
                waypoints[i].append(way.copy())
                q[i] = reached
                best[i] = value


def join_stalled(
    ctx: PlanningContext, job: SearchJob, waypoints: np.ndarray, distance: float
) -> tuple[np.ndarray, float]:
    """A search that failed, stalled near its target (``distance`` at most ``job.join_within``), extended by
    RRT-Connect to one of ``job.targets`` (in the same mode, every move checked continuously with
    :data:`clew_ros.core.continuous.MIN_MARGIN_FACTOR` x the clearance, at most :data:`JOIN_ROUNDS` rounds,
    then once more at the validator's 0.002 rad); its waypoints and objective, unchanged when no way was
    found."""
    world = ctx.world
    if job.targets is None or distance > job.join_within:
        return waypoints, distance
    stalled = waypoints[-1]
    # a generator of the join's own, seeded by the planner's seed and where the search stalled: a join that
    # fails leaves the run's random stream, and so the rest of the run, as they would have been without it
    rng = _own_generator(ctx, JOIN_STREAM, stalled, job.pose)
    targets = job.targets(stalled, rng)
    if not len(targets) or ctx.termination():
        return waypoints, distance
    pose = job.mode.get("object_poses")
    held = job.mode.get("grasp_rel")
    mode = {"object_pose": None if pose is None else pose[0], "grasp_rel": None if held is None else held[0]}
    path = join(
        world,
        stalled,
        targets,
        rng,
        **mode,
        min_margin=MIN_MARGIN_FACTOR * ctx.settings.clearance,
        rounds=JOIN_ROUNDS,
        stop=ctx.termination,
    )
    if path is None or not path_valid(world, path, **mode):
        return waypoints, distance
    end = path[-1:]
    return np.vstack([waypoints, path[1:]]), float(job.objective(end, _object_at(ctx, end, job.mode))[0])


def _own_generator(ctx: PlanningContext, stream: int, q: np.ndarray, pose: np.ndarray) -> np.random.Generator:
    """A generator seeded with (planner.seed, ``stream``, the request: configuration ``q`` and ``pose``), for
    work that must leave the run's random stream as it was (a join, the transfer probe's inverse kinematics)."""
    request = np.frombuffer(np.round(np.r_[q, pose], 9).tobytes(), dtype=np.uint32)
    return np.random.default_rng([ctx.settings.seed, stream, *request.tolist()])


def _object_at(ctx: PlanningContext, q: np.ndarray, mode: dict[str, np.ndarray]) -> np.ndarray:
    if mode.get("grasp_rel") is None:
        return np.broadcast_to(mode["object_poses"], (len(q), 3))
    return compose(tip_poses(ctx.world.robot, q), mode["grasp_rel"])


def _refine(
    ctx: PlanningContext,
    q: np.ndarray,
    error: Callable[[np.ndarray], np.ndarray],
    accept: float,
    mode: dict[str, np.ndarray],
    *,
    iterations: int = 30,
) -> np.ndarray:
    """Damped least squares on ``error``, moved one joint at a time within free intervals."""
    n = len(q)
    waypoints = [q.copy()]
    h = 1e-6
    for _ in range(iterations):
        if ctx.termination():
            break
        e = error(q[None])[0]
        if np.linalg.norm(e) <= accept:
            break
        jacobian = (error(q[None] + h * np.eye(n)) - e[None]).T / h  # (m, n)
        damping = 1e-4
        step = -jacobian.T @ np.linalg.solve(jacobian @ jacobian.T + damping * np.eye(len(e)), e)
        largest = np.max(np.abs(step))
        if largest > 0.3:
            step *= 0.3 / largest
        moved = single_moves(ctx.world, q, step, margin_m=ctx.settings.clearance, counters=ctx.counters, **mode)
        if len(moved) < 2 or np.max(np.abs(moved[-1] - q)) < 1e-10:
            break
        waypoints.extend(moved[1:])
        if np.linalg.norm(error(moved[-1][None])[0]) >= np.linalg.norm(e) - 1e-9:
            q = moved[-1]
            break  # clamped by an obstacle: no more progress
        q = moved[-1]
    return np.array(waypoints)


def search_transit(
    ctx: PlanningContext, q0: np.ndarray, object_pose: np.ndarray, grasp: int, approach: np.ndarray | None = None
) -> PathResult:
    """SEARCH_TRANSIT: move the arm, object at rest, until its tip holds ``grasp``.

    ``approach`` (cells of :func:`clew_ros.core.reach.approach_cells`) restricts
    the last link's direction in the object's frame: the residual gains the
    angle to the nearest allowed cell, times the last link's length. For a
    two-joint arm whose valid holding configurations all bend the elbow one
    way, the residual also gains how far the elbow bends the other way.
    """
    return search_transits(ctx, [(q0, object_pose, grasp, approach)])[0]


def search_transits(ctx: PlanningContext, requests: list[TransitRequest]) -> list[PathResult]:
    """:func:`search_transit` for independent requests ``(q0, object_pose, grasp, approach)`` at once:
    their genetic algorithms run as islands of one batch."""
    world = ctx.world
    results: list[PathResult | None] = []
    jobs, slots = [], []
    many = world.robot.dof >= ctx.many.straight_probe_joints
    samples = max(ctx.hold_samples, ctx.many.hold_samples) if many else ctx.hold_samples
    for q0, object_pose, grasp, approach in requests:
        job = _transit_job(
            world,
            np.asarray(q0, float),
            np.asarray(object_pose, float),
            grasp,
            approach,
            samples=samples,
            joins=ctx.transit_joins,
            straight=ctx.many.straight_probes if many else 0,
            many=ctx.many if many else None,
        )
        if isinstance(job, PathResult):
            results.append(job)
        else:
            slots.append(len(results))
            results.append(None)
            jobs.append(job)
    if jobs:
        for slot, job, (found, reached) in zip(slots, jobs, local_search(ctx, jobs), strict=True):
            success = reached <= 0.5 * world.grasp_tolerance
            waypoints, distance = (found, reached) if success else join_stalled(ctx, job, found, reached)
            success = distance <= 0.5 * world.grasp_tolerance
            grasp_rel = relative(tip_poses(world.robot, waypoints[-1:])[0], job.pose) if success else None
            results[slot] = PathResult(success, waypoints, distance, grasp_rel=grasp_rel)
    return [result for result in results if result is not None]  # every slot is filled by now


def _transit_job(
    world: World,
    q0: np.ndarray,
    object_pose: np.ndarray,
    grasp: int,
    approach: np.ndarray | None,
    *,
    samples: int,
    joins: bool,
    straight: int = 0,
    many: ManyJoints | None = None,
) -> SearchJob | PathResult:
    """SEARCH_TRANSIT's objective for one request, or its failure when it is hopeless. Arms of ``many``
    joints also get holds solved from ``q0`` itself (:func:`holding_configurations_near`)."""
    target = transform_points(object_pose, world.object.grasps[grasp][None])  # (1, 2)
    holds = _holding_configurations(world, object_pose, grasp, approach, samples, aimed=straight > 0)
    if many is not None:
        near = holding_configurations_near(
            world, q0, object_pose, grasp, approach, starts=many.near_holds, spread_rad=many.near_spread_rad
        )
        holds = np.vstack([near, holds])
    excess = approach_excess(approach) if approach is not None else None
    last = float(world.robot.link_lengths[-1])
    two_joints = world.robot.dof == 2
    bends = np.unique(np.sign(wrap_angle(holds[:, 1]))) if two_joints else np.zeros(0)
    elbow = float(bends[0]) if len(bends) == 1 and bends[0] != 0 else None

    def tip_error(q: np.ndarray) -> np.ndarray:
        tips = tip_poses(world.robot, q)
        terms = [tips[:, :2] - target]
        if excess is not None:
            terms.append(last * excess(tips[:, 2] - object_pose[2])[:, None])
        if elbow is not None:
            terms.append(last * np.maximum(0.0, -elbow * wrap_angle(q[:, 1]))[:, None])
        return np.concatenate(terms, axis=1)

    def objective(q: np.ndarray, _poses: np.ndarray | None) -> np.ndarray:
        distance: np.ndarray = np.linalg.norm(tip_error(q), axis=1)
        return distance

    hopeless = (approach is not None and not approach.any()) or not len(holds)
    if hopeless or not within_reach(world, target[0]):
        return PathResult(False, q0[None], float(objective(q0[None], None)[0]))
    mode = {"object_poses": object_pose[None]}
    held = holds[objective(holds, None) <= 0.5 * world.grasp_tolerance]  # the transit's own success test
    # the greedy probe heads for the nearest of them (joint travel)
    toward = held[np.argmin(np.abs(held - q0).sum(axis=1))] if len(held) else None
    nearest = held[np.argsort(np.abs(held - q0).sum(axis=1), kind="stable")[:straight]] if straight else None
    if not joins:
        return SearchJob(q0, objective, tip_error, 0.25 * world.grasp_tolerance, mode, toward=toward, straight=nearest)

    def targets(_stalled: np.ndarray, _rng: np.random.Generator) -> np.ndarray:
        return held

    within = JOIN_RADIUS * world.robot.reach
    return SearchJob(q0, objective, tip_error, 0.25 * world.grasp_tolerance, mode, targets, within, toward, nearest)


def _holding_configurations(
    world: World,
    object_pose: np.ndarray,
    grasp: int,
    approach: np.ndarray | None,
    samples: int,
    *,
    aimed: bool = False,
) -> np.ndarray:
    """The valid configurations holding ``grasp`` (with an allowed approach), which a transit can
    only end near: all of them for two-joint arms (:func:`two_link_grasps`), a sample for others
    (:func:`holding_configurations`). Empty: the transit is given up as hopeless."""
    if world.robot.dof == 2:
        holds = two_link_grasps(world, object_pose, grasp)
    else:
        holds = holding_configurations(world, object_pose, grasp, samples)
    if approach is None or (not len(holds) and not aimed):
        return holds
    psi = tip_poses(world.robot, holds)[:, 2] - object_pose[2]
    allowed: np.ndarray = holds[approach[approach_cell(psi, len(approach))]]
    if aimed:  # arms of many joints: few unaimed samples come in at an allowed angle
        allowed = np.vstack([allowed, holding_configurations_aimed(world, object_pose, grasp, approach, samples)])
    return allowed


def goal_error(world: World, object_poses: np.ndarray, goal: np.ndarray) -> np.ndarray:
    """Residual ``(B, 3)`` between object poses and the goal: position (m), excess angle as arc (m)."""
    d_theta = wrap_angle(object_poses[:, 2] - goal[2])
    slack = np.inf if world.goal_angle_tolerance >= np.pi - 1e-6 else 0.8 * world.goal_angle_tolerance
    excess = np.sign(d_theta) * np.maximum(0.0, np.abs(d_theta) - slack)
    return np.concatenate([object_poses[:, :2] - goal[:2], world.object.radius * excess[:, None]], axis=1)


def goal_reached(world: World, object_pose: np.ndarray, goal: np.ndarray) -> bool:
    """Whether ``object_pose`` is within the goal tolerances of ``goal`` (section 2)."""
    return bool(goals_reached(world, np.asarray(object_pose, dtype=float)[None], goal)[0])


def goals_reached(world: World, object_poses: np.ndarray, goal: np.ndarray) -> np.ndarray:
    """Which of ``object_poses`` ``(B, 3)`` are within the goal tolerances of ``goal``, as :func:`goal_reached`."""
    position = np.hypot(object_poses[:, 0] - goal[0], object_poses[:, 1] - goal[1])
    angle = np.abs(wrap_angle(object_poses[:, 2] - goal[2]))
    reached: np.ndarray = (position <= world.goal_tolerance) & (angle <= world.goal_angle_tolerance + 1e-9)
    return reached


def goal_configurations(
    world: World,
    q0: np.ndarray,
    grasp_rel: np.ndarray,
    goal: np.ndarray,
    rng: np.random.Generator,
    *,
    min_margin: float = 0.0,
) -> np.ndarray:
    """Configurations ``(m, n)`` valid with ``min_margin`` (m) to spare (the compiled first pass) holding the
    object (as ``grasp_rel``) within the goal's tolerances, as SEARCH_TRANSFER's success asks, nearest ``q0``
    first: inverse kinematics (:func:`solve_point`) from ``q0``
    and :data:`GOAL_SEEDS` - 1 configurations drawn within the joint limits, once for the goal's own angle (the
    middle of the tolerance, clear of a pocket's walls when the arm can hold it there) and once for any angle
    within the tolerance (for an arm that cannot)."""
    robot = world.robot
    drawn = rng.uniform(robot.joint_lower, robot.joint_upper, (GOAL_SEEDS - 1, robot.dof))
    seeds = np.vstack([np.asarray(q0, float)[None], drawn])
    grasp_rel = np.asarray(grasp_rel, float)
    within = np.pi if world.goal_angle_tolerance >= np.pi - 1e-6 else 0.8 * world.goal_angle_tolerance
    q = np.vstack(
        [
            solve_point(
                robot,
                seeds,
                np.asarray(goal[:2], float)[None],
                offsets=grasp_rel[None, :2],
                angles=np.array([goal[2] - grasp_rel[2]]),
                angle_tolerance=tolerance,
                angle_scale=world.object.radius,
                tolerance_m=0.1 * world.goal_tolerance,
            ).q
            for tolerance in (0.0, within)
        ]
    )
    poses = compose(tip_poses(robot, q), grasp_rel)
    close = np.linalg.norm(goal_error(world, poses, goal), axis=1) <= 0.5 * world.goal_tolerance
    held = close & goals_reached(world, poses, goal)
    if held.any():  # the margin a join's first move from it asks for (clew_ros.core.continuous)
        rounded = dataclasses.replace(packed_world(world), rounding=min_margin)
        held[held] = clearly_valid(rounded, np.ascontiguousarray(q[held]), poses[held])
    found = q[held][np.argsort(np.max(np.abs(q[held] - q0), axis=1), kind="stable")]
    distinct = [i for i in range(len(found)) if not any(np.max(np.abs(found[i] - found[:i]), axis=1) < 1e-3)]
    kept: np.ndarray = found[distinct]
    return kept


def transfer_probe_target(
    ctx: PlanningContext, q0: np.ndarray, grasp_rel: np.ndarray, goal: np.ndarray
) -> np.ndarray | None:
    """The configuration SEARCH_TRANSFER's greedy probe heads for: the nearest (largest joint move) of
    :func:`goal_configurations` from ``q0``, drawn from a generator of its own seeded by the planner's seed
    and the request (the run's stream stays as it was); ``None`` when the probe is off or no configuration
    holds the object at the goal."""
    if not (GREEDY_PROBE and TRANSFER_PROBE):
        return None
    rng = _own_generator(ctx, PROBE_STREAM, q0, grasp_rel)
    margin = MIN_MARGIN_FACTOR * ctx.settings.clearance
    held = goal_configurations(ctx.world, q0, grasp_rel, goal, rng, min_margin=margin)
    return held[0] if len(held) else None


def _moves_clear_stopping(
    ctx: PlanningContext,
    starts: np.ndarray,
    ends: np.ndarray,
    *,
    object_pose: np.ndarray | None = None,
    grasp_rel: np.ndarray | None = None,
    until: bool,
) -> np.ndarray:
    """Arms of many joints: :func:`~clew_ros.core.continuous.straight_moves_clear` (``MIN_MARGIN_FACTOR`` x the
    clearance) of each move ``starts[k] -> ends[k]`` in turn, each split into pieces that sweep at most
    :attr:`ManyJoints.check_sweep_m` (the bound ``sum_j |dq_j| R_j`` of the check's module), the termination
    asked before each piece: one compiled check of a long move near a contact can take seconds, past the time
    limit. The moves are checked in order until the first whose answer is ``until`` (the first clear one, or
    the first blocked one); the others, and a move whose check was stopped, come back not clear."""
    world = ctx.world
    lengths = world.robot.link_lengths
    arm = np.cumsum(lengths[::-1])[::-1] + (world.object.radius if grasp_rel is not None else 0.0)
    margin = MIN_MARGIN_FACTOR * ctx.settings.clearance
    budget = StopOnly(ctx.termination)
    out = np.zeros(len(starts), dtype=bool)
    for k, (a, b) in enumerate(zip(starts, ends, strict=True)):
        sweep = float(np.abs(b - a) @ arm)
        t = np.linspace(0.0, 1.0, max(1, int(np.ceil(sweep / ctx.many.check_sweep_m))) + 1)[:, None]
        points = a + t * (b - a)
        out[k] = all(
            straight_move_clear(
                world, p, r, object_pose=object_pose, grasp_rel=grasp_rel, min_margin=margin, budget=budget
            )
            for p, r in itertools.pairwise(points)
        )
        if out[k] == until or budget.stop():
            break
    return out


def _sampled_clear(
    world: World,
    starts: np.ndarray,
    ends: np.ndarray,
    *,
    object_pose: np.ndarray | None = None,
    grasp_rel: np.ndarray | None = None,
    step_rad: float = 0.05,
) -> np.ndarray:
    """Whether each straight move ``starts[k] -> ends[k]`` is valid at configurations ``step_rad`` apart (a
    quick screen, so that the continuous check, which can take seconds on a long move of many joints
    near a contact, runs only on moves that look clear)."""
    counts = np.maximum(1, np.ceil(np.abs(ends - starts).max(axis=1) / step_rad).astype(int))
    piece = np.repeat(np.arange(len(starts)), counts + 1)
    offsets = np.cumsum(counts + 1) - (counts + 1)
    t = (np.arange(len(piece)) - offsets[piece]) / counts[piece]
    q = starts[piece] + t[:, None] * (ends[piece] - starts[piece])
    if grasp_rel is not None:
        poses = compose(tip_poses(world.robot, q), np.asarray(grasp_rel, float)[None])
    else:
        poses = np.broadcast_to(np.asarray(object_pose, float), (len(q), 3))
    bad = np.unique(piece[~is_valid(world, q, poses)])
    clear = np.ones(len(starts), dtype=bool)
    clear[bad] = False
    return clear


def _backed_line(
    world: World, q: np.ndarray, back: float, steps: int, toward: np.ndarray | None = None
) -> list[np.ndarray] | None:
    """Configurations from ``q`` (excluded) with the tip backed by ``back`` (m) in ``steps`` equal steps
    against its own heading (or, with ``toward``, straight away from the point ``toward``),
    its angle kept (inverse kinematics from the previous one); ``None`` when the arm cannot follow that line."""
    robot = world.robot
    tip = tip_poses(robot, q[None])[0]
    heading = np.array([np.cos(tip[2]), np.sin(tip[2])])
    if toward is not None and np.linalg.norm(tip[:2] - toward) > 1e-9:
        heading = (toward - tip[:2]) / np.linalg.norm(toward - tip[:2])  # backed away from ``toward``
    line = [q]
    steps = max(steps, int(np.ceil(back / 0.02)))  # 2 cm at most a step, for the solver to follow
    for step in range(1, steps + 1):
        point = tip[:2] - back * step / steps * heading
        solved = solve_point(
            robot, line[-1][None], point[None], angles=np.array([tip[2]]), angle_tolerance=1e-4, iterations=100
        )
        reached = tip_poses(robot, solved.q)[0]
        if np.linalg.norm(reached[:2] - point) > 1e-4 or abs(wrap_angle(reached[2] - tip[2])) > 1e-3:
            return None
        line.append(solved.q[0])
    return line[1:]


def _straight_transfer(ctx: PlanningContext, job: SearchJob, goal: np.ndarray) -> PathResult | None:
    """Arms of many joints (:class:`ManyJoints`): SEARCH_TRANSFER by straight joint-space moves, checked
    continuously, to a configuration holding the object at the goal (:func:`goal_configurations`, nearest
    first), directly or by way of the line along which the tip, backed along its own heading, puts the
    object in place; ``None`` when none is clear. Its own generator (the run's stream is untouched)."""
    world, many = ctx.world, ctx.many
    grasp_rel = job.pose
    rng = _own_generator(ctx, PROBE_STREAM + 1, job.q0, grasp_rel)
    margin = MIN_MARGIN_FACTOR * ctx.settings.clearance
    held = goal_configurations(world, job.q0, grasp_rel, goal, rng, min_margin=margin)[: many.straight_probes]
    back = many.approach_radii * world.object.radius
    for target in held:
        if ctx.termination():
            return None
        ways = [np.array([job.q0, target])]
        # the object backed out along the line from its origin to the grasp, as a gripper pulls it
        origin = compose(tip_poses(world.robot, target[None]), grasp_rel[None])[0, :2]
        line = _backed_line(world, target, back, many.approach_steps, toward=origin)
        if line is not None:
            ways.append(np.array([job.q0, *line[::-1], target]))
            turned = job.q0.copy()  # the whole arm turned by joint 1 first (rigidly), then straight
            turned[0] = line[-1][0]
            ways.append(np.array([job.q0, turned, *line[::-1], target]))
        for way in ways:
            if not _sampled_clear(world, way[:-1], way[1:], grasp_rel=grasp_rel).all():
                continue
            if _moves_clear_stopping(ctx, way[:-1], way[1:], grasp_rel=grasp_rel, until=False).all():
                pose = compose(tip_poses(world.robot, way[-1:]), grasp_rel[None])[0]
                distance = float(np.linalg.norm(goal_error(world, pose[None], goal)[0]))
                if goal_reached(world, pose, goal) and distance <= 0.5 * world.goal_tolerance:
                    return PathResult(True, way, distance, object_pose=pose)
    return None


def search_transfer(
    ctx: PlanningContext, q0: np.ndarray, grasp_rel: np.ndarray, goal: np.ndarray, *, joins: bool = True
) -> PathResult:
    """SEARCH_TRANSFER: carry the object (held as ``grasp_rel``) toward the ``goal`` placement; stalled near it,
    joined to it (:func:`join_stalled`, towards :func:`goal_configurations`) unless ``joins`` is false."""
    world = ctx.world
    mode = {"grasp_rel": np.asarray(grasp_rel, float)[None]}

    def error(q: np.ndarray) -> np.ndarray:
        return goal_error(world, compose(tip_poses(world.robot, q), mode["grasp_rel"]), goal)

    def objective(_q: np.ndarray | None, poses: np.ndarray) -> np.ndarray:
        distance: np.ndarray = np.linalg.norm(goal_error(world, poses, goal), axis=1)
        return distance

    accept = 0.25 * world.goal_tolerance
    if not goal_within_reach(world, grasp_rel, goal):
        start_pose = compose(tip_poses(world.robot, np.asarray(q0, float)[None]), mode["grasp_rel"])
        return PathResult(
            False, np.asarray(q0, float)[None], float(objective(None, start_pose)[0]), object_pose=start_pose[0]
        )

    def targets(stalled: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        margin = MIN_MARGIN_FACTOR * ctx.settings.clearance
        return goal_configurations(world, stalled, mode["grasp_rel"][0], goal, rng, min_margin=margin)

    within = JOIN_RADIUS * world.robot.reach
    toward = transfer_probe_target(ctx, np.asarray(q0, float), mode["grasp_rel"][0], goal)
    job = SearchJob(np.asarray(q0, float), objective, error, accept, mode, targets if joins else None, within, toward)
    if world.robot.dof >= ctx.many.straight_probe_joints:
        straight = _straight_transfer(ctx, job, goal)
        if straight is not None:
            return straight
    if world.robot.dof >= ctx.many.straight_probe_joints and not ctx.many.transfer_ga:
        start = np.asarray(q0, float)[None]
        waypoints, distance = start, float(objective(None, _object_at(ctx, start, mode))[0])
    else:
        [(waypoints, distance)] = local_search(ctx, [job])

    def succeeded(path: np.ndarray, reached: float) -> tuple[bool, np.ndarray]:
        pose = compose(tip_poses(world.robot, path[-1:]), mode["grasp_rel"])[0]
        return goal_reached(world, pose, goal) and reached <= 0.5 * world.goal_tolerance, pose

    success, final_pose = succeeded(waypoints, distance)
    if not success:
        waypoints, distance = join_stalled(ctx, job, waypoints, distance)
        success, final_pose = succeeded(waypoints, distance)
    return PathResult(success, waypoints, distance, object_pose=final_pose)
