"""The proposals' parts (:mod:`clew_ros.planar.regrasp`): their tuning, the work they count, the ways along a
move and the batched inverse kinematics and validity with a margin that finds their key configurations.

:class:`Kinematics` solves for the tip on a point (:func:`clew_ros.planar.inverse.solve_point`) from many seeds
at once and checks configurations with ``margin_m`` to spare through the compiled first pass of the validity
test, counting configurations checked and inverse-kinematics steps (:class:`Effort`), which
:mod:`clew_ros.planar.improve` charges to its budget. :func:`route_waypoints` lays out the ways along a move
(:data:`ROUTES`) and :func:`screen_samples` the configurations the screen tries along one.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from clew_ros.planar.collision import packed_world
from clew_ros.planar.inverse import FULL_TURN_RAD, mirrored, solve_point
from clew_ros.planar.kernel import clearly_valid, screen_routes
from clew_ros.planar.kinematics import compose, tip_poses, transform_points
from clew_ros.planar.search import goals_reached
from clew_ros.planar.world import World

__all__ = [
    "ROUTES",
    "Effort",
    "Kinematics",
    "Proposal",
    "RegraspSettings",
    "directions",
    "goal_holds_near",
    "l1_distances",
    "route_waypoints",
    "screen_samples",
    "unique_rows",
    "with_mirrors",
]

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
    screens: int = 0  # compiled calls of the screen (:meth:`Kinematics.routes`), each many moves


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
    return (8 * 2 ** np.clip(np.ceil(np.log2(np.maximum(l1_distances(a, b) / step_rad, 1.0) / 8.0)), 0, 2)).astype(
        np.int64
    )


class Kinematics:
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
    kinematics = Kinematics(world, margin_m, settings=settings)
    q, ok = kinematics.at_goal(np.asarray(grasp_rel, dtype=float), np.asarray(seeds, dtype=float), goal)
    return q, ok, kinematics.effort


def _within_reach(lengths: np.ndarray, distance: np.ndarray, slack: float) -> np.ndarray:
    """Whether a chain of ``lengths`` (``(n,)`` or ``(B, n)``) can end ``distance`` ``(B,)`` from its base."""
    lengths = np.atleast_2d(lengths)
    total = lengths.sum(axis=1)
    inner = np.maximum(0.0, 2.0 * lengths.max(axis=1) - total)
    reachable: np.ndarray = (distance >= inner - slack) & (distance <= total + slack)
    return reachable


def directions(world: World, points: np.ndarray) -> np.ndarray:
    v = np.asarray(points, float) - world.robot.base
    direction: np.ndarray = np.arctan2(v[..., 1], v[..., 0])
    return direction


def with_mirrors(world: World, q: np.ndarray, targets: np.ndarray) -> np.ndarray:
    """Seeds ``(2 B, n)``: ``q`` ``(B, n)`` and its mirror images about the lines from the base to ``targets``."""
    return np.concatenate([q, mirrored(world.robot, q, directions(world, targets))])


def l1_distances(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    distance: np.ndarray = np.abs(a - b).sum(axis=-1)
    return distance


def unique_rows(q: np.ndarray, tolerance: float) -> np.ndarray:
    """Indices of the first of each group of rows closer than ``tolerance`` (largest joint difference)."""
    keep: list[int] = []
    for i in range(len(q)):
        if not keep or np.min(np.max(np.abs(q[keep] - q[i]), axis=1)) > tolerance:
            keep.append(i)
    return np.array(keep, dtype=int)
