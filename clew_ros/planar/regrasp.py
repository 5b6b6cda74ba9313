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

from clew_ros.planar.collision import packed_world
from clew_ros.planar.inverse import FULL_TURN_RAD, mirrored, solve_point
from clew_ros.planar.kernel import clearly_valid, screen_routes
from clew_ros.planar.kinematics import compose, relative, tip_poses, transform_points
from clew_ros.planar.search import goals_reached
from clew_ros.planar.world import World

__all__ = ["ROUTES", "Effort", "Proposal", "RegraspSettings", "propose", "route_waypoints", "screen_samples"]

#: Ways along a move, as :func:`route_waypoints` lays them out: straight, one joint after the other
#: (first joint first), one joint after the other (last joint first). All are as long in joint travel.
ROUTES = ("straight", "first joint first", "last joint first")


@dataclass(frozen=True)
class RegraspSettings:
    """Tuning of :func:`propose` and :func:`goal_holds_near` (passed in; a test or a benchmark varies a copy)."""

    #: A grasp configuration puts the tip this close to the grasp point (m).
    hold_error_m: float = 1e-9
    #: The goal's inverse kinematics, in passes of (share of goal_angle_tolerance the object's angle is brought
    #: within, share of goal_tolerance the solver's error may leave, the angle's weight in m/rad or None for the
    #: object's radius); a pass after the first only for the rows the ones before left off the goal, on a goal of
    #: narrow angle and an arm of two joints (more set the angle apart from the position). First with room to
    #: spare (a goal configuration puts the object's origin within a quarter of goal_tolerance); then with nearly
    #: all of both tolerances and the angle weighted heavily, so that the position gives way to it: an arm of two
    #: joints may carry a grasp onto the goal only at the edge of both (shapes2 seed 60: no one-transfer proposal
    #: was made and every plan kept a regrasp, 7.43 rad, where the grid reference carries the object once in 5.84
    #: rad, 0.49 rad and 0.015 m off the goal).
    goal_passes: tuple[tuple[float, float, float | None], ...] = ((0.8, 0.25, None), (0.99, 0.9, 1.0))
    #: Release configurations drawn per grasp configuration (and per its mirror image) along the way to where
    #: the object comes closest to the goal.
    towards: int = 6
    #: Release configurations drawn per grasp configuration (and per its mirror image) putting the object down
    #: around the goal.
    near: int = 20
    #: Release configurations drawn per grasp configuration anywhere.
    anywhere: int = 8
    #: Releases drawn around the goal put the object within this distance of it (m).
    near_radius_m: float = 0.6
    #: Releases tried per configuration where the plan put the object down (itself, then drawn around it).
    hinted: int = 4
    #: The spread (rad) of the releases drawn around where the plan put the object down.
    hint_spread_rad: float = 0.2
    #: Refinement rounds around the best releases of each grasp configuration: how many are kept, samples
    #: around each, spread (rad).
    rounds: tuple[tuple[int, int, float], ...] = ((4, 6, 0.3), (3, 6, 0.1))
    #: Releases refined in one round, and proposals returned, lie at least this far apart (rad, largest joint
    #: difference) when they take the same grasps.
    distinct_rad: float = 0.3
    #: Continuations (grasp and posture after a release) screened per release (the shortest ways).
    continuations: int = 2
    #: Releases screened per grasp configuration and round (the shortest ways; the others are dropped).
    screened: int = 8
    #: Joint travel (rad) between configurations sampled by the screen, about.
    screen_step_rad: float = 0.1
    #: Joint travel (rad) a move that looks blocked counts extra when proposals are ranked.
    blocked_penalty_rad: float = 8.0
    #: Configurations closer than this (rad, largest joint difference) count as one.
    unique_rad: float = 1e-6
    #: Configurations drawn per placement to seed how each grasp can hold the goal (:func:`_goal_holds`).
    aligned_draws: int = 4
    #: Proposals returned at most.
    max_proposals: int = 24
    #: On an arm of three or more joints, inverse kinematics for a placement's grasp configurations and, for
    #: one-transfer proposals, the goal's is also solved from this many seeds drawn around each seed (normal,
    #: :attr:`restart_spreads_rad` in turn), and the valid solution nearest the seed (joint travel; around the
    #: plan's own grasp configuration, nearest the arm's) is added: a redundant arm's first solution often folds
    #: into an obstacle, the object or itself, or lies far from where the arm is.
    restarts: int = 8
    #: The spreads (rad) of the restarts' seeds, in turn.
    restart_spreads_rad: tuple[float, ...] = (0.5, 1.0)


