"""Anytime improvement of a found plan (issue 14): fewer transfers, shorter paths, never worse.

The ACA keeps every single manipulation path that led to the goal, made of
Manhattan moves (one joint at a time, in large arcs), and takes the object
wherever its search happened to: often with the elbow the wrong way round,
or put down far from where a regrasp was needed. Once a plan is found,
:func:`improve` spends a bounded budget (``planner.improve_time``) on it:

1. **Back-and-forth pruning** (free): a transfer put down and taken again by
   the same grasp where the arm stopped becomes one transfer
   (:func:`_joined_regrasps`); a waypoint between two collinear
   pieces (a joint moving one way, then back) is dropped, and so is a loop
   that comes back to an earlier waypoint. The configurations left were
   already on the plan, so nothing needs checking.
2. **Rebuilding the manipulation** (at most :data:`REBUILD_SHARE` of the
   budget): from each placement of the plan (the start, then where each
   transfer put the object down), :func:`clew_ros.core.regrasp.propose`
   lists ways to finish with one transfer or, when none of those made the
   plan better (fewer transfers always win), two (one regrasp), through any
   grasp, either elbow and release placements drawn around the goal, made
   of straight moves between key configurations found by inverse
   kinematics (on arms of three or more joints also grasps whose approach can
   hold the object on the goal, a rigid grasp keeping it while carried; a
   round's inverse kinematics counts against its allowance of checks). They
   are ranked by joint travel plus a penalty per move that a quick sampled
   check found blocked, and checked in that order: each
   move continuously (below), straight or one joint after the other (as
   long in joint travel), else through a configuration drawn inside the box
   between its ends (as long too) or around its middle. Proposals with a move
   that looked blocked are checked too (fewer: :data:`BLOCKED_TRIES`), after
   all of the placement's that looked clear (one transfer, then two), fewer
   transfers first, when they would still make the plan better: such a move
   is routed by RRT-Connect (:meth:`_Improver.connect`, moves checked
   continuously, then shortened; on an arm of at most three joints the
   shortest path on a joint-space lattice, :mod:`clew_ros.core.lattice`,
   replaces it when shorter), given up, when no routed proposal made the
   plan better, after :data:`CONNECT_PROBES` routings that found no path or
   :data:`ROUTED_PROBES` routed proposals that did not make it better. A move found blocked makes alike proposals
   (both ends within :data:`MOVE_ALIKE_RAD`) skipped. A proposal is compared
   with its last transfer ended on the goal sooner where it can be (the goal
   shortcut of step 5); each that makes the plan better replaces the plan's
   end from that placement on, and the later ones must beat it. Passes repeat while they find something
   (:data:`REBUILD_IDLE_PASSES`); a placement from which every proposal looked
   blocked and none worked (a cluttered world) ends the rebuilding, leaving
   the budget to shortcuts.
3. **One regrasp on the lattice** (an arm of three joints; each search within :data:`REGRASP_SHARE` of the
   budget, none started once :data:`REGRASP_TOTAL_SHARE` of it is spent): from the start of a transfer to the
   end of a later one, the longest spans first, :func:`clew_ros.core.lattice.lattice_regrasp` carries the
   object with the first one's grasp to the release where the way is shortest, puts it down, takes it
   as the last one holds it and carries it on to that one's end, every move checked continuously; it
   replaces every piece between when that makes the plan better (:meth:`_Improver.lattice_regrasps`).
   In clutter the rebuilding's straight-move proposals all look blocked, and this is what takes a
   transfer out.
4. **Fewer transfers**: from the start of each transfer but the last
   (earliest first), SEARCH_TRANSFER tries to carry the object, with that
   transfer's grasp, straight to the goal; the first success replaces every
   later segment. A search may take a whole population's decoding for
   every generation and round, more than the default budget, so it starts
   only when that much work fits in :data:`TRANSFER_SHARE` of the budget
   (a larger ``planner.improve_time``).
5. **Shortcuts**: a sub-path of one segment is replaced by one straight
   joint-space move (all joints together): first greedily, from each waypoint
   to the farthest later one that is clear (the segment's last, else halfway
   there, a quarter, ...), then between pairs of waypoints and pairs of points
   along the path drawn by the run's generator; or, between two such points, one joint is made to move
   evenly while the others move as before (a partial shortcut: a joint that
   went back and forth there goes straight). These are drawn in batches of
   :data:`SHORTCUT_BATCH` on one segment, scored in one compiled call, and those that would
   shorten it are checked in one compiled call; the clear ones that do not
   overlap are taken, the largest gain first. A segment's end points never
   change, so every grasp and ungrasp stays where it was (the tip still
   holds its grasp) and the object rests or is carried exactly as before;
   but the last transfer may end anywhere on the goal: before and after
   them, *goal shortcuts* (:meth:`_Improver.goal_shortcuts`) join one of its
   waypoints straight to a configuration holding the object on the goal
   that inverse kinematics finds from there, when that is shorter.
6. **Another first grasp on the lattice** (an arm of three joints; after the shortcuts, then the shortcuts again
   if it changed the plan; each search within :data:`REGRASP_SHARE`, none started once
   :data:`REGRASP_TOTAL_SHARE` is spent): the plan's transit to its first grasp routed again on the lattice
   (:meth:`_Improver.first_transit`, kept when shorter), then the ways to take the object at the start
   (:func:`clew_ros.core.lattice.grasp_configurations`), least joint travel from the start and on to the last
   transfer's end first, each with the transit to it routed on the lattice and one regrasp placed as step 3
   places it, replacing the plan up to its last transfer when that makes it better
   (:meth:`_Improver.lattice_first_grasps`). After the shortcuts, because the lattice's paths are about as short
   as shortcuts make them and the first plan's are not.

Steps 2 to 6 are one round. Rounds repeat while the last one made the plan
better and work is left; after the first, the rebuilding may use the whole
budget (what the shortcuts left: a plan of straight moves leaves them nothing
to do).

A change is kept only when it lowers ``(transfers, joint travel)`` or keeps
them and drops waypoints; joint travel is the sum over joints of the
absolute motion (rad). The first plan is kept when nothing better is found.

**Every new move is checked continuously**
(:func:`clew_ros.core.continuous.straight_move_clear`): valid at any
checking resolution, keeping at least :data:`MIN_MARGIN_FACTOR` x
``planner.clearance`` from everything, like the planner's own paths. The whole improved plan is checked once more
at the validator's 0.002 rad, and the object's end against the goal's tolerances; if that ever failed,
the first plan would be returned, and ``improve_refused`` in its stats would say why.

**Determinism.** All choices come from a generator seeded with
``planner.seed`` (apart from the planner's own), and the budget is counted
in work, not seconds: :data:`WORK_PER_SECOND` units per second of
``planner.improve_time``; a configuration checked costs
:data:`BATCH_CHECK_SHARE` units, or more in a world whose check compares
more pieces (:func:`check_work`), plus
:data:`MOVE_CALL_WORK` per call of the compiled straight-move check,
:data:`CALL_WORK` per call of the configuration check, :data:`BATCH_WORK` per batch of
random shortcuts, :data:`SHORTCUT_TRY_WORK` and :data:`WAYPOINT_WORK` per
greedy shortcut tried, :data:`IK_WORK` per step of inverse kinematics and
:data:`EVALUATION_WORK` per genetic-algorithm individual.
The final check of the segments changed so far at the validator's step is
reserved from the budget as they change (:data:`DENSE_WORK` of what a
configuration checked costs, per configuration), so it fits in the budget too. Attempts run
until the work is spent, so the same seed gives the same plan on any machine.
Only the planner's time limit and cancel stop it by the clock (between
calls of the checks and between rounds of routing calls, well within 100 ms),
and then the best plan so far is returned.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, replace

import numpy as np

from clew_ros.core.connect import rrt_connect, shortened
from clew_ros.core.continuous import (
    CHECK_STEP_RAD,
    MIN_MARGIN_FACTOR,
    path_valid,
    straight_moves_clear,
)
from clew_ros.core.kernel import pruned_path, shortcuts
from clew_ros.core.kinematics import compose, relative, tip_poses
from clew_ros.core.lattice import KnownNodes, grasp_configurations, lattice_regrasp, lattice_route, lattice_step
from clew_ros.core.regrasp import ROUTES, Proposal, goal_holds_near, propose, route_waypoints
from clew_ros.core.search import PlanningContext, goal_reached, search_transfer
from clew_ros.core.tree import Segment
from clew_ros.core.world import World

__all__ = [
    "BATCH_CHECK_SHARE",
    "BATCH_WORK",
    "CALL_WORK",
    "EVALUATION_WORK",
    "FLOOD_WORK",
    "IK_WORK",
    "MIN_MARGIN_FACTOR",
    "MOVE_CALL_WORK",
    "REFERENCE_COST",
    "RELEASE_WORK",
    "ROUND_WORK",
    "SHORTCUT_TRY_WORK",
    "WAYPOINT_WORK",
    "WORK_PER_SECOND",
    "Improvement",
    "check_work",
    "improve",
    "joint_travel",
]

#: Work units per second of ``planner.improve_time``: on the machine of docs/benchmarks.md, when quiet, the
#: improvement's wall time is 0.5-1.3 of the seconds its work stands for on 27 of the 28 worlds there (medians
#: per world over two runs, ``benchmarks.improvement``'s last column; shapes2_1, 0.02 s in all, up to 1.8) and
#: at most 0.54 s of the default 0.5 s; up to twice that with its 2 cores shared with other jobs. The same work
#: everywhere.
WORK_PER_SECOND = 5.25e5
#: Work of one configuration checked in a batched call of the compiled checks, per unit of :func:`check_work`:
#: such a check takes 0.4-1.3 of what this charges at :data:`WORK_PER_SECOND`, 0.13-0.40 of a whole unit
#: (``python -m benchmarks.check_cost``: 8,000 configurations a call, each checked still or along a move, eight
#: worlds), the Python around each call being charged by the call (:data:`CALL_WORK`, :data:`MOVE_CALL_WORK`).
BATCH_CHECK_SHARE = 0.3
#: Work of one call of the compiled configuration check from Python (the Python around it: the proposals'
#: inverse kinematics computes poses and checks its solutions), in work units.
CALL_WORK = 200
#: Work of one call of the compiled straight-move check (:func:`clew_ros.core.continuous.straight_moves_clear`:
#: the Python around it, one or several moves), or of the proposals' compiled screen
#: (:func:`clew_ros.core.kernel.screen_routes`), in the same units.
MOVE_CALL_WORK = 20
#: Work of one round of RRT-Connect besides its checks (drawing its configuration, finding the nearest node), in
#: the same units.
ROUND_WORK = 2.0
#: Work of one genetic-algorithm individual (a decoded Manhattan path), in units (110 at 3.5e5 units a second,
#: scaled with :data:`WORK_PER_SECOND` in session 20: a whole search, 24 x 12 x 3 individuals, still does not fit
#: :data:`TRANSFER_SHARE` of the default budget; no plan of the 28 benchmark worlds changed).
EVALUATION_WORK = 165
#: Random shortcuts drawn, scored and checked together (:meth:`_Improver.random_shortcuts`: one compiled call
#: checks every move of those that would make the path shorter).
SHORTCUT_BATCH = 16
#: Work of one batch of random shortcuts besides its checks (drawing and scoring them, compiled; splicing them), in
#: units.
BATCH_WORK = 150
#: Work of one shortcut tried by :meth:`_Improver.try_shortcut` besides its check (the Python that splices and
#: prunes the path and scores it), and more for each waypoint of the segment: on a 7-joint plan of 150 waypoints a
#: try took 0.27 ms where its check was charged 0.18 ms (``benchmarks.improvement_stages``: the greedy shortcuts'
#: wall time 1.4 times their work).
SHORTCUT_TRY_WORK, WAYPOINT_WORK = 40, 1.0
#: Batches of random shortcuts in a row that change nothing end them.
IDLE_BATCHES = 12
#: Work of one step of inverse kinematics (one configuration, one iteration), in units.
IK_WORK = 0.125
#: The cost of one configuration check, in joints (the links are what the compiled check places and tests,
#: each against the obstacles' boxes, the object and each other): each pair of links tested for
#: self-collision costs this many joints, and so does each of :data:`OBSTACLES_PER_JOINT` obstacles.
SELF_PAIR_JOINTS = 0.2
OBSTACLES_PER_JOINT = 16
#: figure1's check cost in those terms (2 joints, 2 obstacles): a :func:`check_work` of 1.
REFERENCE_COST = 2.125
#: Share of the budget that attempts to drop transfers may start in.
TRANSFER_SHARE = 0.5
#: Share of the budget that rebuilding the manipulation from straight moves may start in.
REBUILD_SHARE = 0.6
#: Share of what is left of the rebuilding's budget one round of proposals may spend (checks, inverse kinematics).
PROPOSE_SHARE = 0.5
#: Rebuilding stops after this many passes in a row that found nothing better.
REBUILD_IDLE_PASSES = 2
#: Proposals checked per placement at most (none with a move that looked blocked).
REBUILD_TRIES = 6
#: Proposals whose key configurations all lie this close (rad) to one that failed are not checked.
ALIKE_RAD = 0.3
#: Detours tried around a straight move of a proposal that is not clear.
DETOURS = 3
#: Proposals with a move that looked blocked checked per placement at most (their blocked moves are routed
#: by :meth:`_Improver.connect`).
BLOCKED_TRIES = 3
#: Routings by :meth:`_Improver.connect` that may find no path, and proposals with a routed move that may fail
#: to make the plan better, before the first that does; after that many and none that did, proposals with a move
#: that looked blocked are no longer checked (a cluttered world: the budget is left to the shortcuts).
CONNECT_PROBES, ROUTED_PROBES = 1, 2
#: Share of the budget one :meth:`_Improver.connect` may spend at most, and its rounds at most.
CONNECT_SHARE, CONNECT_STEPS = 0.2, 1000
#: :meth:`_Improver.lattice_regrasps`: the share of the budget one search may take, and the share spent after
#: which none starts (the rest is the shortcuts').
REGRASP_SHARE, REGRASP_TOTAL_SHARE = 0.35, 0.6
#: :meth:`_Improver.lattice_first_grasps`: tip angles tried around each grasp point.
FIRST_GRASP_APPROACHES = 24
#: Work units per node a Dijkstra search of :func:`clew_ros.core.lattice.lattice_regrasp` expands (measured: 1.2 ms
#: for 5,300 nodes of obstacles_32's lattice, 0.12 units a node at :data:`WORK_PER_SECOND`).
FLOOD_WORK = 0.12
#: Work units per release per round of :func:`clew_ros.core.lattice.lattice_regrasp`: totalling the releases
#: (compiled, :func:`clew_ros.core.kernel.release_totals`, when a search changed) and picking the best not found
#: blocked, with the round's Python (measured: 0.26 ms a round of about 5,000 releases on obstacles_16, 24 and 32,
#: 0.027 units a release at :data:`WORK_PER_SECOND`).
RELEASE_WORK = 0.03
#: A move whose ends both lie this close (rad, largest joint difference) to those of a move found blocked
#: in the same mode is taken as blocked too.
MOVE_ALIKE_RAD = 0.1
#: A partial shortcut spans at most this many pieces of the path.
PARTIAL_PIECES = 8
#: Stream of the generator the proposals' inverse-kinematics restarts draw from (with ``planner.seed``).
RESTART_STREAM = 19
#: Joint travel below this (rad) counts as equal.
TRAVEL_EPS = 1e-9
#: Work of one configuration of the final check at the validator's step, as a share of what a configuration
#: checked costs (:data:`BATCH_CHECK_SHARE` x :func:`check_work`). The final check of the segments changed so
#: far is kept out of the budget.
DENSE_WORK = 0.5
#: Work of one node expanded by the lattice's compiled A* (:func:`clew_ros.core.kernel.lattice_search`), in units
#: (0.26 microseconds a node, measured on a 34^3 lattice with a wall).
EXPANSION_WORK = 0.2
#: Configurations this close (rad, largest joint difference) count as the same where a transfer is put down
#: and taken again (:func:`_joined_regrasps`).
SAME_RAD = 1e-12


def joint_travel(segments: list[Segment] | list[np.ndarray]) -> float:
    """Sum over joints of the absolute motion (rad) along segments (or waypoint arrays)."""
    total = 0.0
    for segment in segments:
        waypoints = np.asarray(segment.waypoints if isinstance(segment, Segment) else segment, dtype=float)
        if len(waypoints) > 1:
            total += float(np.abs(np.diff(waypoints, axis=0)).sum())
    return total


@dataclass
class Improvement:
    """What :func:`improve` made of a plan (``segments`` is the first plan when nothing was better)."""

    segments: list[Segment]
    final_object_pose: np.ndarray
    first_travel: float  # rad
    first_transfers: int
    travel: float  # rad
    transfers: int
    shortcuts: int  # straight moves accepted
    work: int  # work units spent (deterministic)
    stopped: bool  # the time limit or cancel cut it short
    refused: str = ""  # why a better plan was not returned: "" (it was, or none was found), or what failed of it


@dataclass
class _Piece:
    """One segment as the improvement sees it: the object's pose at its start, the grasp's relative pose."""

    kind: str
    grasp: int | None
    waypoints: np.ndarray  # (m, n)
    start_pose: np.ndarray  # (3,) where the object is when the segment starts
    grasp_rel: np.ndarray | None  # (3,) object in the end-effector frame (transfer)

    def end_pose(self, world: World) -> np.ndarray:
        if self.grasp_rel is None:
            return self.start_pose
        end: np.ndarray = compose(tip_poses(world.robot, self.waypoints[-1:]), self.grasp_rel)[0]
        return end

    def segment(self) -> Segment:
        return Segment(self.kind, self.grasp, [w.copy() for w in self.waypoints])


def _pieces(world: World, segments: list[Segment]) -> list[_Piece]:
    """The plan's segments with the object carried along (as :func:`clew_ros.core.plan.replay` does)."""
    pose = np.asarray(world.object.initial, dtype=float)
    pieces = []
    for segment in segments:
        waypoints = np.array(segment.waypoints, dtype=float)
        grasp_rel = None
        if segment.kind == "transfer":
            grasp_rel = relative(tip_poses(world.robot, waypoints[:1])[0], pose)
        piece = _Piece(segment.kind, segment.grasp, waypoints, pose, grasp_rel)
        pose = piece.end_pose(world)
        pieces.append(piece)
    return pieces


