"""Where to grasp and where to put the object down: straight-move manipulations to the goal (issue 14).

A found plan fixes every configuration where a grasp is made or the object is put down, and a
shortcut cannot move them, so a plan that took the object with the elbow the wrong way round, or
put it down far from where a regrasp was needed, stays long. :func:`propose` lists other ways to
finish from a placement of the plan (the start, or where a transfer put the object down), each
made of straight joint-space moves between key configurations:

* one transfer: a transit to a configuration holding grasp ``g``, then a transfer to a configuration
  putting the object on the goal;
* two transfers: the same to a *release* configuration instead of the goal, a transit to a
  configuration holding grasp ``g'`` (another grasp, or the same with another posture) where the
  object now rests, and a transfer to the goal.

Key configurations come from inverse kinematics (:func:`clew_ros.planar.inverse.solve_point`) from
seeds: the configuration before (so a redundant arm moves little) and its mirror image about the
line from the base to the target (the other elbow), plus the plan's own grasp configurations. On
an arm of three or more joints, the grasp configurations at the placement and, for one transfer, at the
goal are also solved from seeds drawn around each seed (:attr:`RegraspSettings.restarts`), the valid one nearest the
seed added (around the plan's own grasp configuration, the one nearest the arm's configuration):
a redundant arm's first solution often folds into an obstacle, the object or itself, or lies far
from where the arm is. Of the restarts' grasp configurations, two-transfer proposals start only
from those standing in for a seed whose own solution is not valid. A rigid grasp keeps its approach (the
object's angle in the tip's frame) while carried, so an arm of three or more joints also takes
each grasp with an approach that can hold the object on the goal (:func:`_goal_holds`), at the
placement and at releases.
Release configurations are drawn from the run's generator: along the way from the grasp to where
the object comes closest to the goal, putting the object down at points drawn around the goal, at
and around where the plan put it down, and anywhere within the joint limits; then refined around
the best of each grasp configuration (cross-entropy style). A proposal's joint travel is the sum
of its moves (sum over joints of ``|dq|``). Every key configuration is valid with ``margin_m`` to
spare; each move is *screened*: configurations sampled along it, straight and one joint after the
other in either order (:data:`ROUTES`, all as long in joint travel), go through the compiled
first pass of the validity test, and a move none of whose ways passes counts
:attr:`RegraspSettings.blocked_penalty_rad` extra in the ranking. The screen samples, it proves nothing:
:mod:`clew_ros.planar.improve` checks the moves continuously and keeps a proposal only when the
plan gets better. Everything is batched (numpy and compiled kernels); :class:`Effort` counts the
work done, which :mod:`clew_ros.planar.improve` charges to its budget.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from clew_ros.planar.inverse import mirrored
from clew_ros.planar.kinematics import compose, relative, tip_poses, transform_points
from clew_ros.planar.regrasp_keys import (
    ROUTES,
    Effort,
    Kinematics,
    Proposal,
    RegraspSettings,
    directions,
    goal_holds_near,
    l1_distances,
    route_waypoints,
    screen_samples,
    unique_rows,
    with_mirrors,
)
from clew_ros.planar.world import World

__all__ = [
    "ROUTES",
    "Effort",
    "PlanHints",
    "Proposal",
    "ProposalLimits",
    "RegraspSettings",
    "goal_holds_near",
    "propose",
    "route_waypoints",
    "screen_samples",
]


@dataclass(frozen=True)
class PlanHints:
    """What the plan being improved tells :func:`propose`: its grasp configurations ``own`` (``(grasp, q)``) that
    hold the object at the placement, tried as they are; the configurations ``releases`` ``(m, n)`` where it put
    the object down, tried (and around them) as releases; and its configurations at the goal ``finals``
    ``(m, n)``, from which :func:`_goal_holds` finds how each grasp can hold the goal."""

    own: tuple[tuple[int, np.ndarray], ...] = ()
    releases: np.ndarray | None = None
    finals: np.ndarray | None = None


@dataclass(frozen=True)
class ProposalLimits:
    """When :func:`propose` stops: ``should_stop`` (the planner's termination) says so, asked between stages (each
    a few tens of milliseconds at most), or ``max_checks`` configurations have been checked, each
    inverse-kinematics step (one configuration, one iteration) counting ``step_checks`` (moves not checked then
    count as blocked)."""

    should_stop: Callable[[], bool] | None = None
    max_checks: int | None = None
    step_checks: float = 0.0


@dataclass
class _Start:
    """The grasp configurations to start with (``A`` of them) and their first transit's way."""

    start: np.ndarray  # (n,)
    placement: np.ndarray  # (3,)
    first: np.ndarray  # (A, n)
    grasps: np.ndarray  # (A,)
    grasp_rel: np.ndarray  # (A, 3)
    route: np.ndarray  # (A,)
    goal_seeds: np.ndarray  # (A, n) a configuration holding the goal with the same approach (NaN: none known)
    drawn: np.ndarray  # (A,) found by restarts (:meth:`Kinematics.restarted`) besides their seed's own

    def seeded(self) -> _Start:
        """Without the configurations found by restarts besides a valid one from their seed: the two-transfer
        proposals draw releases for every grasp configuration, so those would double their work for little
        (they shorten transits). A restart standing in for a seed whose own solution is not valid stays: on
        arm3_regrasp grasp 1's solutions from the start and its mirror image collide, and without the
        restart's no two-transfer proposal started with that grasp."""
        keep = ~self.drawn
        return _Start(
            self.start,
            self.placement,
            self.first[keep],
            self.grasps[keep],
            self.grasp_rel[keep],
            self.route[keep],
            self.goal_seeds[keep],
            self.drawn[keep],
        )


