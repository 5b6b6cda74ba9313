"""SEARCH_TRANSIT and SEARCH_TRANSFER on the planar space: their objectives, probes and joins (paper 1.3.2, 1.3.4).

The do-while loop over Manhattan paths is :func:`clew_ros.core.search.local_search`;
this module builds its jobs for a planar world. Inverse kinematics never
builds a Manhattan path, so redundant arms work alike; configurations that
hold a grasp (closed form for two joints, sampled for more:
:mod:`clew_ros.planar.reach`) refuse hopeless transits, for two joints steer
the elbow, and give SEARCH_TRANSIT's greedy probe a configuration to head for
before the GA; SEARCH_TRANSFER's probe heads for the nearest configuration
holding the object at the goal (:func:`transfer_probe_target`).

A SEARCH_TRANSFER that stalls near the goal (``SearchSettings.join_radius``) is
joined to it (:func:`join_stalled`): configurations that hold the object within
the goal's tolerances are found by inverse kinematics
(:func:`goal_configurations`) and reached by RRT-Connect in the same mode,
every move checked continuously (:func:`clew_ros.planar.connect.join`), drawing
from a generator of its own. This departs from the paper (docs/algorithm.md).
"""

from __future__ import annotations

import dataclasses
import itertools

import numpy as np

from clew_ros.core.search import SearchJob, local_search, object_at, own_generator
from clew_ros.core.settings import ManyJoints, SearchSettings
from clew_ros.core.space import Mode, PathResult, PlanningContext, TransitRequest
from clew_ros.planar.collision import is_valid, packed_world
from clew_ros.planar.connect import join
from clew_ros.planar.continuous import StopOnly, path_valid, straight_move_clear
from clew_ros.planar.inverse import solve_point
from clew_ros.planar.kernel import clearly_valid
from clew_ros.planar.kinematics import compose, relative, tip_poses, transform_points, wrap_angle
from clew_ros.planar.reach import (
    REACH,
    ReachSettings,
    approach_cell,
    approach_excess,
    goal_within_reach,
    holding_configurations,
    holding_configurations_aimed,
    holding_configurations_near,
    reach_of,
    two_link_grasps,
    within_reach,
)
from clew_ros.planar.world import World

__all__ = [
    "goal_configurations",
    "goal_error",
    "goal_reached",
    "goals_reached",
    "join_stalled",
    "sampled_clear",
    "search_transfer",
    "search_transit",
    "search_transits",
    "straight_probe",
    "transfer_probe_target",
]


@dataclasses.dataclass(frozen=True)
class SearchStreams:
    """The random streams of SEARCH's own draws: a generator is seeded with (``planner.seed``, the stream,
    where the draw happens), so that each draw is the same whatever ran before it."""

    #: A join's generator (with where the search stalled).
    join: int = 13
    #: The transfer probe's inverse kinematics (with where the transfer starts); the connection probe
    #: uses the next stream.
    probe: int = 17


#: The streams SEARCH draws from.
STREAMS = SearchStreams()