class _Budget:
    """Work units left, and the clock's stop test (time limit, cancel)."""

    def __init__(self, ctx: PlanningContext, total: float) -> None:
        self.ctx = ctx
        self.total = total
        self.spent = 0
        self.evaluations_at_start = ctx.counters.evaluations
        self.stopped = False
        self.check_work = BATCH_CHECK_SHARE * check_work(ctx.world)
        self.reserve = 0  # work the final check of the segments changed so far will take

    def spend(self, units: int) -> None:
        self.spent += units

    def spend_checks(self, configurations: int, calls: int = 1) -> None:
        """Charge ``configurations`` checked in ``calls`` calls of the compiled check."""
        self.spent += math.ceil(configurations * self.check_work) + calls * CALL_WORK

    def spend_move_checks(self, configurations: int) -> None:
        """Charge one call of the compiled straight-move check that checked ``configurations``."""
        self.spent += math.ceil(configurations * self.check_work) + MOVE_CALL_WORK

    def units_left(self) -> float:
        """Work units left of the budget, the final check's reserve kept out."""
        return self.total - self.reserve - self.spent

    def left(self, share: float = 1.0) -> bool:
        """Whether work is left (within ``share`` of the budget) and the clock allows more."""
        if self.stop():
            return False
        return self.spent + self.reserve < share * self.total

    def stop(self) -> bool:
        if not self.stopped and self.ctx.termination():
            self.stopped = True
        return self.stopped