def propose(
    world: World,
    start: np.ndarray,
    placement: np.ndarray,
    goal: np.ndarray,
    rng: np.random.Generator,
    *,
    hints: PlanHints | None = None,
    one_transfer: bool = True,
    two_transfers: bool = True,
    margin_m: float = 0.0,
    limits: ProposalLimits | None = None,
    restarts: np.random.Generator | None = None,
    settings: RegraspSettings | None = None,
) -> tuple[list[Proposal], Effort]:
    """Ways to the goal from the arm at ``start`` with the object resting at ``placement``, with one transfer
    (if ``one_transfer``) and two (if ``two_transfers``), using what the plan tells (``hints``, default none).
    Ranked by joint travel plus :attr:`RegraspSettings.blocked_penalty_rad` per move that looked blocked; alike
    ones dropped (:func:`_distinct`).

    When ``limits`` (default none) say stop, the proposals found so far are returned.
    ``restarts``: the generator the inverse kinematics' restarts (:attr:`RegraspSettings.restarts`) draw from, default
    ``rng``; one of its own leaves ``rng``'s stream to the releases. ``settings``: the tuning, the default
    :class:`RegraspSettings` when not given.
    Returns the proposals (at most :attr:`RegraspSettings.max_proposals`) and the work done.
    """
    hints = hints if hints is not None else PlanHints()
    limits = limits if limits is not None else ProposalLimits()
    kinematics = Kinematics(
        world, margin_m, limits.should_stop, limits.max_checks, limits.step_checks, settings=settings
    )
    own, releases, finals = list(hints.own), hints.releases, hints.finals
    restarts = rng if restarts is None else restarts
    start, placement = np.asarray(start, float), np.asarray(placement, float)
    finals = np.zeros((0, len(start))) if finals is None else np.asarray(finals, float)
    holds = _goal_holds(kinematics, start, goal, finals=finals, rng=rng)
    aligned = _aligned_at(kinematics, start, placement, holds)
    begin = _grasps_at_start(
        kinematics, start, placement, own, aligned, rng=restarts, own_goal=finals[-1] if len(finals) else None
    )
    if begin is None:
        return [], kinematics.effort
    proposals = _one_transfer(kinematics, begin, goal, restarts) if one_transfer else []
    seeded = begin.seeded()
    if two_transfers and len(seeded.first) and not kinematics.stop():
        tried = np.zeros((0, len(begin.start))) if releases is None else np.asarray(releases, float)
        proposals += _two_transfers(kinematics, seeded, goal, rng, tried, holds=holds.first_per_grasp())
    proposals.sort(key=lambda p: p.rank)
    return _distinct(proposals, kinematics.settings), kinematics.effort


