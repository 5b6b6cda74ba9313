"""SEARCH's do-while loop: local planning as optimisation over Manhattan paths (paper 1.3.2, 1.3.4).

SEARCH_TRANSIT and SEARCH_TRANSFER both minimise a distance over Manhattan
paths of order k coded with bouncing (so every candidate is collision-free),
with the genetic algorithm, repeating from the best end point while it
improves (the paper's do-while loop). A short numeric refinement then closes
the last millimetres: damped least squares on a finite-difference Jacobian,
applied as single-joint moves clamped to their free intervals. Before the GA, a
job with a configuration to head for tries one Manhattan path towards it
(:func:`_greedy_probe`), and arms of many joints try straight moves
(:meth:`~clew_ros.core.space.Space.straight_probe`).

What a job minimises (its objective, its error, what it may be joined to) is
the space's: :meth:`~clew_ros.core.space.Space.search_transits` and
:meth:`~clew_ros.core.space.Space.search_transfer` build the jobs and call
:func:`local_search`; this module never looks at a world.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from clew_ros.core.genetic import minimize_islands
from clew_ros.core.space import Mode, PlanningContext, SearchJob

__all__ = ["SearchJob", "local_search", "object_at", "own_generator"]


def local_search(ctx: PlanningContext, jobs: list[SearchJob]) -> list[tuple[np.ndarray, float]]:
    """SEARCH's do-while loop for independent jobs at once: a greedy probe (:func:`_greedy_probe`), GA
    rounds from each job's best end point (the jobs' populations are islands of one batch,
    :func:`minimize_islands`), then refinement.

    All jobs are transits or all are transfers. Returns each job's waypoints and final objective.
    """
    n = ctx.space.dof
    k = ctx.settings.manhattan_order
    size = ctx.settings.population
    kind = jobs[0].mode  # all transits or all transfers: their poses stacked in this kind of mode
    poses = np.array([job.pose for job in jobs])
    q = np.array([np.asarray(job.q0, dtype=float) for job in jobs])
    waypoints: list[list[np.ndarray]] = [[row[None].copy()] for row in q]
    best = np.array(
        [float(job.objective(q[i][None], object_at(ctx, q[i][None], job.mode))[0]) for i, job in enumerate(jobs)]
    )
    refine_radius = ctx.search.refine_radius * ctx.space.reach
    ga_target = refine_radius * ctx.search.ga_target_share
    ctx.space.straight_probe(ctx, jobs, q, best, waypoints)
    if ctx.search.greedy_probe:
        _greedy_probe(ctx, jobs, q, best, waypoints, kind=kind, poses=poses, target=ga_target)
    searching = np.arange(len(jobs))
    if n >= ctx.many.straight_probe_joints and not ctx.many.transit_ga:  # a transit is the straight probe's, or none
        searching = np.array([i for i, job in enumerate(jobs) if job.straight is None], dtype=int)
    for _ in range(ctx.settings.search_rounds):
        searching = searching[best[searching] > ga_target]
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
                kind.with_poses(np.repeat(poses[searching[islands]], children, axis=0)),
            )
            ctx.counters.evaluations += count * children
            finals = paths.final.reshape(count, children, n)
            ends = paths.object_poses.reshape(count, children, -1)
            return np.array([jobs[searching[island]].objective(finals[a], ends[a]) for a, island in enumerate(islands)])

        initial = ctx.initial_genes(size, islands=len(searching)).reshape(len(searching), size, k * n)
        results = minimize_islands(
            evaluate,
            initial,
            ctx.rng,
            ctx.settings.genetic,
            targets=np.full(len(searching), ga_target),
            should_stop=ctx.termination,
        )
        moved = np.array(
            [result.fitness < best[i] - ctx.search.min_progress for i, result in zip(searching, results, strict=True)],
            dtype=bool,
        )  # else a local minimum: the end point did not move closer
        if not moved.any():
            break
        genes = np.array([result.genes for result in results])[moved].reshape(-1, k, n)
        searching = searching[moved]
        paths = ctx.manhattan(q[searching], genes, kind.with_poses(poses[searching]))
        for row, i in enumerate(searching):
            waypoints[i].append(paths.waypoints[row, 1:])
            q[i] = paths.final[row]
            best[i] = float(jobs[i].objective(q[i][None], object_at(ctx, q[i][None], jobs[i].mode))[0])
    answers = []
    for i, job in enumerate(jobs):
        if best[i] <= refine_radius:
            refined = _refine(ctx, q[i], job.error, job.accept, job.mode)
            waypoints[i].append(refined[1:])
            q[i] = refined[-1]
            best[i] = float(job.objective(q[i][None], object_at(ctx, q[i][None], job.mode))[0])
        answers.append((np.concatenate(waypoints[i]), float(best[i])))
    return answers


def _greedy_probe(
    ctx: PlanningContext,
    jobs: list[SearchJob],
    q: np.ndarray,
    best: np.ndarray,
    waypoints: list[list[np.ndarray]],
    *,
    kind: Mode,
    poses: np.ndarray,
    target: float,
) -> None:
    """Before the GA, every job with a configuration to head for (``toward``) and not yet within
    ``target`` tries one Manhattan path: each joint in turn moved by what separates it from ``toward``,
    bounced into its free interval as a GA individual's gene would be (RRT-Connect's greedy connection
    to its goal, one joint at a time), the object at the jobs' ``poses`` in a mode of ``kind`` (as
    :func:`local_search` has them). Kept, in ``q``, ``best`` and ``waypoints``, where it gets closer.
    One decoded path per job, cheap next to a generation; where the way is open the GA has nothing
    left to do."""
    probe = [i for i in np.flatnonzero(best > target) if jobs[i].toward is not None]
    if not probe:
        return
    genes = np.zeros((len(probe), ctx.settings.manhattan_order, ctx.space.dof))
    for a, i in enumerate(probe):
        genes[a, 0] = np.asarray(jobs[i].toward) - q[i]
    paths = ctx.manhattan(q[probe], genes, kind.with_poses(poses[probe]))
    ctx.counters.evaluations += len(probe)
    for a, i in enumerate(probe):
        value = float(jobs[i].objective(paths.final[a][None], paths.object_poses[a][None])[0])
        if value < best[i] - ctx.search.min_progress:
            waypoints[i].append(paths.waypoints[a, 1:])
            q[i] = paths.final[a]
            best[i] = value


def own_generator(ctx: PlanningContext, stream: int, q: np.ndarray, pose: np.ndarray) -> np.random.Generator:
    """A generator seeded with (planner.seed, ``stream``, the request: configuration ``q`` and ``pose``), for
    work that must leave the run's random stream as it was (a join, the transfer probe's inverse kinematics)."""
    request = np.frombuffer(np.round(np.r_[q, pose], 9).tobytes(), dtype=np.uint32)
    return np.random.default_rng([ctx.settings.seed, stream, *request.tolist()])


def object_at(ctx: PlanningContext, q: np.ndarray, mode: Mode) -> np.ndarray:
    """Where the object is at configurations ``q`` ``(B, n)`` in ``mode``: at rest, or held."""
    if not mode.transfer:
        return np.broadcast_to(mode.poses, (len(q), mode.poses.shape[-1]))
    return ctx.space.held_object_poses(q, mode.poses)


def _refine(
    ctx: PlanningContext,
    q: np.ndarray,
    error: Callable[[np.ndarray], np.ndarray],
    accept: float,
    mode: Mode,
) -> np.ndarray:
    """Damped least squares on ``error``, moved one joint at a time within free intervals (the tuning:
    ``SearchSettings.refine_iterations``, ``refine_damping``, ``refine_step_rad``)."""
    n = len(q)
    waypoints = [q.copy()]
    h = 1e-6  # finite-difference step (rad): far above rounding, far below any move
    tuning = ctx.search
    for _ in range(tuning.refine_iterations):
        if ctx.termination():
            break
        e = error(q[None])[0]
        if np.linalg.norm(e) <= accept:
            break
        jacobian = (error(q[None] + h * np.eye(n)) - e[None]).T / h  # (m, n)
        step = -jacobian.T @ np.linalg.solve(jacobian @ jacobian.T + tuning.refine_damping * np.eye(len(e)), e)
        largest = np.max(np.abs(step))
        if largest > tuning.refine_step_rad:
            step *= tuning.refine_step_rad / largest
        moved = ctx.space.single_moves(q, step, mode, margin_m=ctx.settings.clearance, counters=ctx.counters)
        if len(moved) < 2 or np.max(np.abs(moved[-1] - q)) < 1e-10:
            break
        waypoints.extend(moved[1:])
        if np.linalg.norm(error(moved[-1][None])[0]) >= np.linalg.norm(e) - 1e-9:
            q = moved[-1]
            break  # clamped by an obstacle: no more progress
        q = moved[-1]
    return np.array(waypoints)