class _RoutingShare:
    """A routing's part of the budget (:class:`clew_ros.core.connect.RoutingBudget`): what is left of the
    budget, and at most until ``limit`` units are spent; each compiled call of its rounds costs
    :data:`MOVE_CALL_WORK` more."""

    round_work = ROUND_WORK

    def __init__(self, budget: _Budget, limit: float) -> None:
        self.budget = budget
        self.limit = limit
        self.check_work = budget.check_work

    def allowance(self) -> float:
        return min(self.limit - self.budget.spent, self.budget.units_left())

    def spend(self, units: float) -> None:
        self.budget.spend(math.ceil(units) + MOVE_CALL_WORK)

    def stop(self) -> bool:
        return self.budget.stop()


def check_work(world: World) -> float:
    """How much one configuration check costs in ``world`` relative to figure1's, at least 1 (the budget charges
    :data:`BATCH_CHECK_SHARE` units for each): its cost in joints
    (:data:`SELF_PAIR_JOINTS`, :data:`OBSTACLES_PER_JOINT`) over figure1's (:data:`REFERENCE_COST`). Measured
    with the compiled check's broad phase (valid configurations, docs/benchmarks.md): within a factor of
    two of the time a check takes on every benchmark world, where counting the pairs of pieces compared
    (as before the broad phase) charged obstacles_32 five times too much."""
    n = world.robot.dof
    pairs = (n - 1) * (n - 2) / 2 if world.robot.self_collision else 0.0
    cost = n + SELF_PAIR_JOINTS * pairs + len(world.obstacles) / OBSTACLES_PER_JOINT
    return max(1.0, cost / REFERENCE_COST)


def _dense_count(waypoints: np.ndarray) -> int:
    """Configurations the validator's check of a path takes (:data:`CHECK_STEP_RAD` per joint at most)."""
    if len(waypoints) < 2:
        return 1
    steps = np.ceil(np.max(np.abs(np.diff(waypoints, axis=0)), axis=1) / CHECK_STEP_RAD)
    return 1 + int(np.maximum(steps, 1).sum())


def _dense_clear(world: World, piece: _Piece) -> bool:
    """The validator's check of one segment."""
    if piece.grasp_rel is None:
        return path_valid(world, piece.waypoints, object_pose=piece.start_pose)
    return path_valid(world, piece.waypoints, grasp_rel=piece.grasp_rel)


def _joined_regrasps(pieces: list[_Piece]) -> list[_Piece]:
    """``pieces`` with each transfer that is put down and taken again by the same grasp without the arm moving
    (a transit of no joint travel between two transfers of one grasp) made one transfer: the arm and the
    object move exactly as before, the object held the same way (the tip and the object did not move in
    between), so nothing needs checking, and the plan has one transfer fewer."""
    joined: list[_Piece] = []
    for piece in pieces:
        if len(joined) >= 2 and piece.kind == "transfer" and [p.kind for p in joined[-2:]] == ["transfer", "transit"]:
            carried, still = joined[-2], joined[-1]
            junction = np.vstack([carried.waypoints[-1:], still.waypoints, piece.waypoints[:1]])
            if piece.grasp == carried.grasp and float(np.abs(junction - junction[0]).max()) <= SAME_RAD:
                joined[-2:] = [
                    _Piece(
                        "transfer",
                        carried.grasp,
                        np.vstack([carried.waypoints, piece.waypoints[1:]]),
                        carried.start_pose,
                        carried.grasp_rel,
                    )
                ]
                continue
        joined.append(piece)
    return joined


