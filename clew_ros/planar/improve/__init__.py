"""Anytime improvement of a found plan (issue 14): fewer transfers, shorter paths, never worse.

The ACA keeps every single manipulation path that led to the goal, made of
Manhattan moves (one joint at a time, in large arcs), and takes the object
wherever its search happened to: often with the elbow the wrong way round,
or put down far from where a regrasp was needed. Once a plan is found,
:func:`improve` spends a bounded budget (``planner.improve_time``) on it:

1. **Back-and-forth pruning** (free): a transfer put down and taken again by
   the same grasp where the arm stopped becomes one transfer
   (:func:`clew_ros.core.improve.joined_regrasps`); a waypoint between two collinear
   pieces (a joint moving one way, then back) is dropped, and so is a loop
   that comes back to an earlier waypoint. The configurations left were
   already on the plan, so nothing needs checking.
2. **Rebuilding the manipulation** (at most :attr:`ImproveSettings.rebuild_share` of the
   budget): from each placement of the plan (the start, then where each
   transfer put the object down), :func:`clew_ros.planar.regrasp.propose`
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
   that looked blocked are checked too (fewer: :attr:`ImproveSettings.blocked_tries`), after
   all of the placement's that looked clear (one transfer, then two), fewer
   transfers first, when they would still make the plan better: such a move
   is routed by RRT-Connect (:meth:`_Improver.connect`, moves checked
   continuously, then shortened; on an arm of at most three joints the
   shortest path on a joint-space lattice, :mod:`clew_ros.planar.lattice`,
   replaces it when shorter), given up, when no routed proposal made the
   plan better, after :attr:`ImproveSettings.connect_probes` routings that found no path or
   :attr:`ImproveSettings.routed_probes` routed proposals that did not make it better. A move found blocked makes alike
   proposals (both ends within :attr:`ImproveSettings.move_alike_rad`) skipped. A proposal is compared
   with its last transfer ended on the goal sooner where it can be (the goal
   shortcut of step 5); each that makes the plan better replaces the plan's
   end from that placement on, and the later ones must beat it. Passes repeat while they find something
   (:attr:`ImproveSettings.rebuild_idle_passes`); a placement from which every proposal looked
   blocked and none worked (a cluttered world) ends the rebuilding, leaving
   the budget to shortcuts.
3. **One regrasp on the lattice** (an arm of three joints; each search within
   :attr:`ImproveSettings.regrasp_share` of the budget, none started once :attr:`ImproveSettings.regrasp_total_share`
   of it is spent): from the start of a transfer to the end of a later one, the longest spans first,
   :func:`clew_ros.planar.lattice.lattice_regrasp` carries the
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
   only when that much work fits in :attr:`ImproveSettings.transfer_share` of the budget
   (a larger ``planner.improve_time``).
5. **Shortcuts**: a sub-path of one segment is replaced by one straight
   joint-space move (all joints together): first greedily, from each waypoint
   to the farthest later one that is clear (the segment's last, else halfway
   there, a quarter, ...), then between pairs of waypoints and pairs of points
   along the path drawn by the run's generator; or, between two such points, one joint is made to move
   evenly while the others move as before (a partial shortcut: a joint that
   went back and forth there goes straight). These are drawn in batches of
   :attr:`ImproveSettings.shortcut_batch` on one segment, scored in one compiled call, and those that would
   shorten it are checked in one compiled call; the clear ones that do not
   overlap are taken, the largest gain first. A segment's end points never
   change, so every grasp and ungrasp stays where it was (the tip still
   holds its grasp) and the object rests or is carried exactly as before;
   but the last transfer may end anywhere on the goal: before and after
   them, *goal shortcuts* (:meth:`_Improver.goal_shortcuts`) join one of its
   waypoints straight to a configuration holding the object on the goal
   that inverse kinematics finds from there, when that is shorter.
6. **Another first grasp on the lattice** (an arm of three joints; after the shortcuts, then the shortcuts again
   if it changed the plan; each search within :attr:`ImproveSettings.regrasp_share`, none started once
   :attr:`ImproveSettings.regrasp_total_share` is spent): the plan's transit to its first grasp routed again on the
   lattice (:meth:`_Improver.first_transit`, kept when shorter), then the ways to take the object at the start
   (:func:`clew_ros.planar.lattice.grasp_configurations`), least joint travel from the start and on to the last
   transfer's end first, each with the transit to it routed on the lattice and one regrasp placed as step 3
   places it, replacing the plan up to its last transfer when that makes it better
   (:meth:`_Improver.lattice_first_grasps`). After the shortcuts, because the lattice's paths are about as short
   as shortcuts make them and the first plan's are not.

Steps 2 to 6 are one round. Rounds repeat while the last one made the plan
better and work is left; after the first, the rebuilding may use the whole
budget (what the shortcuts left: a plan of straight moves leaves them nothing
to do).

**Arms of many joints** (at least ``ManyJoints.straight_probe_joints``, so arms of up to 10 joints are
improved exactly as before): after the pruning and before the rounds, the plan's postures are solved again
along its tip's path (:mod:`clew_ros.planar.improve.many`: every grasp, release and placement and the
object's path kept, the joints moving as little as the tip needs; up to :attr:`ImproveSettings.many_resolve_passes`
passes, each from the plan the last left), goal shortcuts check their moves a few at a time, shortest first
(:attr:`ImproveSettings.many_goal_batch`), and the budget is multiplied by the square
(:attr:`ImproveSettings.many_budget_power`) of the joints over :attr:`ImproveSettings.many_budget_joints` (a check
costs about the square of the joints).

A change is kept only when it lowers ``(transfers, joint travel)`` or keeps
them and drops waypoints; joint travel is the sum over joints of the
absolute motion (rad). The first plan is kept when nothing better is found.

**Every new move is checked continuously**
(:func:`clew_ros.planar.continuous.straight_move_clear`): valid at any
checking resolution, keeping at least ``min_margin_factor`` (:attr:`ImproveSettings.moves`) x
``planner.clearance`` from everything, like the planner's own paths. The whole improved plan is checked once more
at the validator's 0.002 rad, and the object's end against the goal's tolerances; if that ever failed,
the first plan would be returned, and ``improve_refused`` in its stats would say why.

**Determinism.** All choices come from a generator seeded with
``planner.seed`` (apart from the planner's own), and the budget is counted
in work, not seconds: :attr:`ImproveSettings.work_per_second` units per second of
``planner.improve_time``; a configuration checked costs
:attr:`ImproveSettings.batch_check_share` units, or more in a world whose check compares
more pieces (:func:`clew_ros.planar.improve.budget.check_work`), plus
:attr:`ImproveSettings.move_call_work` per call of the compiled straight-move check,
:attr:`ImproveSettings.call_work` per call of the configuration check, :attr:`ImproveSettings.batch_work` per batch of
random shortcuts, :attr:`ImproveSettings.shortcut_try_work` and :attr:`ImproveSettings.waypoint_work` per
greedy shortcut tried, :attr:`ImproveSettings.ik_work` per step of inverse kinematics and
:attr:`ImproveSettings.evaluation_work` per genetic-algorithm individual.
The final check of the segments changed so far at the validator's step is
reserved from the budget as they change (:attr:`ImproveSettings.dense_work` of what a
configuration checked costs, per configuration), so it fits in the budget too. Attempts run
until the work is spent, so the same seed gives the same plan on any machine.
Only the planner's time limit and cancel stop it by the clock (between
calls of the checks and between rounds of routing calls, well within 100 ms),
and then the best plan so far is returned.

Every tuning number is a field of :class:`ImproveSettings` (:mod:`clew_ros.planar.improve.settings`), passed to
:func:`improve`. What is generic over a space comes from :mod:`clew_ros.core.improve`: joint travel and which plan
is better (``compare``), the work budget (``budget``: :class:`~clew_ros.core.improve.WorkBudget`,
:class:`~clew_ros.core.improve.RoutingShare`), the pruning of step 1 (``prune``: ``pruned_path``,
``joined_regrasps``). The random shortcuts of step 5 are the planar specialisation of
:func:`clew_ros.core.improve.shortcut_path`: drawn in batches, scored and checked in one compiled call each. The
package's modules:

============== ==========================================================================================
``settings``   :class:`ImproveSettings`: the tuning numbers, with units and why (the proposals' in ``regrasp``)
``pieces``     the plan as pieces (a segment, the object's pose at its start, the grasp's relative pose)
``many``       arms of many joints: the postures solved again along the tip's path
``budget``     the planar cost model of the work budget: :func:`check_work`, :func:`work_costs`
``base``       the improver's state: continuous checks charged to the budget, the final check's reserve, pruning
``shortcuts``  greedy, random (batched, partial) and goal shortcuts (step 5)
``lattice``    moves, regrasps and first grasps on the joint-space lattice (steps 3 and 6)
``proposals``  a proposal's moves checked, detoured or routed (RRT-Connect, lattice) (step 2)
``rebuild``    the rebuilding from each placement (step 2) and fewer transfers (step 4)
``final``      the final check at the validator's step and its refusal
``__init__``   :func:`improve`: the rounds (:class:`_Improver`) and the final checks
============== ==========================================================================================
"""