def straight_probe(
    world: World,
    ctx: PlanningContext,
    jobs: list[SearchJob],
    q: np.ndarray,
    best: np.ndarray,
    *,
    waypoints: list[list[np.ndarray]],
) -> None:
    """Jobs with ``straight`` configurations (transits of arms of ``ManyJoints.straight_transit_joints`` or more)
    try a straight joint-space move from their start to each, nearest first, checked continuously with
    ``SearchSettings.min_margin_factor`` x the clearance as the improvement's moves are
    (valid at any checking step); the first clear one ends the search there. On arms of
    ``ManyJoints.straight_probe_joints`` or more, when none is clear, also by way of a retreat and an approach
    along the tip's headings. Draws nothing at random."""
    for i, job in enumerate(jobs):
        if job.straight is None or not len(job.straight) or ctx.termination():
            continue
        targets = job.straight
        pose = None if job.mode.transfer else job.pose
        rel = job.pose if job.mode.transfer else None
        starts = np.broadcast_to(q[i], targets.shape)
        clear = sampled_clear(
            world, starts, targets, object_pose=pose, grasp_rel=rel, step_rad=ctx.many.screen_step_rad
        )
        if clear.any():
            clear[clear] = _moves_clear_stopping(
                world, ctx, starts[clear], targets[clear], object_pose=pose, grasp_rel=rel, until=True
            )
        way = targets[int(np.argmax(clear))][None] if clear.any() else None
        detour = world.robot.dof >= ctx.many.straight_probe_joints  # below: direct moves only, then the GA
        if way is None and detour:  # by way of a retreat along the tip's heading and an approach along the target's
            back = ctx.many.approach_radii * world.object.radius / 2
            retreat = (
                _backed_line(world, q[i], back, ctx.many.approach_steps // 2, step_m=ctx.many.approach_step_m) or []
            )
            for target in targets if retreat else []:
                if ctx.termination():
                    break
                approach = _backed_line(
                    world, target, back, ctx.many.approach_steps // 2, step_m=ctx.many.approach_step_m
                )
                if approach is None:
                    continue
                path = np.array([q[i], *retreat, *approach[::-1], target])
                if not sampled_clear(
                    world, path[:-1], path[1:], object_pose=pose, grasp_rel=rel, step_rad=ctx.many.screen_step_rad
                ).all():
                    continue
                if _moves_clear_stopping(
                    world, ctx, path[:-1], path[1:], object_pose=pose, grasp_rel=rel, until=False
                ).all():
                    way = path[1:]
                    break
        if way is not None:
            reached = way[-1]
            value = float(job.objective(reached[None], object_at(ctx, reached[None], job.mode))[0])
            if value < best[i]:
                waypoints[i].append(way.copy())
                q[i] = reached
                best[i] = value


def join_stalled(
    world: World, ctx: PlanningContext, job: SearchJob, waypoints: np.ndarray, distance: float
) -> tuple[np.ndarray, float]:
    """A search that failed, stalled near its target (``distance`` at most ``job.join_within``), extended by
    RRT-Connect to one of ``job.targets`` (in the same mode, every move checked continuously with
    ``SearchSettings.min_margin_factor`` x the clearance, at most ``SearchSettings.join_rounds`` rounds,
    then once more at the validator's 0.002 rad); its waypoints and objective, unchanged when no way was
    found."""
    if job.targets is None or distance > job.join_within:
        return waypoints, distance
    stalled = waypoints[-1]
    # a generator of the join's own, seeded by the planner's seed and where the search stalled: a join that
    # fails leaves the run's random stream, and so the rest of the run, as they would have been without it
    rng = own_generator(ctx, STREAMS.join, stalled, job.pose)
    targets = job.targets(stalled, rng)
    if not len(targets) or ctx.termination():
        return waypoints, distance
    pose = job.mode.object_poses
    held = job.mode.grasp_rel
    mode = {"object_pose": None if pose is None else pose[0], "grasp_rel": None if held is None else held[0]}
    path = join(
        world,
        stalled,
        targets,
        rng,
        **mode,
        min_margin=ctx.search.min_margin_factor * ctx.settings.clearance,
        rounds=ctx.search.join_rounds,
        stop=ctx.termination,
    )
    if path is None or not path_valid(world, path, **mode):
        return waypoints, distance
    end = path[-1:]
    return np.vstack([waypoints, path[1:]]), float(job.objective(end, object_at(ctx, end, job.mode))[0])


def search_transit(
    world: World,
    ctx: PlanningContext,
    q0: np.ndarray,
    object_pose: np.ndarray,
    *,
    grasp: int,
    approach: np.ndarray | None = None,
) -> PathResult:
    """SEARCH_TRANSIT: move the arm, object at rest, until its tip holds ``grasp``.

    ``approach`` (cells of :func:`clew_ros.planar.reach.approach_cells`) restricts
    the last link's direction in the object's frame: the residual gains the
    angle to the nearest allowed cell, times the last link's length. For a
    two-joint arm whose valid holding configurations all bend the elbow one
    way, the residual also gains how far the elbow bends the other way.
    """
    return search_transits(world, ctx, [TransitRequest(q0, object_pose, grasp, approach)])[0]


def search_transits(world: World, ctx: PlanningContext, requests: list[TransitRequest]) -> list[PathResult]:
    """:func:`search_transit` for independent requests ``(q0, object_pose, grasp, approach)`` at once:
    their genetic algorithms run as islands of one batch."""
    results: list[PathResult | None] = []
    jobs, slots = [], []
    many = world.robot.dof >= ctx.many.straight_probe_joints
    straight = world.robot.dof >= ctx.many.straight_transit_joints
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
            join_radius=ctx.search.join_radius,
            straight=ctx.many.straight_probes if straight else 0,
            many=ctx.many if many else None,
            reach=reach_of(ctx),
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
            waypoints, distance = (found, reached) if success else join_stalled(world, ctx, job, found, reached)
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
    join_radius: float,
    straight: int = 0,
    many: ManyJoints | None = None,
    reach: ReachSettings = REACH,
) -> SearchJob | PathResult:
    """SEARCH_TRANSIT's objective for one request, or its failure when it is hopeless. Arms of ``many``
    joints also get holds solved from ``q0`` itself (:func:`holding_configurations_near`)."""
    target = transform_points(object_pose, world.object.grasps[grasp][None])  # (1, 2)
    holds = _holding_configurations(world, object_pose, grasp, approach, samples, aimed=many is not None, reach=reach)
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
    mode = Mode.resting(object_pose[None])
    held = holds[objective(holds, None) <= 0.5 * world.grasp_tolerance]  # the transit's own success test
    # the greedy probe heads for the nearest of them (joint travel)
    toward = held[np.argmin(np.abs(held - q0).sum(axis=1))] if len(held) else None
    nearest = held[np.argsort(np.abs(held - q0).sum(axis=1), kind="stable")[:straight]] if straight else None
    if not joins:
        return SearchJob(q0, objective, tip_error, 0.25 * world.grasp_tolerance, mode, toward=toward, straight=nearest)

    def targets(_stalled: np.ndarray, _rng: np.random.Generator) -> np.ndarray:
        return held

    within = join_radius * world.robot.reach
    return SearchJob(q0, objective, tip_error, 0.25 * world.grasp_tolerance, mode, targets, within, toward, nearest)