def _without_repeats(waypoints: list[np.ndarray]) -> np.ndarray:
    """``waypoints`` without those within 1e-12 rad (each joint) of the one before."""
    points = np.array(waypoints, dtype=float)
    moved = np.max(np.abs(np.diff(points, axis=0)), axis=1) > 1e-12
    kept: np.ndarray = points[np.concatenate([[True], moved])]
    return kept


@dataclass
class _Shortcuts:
    """Shortcuts of one path (``K`` of them), each replacing the stretch between a point on piece ``first`` and
    one on piece ``last`` (``first < last``) by ``paths`` ``(K, PARTIAL_PIECES + 2, n)``: its first point, the
    new waypoints and its last point, padded with the last (zero moves). ``gain``: joint travel saved (rad)."""

    first: np.ndarray
    last: np.ndarray
    paths: np.ndarray
    gain: np.ndarray
    fewer: np.ndarray  # a straight one that drops waypoints: as long, it is still better

    def improving(self) -> np.ndarray:
        """The shortcuts that would make the path better, the largest gain first."""
        rows = np.flatnonzero((self.gain > TRAVEL_EPS) | (self.fewer & (self.gain >= -TRAVEL_EPS)))
        return rows[np.argsort(-self.gain[rows], kind="stable")]


def _draw_shortcuts(waypoints: np.ndarray, rng: np.random.Generator, count: int) -> _Shortcuts:
    """``count`` shortcuts of a path drawn at random, a third of each kind: two waypoints joined straight; two
    points along the path (by joint travel) joined straight; and between two such points at most
    :data:`PARTIAL_PIECES` pieces apart, one joint (drawn) moving evenly along the path while the others move
    as before (a *partial* shortcut: a joint that went back and forth there goes straight). Draws that replace
    nothing (both points on one piece, or a partial one spanning more pieces) come back with ``gain`` -inf.
    The draws come from ``rng``; the paths and gains from one compiled call (:func:`clew_ros.core.kernel.shortcuts`)."""
    return _Shortcuts(*shortcuts(waypoints, rng.random((count, 6)), PARTIAL_PIECES))


def _better(old: tuple[int, float, int], new: tuple[int, float, int]) -> bool:
    """Lexicographic (transfers, travel, waypoints); travel within :data:`TRAVEL_EPS` counts as equal."""
    if new[0] != old[0]:
        return new[0] < old[0]
    if abs(new[1] - old[1]) > TRAVEL_EPS:
        return new[1] < old[1]
    return new[2] < old[2]


def _alike(a: Proposal, b: Proposal) -> bool:
    """Whether two proposals take the same grasps at key configurations within :data:`ALIKE_RAD` of each other."""
    return a.grasps == b.grasps and float(np.max(np.abs(a.keys - b.keys))) <= ALIKE_RAD


def _span_key(one: _Piece, two: _Piece, length: int) -> bytes:
    """What :meth:`_Improver.lattice_regrasps` knows a span by: where its first transfer starts, where its last
    ends, and how many pieces from one to the other."""
    key: bytes = one.waypoints[0].tobytes() + two.waypoints[-1].tobytes() + length.to_bytes(8, "little")
    return key


def _score(pieces: list[_Piece]) -> tuple[int, float, int]:
    return (
        sum(p.kind == "transfer" for p in pieces),
        joint_travel([p.waypoints for p in pieces]),
        sum(len(p.waypoints) for p in pieces),
    )