def _distinct(proposals: list[Proposal], settings: RegraspSettings) -> list[Proposal]:
    """The first :attr:`RegraspSettings.max_proposals` of ``proposals`` that differ from every one before them:
    other grasps, or a key configuration more than :attr:`RegraspSettings.distinct_rad` away (largest joint
    difference)."""
    kept: list[Proposal] = []
    for proposal in proposals:
        if len(kept) == settings.max_proposals:
            break
        if not any(
            other.grasps == proposal.grasps
            and float(np.max(np.abs(other.keys - proposal.keys))) <= settings.distinct_rad
            for other in kept
        ):
            kept.append(proposal)
    return kept


def _grasps_at_start(
    kinematics: Kinematics,
    start: np.ndarray,
    placement: np.ndarray,
    own: list[tuple[int, np.ndarray]],
    aligned: list[tuple[int, np.ndarray, np.ndarray]],
    *,
    rng: np.random.Generator,
    own_goal: np.ndarray | None = None,
) -> _Start | None:
    """Every grasp from the start and from its mirror image, the plan's own grasp configurations (with
    ``own_goal``, the plan's configuration at the goal, seeding their goal's inverse kinematics) and, on
    an arm of three or more joints, ones around them nearer the start, and those aligned with the goal
    (:func:`_aligned_at`, with their configuration at the goal)."""
    world = kinematics.world
    n = len(start)
    first, grasps, drawn = _grasp_configurations(kinematics, start, placement, own, rng)
    extra = [(g, q, np.full(n, np.nan) if own_goal is None else own_goal) for g, q in own] + aligned
    goal_seeds = np.full((len(first), n), np.nan)
    if extra:
        drawn = np.concatenate([drawn, np.zeros(len(extra), dtype=bool)])
        grasps = np.concatenate([grasps, [g for g, _, _ in extra]]).astype(int)
        first = np.concatenate([first, np.array([q for _, q, _ in extra], dtype=float).reshape(-1, n)])
        goal_seeds = np.concatenate([goal_seeds, np.array([e for _, _, e in extra], dtype=float).reshape(-1, n)])
    if not len(first):
        return None
    unique = unique_rows(first, kinematics.settings.unique_rad)
    for k in np.flatnonzero(~np.isnan(goal_seeds[:, 0])):  # a row kept for an aligned one takes its goal seed
        kept = unique[np.max(np.abs(first[unique] - first[k]), axis=1) <= kinematics.settings.unique_rad][0]
        if np.isnan(goal_seeds[kept, 0]):
            goal_seeds[kept] = goal_seeds[k]
    first, grasps, goal_seeds, drawn = first[unique], grasps[unique], goal_seeds[unique], drawn[unique]
    grasp_rel = relative(tip_poses(world.robot, first), placement)  # as plan.replay computes it
    starts = np.broadcast_to(start, first.shape)
    route = kinematics.routes(starts, first, resting=np.broadcast_to(placement, (len(first), 3)))
    return _Start(start, placement, first, grasps, grasp_rel, route, goal_seeds, drawn)