def _holding_configurations(
    world: World,
    object_pose: np.ndarray,
    grasp: int,
    approach: np.ndarray | None,
    samples: int,
    *,
    aimed: bool = False,
    reach: ReachSettings = REACH,
) -> np.ndarray:
    """The valid configurations holding ``grasp`` (with an allowed approach), which a transit can
    only end near: all of them for two-joint arms (:func:`two_link_grasps`), a sample for others
    (:func:`holding_configurations`). Empty: the transit is given up as hopeless."""
    if world.robot.dof == 2:
        holds = two_link_grasps(world, object_pose, grasp, probes=reach.two_link_probes)
    else:
        holds = holding_configurations(world, object_pose, grasp, samples, iterations=reach.hold_iterations)
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
    seeds: int = SearchSettings().goal_seeds,
) -> np.ndarray:
    """Configurations ``(m, n)`` valid with ``min_margin`` (m) to spare (the compiled first pass) holding the
    object (as ``grasp_rel``) within the goal's tolerances, as SEARCH_TRANSFER's success asks, nearest ``q0``
    first: inverse kinematics (:func:`solve_point`) from ``q0``
    and ``seeds`` - 1 configurations drawn within the joint limits, once for the goal's own angle (the
    middle of the tolerance, clear of a pocket's walls when the arm can hold it there) and once for any angle
    within the tolerance (for an arm that cannot)."""
    robot = world.robot
    drawn = rng.uniform(robot.joint_lower, robot.joint_upper, (seeds - 1, robot.dof))
    starts = np.vstack([np.asarray(q0, float)[None], drawn])
    grasp_rel = np.asarray(grasp_rel, float)
    within = np.pi if world.goal_angle_tolerance >= np.pi - 1e-6 else 0.8 * world.goal_angle_tolerance
    q = np.vstack(
        [
            solve_point(
                robot,
                starts,
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
    if held.any():  # the margin a join's first move from it asks for (clew_ros.planar.continuous)
        rounded = dataclasses.replace(packed_world(world), rounding=min_margin)
        held[held] = clearly_valid(rounded, np.ascontiguousarray(q[held]), poses[held])
    found = q[held][np.argsort(np.max(np.abs(q[held] - q0), axis=1), kind="stable")]
    distinct = [i for i in range(len(found)) if not any(np.max(np.abs(found[i] - found[:i]), axis=1) < 1e-3)]
    kept: np.ndarray = found[distinct]
    return kept


def transfer_probe_target(
    world: World, ctx: PlanningContext, q0: np.ndarray, grasp_rel: np.ndarray, goal: np.ndarray
) -> np.ndarray | None:
    """The configuration SEARCH_TRANSFER's greedy probe heads for: the nearest (largest joint move) of
    :func:`goal_configurations` from ``q0``, drawn from a generator of its own seeded by the planner's seed
    and the request (the run's stream stays as it was); ``None`` when the probe is off or no configuration
    holds the object at the goal."""
    if not (ctx.search.greedy_probe and ctx.search.transfer_probe):
        return None
    rng = own_generator(ctx, STREAMS.probe, q0, grasp_rel)
    margin = ctx.search.min_margin_factor * ctx.settings.clearance
    held = goal_configurations(world, q0, grasp_rel, goal, rng, min_margin=margin, seeds=ctx.search.goal_seeds)
    return held[0] if len(held) else None


def _moves_clear_stopping(
    world: World,
    ctx: PlanningContext,
    starts: np.ndarray,
    ends: np.ndarray,
    *,
    object_pose: np.ndarray | None = None,
    grasp_rel: np.ndarray | None = None,
    until: bool,
) -> np.ndarray:
    """Arms of many joints: :func:`~clew_ros.planar.continuous.straight_moves_clear`
    (``SearchSettings.min_margin_factor`` x the clearance) of each move ``starts[k] -> ends[k]`` in turn,
    each split into pieces that sweep at most :attr:`ManyJoints.check_sweep_m` (the bound
    ``sum_j |dq_j| R_j`` of the check's module), the termination asked before each piece: one compiled
    check of a long move near a contact can take seconds, past the time limit. The moves are checked in
    order until the first whose answer is ``until`` (the first clear one, or the first blocked one); the
    others, and a move whose check was stopped, come back not clear."""
    lengths = world.robot.link_lengths
    arm = np.cumsum(lengths[::-1])[::-1] + (world.object.radius if grasp_rel is not None else 0.0)
    margin = ctx.search.min_margin_factor * ctx.settings.clearance
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


def sampled_clear(
    world: World,
    starts: np.ndarray,
    ends: np.ndarray,
    *,
    object_pose: np.ndarray | None = None,
    grasp_rel: np.ndarray | None = None,
    step_rad: float,
) -> np.ndarray:
    """Whether each straight move ``starts[k] -> ends[k]`` is valid at configurations ``step_rad`` apart (a
    quick screen, so that the continuous check, which can take seconds on a long move of many joints
    near a contact, runs only on moves that look clear; ``ManyJoints.screen_step_rad``)."""
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
    world: World, q: np.ndarray, back: float, steps: int, *, step_m: float, toward: np.ndarray | None = None
) -> list[np.ndarray] | None:
    """Configurations from ``q`` (excluded) with the tip backed by ``back`` (m) in ``steps`` equal steps (more
    when needed to keep each at most ``step_m``, m) against its own heading (or, with ``toward``, straight away
    from the point ``toward``),
    its angle kept (inverse kinematics from the previous one); ``None`` when the arm cannot follow that line."""
    robot = world.robot
    tip = tip_poses(robot, q[None])[0]
    heading = np.array([np.cos(tip[2]), np.sin(tip[2])])
    if toward is not None and np.linalg.norm(tip[:2] - toward) > 1e-9:
        heading = (toward - tip[:2]) / np.linalg.norm(toward - tip[:2])  # backed away from ``toward``
    line = [q]
    steps = max(steps, int(np.ceil(back / step_m)))
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


def _straight_transfer(world: World, ctx: PlanningContext, job: SearchJob, goal: np.ndarray) -> PathResult | None:
    """Arms of many joints (:class:`ManyJoints`): SEARCH_TRANSFER by straight joint-space moves, checked
    continuously, to a configuration holding the object at the goal (:func:`goal_configurations`, nearest
    first), directly or by way of the line along which the tip, backed along its own heading, puts the
    object in place; ``None`` when none is clear. Its own generator (the run's stream is untouched)."""
    many = ctx.many
    grasp_rel = job.pose
    rng = own_generator(ctx, STREAMS.probe + 1, job.q0, grasp_rel)
    margin = ctx.search.min_margin_factor * ctx.settings.clearance
    held = goal_configurations(world, job.q0, grasp_rel, goal, rng, min_margin=margin, seeds=ctx.search.goal_seeds)[
        : many.straight_probes
    ]
    back = many.approach_radii * world.object.radius
    for target in held:
        if ctx.termination():
            return None
        ways = [np.array([job.q0, target])]
        # the object backed out along the line from its origin to the grasp, as a gripper pulls it
        origin = compose(tip_poses(world.robot, target[None]), grasp_rel[None])[0, :2]
        line = _backed_line(world, target, back, many.approach_steps, step_m=many.approach_step_m, toward=origin)
        if line is not None:
            ways.append(np.array([job.q0, *line[::-1], target]))
            turned = job.q0.copy()  # the whole arm turned by joint 1 first (rigidly), then straight
            turned[0] = line[-1][0]
            ways.append(np.array([job.q0, turned, *line[::-1], target]))
        for way in ways:
            if not sampled_clear(world, way[:-1], way[1:], grasp_rel=grasp_rel, step_rad=many.screen_step_rad).all():
                continue
            if _moves_clear_stopping(world, ctx, way[:-1], way[1:], grasp_rel=grasp_rel, until=False).all():
                pose = compose(tip_poses(world.robot, way[-1:]), grasp_rel[None])[0]
                distance = float(np.linalg.norm(goal_error(world, pose[None], goal)[0]))
                if goal_reached(world, pose, goal) and distance <= 0.5 * world.goal_tolerance:
                    return PathResult(True, way, distance, object_pose=pose)
    return None


def search_transfer(
    world: World, ctx: PlanningContext, q0: np.ndarray, grasp_rel: np.ndarray, goal: np.ndarray, *, joins: bool = True
) -> PathResult:
    """SEARCH_TRANSFER: carry the object (held as ``grasp_rel``) toward the ``goal`` placement; stalled near it,
    joined to it (:func:`join_stalled`, towards :func:`goal_configurations`) unless ``joins`` is false."""
    carried = np.asarray(grasp_rel, float)[None]
    mode = Mode.held(carried)

    def error(q: np.ndarray) -> np.ndarray:
        return goal_error(world, compose(tip_poses(world.robot, q), carried), goal)

    def objective(_q: np.ndarray | None, poses: np.ndarray) -> np.ndarray:
        distance: np.ndarray = np.linalg.norm(goal_error(world, poses, goal), axis=1)
        return distance

    accept = 0.25 * world.goal_tolerance
    if not goal_within_reach(world, grasp_rel, goal):
        start_pose = compose(tip_poses(world.robot, np.asarray(q0, float)[None]), carried)
        return PathResult(
            False, np.asarray(q0, float)[None], float(objective(None, start_pose)[0]), object_pose=start_pose[0]
        )

    def targets(stalled: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        margin = ctx.search.min_margin_factor * ctx.settings.clearance
        return goal_configurations(
            world, stalled, carried[0], goal, rng, min_margin=margin, seeds=ctx.search.goal_seeds
        )

    within = ctx.search.join_radius * world.robot.reach
    toward = transfer_probe_target(world, ctx, np.asarray(q0, float), carried[0], goal)
    job = SearchJob(np.asarray(q0, float), objective, error, accept, mode, targets if joins else None, within, toward)
    if world.robot.dof >= ctx.many.straight_probe_joints:
        straight = _straight_transfer(world, ctx, job, goal)
        if straight is not None:
            return straight
    if world.robot.dof >= ctx.many.straight_probe_joints and not ctx.many.transfer_ga:
        start = np.asarray(q0, float)[None]
        waypoints, distance = start, float(objective(None, object_at(ctx, start, mode))[0])
    else:
        [(waypoints, distance)] = local_search(ctx, [job])

    def succeeded(path: np.ndarray, reached: float) -> tuple[bool, np.ndarray]:
        pose = compose(tip_poses(world.robot, path[-1:]), carried)[0]
        return goal_reached(world, pose, goal) and reached <= 0.5 * world.goal_tolerance, pose

    success, final_pose = succeeded(waypoints, distance)
    if not success:
        waypoints, distance = join_stalled(world, ctx, job, waypoints, distance)
        success, final_pose = succeeded(waypoints, distance)
    return PathResult(success, waypoints, distance, object_pose=final_pose)