class _Improver:
    def __init__(self, ctx: PlanningContext, pieces: list[_Piece], goal: np.ndarray) -> None:
        self.ctx = ctx
        self.world = ctx.world
        self.pieces = pieces
        self.first = [p.waypoints for p in pieces]
        self.goal = goal
        self.budget = _Budget(ctx, ctx.settings.improve_time * WORK_PER_SECOND)
        self.min_margin = MIN_MARGIN_FACTOR * ctx.settings.clearance
        self.shortcuts = 0
        self.rebuilt = 0
        self.blocked_moves: list[tuple[str, np.ndarray, np.ndarray]] = []  # (kind, start, end) found blocked
        self.connected = [0, 0]  # proposals with a move routed by connect that did not make the plan better, that did
        self.connect_failed = 0  # routings by connect that found no path
        self.routings = 0  # routings by connect for the proposal being checked
        self.rebuild_share = REBUILD_SHARE  # of the budget, the rebuilding may start in (all of it after a round)
        # the inverse kinematics' restarts draw from a generator of their own: the run's stream stays the releases'
        self.restarts = np.random.default_rng([ctx.settings.seed, RESTART_STREAM])
        self.known_nodes: dict[bytes, KnownNodes] = {}  # per mode: the lattice nodes checked so far
        # the spans lattice_regrasps searched (their ends, their length), the first grasps lattice_first_grasps tried
        self.regrasps_tried: set[bytes] = set()

    def clear(self, piece: _Piece, a: np.ndarray, b: np.ndarray) -> bool:
        """Whether the straight move ``a -> b`` is clear in ``piece``'s mode."""
        return self.path_clear(piece, np.array([a, b], dtype=float))

    def path_clear(self, piece: _Piece, path: np.ndarray) -> bool:
        """Whether every move of ``path`` is clear in ``piece``'s mode (one call of the check; it stops at the
        first move that is not)."""
        path = np.asarray(path, dtype=float)
        return bool(self.moves_clear(piece, path[:-1], path[1:], every=True).all())

    def moves_clear(self, piece: _Piece, starts: np.ndarray, ends: np.ndarray, *, every: bool = False) -> np.ndarray:
        """Which straight moves ``starts[k] -> ends[k]`` are clear in ``piece``'s mode, with the improver's
        margin, charged to the budget (:func:`clew_ros.core.continuous.straight_moves_clear`, one call)."""
        return straight_moves_clear(
            self.world,
            starts,
            ends,
            object_pose=piece.start_pose,
            grasp_rel=piece.grasp_rel,
            min_margin=self.min_margin,
            budget=self.budget,
            every=every,
        )

    def reserve(self) -> None:
        """Keep the work of the final check of the segments changed so far out of the budget (:data:`DENSE_WORK`)."""
        count = sum(
            _dense_count(piece.waypoints)
            for index, piece in enumerate(self.pieces)
            if index >= len(self.first) or not np.array_equal(piece.waypoints, self.first[index])
        )
        self.budget.reserve = math.ceil(DENSE_WORK * self.budget.check_work * count)

    def prune(self) -> None:
        self.pieces = _joined_regrasps(self.pieces)
        for piece in self.pieces:
            pruned = pruned_path(piece.waypoints)
            if _better(
                (0, joint_travel([piece.waypoints]), len(piece.waypoints)), (0, joint_travel([pruned]), len(pruned))
            ):
                piece.waypoints = pruned
        self.reserve()

    def cuts(self) -> list[tuple[int, np.ndarray, np.ndarray]]:
        """Where the plan could be finished differently: ``(kept, configuration, placement)`` for the start
        (no piece kept) and after each transfer but one ending at the goal (the pieces through it kept)."""
        cuts = [(0, self.pieces[0].waypoints[0], np.asarray(self.world.object.initial, dtype=float))]
        for index, piece in enumerate(self.pieces[:-1]):
            if piece.kind == "transfer":
                cuts.append((index + 1, piece.waypoints[-1], piece.end_pose(self.world)))
        return cuts

    def rebuild(self) -> None:
        """Passes of :meth:`rebuild_pass` while they find better plans (or the share of the budget lasts);
        none after a pass that found nothing and met a placement from which every proposal looked blocked."""
        idle = 0
        while idle < REBUILD_IDLE_PASSES and self.budget.left(self.rebuild_share):
            better, blocked = self.rebuild_pass()
            if blocked and not better:
                return
            idle = 0 if better else idle + 1

    def rebuild_pass(self) -> tuple[bool, bool]:
        """From each placement of the plan, earliest first: finish with straight moves through other grasps,
        postures and release placements (:func:`clew_ros.core.regrasp.propose`) when that is better.
        Proposals with a move that looked blocked are checked too, fewer (:meth:`try_proposals`); a placement
        from which every proposal looked blocked and none made the plan better ends the pass. Returns whether
        the plan got better, and whether such a placement ended the pass."""
        position = 0
        better = False
        while self.budget.left(self.rebuild_share):
            cuts = [cut for cut in self.cuts() if cut[0] >= position]
            if not cuts:
                break
            kept, configuration, placement = cuts[0]
            position = kept + 1
            before = self.pieces[:kept]
            transfers = sum(p.kind == "transfer" for p in before)
            score = _score(self.pieces)
            if transfers + 1 > score[0]:
                break
            after = self.pieces[kept:]
            own = [(int(p.grasp), p.waypoints[0]) for p in after[1:2] if p.grasp is not None]
            hints = np.array([p.waypoints[-1] for p in after[:-1] if p.kind == "transfer"]).reshape(
                -1, len(configuration)
            )
            found, blocked = False, True
            tried: list[Proposal] = []
            for grasps in (1, 2):  # a plan with fewer transfers is better: two only when none with one worked
                if found or transfers + grasps > score[0] or not self.budget.left(self.rebuild_share):
                    break
                proposals, effort = propose(
                    self.world,
                    configuration,
                    placement,
                    self.goal,
                    self.ctx.rng,
                    own=own,
                    releases=hints,
                    finals=self.pieces[-1].waypoints[-1:],
                    one_transfer=grasps == 1,
                    two_transfers=grasps == 2,
                    margin_m=self.min_margin,
                    should_stop=self.budget.stop,
                    max_checks=self.proposal_checks(),
                    step_checks=IK_WORK / self.budget.check_work,
                    restarts=self.restarts,
                )
                self.budget.spend_checks(effort.checks, effort.calls)
                self.budget.spend(MOVE_CALL_WORK * effort.screens)  # the Python around each compiled screen
                self.budget.spend(math.ceil(IK_WORK * effort.steps))
                found = self.try_proposals(proposals, kept, placement, routed=False)
                blocked &= bool(proposals) and all(p.blocked for p in proposals)
                tried += proposals
            if tried:  # routing is dear: only after every proposal that looked clear, for those still better
                tried.sort(key=lambda p: (len(p.grasps), p.rank))  # fewer transfers always win: those first
                found |= self.try_proposals(tried, kept, placement, routed=True)
            better |= found
            if blocked and not found:
                return better, True  # every way from here looked blocked: cluttered, leave the budget to shortcuts
        return better, False

    def proposal_checks(self) -> int:
        """Configurations :func:`clew_ros.core.regrasp.propose` may check (its inverse-kinematics steps count
        too): :data:`PROPOSE_SHARE` of what is left of the rebuilding's share of the budget."""
        left = self.rebuild_share * self.budget.total - self.budget.spent
        return max(0, int(PROPOSE_SHARE * left / self.budget.check_work))

    def try_proposals(self, proposals: list[Proposal], kept: int, placement: np.ndarray, *, routed: bool) -> bool:
        """Check ``proposals`` (after the first ``kept`` pieces) in their order: if ``routed``, those with a move
        that looked blocked (routed by :meth:`connect`), else the others. Each whose moves are clear and that
        makes the plan better replaces the plan's end, and the later ones must beat it. At most
        :data:`REBUILD_TRIES` failures among those whose moves all looked clear and :data:`BLOCKED_TRIES` among
        the others. Returns whether the plan got better."""
        before = self.pieces[:kept]
        transfers = sum(p.kind == "transfer" for p in before)
        travel_before = joint_travel([p.waypoints for p in before])
        failed: list[Proposal] = []
        failures = {False: 0, True: 0}  # by whether the proposal looked blocked
        limits = {False: REBUILD_TRIES, True: BLOCKED_TRIES}
        better = False
        for proposal in proposals:
            if (proposal.blocked > 0) != routed:
                continue  # those that looked clear first, those with a blocked move to route in a call of their own
            score = _score(self.pieces)
            if not _better(score, (transfers + len(proposal.grasps), travel_before + proposal.travel, 0)):
                continue
            if any(_alike(proposal, other) for other in failed) or self.known_blocked(proposal):
                continue  # as good as one that failed: try something else
            blocked = proposal.blocked > 0
            if blocked and self.routing_gave_nothing():
                failures[blocked] = limits[blocked]  # routing around blocked moves never worked here
            if failures[blocked] >= limits[blocked]:
                break
            if not self.budget.left(self.rebuild_share):
                break
            self.routings = 0
            fewer = transfers + len(proposal.grasps) < score[0]  # then any travel makes the plan better
            slack = math.inf if fewer else score[1] - travel_before - proposal.travel
            tail = self.checked_tail(proposal, placement, slack)
            # compared where it could end on the goal, as the plan's last transfer
            ended_sooner = tail is not None and self.goal_shortcut(tail[-1])
            accepted = tail is not None and _better(score, _score(before + tail))
            if self.routings:
                self.connected[accepted] += 1
            if tail is not None and accepted:
                self.shortcuts += ended_sooner  # a straight move accepted only with the proposal
                self.pieces = before + tail
                self.reserve()
                self.rebuilt += 1
                better = True
                continue
            failed.append(proposal)
            failures[blocked] += 1
        return better

    def routing_gave_nothing(self) -> bool:
        """Whether routing blocked moves looks hopeless here (a cluttered world): no routed proposal made the plan
        better, and :data:`CONNECT_PROBES` routings found no path or :data:`ROUTED_PROBES` routed proposals did not
        (a routing found no path or one too long, or another move stayed blocked)."""
        return self.connected[1] == 0 and (self.connect_failed >= CONNECT_PROBES or self.connected[0] >= ROUTED_PROBES)

    def proposal_moves(self, proposal: Proposal) -> list[tuple[str, np.ndarray, np.ndarray]]:
        """``(kind, start, end)`` of each move of ``proposal`` (a transit, then a transfer, ...)."""
        keys = proposal.keys
        return [("transit" if k % 2 == 0 else "transfer", keys[k], keys[k + 1]) for k in range(len(keys) - 1)]

    def known_blocked(self, proposal: Proposal) -> bool:
        """Whether a move of ``proposal`` is like one found blocked before (:data:`MOVE_ALIKE_RAD`)."""
        return any(
            kind == other_kind
            and float(np.max(np.abs(a - other_a))) <= MOVE_ALIKE_RAD
            and float(np.max(np.abs(b - other_b))) <= MOVE_ALIKE_RAD
            for kind, a, b in self.proposal_moves(proposal)
            for other_kind, other_a, other_b in self.blocked_moves
        )

    def checked_tail(self, proposal: Proposal, placement: np.ndarray, slack: float = math.inf) -> list[_Piece] | None:
        """``proposal``'s moves as pieces, the object starting at ``placement``, each move checked
        continuously (:meth:`route`), the shortest first (they are the cheapest to check, and the ones
        near the object, leaving or taking a grasp, are short); ``None`` if a move stays blocked. ``slack``:
        the joint travel (rad) the moves may add to the proposal's straight moves for it to still make the plan
        better; each move taken longer than straight uses some, and what is left bounds the lattice's path of
        a move routed around what blocks it (:meth:`connect`)."""
        pieces: list[_Piece] = []
        keys = proposal.keys
        pose = np.asarray(placement, dtype=float)
        for step, grasp in enumerate(proposal.grasps):
            start, hold, end = keys[2 * step], keys[2 * step + 1], keys[2 * step + 2]
            grasp_rel = relative(tip_poses(self.world.robot, hold[None])[0], pose)  # as plan.replay computes it
            transfer = _Piece("transfer", grasp, np.array([hold, end]), pose, grasp_rel)
            pieces += [_Piece("transit", None, np.array([start, hold]), pose, None), transfer]
            pose = transfer.end_pose(self.world)
        for index in np.argsort([joint_travel([p.waypoints]) for p in pieces], kind="stable"):
            piece = pieces[index]
            a, b = piece.waypoints[0], piece.waypoints[-1]
            path = self.route(piece, a, b, proposal.routes[index])
            if path is None and proposal.routes[index] < 0 and not self.budget.stop():
                path = self.connect(piece, a, b, float(np.abs(b - a).sum()) + slack)
                self.routings += 1
                self.connect_failed += path is None
            if path is None:
                self.blocked_moves.append((piece.kind, a, b))
                return None
            piece.waypoints = path
            slack -= joint_travel([path]) - float(np.abs(b - a).sum())
        return pieces

    def connect(self, piece: _Piece, a: np.ndarray, b: np.ndarray, longest: float = math.inf) -> np.ndarray | None:
        """A path from ``a`` to ``b`` in ``piece``'s mode around what blocks the straight move: RRT-Connect
        (:func:`clew_ros.core.connect.rrt_connect`, each extension checked continuously), then shortened
        greedily. At most :data:`CONNECT_STEPS` rounds and :data:`CONNECT_SHARE` of the budget; ``None`` when
        the trees did not meet. On an arm with a lattice (:func:`clew_ros.core.lattice.lattice_step`), the
        lattice's shortest path (:meth:`lattice`) replaces it when it is shorter than both it and ``longest``
        (rad: the proposal's bound), within :data:`CONNECT_SHARE` of the budget more."""
        limit = self.budget.spent + CONNECT_SHARE * self.budget.total

        def clear(p: np.ndarray, q: np.ndarray) -> bool:
            return self.clear(piece, p, q)

        path = rrt_connect(
            self.world,
            a,
            np.asarray(b, dtype=float)[None],
            self.ctx.rng,
            object_pose=piece.start_pose,
            grasp_rel=piece.grasp_rel,
            min_margin=self.min_margin,
            rounds=CONNECT_STEPS,
            budget=_RoutingShare(self.budget, limit),
        )
        if path is None:
            return None
        path = shortened(clear, path, lambda: self.budget.spent > limit)
        if lattice_step(self.world) is None or self.budget.stop():
            return path
        bound = min(longest, joint_travel([path])) - TRAVEL_EPS
        shortest = self.lattice(piece, a, b, bound, min(CONNECT_SHARE * self.budget.total, self.budget.units_left()))
        return path if shortest is None else shortest

    def route(self, piece: _Piece, a: np.ndarray, b: np.ndarray, hint: int) -> np.ndarray | None:
        """Waypoints from ``a`` to ``b`` in ``piece``'s mode, each move checked continuously: the ways of
        :data:`clew_ros.core.regrasp.ROUTES` (the one that looked clear, ``hint``, first; all as long in
        joint travel), then through a configuration drawn inside the box ``[a, b]`` (as long too), then
        through one drawn around the middle (:data:`DETOURS` tries each); ``None`` when none is clear."""
        ways = [hint] if hint >= 0 else []
        for way in [*ways, *(w for w in range(len(ROUTES)) if w != hint)]:
            path = route_waypoints(a, b, way)
            if self.budget.stop():
                return None
            if self.path_clear(piece, path):
                return path
        n = len(a)
        lower, upper = self.world.robot.joint_lower, self.world.robot.joint_upper
        spread = 0.25 * float(np.max(np.abs(b - a))) + 0.1
        for monotone in (True, False):
            for _ in range(DETOURS):
                if self.budget.stop():
                    return None
                if monotone:
                    via = a + self.ctx.rng.uniform(0.0, 1.0, size=n) * (b - a)
                else:
                    via = np.clip(0.5 * (a + b) + self.ctx.rng.normal(0.0, spread, size=n), lower, upper)
                if self.path_clear(piece, np.array([a, via, b])):
                    return np.array([a, via, b])
        return None

    def fewer_transfers(self) -> None:
        """From the start of each transfer but the last, earliest first: carry the object to the goal. An
        attempt starts only when the work it may take (every individual of every round) fits in
        :data:`TRANSFER_SHARE` of the budget."""
        settings = self.ctx.settings
        attempt = EVALUATION_WORK * settings.population * settings.generations * settings.search_rounds
        transfers = [i for i, p in enumerate(self.pieces) if p.kind == "transfer"]
        for index in transfers[:-1]:
            if not self.budget.left(TRANSFER_SHARE) or self.budget.spent + attempt > TRANSFER_SHARE * self.budget.total:
                return
            piece = self.pieces[index]
            assert piece.grasp_rel is not None
            before = self.ctx.counters.evaluations
            result = search_transfer(self.ctx, piece.waypoints[0], piece.grasp_rel, self.goal, joins=False)
            self.budget.spend(EVALUATION_WORK * (self.ctx.counters.evaluations - before))
            if not result.success:
                continue
            carried = _Piece("transfer", piece.grasp, pruned_path(result.waypoints), piece.start_pose, piece.grasp_rel)
            candidate = [*self.pieces[:index], carried]
            if _better(_score(self.pieces), _score(candidate)):
                self.pieces = candidate
                self.reserve()
                return

    def try_shortcut(self, index: int, first: int, last: int, a: np.ndarray, b: np.ndarray) -> bool:
        """Replace waypoints ``first..last`` (inclusive, ``first < last``) of piece ``index`` by ``a``,
        ``b`` (points on the pieces before ``first`` and after ``last``) joined straight."""
        piece = self.pieces[index]
        w = piece.waypoints
        self.budget.spend(math.ceil(SHORTCUT_TRY_WORK + WAYPOINT_WORK * len(w)))
        joined = [*w[:first], a, b, *w[last + 1 :]]
        new = pruned_path(_without_repeats(joined))
        old_score = (0, joint_travel([w]), len(w))
        if not _better(old_score, (0, joint_travel([new]), len(new))):
            return False
        if not self.clear(piece, a, b):
            return False
        piece.waypoints = new
        self.shortcuts += 1
        self.reserve()
        return True

    def greedy_shortcuts(self) -> None:
        """Along each segment, from its first waypoint: a straight move to the farthest later waypoint that
        is clear (the last, else halfway there, a quarter, ...), then on from there; the longest segments
        (in joint travel) first."""
        order = np.argsort([-joint_travel([p.waypoints]) for p in self.pieces], kind="stable")
        for index in order.tolist():
            piece = self.pieces[index]
            i = 0
            while i < len(piece.waypoints) - 2:
                if not self.budget.left():
                    return
                last = len(piece.waypoints) - 1
                span = last - i
                while span >= 2 and not self.try_shortcut(
                    index, i + 1, i + span - 1, piece.waypoints[i], piece.waypoints[i + span]
                ):
                    if not self.budget.left():
                        return
                    span //= 2
                i += 1

    def random_shortcuts(self) -> None:
        """Batches of :data:`SHORTCUT_BATCH` shortcuts of one segment (:func:`_draw_shortcuts`; the segment
        drawn by its joint travel), until the work is spent or :data:`IDLE_BATCHES` batches in a row changed
        nothing. Those of a batch that would make the path better are checked in one call; the clear ones are
        taken, the largest gain first, as long as they do not overlap one taken."""
        rng = self.ctx.rng
        idle = 0
        changed = True
        travels = np.zeros(0)
        while self.budget.left() and idle < IDLE_BATCHES:
            if changed:  # how much each piece could still gain
                travels = np.array([joint_travel([p.waypoints]) if len(p.waypoints) > 2 else 0.0 for p in self.pieces])
            if travels.sum() <= 0:
                return
            index = int(rng.choice(len(self.pieces), p=travels / travels.sum()))
            self.budget.spend(BATCH_WORK)  # drawing, scoring and splicing them, besides the checks
            piece = self.pieces[index]
            changed = self.take_shortcuts(piece, _draw_shortcuts(piece.waypoints, rng, SHORTCUT_BATCH))
            idle = 0 if changed else idle + 1

    def take_shortcuts(self, piece: _Piece, drawn: _Shortcuts) -> bool:
        """Check the shortcuts of ``drawn`` that would make ``piece``'s path better (every move of all of them
        in one call of the continuous check) and take the clear ones that do not overlap, the largest gain
        first. Returns whether the path changed."""
        rows = drawn.improving()
        if not len(rows):
            return False
        paths = drawn.paths[rows]
        starts, ends = paths[:, :-1].reshape(-1, paths.shape[2]), paths[:, 1:].reshape(-1, paths.shape[2])
        owner = np.repeat(np.arange(len(rows)), paths.shape[1] - 1)
        moving = np.max(np.abs(ends - starts), axis=1) > 1e-12
        clear = np.ones(len(starts), dtype=bool)
        if moving.any():
            clear[moving] = self.moves_clear(piece, starts[moving], ends[moving])
        if self.budget.stopped:
            return False
        blocked = np.bincount(owner[~clear], minlength=len(rows)) > 0
        taken: list[int] = []
        for k in np.flatnonzero(~blocked).tolist():  # the largest gain first
            first, last = drawn.first[rows[k]], drawn.last[rows[k]]
            if all(last < drawn.first[rows[t]] or first > drawn.last[rows[t]] for t in taken):
                taken.append(k)
        if not taken:
            return False
        w = list(piece.waypoints)
        for k in sorted(taken, key=lambda t: -drawn.first[rows[t]]):  # from the path's end: indices stay true
            first, last = int(drawn.first[rows[k]]), int(drawn.last[rows[k]])
            w[first + 1 : last + 1] = list(paths[k])
        new = pruned_path(_without_repeats(w))
        if not _better((0, joint_travel([piece.waypoints]), len(piece.waypoints)), (0, joint_travel([new]), len(new))):
            return False
        piece.waypoints = new
        self.shortcuts += len(taken)
        self.reserve()
        return True

    def goal_shortcuts(self) -> bool:
        """The object may end anywhere on the goal (within its tolerances), and a redundant arm, or one whose
        goal leaves the object's angle free, holds it there in many ways. From each waypoint of the last
        transfer but its end, the configuration inverse kinematics finds from there putting the object on
        the goal, held as that transfer holds it (:func:`clew_ros.core.regrasp.goal_holds_near`, valid with
        the margin), joined straight, ends the transfer when that makes it shorter: the shortest clear one
        (one batch of inverse kinematics and one call of the continuous check; once is enough, since a
        second batch from the waypoints kept would find the same). Returns whether the plan changed."""
        if not self.goal_shortcut(self.pieces[-1]):
            return False
        self.shortcuts += 1
        self.reserve()
        return True

    def goal_shortcut(self, piece: _Piece) -> bool:
        """:meth:`goal_shortcuts` of ``piece``, a transfer ending on the goal (the plan's last, or a proposal's):
        whether its waypoints changed (the caller counts the shortcut when it keeps it)."""
        if piece.kind != "transfer" or piece.grasp_rel is None or len(piece.waypoints) < 2 or not self.budget.left():
            return False
        w = piece.waypoints
        seeds = w[:-1]
        holding = np.broadcast_to(piece.grasp_rel, (len(seeds), 3))
        held, ok, effort = goal_holds_near(self.world, holding, seeds, self.goal, margin_m=self.min_margin)
        self.budget.spend_checks(effort.checks, effort.calls)
        self.budget.spend(math.ceil(IK_WORK * effort.steps))
        steps = np.abs(np.diff(w, axis=0)).sum(axis=1)
        travel = np.cumsum(steps) - steps + np.abs(held - seeds).sum(axis=1)  # to each seed, then to the goal
        rows = np.flatnonzero(ok & (travel < steps.sum() - TRAVEL_EPS))
        if not len(rows):
            return False
        clear = self.moves_clear(piece, seeds[rows], held[rows])
        if self.budget.stopped or not clear.any():
            return False
        best = rows[clear][np.argmin(travel[rows[clear]])]
        piece.waypoints = _without_repeats([*w[: best + 1], held[best]])  # a waypoint on the goal already: itself
        return True

    def lattice(
        self, piece: _Piece, a: np.ndarray, b: np.ndarray, shorter_than: float, allowance: float
    ) -> np.ndarray | None:
        """The lattice's shortest path from ``a`` to ``b`` in ``piece``'s mode, shorter than ``shorter_than``
        rad, within ``allowance`` work units (:func:`clew_ros.core.lattice.lattice_route`, the nodes checked in
        this mode before not checked again), without its collinear waypoints; ``None`` if none was found."""
        known = self.known(piece.kind, piece.start_pose if piece.grasp_rel is None else piece.grasp_rel)
        path = lattice_route(
            self.world,
            a,
            b,
            object_pose=piece.start_pose,
            grasp_rel=piece.grasp_rel,
            min_margin=self.min_margin,
            shorter_than=shorter_than,
            budget=self.budget,
            allowance=allowance,
            expansion_work=EXPANSION_WORK,
            nodes_known=known,
        )
        return None if path is None else pruned_path(path)

    def known(self, kind: str, mode: np.ndarray) -> KnownNodes:
        """The lattice nodes checked so far in one mode: a transit's object pose or a transfer's grasp."""
        return self.known_nodes.setdefault(kind.encode() + np.asarray(mode, dtype=float).tobytes(), KnownNodes())

    def lattice_regrasps(self) -> bool:
        """On a 3-joint arm: from the start of a transfer to the end of a later one, one regrasp placed where
        the lattice finds it shortest (:func:`clew_ros.core.lattice.lattice_regrasp`), replacing every
        transfer and transit between, when that makes the plan better. The longest spans (most pieces)
        first; each search within :data:`REGRASP_SHARE` of the budget (its last round may run past it), and new
        ones only while less than :data:`REGRASP_TOTAL_SHARE` of it is spent, the final check's reserve
        counted. Returns whether the plan changed."""
        if self.world.robot.dof != 3 or lattice_step(self.world) is None:
            return False
        changed = False
        while True:
            transfers = [i for i, p in enumerate(self.pieces) if p.kind == "transfer"]
            spans = sorted(
                ((i, j) for k, i in enumerate(transfers) for j in transfers[k + 1 :]), key=lambda s: (s[0] - s[1], s[0])
            )
            for i, j in spans:
                if not self.budget.left(REGRASP_TOTAL_SHARE):
                    return changed
                one, two = self.pieces[i], self.pieces[j]
                key = _span_key(one, two, j - i)
                if key in self.regrasps_tried or one.grasp_rel is None or two.grasp_rel is None:
                    continue
                self.regrasps_tried.add(key)
                fewer = sum(p.kind == "transfer" for p in self.pieces[i : j + 1]) > 2
                bound = math.inf if fewer else joint_travel([p.waypoints for p in self.pieces[i : j + 1]])
                allowance = min(REGRASP_SHARE * self.budget.total, self.budget.units_left())
                regrasped = self.regrasped(one, two, bound, allowance)
                if regrasped is None:
                    continue
                if self.take([*self.pieces[:i], *regrasped, *self.pieces[j + 1 :]], regrasped):
                    changed = True
                    break  # the spans of the new plan
            else:
                return changed

    def lattice_first_grasps(self) -> bool:
        """On a 3-joint arm: the plan's transit to its first grasp routed again on the lattice
        (:meth:`first_transit`), then the plan from its start to the end of its last transfer again with another first
        grasp (:func:`clew_ros.core.lattice.grasp_configurations` at the start): the transit to it routed on the
        lattice, then one regrasp on the lattice as :meth:`lattice_regrasps` places it (a plan of one transfer is
        left alone: two are never better). The grasps whose joint travel from the start and on to the last
        transfer's end is least first, those only that come below the plan's travel there (any, when it has more
        than two transfers); each within :data:`REGRASP_SHARE` of the budget, none started once
        :data:`REGRASP_TOTAL_SHARE` is spent. Returns whether the plan changed."""
        pieces = self.pieces
        transfers = [i for i, p in enumerate(pieces) if p.kind == "transfer"]
        if (
            self.world.robot.dof != 3
            or lattice_step(self.world) is None
            or len(transfers) < 2  # one transfer: two, with a regrasp, are never better
            or pieces[0].kind != "transit"
            or transfers[0] != 1
            or pieces[transfers[-1]].grasp_rel is None
            or not self.budget.left(REGRASP_TOTAL_SHARE)
        ):
            return False
        changed = self.first_transit()
        pieces = self.pieces
        j = transfers[-1]
        start, last, two = pieces[0].waypoints[0], pieces[j].waypoints[-1], pieces[j]
        assert two.grasp_rel is not None  # checked above
        span = joint_travel([p.waypoints for p in pieces[: j + 1]])
        fewer = len(transfers) > 2  # then any way with 2 is better, however long
        q, which, rels = grasp_configurations(self.world, pieces[0].start_pose, start, FIRST_GRASP_APPROACHES)
        on = np.abs(last - q).sum(axis=1)
        bound = np.abs(q - start).sum(axis=1) + on
        hopeful = np.flatnonzero(bound < (math.inf if fewer else span))
        if not len(hopeful):
            return changed
        hopeful = hopeful[self.moves_clear(pieces[0], q[hopeful], q[hopeful])]  # taking the object: clear
        for k in hopeful[np.argsort(bound[hopeful], kind="stable")].tolist():
            if not self.budget.left(REGRASP_TOTAL_SHARE):
                return changed
            key = b"first" + q[k].tobytes() + last.tobytes()
            if key in self.regrasps_tried:
                continue
            self.regrasps_tried.add(key)
            allowance = min(REGRASP_SHARE * self.budget.total, self.budget.units_left())
            limit = self.budget.spent + allowance
            transit = self.lattice(pieces[0], start, q[k], math.inf if fewer else span - on[k], allowance)
            if transit is None:
                continue
            one = _Piece("transfer", int(which[k]), q[k][None], pieces[0].start_pose, rels[k])
            shorter = math.inf if fewer else span - joint_travel([transit])
            regrasped = self.regrasped(one, two, shorter, limit - self.budget.spent)
            taken = _Piece("transit", None, transit, pieces[0].start_pose, None)
            if regrasped is not None and self.take([taken, *regrasped, *pieces[j + 1 :]], regrasped):
                return True
        return changed

    def regrasped(
        self, one: _Piece, two: _Piece, shorter_than: float, allowance: float
    ) -> tuple[_Piece, _Piece, _Piece] | None:
        """From where transfer ``one`` starts (its grasp) to where transfer ``two`` ends, one regrasp placed on the
        lattice (:func:`clew_ros.core.lattice.lattice_regrasp`) within ``allowance`` work units, shorter than
        ``shorter_than`` rad: the transfer, the put-down transit and the transfer, or ``None``."""
        assert one.grasp_rel is not None  # transfers
        assert two.grasp_rel is not None
        found = lattice_regrasp(
            self.world,
            one.waypoints[0],
            one.grasp_rel,
            two.waypoints[-1],
            two.grasp_rel,
            min_margin=self.min_margin,
            shorter_than=shorter_than,
            budget=self.budget,
            allowance=allowance,
            expansion_work=FLOOD_WORK,
            release_work=RELEASE_WORK,
            nodes_known=(self.known("transfer", one.grasp_rel), self.known("transfer", two.grasp_rel)),
        )
        if found is None:
            return None
        carried = _Piece("transfer", one.grasp, pruned_path(found[0]), one.start_pose, one.grasp_rel)
        pose = carried.end_pose(self.world)
        put_down = _Piece("transit", None, found[1], pose, None)
        return carried, put_down, _Piece("transfer", two.grasp, pruned_path(found[2]), pose, two.grasp_rel)

    def take(self, candidate: list[_Piece], regrasped: tuple[_Piece, _Piece, _Piece]) -> bool:
        """Make ``candidate``, a plan holding the pieces ``regrasped`` placed on the lattice, the plan if it is
        better; their span is then marked searched (a search from the same ends would find them again)."""
        if not _better(_score(self.pieces), _score(candidate)):
            return False
        self.pieces = candidate
        self.regrasps_tried.add(_span_key(regrasped[0], regrasped[2], 2))
        self.reserve()
        self.rebuilt += 1
        return True

    def first_transit(self) -> bool:
        """The plan's first transit (to its first grasp) routed again on the lattice, kept when shorter."""
        first = self.pieces[0]
        key = b"transit" + first.waypoints[0].tobytes() + first.waypoints[-1].tobytes()
        if key in self.regrasps_tried:
            return False
        self.regrasps_tried.add(key)
        travel = joint_travel([first.waypoints])
        allowance = min(REGRASP_SHARE * self.budget.total, self.budget.units_left())
        path = self.lattice(first, first.waypoints[0], first.waypoints[-1], travel, allowance)
        if path is None or joint_travel([path]) >= travel:
            return False
        self.pieces = [replace(first, waypoints=path), *self.pieces[1:]]
        self.reserve()
        return True

    def shorten(self) -> None:
        """Pruning, then shortcuts: to the goal, greedy, random (and random again after goal shortcuts)."""
        self.prune()
        self.goal_shortcuts()
        self.greedy_shortcuts()
        self.random_shortcuts()
        if self.goal_shortcuts():
            self.random_shortcuts()

    def run(self) -> list[_Piece]:
        """Rounds of rebuilding, fewer transfers and shortcuts while work is left and the last round made the
        plan better (after the first, the rebuilding may use all that is left: the shortcuts had too little to
        do)."""
        self.prune()
        while True:
            score = _score(self.pieces)
            self.rebuild()
            self.lattice_regrasps()
            self.fewer_transfers()
            self.shorten()
            if self.lattice_first_grasps():
                self.shorten()
            if not self.budget.left() or not _better(score, _score(self.pieces)):
                return self.pieces
            self.rebuild_share = 1.0