def _grasp_configurations(
    kinematics: Kinematics,
    start: np.ndarray,
    placement: np.ndarray,
    own: list[tuple[int, np.ndarray]],
    rng: np.random.Generator,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Valid configurations holding each grasp from the start and its mirror image, with the restarts'
    (:meth:`Kinematics.restarted`) and, around the plan's own grasp configurations, ones nearer the start
    (three joints or more; the plan's own are proposed as they are by the caller):
    the configurations, their grasps, and which came from restarts besides a valid solution from their seed
    (a restart in place of a seed whose own solution is not valid counts as that seed's)."""
    world = kinematics.world
    n = len(start)
    grasps = np.repeat(np.arange(len(world.object.grasps)), 2)
    targets = transform_points(placement, world.object.grasps)[grasps]
    seeds = mirrored(world.robot, np.repeat(start[None], len(grasps), axis=0), directions(world, targets))
    seeds[0::2] = start
    placements = np.broadcast_to(placement, (len(grasps), 3))
    rows, first, ok = kinematics.restarted(lambda k, q: kinematics.holding(placements[k], grasps[k], q), seeds, rng)
    # a restart's solution is extra only beside a valid one from its seed; one standing in for a seed whose own
    # solution is not valid takes its place (so the two-transfer proposals start from it too)
    drawn = (np.arange(len(rows)) >= len(seeds)) & ok[rows]  # the first rows are the seeds' own, in order
    first, grasps, drawn = first[ok], grasps[rows[ok]], drawn[ok]
    if own and world.robot.dof >= 3:  # the plan's own are kept as they are (by the caller); ones around them
        # nearer the start are added (restarts: three or more joints only)
        own_grasps = np.array([g for g, _ in own], dtype=int)
        own_q = np.array([q for _, q in own], dtype=float).reshape(-1, n)
        here = np.broadcast_to(placement, (len(own_q), 3))
        rows, near, ok = kinematics.restarted(
            lambda k, q: kinematics.holding(here[k], own_grasps[k], q),
            own_q,
            rng,
            origins=np.broadcast_to(start, own_q.shape),
        )
        added = (np.arange(len(rows)) >= len(own_q)) & ok
        first = np.concatenate([first, near[added]])
        grasps = np.concatenate([grasps, own_grasps[rows[added]]])
        drawn = np.concatenate([drawn, np.ones(int(added.sum()), dtype=bool)])
    return first, grasps, drawn


@dataclass(frozen=True)
class _GoalHolds:
    """Ways each grasp can hold the object on the goal: ``at_goal`` ``(H, n)`` holding ``grasps`` ``(H,)``,
    and ``approach`` ``(H,)``, the object's angle in the tip's frame, which a rigid grasp keeps while
    carried."""

    grasps: np.ndarray
    at_goal: np.ndarray
    approach: np.ndarray

    def first_per_grasp(self) -> _GoalHolds:
        """The first way of each grasp."""
        _, first = np.unique(self.grasps, return_index=True)
        return _GoalHolds(self.grasps[first], self.at_goal[first], self.approach[first])


def _goal_holds(
    kinematics: Kinematics, start: np.ndarray, goal: np.ndarray, *, finals: np.ndarray, rng: np.random.Generator
) -> _GoalHolds:
    """How each grasp can hold the object on the goal, valid with the margin: inverse kinematics from the
    start, from ``finals`` ``(m, n)`` (the plan's configurations at the goal), from
    :attr:`RegraspSettings.aligned_draws` configurations drawn within the joint limits and from the mirror images
    of all these. None for an arm of two joints: it holds a placement in at most two ways (its elbows), which are
    tried anyway."""
    world = kinematics.world
    robot = world.robot
    count = len(world.object.grasps)
    if robot.dof < 3 or kinematics.stop():
        return _GoalHolds(np.zeros(0, dtype=int), np.zeros((0, robot.dof)), np.zeros(0))
    drawn = rng.uniform(robot.joint_lower, robot.joint_upper, size=(kinematics.settings.aligned_draws, robot.dof))
    origins = np.vstack([start[None], finals.reshape(-1, robot.dof), drawn])
    grasps = np.tile(np.arange(count), 2 * len(origins))
    seeds = np.repeat(origins, count, axis=0)
    seeds = with_mirrors(world, seeds, transform_points(goal, world.object.grasps)[grasps[: len(seeds)]])
    goals = np.broadcast_to(goal, (len(grasps), 3))
    held, ok = kinematics.holding(goals, grasps, seeds)
    grasps, held = grasps[ok], held[ok]
    unique = unique_rows(held, kinematics.settings.unique_rad)
    grasps, held = grasps[unique], held[unique]
    approach = relative(tip_poses(robot, held), goals[: len(held)])[:, 2]
    return _GoalHolds(grasps, held, approach)


def _aligned_at(
    kinematics: Kinematics, start: np.ndarray, placement: np.ndarray, holds: _GoalHolds
) -> list[tuple[int, np.ndarray, np.ndarray]]:
    """Grasp configurations ``(grasp, q, at_goal)`` near ``start`` holding the object at ``placement`` with the
    approach of one of ``holds`` (whose configuration at the goal comes with it): carried rigidly, the
    object can end on the goal."""
    if not len(holds.grasps):
        return []
    here = np.broadcast_to(placement, (len(holds.grasps), 3))
    seeds = np.repeat(start[None], len(holds.grasps), axis=0)
    first, ok = kinematics.holding(here, holds.grasps, seeds, placement[2] - holds.approach)
    return [(int(g), q, e) for g, q, e in zip(holds.grasps[ok], first[ok], holds.at_goal[ok], strict=True)]


def _and_goal_seeds(seeds: np.ndarray, rows: np.ndarray, goal_seeds: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``seeds`` for the goal's inverse kinematics of configurations ``rows``, and after them the known goal
    configurations (rows of ``goal_seeds`` that are not NaN: an aligned grasp's) of the configurations
    they belong to."""
    known = np.flatnonzero(~np.isnan(goal_seeds[:, 0]))
    return np.concatenate([seeds, goal_seeds[known]]), np.concatenate([rows, known])


def _one_transfer(kinematics: Kinematics, begin: _Start, goal: np.ndarray, rng: np.random.Generator) -> list[Proposal]:
    """Grasp configurations carried straight to the goal."""
    world = kinematics.world
    first = begin.first
    seeds = with_mirrors(world, first, np.broadcast_to(goal[:2], (len(first), 2)))
    rows = np.tile(np.arange(len(first)), 2)
    seeds, rows = _and_goal_seeds(seeds, rows, begin.goal_seeds)
    queries, ends, ok = kinematics.restarted(
        lambda k, q: kinematics.at_goal(begin.grasp_rel[rows[k]], q, goal), seeds, rng
    )
    rows, ends = rows[queries[ok]], ends[ok]
    route = kinematics.routes(first[rows], ends, grasp_rel=begin.grasp_rel[rows])
    travel = l1_distances(begin.start, first[rows]) + l1_distances(first[rows], ends)
    return [
        Proposal(
            float(travel[k]),
            int(begin.route[a] < 0) + int(route[k] < 0),
            (int(begin.grasps[a]),),
            np.stack([begin.start, first[a], ends[k]]),
            (int(begin.route[a]), int(route[k])),
            kinematics.settings.blocked_penalty_rad,
        )
        for k, a in enumerate(rows)
    ]


@dataclass
class _Releases:
    """Release configurations and their best continuation to the goal."""

    option: np.ndarray  # (S,) index of the grasp configuration they are carried with
    release: np.ndarray  # (S, n)
    grasp: np.ndarray  # (S,) the grasp taken after the release
    regrasp: np.ndarray  # (S, n)
    end: np.ndarray  # (S, n) at the goal
    travel: np.ndarray  # (S,) whole joint travel (inf: no way)
    routes: np.ndarray  # (S, 4) per move, as Proposal.routes

    def joined(self, other: _Releases) -> _Releases:
        return _Releases(
            *(np.concatenate([getattr(self, f.name), getattr(other, f.name)]) for f in dataclasses.fields(self))
        )

    @property
    def blocked(self) -> np.ndarray:
        count: np.ndarray = (self.routes < 0).sum(axis=1)
        return count

    def score(self, penalty_rad: float) -> np.ndarray:
        """Joint travel plus ``penalty_rad`` per move that looked blocked."""
        score: np.ndarray = self.travel + penalty_rad * self.blocked
        return score


def _continue(
    kinematics: Kinematics,
    begin: _Start,
    option: np.ndarray,
    release: np.ndarray,
    goal: np.ndarray,
    *,
    holds: _GoalHolds,
) -> _Releases:
    """For each release configuration ``release`` ``(S, n)`` carried with grasp configuration ``option``:
    the grasp to take next (from the release and its mirror image, and with the approach of each of
    ``holds``) and the goal configuration after it, the cheapest of the :attr:`RegraspSettings.continuations` shortest
    once blocked moves count."""
    world = kinematics.world
    n = release.shape[1]
    first, rel = begin.first[option], begin.grasp_rel[option]
    placement = compose(tip_poses(world.robot, release), rel)
    found = _Releases(
        option,
        release,
        np.full(len(release), -1),
        np.zeros((len(release), n)),
        np.zeros((len(release), n)),
        np.full(len(release), np.inf),
        np.full((len(release), 4), -1),
    )
    alive = np.flatnonzero(kinematics.valid(release, placement))
    count = len(world.object.grasps)
    rows = np.repeat(alive, count)  # (release, grasp) pairs
    grasp = np.tile(np.arange(count), len(alive))
    targets = transform_points(placement[rows], world.object.grasps)[np.arange(len(rows)), grasp]
    seeds = with_mirrors(world, release[rows], targets)
    rows, grasp = np.tile(rows, 2), np.tile(grasp, 2)
    regrasp, ok = kinematics.holding(placement[rows], grasp, seeds)
    unaligned = (rows[ok], grasp[ok], regrasp[ok], np.full((int(ok.sum()), n), np.nan))
    rows, grasp, regrasp, goal_seeds = _and_aligned(
        kinematics, placement, release, alive, holds=holds, regrasps=unaligned
    )
    rel2 = relative(tip_poses(world.robot, regrasp), placement[rows])
    seeds = with_mirrors(world, regrasp, np.broadcast_to(goal[:2], (len(regrasp), 2)))
    pick = np.tile(np.arange(len(regrasp)), 2)
    seeds, pick = _and_goal_seeds(seeds, pick, goal_seeds)
    end, ok = kinematics.at_goal(rel2[pick], seeds, goal)
    pick, end = pick[ok], end[ok]
    rows, grasp, regrasp, rel2 = rows[pick], grasp[pick], regrasp[pick], rel2[pick]
    travel = l1_distances(release[rows], regrasp) + l1_distances(regrasp, end)
    order = np.lexsort((travel, rows))  # per release, its shortest continuations first
    rank = np.zeros(len(order), dtype=int)
    if len(order):
        starts = np.r_[True, rows[order][1:] != rows[order][:-1]]
        group = np.cumsum(starts) - 1
        rank[order] = np.arange(len(order)) - np.flatnonzero(starts)[group]
    total = l1_distances(begin.start, first[rows]) + l1_distances(first[rows], release[rows]) + travel
    screened = _shortest_per_option(option, rows, total, kinematics.settings.screened)
    keep = np.flatnonzero((rank < kinematics.settings.continuations) & np.isin(rows, screened))
    rows, grasp, regrasp, end, rel2, total = rows[keep], grasp[keep], regrasp[keep], end[keep], rel2[keep], total[keep]
    carried = np.unique(rows)
    carry = np.full(len(release), -1)
    carry[carried] = kinematics.routes(first[carried], release[carried], grasp_rel=rel[carried])
    transit = kinematics.routes(release[rows], regrasp, resting=placement[rows])
    last = kinematics.routes(regrasp, end, grasp_rel=rel2)
    routes = np.stack([begin.route[option[rows]], carry[rows], transit, last], axis=1)
    score = total + kinematics.settings.blocked_penalty_rad * (routes < 0).sum(axis=1)
    order = np.lexsort((score, rows))
    best = order[np.r_[True, rows[order][1:] != rows[order][:-1]]] if len(order) else order
    at = rows[best]
    found.grasp[at] = grasp[best]
    found.regrasp[at] = regrasp[best]
    found.end[at] = end[best]
    found.travel[at] = total[best]
    found.routes[at] = routes[best]
    return found


def _and_aligned(
    kinematics: Kinematics,
    placement: np.ndarray,
    release: np.ndarray,
    alive: np.ndarray,
    *,
    holds: _GoalHolds,
    regrasps: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray],
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """``regrasps`` (the release's index, the grasp, its configuration, a goal configuration with the same
    approach or NaN) and after them the regrasps at the placements ``placement[alive]`` (where releases
    ``release[alive]`` put the object) with the approach of each of ``holds``, from the release, that
    hold validly."""
    if not len(holds.grasps) or not len(alive):
        return regrasps
    way = np.tile(np.arange(len(holds.grasps)), len(alive))
    at = np.repeat(alive, len(holds.grasps))
    tip_angles = placement[at, 2] - holds.approach[way]
    aligned, ok = kinematics.holding(placement[at], holds.grasps[way], release[at], tip_angles)
    more = (at[ok], holds.grasps[way][ok], aligned[ok], holds.at_goal[way][ok])
    rows, grasp, regrasp, goal_seeds = (np.concatenate(pair) for pair in zip(regrasps, more, strict=True))
    return rows, grasp, regrasp, goal_seeds


def _shortest_per_option(option: np.ndarray, rows: np.ndarray, travel: np.ndarray, count: int) -> np.ndarray:
    """The releases (indices) of the ``count`` shortest ways of each grasp configuration: ``travel[k]`` is the
    joint travel of a way through release ``rows[k]``, carried with grasp configuration ``option[rows[k]]``."""
    order = np.lexsort((travel, rows))
    firsts = order[np.r_[True, rows[order][1:] != rows[order][:-1]]] if len(order) else order
    releases, shortest = rows[firsts], travel[firsts]  # each release once, with its shortest way
    chosen = [
        releases[mine][np.argsort(shortest[mine], kind="stable")[:count]]
        for mine in (option[releases] == a for a in np.unique(option[releases]))
    ]
    return np.concatenate(chosen) if chosen else releases[:0]


def _best_distinct(found: _Releases, option: int, keep: int, settings: RegraspSettings) -> np.ndarray:
    """The ``keep`` best-scored releases carried with grasp configuration ``option``, at least
    :attr:`RegraspSettings.distinct_rad` apart."""
    score = found.score(settings.blocked_penalty_rad)
    rows = np.flatnonzero((found.option == option) & np.isfinite(score))
    ranked = rows[np.argsort(score[rows], kind="stable")][: 8 * keep]
    chosen: np.ndarray = ranked[unique_rows(found.release[ranked], settings.distinct_rad)][:keep]
    return chosen


def _two_transfers(
    kinematics: Kinematics,
    begin: _Start,
    goal: np.ndarray,
    rng: np.random.Generator,
    hints: np.ndarray,
    *,
    holds: _GoalHolds,
) -> list[Proposal]:
    """Grasp configurations carried to a release, regrasped there (also with the approaches of ``holds``),
    and carried to the goal."""
    world = kinematics.world
    robot = world.robot
    tuning = kinematics.settings
    first = begin.first
    count, n = first.shape
    goal_side = np.broadcast_to(goal[:2], (count, 2))
    sides = np.tile(np.arange(count), 2)  # from each grasp configuration and its mirror image
    closest = kinematics.toward(begin.grasp_rel[sides], with_mirrors(world, first, goal_side), goal[:2])
    share = np.linspace(1.0 / tuning.towards, 1.0, tuning.towards)
    along = first[sides][:, None, :] + share[None, :, None] * (closest - first[sides])[:, None, :]
    # around the goal: the object put down at points drawn within near_radius_m of it (both elbows)
    radius = tuning.near_radius_m * np.sqrt(rng.uniform(0.0, 1.0, size=len(sides) * tuning.near))
    angle = rng.uniform(0.0, 2.0 * np.pi, size=len(radius))
    points = goal[:2] + np.stack([radius * np.cos(angle), radius * np.sin(angle)], axis=1)
    near_sides = np.repeat(sides, tuning.near)
    near = kinematics.toward(
        begin.grasp_rel[near_sides], np.repeat(with_mirrors(world, first, goal_side), tuning.near, axis=0), points
    )
    anywhere = rng.uniform(robot.joint_lower, robot.joint_upper, size=(count * tuning.anywhere, n))
    hinted = np.repeat(hints, tuning.hinted, axis=0)  # each hint itself, then drawn around it
    drawn = (np.arange(len(hinted)) % tuning.hinted > 0)[:, None]
    hinted = hinted + drawn * rng.normal(0.0, tuning.hint_spread_rad, size=hinted.shape)
    release = np.concatenate([along.reshape(-1, n), near, anywhere, np.tile(hinted, (count, 1))])
    release = np.clip(release, robot.joint_lower, robot.joint_upper)
    option = np.concatenate(
        [
            np.repeat(sides, tuning.towards),
            near_sides,
            np.repeat(np.arange(count), tuning.anywhere),
            np.repeat(np.arange(count), len(hinted)),
        ]
    )
    found = _continue(kinematics, begin, option, release, goal, holds=holds)
    for keep, samples, spread in tuning.rounds:
        if kinematics.stop():
            break
        best = np.concatenate([_best_distinct(found, a, keep, tuning) for a in range(count)]).astype(int)
        if not len(best):
            break
        option = np.repeat(found.option[best], samples)
        centre = np.repeat(found.release[best], samples, axis=0)
        moved = np.clip(centre + rng.normal(0.0, spread, size=centre.shape), robot.joint_lower, robot.joint_upper)
        found = found.joined(_continue(kinematics, begin, option, moved, goal, holds=holds))
    score = found.score(tuning.blocked_penalty_rad)
    order = np.argsort(score, kind="stable")
    order = order[np.isfinite(score[order])][: tuning.max_proposals]
    return [
        Proposal(
            float(found.travel[k]),
            int(found.blocked[k]),
            (int(begin.grasps[found.option[k]]), int(found.grasp[k])),
            np.stack([begin.start, first[found.option[k]], found.release[k], found.regrasp[k], found.end[k]]),
            tuple(int(r) for r in found.routes[k]),
            kinematics.settings.blocked_penalty_rad,
        )
        for k in order
    ]