from __future__ import annotations

import itertools

import numpy as np

from clew_ros.core.improve import better, joint_travel, plan_score
from clew_ros.core.space import PlanningContext
from clew_ros.core.tree import Segment
from clew_ros.planar.improve.budget import check_work, work_costs
from clew_ros.planar.improve.final import _refusal
from clew_ros.planar.improve.many import _ManyJointMoves
from clew_ros.planar.improve.pieces import Improvement, _Piece, _pieces
from clew_ros.planar.improve.rebuild import _Rebuilding
from clew_ros.planar.improve.settings import ImproveSettings
from clew_ros.planar.improve.shortcuts import _draw_shortcuts
from clew_ros.planar.world import World

__all__ = [
    "ImproveSettings",
    "Improvement",
    "_Improver",
    "_Piece",
    "_draw_shortcuts",
    "_pieces",
    "check_work",
    "improve",
    "joint_travel",
    "work_costs",
]


class _Improver(_Rebuilding, _ManyJointMoves):
    """The improvement's rounds over one plan (its stages: :mod:`clew_ros.planar.improve.rebuild`,
    :mod:`~clew_ros.planar.improve.lattice`, :mod:`~clew_ros.planar.improve.shortcuts`)."""

    def run(self) -> list[_Piece]:
        """Rounds of rebuilding, fewer transfers and shortcuts while work is left and the last round made the
        plan better (after the first, the rebuilding may use all that is left: the shortcuts had too little to
        do)."""
        self.prune()
        many = self.world.robot.dof >= self.ctx.many.straight_probe_joints
        passes = self.settings.many_resolve_passes if many else 0
        for _ in range(passes):
            if not self.resolve_postures():
                break
            self.prune()
        while True:
            score = plan_score(self.pieces)
            self.rebuild()
            self.lattice_regrasps()
            self.fewer_transfers()
            self.shorten()
            if self.lattice_first_grasps():
                self.shorten()
            if not self.budget.left() or not self.better(score, plan_score(self.pieces)):
                return self.pieces
            self.rebuild_share = 1.0