@dataclass
class Effort:
    """The work :func:`propose` did: configurations checked, calls of the check, inverse-kinematics steps (one
    configuration, one iteration), calls of the compiled screen."""

    checks: int = 0
    calls: int = 0
    steps: int = 0
    screens: int = 0  # compiled calls of the screen (:meth:`_Kinematics.routes`), each many moves


@dataclass(frozen=True)
class Proposal:
    """A way to the goal: ``keys`` ``(2 k + 1, n)`` = the arm's configuration, then for each of the ``k``
    transfers its grasp configuration and its end (a release, the last one at the goal). ``routes``:
    per move (transit, transfer, ...) the index into :data:`ROUTES` of the first way that looked
    clear, -1 when none did (``blocked`` counts those)."""

    travel: float  # rad, joint travel of the moves between the keys
    blocked: int
    grasps: tuple[int, ...]
    keys: np.ndarray
    routes: tuple[int, ...]
    penalty_rad: float  # joint travel a move that looked blocked counts extra (RegraspSettings.blocked_penalty_rad)

    @property
    def rank(self) -> tuple[float, int]:
        """What proposals are ranked by: joint travel plus ``penalty_rad`` per move that looked blocked, then
        fewer transfers."""
        return self.travel + self.penalty_rad * self.blocked, len(self.grasps)


def route_waypoints(a: np.ndarray, b: np.ndarray, route: int) -> np.ndarray:
    """The waypoints ``(m, n)`` of way ``route`` (:data:`ROUTES`) from ``a`` to ``b`` (repeated corners dropped)."""
    if route == 0:
        return np.array([a, b])
    order = range(len(a)) if route == 1 else range(len(a) - 1, -1, -1)
    points = [np.asarray(a, dtype=float)]
    for joint in order:
        corner = points[-1].copy()
        corner[joint] = b[joint]
        if corner[joint] != points[-1][joint]:
            points.append(corner)
    if len(points) == 1:
        points.append(points[0].copy())
    return np.array(points)


def screen_samples(a: np.ndarray, b: np.ndarray, step_rad: float) -> np.ndarray:
    """How many configurations the screen samples along each move ``a[k] -> b[k]``: about one every
    ``step_rad`` of joint travel (:attr:`RegraspSettings.screen_step_rad`), at least 8, at most 32."""
    return (8 * 2 ** np.clip(np.ceil(np.log2(np.maximum(_l1(a, b) / step_rad, 1.0) / 8.0)), 0, 2)).astype(np.int64)