def improve(
    ctx: PlanningContext, segments: list[Segment], final_object_pose: np.ndarray, goal: np.ndarray
) -> Improvement:
    """Improve a found plan within ``ctx.settings.improve_time`` of work (module docstring).

    ``ctx`` carries the world, the settings, the generator the improvement draws from and the
    termination (time limit, cancel). Returns the better plan, or the first one.
    """
    world = ctx.world
    first = _pieces(world, segments)
    first_score = _score(first)
    if ctx.settings.improve_time <= 0 or ctx.termination():
        return Improvement(
            segments, final_object_pose, first_score[1], first_score[0], first_score[1], first_score[0], 0, 0, False
        )
    improver = _Improver(ctx, _pieces(world, segments), goal)
    pieces = improver.run()
    pieces = _pieces(world, [p.segment() for p in pieces])  # the object carried along the final paths
    changed = [
        p
        for p, q in itertools.zip_longest(pieces, first)
        if q is None or p is None or not np.array_equal(p.waypoints, q.waypoints)
    ]
    final = pieces[-1].end_pose(world) if pieces else final_object_pose
    better = _better(first_score, _score(pieces))
    refused = _refusal(world, changed, final, goal) if better else ""
    if refused or not better:
        pieces, final = first, final_object_pose
    score = _score(pieces)
    return Improvement(
        [p.segment() for p in pieces],
        final,
        first_score[1],
        first_score[0],
        score[1],
        score[0],
        improver.shortcuts if pieces is not first else 0,
        improver.budget.spent,
        improver.budget.stopped,
        refused,
    )


def _refusal(world: World, changed: list[_Piece | None], final: np.ndarray, goal: np.ndarray) -> str:
    """What the final checks find wrong with an improved plan, "" when nothing: a changed segment not clear at
    the validator's step, or the object off the goal. Every step checks what it builds, so either is a fault;
    the first plan is returned then, and the plan's stats name the fault (``improve_refused``)."""
    if any(p is not None and not _dense_clear(world, p) for p in changed):
        return "a changed segment collides at the validator's step"
    if not goal_reached(world, final, goal):
        return "the object ends off the goal"
    return ""