def improve(
    world: World,
    ctx: PlanningContext,
    segments: list[Segment],
    final_object_pose: np.ndarray,
    goal: np.ndarray,
    *,
    settings: ImproveSettings = ImproveSettings(),
) -> Improvement:
    """Improve a found plan within ``ctx.settings.improve_time`` of work (module docstring).

    ``world`` is the planar world planned in; ``ctx`` carries the settings, the generator the improvement draws
    from and the termination (time limit, cancel); ``settings`` the improvement's tuning. Returns the better
    plan, or the first one.
    """
    first = _pieces(world, segments)
    first_score = plan_score(first)
    if ctx.settings.improve_time <= 0 or ctx.termination():
        return Improvement(
            segments, final_object_pose, first_score[1], first_score[0], first_score[1], first_score[0], 0, 0, False
        )
    improver = _Improver(world, ctx, _pieces(world, segments), goal, settings)
    pieces = improver.run()
    pieces = _pieces(world, [p.segment() for p in pieces])  # the object carried along the final paths
    changed = [
        p
        for p, q in itertools.zip_longest(pieces, first)
        if q is None or p is None or not np.array_equal(p.waypoints, q.waypoints)
    ]
    final = pieces[-1].end_pose(world) if pieces else final_object_pose
    gained = better(first_score, plan_score(pieces), settings.travel_eps)
    refused = _refusal(world, changed, final, goal) if gained else ""
    if refused or not gained:
        pieces, final = first, final_object_pose
    score = plan_score(pieces)
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