class _Kinematics:
    """Batched inverse kinematics (:meth:`solve`) and validity with a margin, counting the work."""

    def __init__(
        self,
        world: World,
        margin_m: float,
        should_stop: Callable[[], bool] | None = None,
        max_checks: int | None = None,
        step_checks: float = 0.0,
        *,
        settings: RegraspSettings | None = None,
    ) -> None:
        self.settings = RegraspSettings() if settings is None else settings
        self.world = world
        self.packed = dataclasses.replace(packed_world(world), rounding=max(margin_m, packed_world(world).rounding))
        self.effort = Effort()
        self.should_stop = should_stop
        self.max_checks = max_checks
        self.step_checks = step_checks

    @property
    def exhausted(self) -> bool:
        """Whether the work allowed is done: configurations checked, and inverse-kinematics steps counted as
        ``step_checks`` checks each."""
        done = self.effort.checks + self.step_checks * self.effort.steps
        return self.max_checks is not None and done >= self.max_checks

    def solve(
        self,
        seeds: np.ndarray,
        targets: np.ndarray,
        reached_m: float,
        *,
        offsets: np.ndarray | None = None,
        angles: np.ndarray | None = None,
        angle_tolerance: float = np.pi,
        angle_scale: float = 1.0,
        tolerance_m: float | None = None,
    ) -> tuple[np.ndarray, np.ndarray]:
        """:func:`solve_point` from ``seeds`` ``(B, n)`` onto ``targets`` (``(B, 2)`` or one point; ``offsets``
        and ``angles`` per row), counting its steps; the rows it leaves more than ``reached_m`` from their
        target are solved again taking a joint that turns all the way round past its limits (``full_turns``),
        and the nearer answer kept. A target behind the base lies past joint 1's limit from seeds on one side
        (shapes2 seed 50: every grasp point, from the start and from its mirror image, so no grasp
        configuration was found there); a redundant arm mostly reaches it without a turn, nearer its seed, as
        before. The configurations and their errors (m)."""
        robot = self.world.robot
        points = np.broadcast_to(np.asarray(targets, float), (len(seeds), 2))

        def solved(rows: np.ndarray | slice, full_turns: bool) -> tuple[np.ndarray, np.ndarray, int]:
            return solve_point(
                robot,
                seeds[rows],
                points[rows],
                offsets=None if offsets is None else offsets[rows],
                angles=None if angles is None else angles[rows],
                angle_tolerance=angle_tolerance,
                angle_scale=angle_scale,
                tolerance_m=tolerance_m,
                full_turns=full_turns,
            )

        q, error, steps = solved(slice(None), False)
        self.effort.steps += steps + len(q)
        short = np.flatnonzero(error > reached_m)
        if len(short) and np.any(robot.joint_upper - robot.joint_lower >= FULL_TURN_RAD):
            again, left, more = solved(short, True)
            self.effort.steps += more + len(short)
            nearer = left < error[short]  # by error alone: the answers differ only where the first met a limit
            q[short[nearer]], error[short[nearer]] = again[nearer], left[nearer]
        return q, error

    def stop(self) -> bool:
        return self.exhausted or (self.should_stop is not None and self.should_stop())

    def valid(self, q: np.ndarray, poses: np.ndarray) -> np.ndarray:
        if not len(q):
            return np.zeros(0, dtype=bool)
        self.effort.checks += len(q)
        self.effort.calls += 1
        return clearly_valid(self.packed, np.ascontiguousarray(q), np.ascontiguousarray(poses))

    def routes(
        self, a: np.ndarray, b: np.ndarray, *, resting: np.ndarray | None = None, grasp_rel: np.ndarray | None = None
    ) -> np.ndarray:
        """Per move ``a[k] -> b[k]``, the first way of :data:`ROUTES` whose sampled configurations are all
        valid (the object resting at ``resting[k]`` or held as ``grasp_rel[k]``); -1 when none is. A move
        is sampled about every :attr:`RegraspSettings.screen_step_rad` of joint travel (at least 8, at most 32 samples),
        every fourth sample first; one compiled call (:func:`clew_ros.planar.kernel.screen_routes`)."""
        if self.exhausted or not len(a):
            return np.full(len(a), -1)
        route, checked = screen_routes(
            self.packed, a, b, screen_samples(a, b, self.settings.screen_step_rad), resting=resting, grasp_rel=grasp_rel
        )
        self.effort.checks += checked
        self.effort.screens += 1
        return route

    def holding(
        self, placements: np.ndarray, grasps: np.ndarray, seeds: np.ndarray, tip_angles: np.ndarray | None = None
    ) -> tuple[np.ndarray, np.ndarray]:
        """Configurations near ``seeds`` holding ``grasps`` of the object resting at ``placements`` (all
        ``(B, .)``), with the tip at ``tip_angles`` ``(B,)`` if given (else any), and which ones do, validly."""
        robot = self.world.robot
        targets = transform_points(placements, self.world.object.grasps)[np.arange(len(grasps)), grasps]
        q = np.array(seeds, dtype=float)
        ok = _within_reach(robot.link_lengths, np.hypot(*(targets - robot.base).T), 0.0)
        angles = None if tip_angles is None else tip_angles[ok]
        solved, error = self.solve(
            seeds[ok], targets[ok], self.settings.hold_error_m, angles=angles, angle_tolerance=0.0
        )
        q[ok] = solved
        ok[ok] = error <= self.settings.hold_error_m
        ok[ok] = self.valid(q[ok], placements[ok])
        return q, ok

    def restarted(
        self,
        solve: Callable[[np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray]],
        seeds: np.ndarray,
        rng: np.random.Generator,
        origins: np.ndarray | None = None,
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``solve(rows, seeds)`` (configurations for queries ``rows`` from ``seeds``, and which are valid) for
        each seed; on an arm of three or more joints also from :attr:`RegraspSettings.restarts` seeds drawn around
        each, whose valid solution nearest the query's origin (joint travel; ``origins`` ``(B, n)``, default the seeds)
        comes as one more row when it is nearer than the seed's own. Returns the query of each row, the
        configurations and which are valid."""
        count, n = seeds.shape
        origins = seeds if origins is None else origins
        q, ok = solve(np.arange(count), seeds)
        if self.world.robot.dof < 3 or not count:
            return np.arange(count), q, ok
        restarts = self.settings.restarts
        spreads = np.resize(np.asarray(self.settings.restart_spreads_rad, dtype=float), restarts)
        drawn = seeds[None] + spreads[:, None, None] * rng.normal(0.0, 1.0, size=(restarts, count, n))
        more, fine = solve(np.tile(np.arange(count), restarts), drawn.reshape(-1, n))
        more, fine = more.reshape(restarts, count, n), fine.reshape(restarts, count)
        distance = np.where(fine, np.abs(more - origins[None]).sum(axis=2), np.inf)
        best = np.argmin(distance, axis=0)
        rows = np.arange(count)
        nearer = np.flatnonzero(distance[best, rows] < np.where(ok, np.abs(q - origins).sum(axis=1), np.inf))
        return (
            np.concatenate([rows, nearer]),
            np.concatenate([q, more[best[nearer], nearer]]),
            np.concatenate([ok, np.ones(len(nearer), dtype=bool)]),
        )

    def at_goal(self, grasp_rel: np.ndarray, seeds: np.ndarray, goal: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Configurations near ``seeds`` putting the object, held as ``grasp_rel``, on the goal within its
        tolerances, and which do, validly."""
        world = self.world
        lengths = np.broadcast_to(world.robot.link_lengths, (len(grasp_rel), world.robot.dof)).copy()
        lengths[:, -1] = np.hypot(lengths[:, -1] + grasp_rel[:, 0], grasp_rel[:, 1])  # joint n to the object
        distance = np.full(len(grasp_rel), float(np.hypot(*(goal[:2] - world.robot.base))))
        narrow = world.goal_angle_tolerance < np.pi - 1e-6
        q = np.array(seeds, dtype=float)
        ok = np.zeros(len(q), dtype=bool)
        # an arm of fewer than three joints cannot set the object's angle apart from its position: on a narrow
        # goal angle its rows the first pass left off the goal try the next
        goal_passes = self.settings.goal_passes
        passes = goal_passes if narrow and world.robot.dof < 3 else goal_passes[:1]
        for slack, share, weight in passes:
            reach = _within_reach(lengths, distance, share * world.goal_tolerance)
            rows = np.flatnonzero(reach & ~ok)  # the rows the tighter pass left off the goal try the wider one
            if not len(rows):
                break
            solved, error = self.solve(
                seeds[rows],
                goal[:2],
                share * world.goal_tolerance,
                offsets=grasp_rel[rows, :2],
                angles=goal[2] - grasp_rel[rows, 2] if narrow else None,
                angle_tolerance=slack * world.goal_angle_tolerance,
                angle_scale=world.object.radius if weight is None else weight,
                tolerance_m=1e-9,
            )
            q[rows] = solved
            ok[rows] = error <= share * world.goal_tolerance
        # That error bounds both the position's error and the angle's weight times its excess over the slack share
        # of the tolerance, which need not keep the angle within the tolerance itself: the goal's own test decides.
        held = compose(tip_poses(world.robot, q[ok]), grasp_rel[ok])
        reached = goals_reached(world, held, goal)
        ok[ok] = reached
        ok[ok] = self.valid(q[ok], held[reached])
        return q, ok

    def toward(self, grasp_rel: np.ndarray, seeds: np.ndarray, points: np.ndarray) -> np.ndarray:
        """Where the object's origin, held as ``grasp_rel``, gets closest to ``points`` from ``seeds`` (reached
        or not)."""
        q, _ = self.solve(seeds, points, 1e-6, offsets=grasp_rel[:, :2], tolerance_m=1e-6)
        return q


def goal_holds_near(
    world: World,
    grasp_rel: np.ndarray,
    seeds: np.ndarray,
    goal: np.ndarray,
    *,
    margin_m: float,
    settings: RegraspSettings | None = None,
) -> tuple[np.ndarray, np.ndarray, Effort]:
    """Configurations near ``seeds`` ``(B, n)`` (inverse kinematics from each) putting the object, held as
    ``grasp_rel`` ``(B, 3)``, on ``goal`` within its tolerances, which ones do, valid with ``margin_m`` to
    spare, and the work done: the goal configurations of :func:`propose`'s one-transfer proposals (``settings``:
    the tuning, the default :class:`RegraspSettings` when not given)."""
    kinematics = _Kinematics(world, margin_m, settings=settings)
    q, ok = kinematics.at_goal(np.asarray(grasp_rel, dtype=float), np.asarray(seeds, dtype=float), goal)
    return q, ok, kinematics.effort


def _within_reach(lengths: np.ndarray, distance: np.ndarray, slack: float) -> np.ndarray:
    """Whether a chain of ``lengths`` (``(n,)`` or ``(B, n)``) can end ``distance`` ``(B,)`` from its base."""
    lengths = np.atleast_2d(lengths)
    total = lengths.sum(axis=1)
    inner = np.maximum(0.0, 2.0 * lengths.max(axis=1) - total)
    reachable: np.ndarray = (distance >= inner - slack) & (distance <= total + slack)
    return reachable


def _direction(world: World, points: np.ndarray) -> np.ndarray:
    v = np.asarray(points, float) - world.robot.base
    direction: np.ndarray = np.arctan2(v[..., 1], v[..., 0])
    return direction


def _with_mirrors(world: World, q: np.ndarray, targets: np.ndarray) -> np.ndarray:
    """Seeds ``(2 B, n)``: ``q`` ``(B, n)`` and its mirror images about the lines from the base to ``targets``."""
    return np.concatenate([q, mirrored(world.robot, q, _direction(world, targets))])


def _l1(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    distance: np.ndarray = np.abs(a - b).sum(axis=-1)
    return distance


def _unique_rows(q: np.ndarray, tolerance: float) -> np.ndarray:
    """Indices of the first of each group of rows closer than ``tolerance`` (largest joint difference)."""
    keep: list[int] = []
    for i in range(len(q)):
        if not keep or np.min(np.max(np.abs(q[keep] - q[i]), axis=1)) > tolerance:
            keep.append(i)
    return np.array(keep, dtype=int)


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
    drawn: np.ndarray  # (A,) found by restarts (:meth:`_Kinematics.restarted`) besides their seed's own

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
    own: list[tuple[int, np.ndarray]] | None = None,
    releases: np.ndarray | None = None,
    finals: np.ndarray | None = None,
    one_transfer: bool = True,
    two_transfers: bool = True,
    margin_m: float = 0.0,
    should_stop: Callable[[], bool] | None = None,
    max_checks: int | None = None,
    step_checks: float = 0.0,
    restarts: np.random.Generator | None = None,
    settings: RegraspSettings | None = None,
) -> tuple[list[Proposal], Effort]:
    """Ways to the goal from the arm at ``start`` with the object resting at ``placement``, with one transfer
    (if ``one_transfer``) and two (if ``two_transfers``). ``own``: grasp configurations ``(grasp, q)`` of
    the plan that hold the object at this placement, tried as they are. ``releases`` ``(m, n)``:
    configurations where the plan put the object down, tried (and around them) as releases. ``finals``
    ``(m, n)``: the plan's configurations at the goal, from which :func:`_goal_holds` finds how each grasp
    can hold the goal, for grasp configurations here and at releases with that approach. Ranked by joint
    travel plus :attr:`RegraspSettings.blocked_penalty_rad` per move that looked blocked; alike ones dropped
    (:func:`_distinct`).

    ``should_stop`` (the planner's termination) is asked between stages (each a few tens of
    milliseconds at most): when it says stop, the proposals found so far are returned; so they are
    once ``max_checks`` configurations have been checked, each inverse-kinematics step (one
    configuration, one iteration) counting ``step_checks`` (moves not checked then count as blocked).
    ``restarts``: the generator the inverse kinematics' restarts (:attr:`RegraspSettings.restarts`) draw from, default
    ``rng``; one of its own leaves ``rng``'s stream to the releases. ``settings``: the tuning, the default
    :class:`RegraspSettings` when not given.
    Returns the proposals (at most :attr:`RegraspSettings.max_proposals`) and the work done.
    """
    kinematics = _Kinematics(world, margin_m, should_stop, max_checks, step_checks, settings=settings)
    restarts = rng if restarts is None else restarts
    start, placement = np.asarray(start, float), np.asarray(placement, float)
    finals = np.zeros((0, len(start))) if finals is None else np.asarray(finals, float)
    holds = _goal_holds(kinematics, start, goal, finals=finals, rng=rng)
    aligned = _aligned_at(kinematics, start, placement, holds)
    begin = _grasps_at_start(
        kinematics, start, placement, own or [], aligned, rng=restarts, own_goal=finals[-1] if len(finals) else None
    )
    if begin is None:
        return [], kinematics.effort
    proposals = _one_transfer(kinematics, begin, goal, restarts) if one_transfer else []
    seeded = begin.seeded()
    if two_transfers and len(seeded.first) and not kinematics.stop():
        hints = np.zeros((0, len(begin.start))) if releases is None else np.asarray(releases, float)
        proposals += _two_transfers(kinematics, seeded, goal, rng, hints, holds=holds.first_per_grasp())
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
    kinematics: _Kinematics,
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
    unique = _unique_rows(first, kinematics.settings.unique_rad)
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
    kinematics: _Kinematics,
    start: np.ndarray,
    placement: np.ndarray,
    own: list[tuple[int, np.ndarray]],
    rng: np.random.Generator,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Valid configurations holding each grasp from the start and its mirror image, with the restarts'
    (:meth:`_Kinematics.restarted`) and, around the plan's own grasp configurations, ones nearer the start
    (three joints or more; the plan's own are proposed as they are by the caller):
    the configurations, their grasps, and which came from restarts besides a valid solution from their seed
    (a restart in place of a seed whose own solution is not valid counts as that seed's)."""
    world = kinematics.world
    n = len(start)
    grasps = np.repeat(np.arange(len(world.object.grasps)), 2)
    targets = transform_points(placement, world.object.grasps)[grasps]
    seeds = mirrored(world.robot, np.repeat(start[None], len(grasps), axis=0), _direction(world, targets))
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
    kinematics: _Kinematics, start: np.ndarray, goal: np.ndarray, *, finals: np.ndarray, rng: np.random.Generator
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
    seeds = _with_mirrors(world, seeds, transform_points(goal, world.object.grasps)[grasps[: len(seeds)]])
    goals = np.broadcast_to(goal, (len(grasps), 3))
    held, ok = kinematics.holding(goals, grasps, seeds)
    grasps, held = grasps[ok], held[ok]
    unique = _unique_rows(held, kinematics.settings.unique_rad)
    grasps, held = grasps[unique], held[unique]
    approach = relative(tip_poses(robot, held), goals[: len(held)])[:, 2]
    return _GoalHolds(grasps, held, approach)


def _aligned_at(
    kinematics: _Kinematics, start: np.ndarray, placement: np.ndarray, holds: _GoalHolds
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


def _one_transfer(kinematics: _Kinematics, begin: _Start, goal: np.ndarray, rng: np.random.Generator) -> list[Proposal]:
    """Grasp configurations carried straight to the goal."""
    world = kinematics.world
    first = begin.first
    seeds = _with_mirrors(world, first, np.broadcast_to(goal[:2], (len(first), 2)))
    rows = np.tile(np.arange(len(first)), 2)
    seeds, rows = _and_goal_seeds(seeds, rows, begin.goal_seeds)
    queries, ends, ok = kinematics.restarted(
        lambda k, q: kinematics.at_goal(begin.grasp_rel[rows[k]], q, goal), seeds, rng
    )
    rows, ends = rows[queries[ok]], ends[ok]
    route = kinematics.routes(first[rows], ends, grasp_rel=begin.grasp_rel[rows])
    travel = _l1(begin.start, first[rows]) + _l1(first[rows], ends)
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
    kinematics: _Kinematics,
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
    seeds = _with_mirrors(world, release[rows], targets)
    rows, grasp = np.tile(rows, 2), np.tile(grasp, 2)
    regrasp, ok = kinematics.holding(placement[rows], grasp, seeds)
    unaligned = (rows[ok], grasp[ok], regrasp[ok], np.full((int(ok.sum()), n), np.nan))
    rows, grasp, regrasp, goal_seeds = _and_aligned(
        kinematics, placement, release, alive, holds=holds, regrasps=unaligned
    )
    rel2 = relative(tip_poses(world.robot, regrasp), placement[rows])
    seeds = _with_mirrors(world, regrasp, np.broadcast_to(goal[:2], (len(regrasp), 2)))
    pick = np.tile(np.arange(len(regrasp)), 2)
    seeds, pick = _and_goal_seeds(seeds, pick, goal_seeds)
    end, ok = kinematics.at_goal(rel2[pick], seeds, goal)
    pick, end = pick[ok], end[ok]
    rows, grasp, regrasp, rel2 = rows[pick], grasp[pick], regrasp[pick], rel2[pick]
    travel = _l1(release[rows], regrasp) + _l1(regrasp, end)
    order = np.lexsort((travel, rows))  # per release, its shortest continuations first
    rank = np.zeros(len(order), dtype=int)
    if len(order):
        starts = np.r_[True, rows[order][1:] != rows[order][:-1]]
        group = np.cumsum(starts) - 1
        rank[order] = np.arange(len(order)) - np.flatnonzero(starts)[group]
    total = _l1(begin.start, first[rows]) + _l1(first[rows], release[rows]) + travel
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
    kinematics: _Kinematics,
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
    chosen: np.ndarray = ranked[_unique_rows(found.release[ranked], settings.distinct_rad)][:keep]
    return chosen


def _two_transfers(
    kinematics: _Kinematics,
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
    closest = kinematics.toward(begin.grasp_rel[sides], _with_mirrors(world, first, goal_side), goal[:2])
    share = np.linspace(1.0 / tuning.towards, 1.0, tuning.towards)
    along = first[sides][:, None, :] + share[None, :, None] * (closest - first[sides])[:, None, :]
    # around the goal: the object put down at points drawn within near_radius_m of it (both elbows)
    radius = tuning.near_radius_m * np.sqrt(rng.uniform(0.0, 1.0, size=len(sides) * tuning.near))
    angle = rng.uniform(0.0, 2.0 * np.pi, size=len(radius))
    points = goal[:2] + np.stack([radius * np.cos(angle), radius * np.sin(angle)], axis=1)
    near_sides = np.repeat(sides, tuning.near)
    near = kinematics.toward(
        begin.grasp_rel[near_sides], np.repeat(_with_mirrors(world, first, goal_side), tuning.near, axis=0), points
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
