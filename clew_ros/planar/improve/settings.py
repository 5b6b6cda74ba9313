"""The improvement's tuning (:class:`ImproveSettings`): the work each step is charged, the shares of the budget
each stage may spend, and the tries and tolerances of each stage. Passed to :func:`clew_ros.planar.improve.improve`;
a benchmark or a test varies a copy (:func:`dataclasses.replace`)."""

from __future__ import annotations

from dataclasses import dataclass

from clew_ros.planar.connect import ConnectSettings
from clew_ros.planar.continuous import ContinuousSettings
from clew_ros.planar.lattice import LatticeSettings
from clew_ros.planar.regrasp import RegraspSettings

__all__ = ["ImproveSettings"]


@dataclass(frozen=True)
class ImproveSettings:
    """Tuning of :mod:`clew_ros.planar.improve` (work in work units, angles in rad, shares of the budget)."""

    #: Work units per second of ``planner.improve_time``: on the machine of docs/benchmarks.md, when quiet, the
    #: improvement's wall time is 0.5-1.3 of the seconds its work stands for on 27 of the 28 worlds there (medians
    #: per world over two runs, ``benchmarks.improvement``'s last column; shapes2_1, 0.02 s in all, up to 1.8) and
    #: at most 0.54 s of the default 0.5 s; up to twice that with its 2 cores shared with other jobs. The same work
    #: everywhere.
    work_per_second: float = 5.25e5
    #: Work of one configuration checked in a batched call of the compiled checks, per unit of
    #: :func:`~clew_ros.planar.improve.budget.check_work`: such a check takes 0.4-1.3 of what this charges at
    #: :attr:`work_per_second`, 0.13-0.40 of a whole unit (``python -m benchmarks.check_cost``: 8,000
    #: configurations a call, each checked still or along a move, eight worlds), the Python around each call being
    #: charged by the call (:attr:`call_work`, :attr:`move_call_work`).
    batch_check_share: float = 0.3
    #: Work of one call of the compiled configuration check from Python (the Python around it: the proposals'
    #: inverse kinematics computes poses and checks its solutions), in work units.
    call_work: int = 200
    #: Work of one call of the compiled straight-move check (:func:`clew_ros.planar.continuous.straight_moves_clear`:
    #: the Python around it, one or several moves), or of the proposals' compiled screen
    #: (:func:`clew_ros.planar.kernel.screen_routes`), in work units.
    move_call_work: int = 20
    #: Work of one round of RRT-Connect besides its checks (drawing its configuration, finding the nearest node), in
    #: work units.
    round_work: float = 2.0
    #: Work of one genetic-algorithm individual (a decoded Manhattan path), in work units (110 at 3.5e5 units a
    #: second, scaled with :attr:`work_per_second`: a whole search, 24 x 12 x 3 individuals, still does not fit
    #: :attr:`transfer_share` of the default budget).
    evaluation_work: int = 165
    #: Random shortcuts drawn, scored and checked together (one compiled call checks every move of those that
    #: would make the path shorter).
    shortcut_batch: int = 16
    #: Work of one batch of random shortcuts besides its checks (drawing and scoring them, compiled; splicing
    #: them), in work units.
    batch_work: int = 150
    #: Work of one greedy shortcut tried besides its check (the Python that splices and prunes the path and scores
    #: it), in work units, and :attr:`waypoint_work` more for each waypoint of the segment: on a 7-joint plan of
    #: 150 waypoints a try took 0.27 ms where its check was charged 0.18 ms (``benchmarks.improvement_stages``:
    #: the greedy shortcuts' wall time 1.4 times their work).
    shortcut_try_work: int = 40
    #: Work per waypoint of the segment of one greedy shortcut tried (see :attr:`shortcut_try_work`), in work units.
    waypoint_work: float = 1.0
    #: Batches of random shortcuts in a row that change nothing end them.
    idle_batches: int = 12
    #: Work of one step of inverse kinematics (one configuration, one iteration), in work units.
    ik_work: float = 0.125
    #: The cost of one configuration check, in joints (the links are what the compiled check places and tests,
    #: each against the obstacles' boxes, the object and each other): each pair of links tested for
    #: self-collision costs this many joints.
    self_pair_joints: float = 0.2
    #: Obstacles that cost as much to check as one joint (see :attr:`self_pair_joints`).
    obstacles_per_joint: int = 16
    #: figure1's check cost in those terms (2 joints, 2 obstacles, in joints): a ``check_work`` of 1.
    reference_cost: float = 2.125
    #: Share of the budget that attempts to drop transfers (SEARCH_TRANSFER to the goal) may start in.
    transfer_share: float = 0.5
    #: Share of the budget that rebuilding the manipulation from straight moves may start in (in the first round;
    #: all of it after).
    rebuild_share: float = 0.6
    #: Share of what is left of the rebuilding's budget one round of proposals may spend (checks, inverse
    #: kinematics).
    propose_share: float = 0.5
    #: Rebuilding stops after this many passes in a row that found nothing better.
    rebuild_idle_passes: int = 2
    #: Proposals checked per placement at most (none with a move that looked blocked).
    rebuild_tries: int = 6
    #: Proposals whose key configurations all lie this close (rad) to one that failed are not checked.
    alike_rad: float = 0.3
    #: Detours tried around a straight move of a proposal that is not clear (each way: inside the box of its
    #: ends, around its middle).
    detours: int = 3
    #: Proposals with a move that looked blocked checked per placement at most (their blocked moves are routed
    #: by RRT-Connect).
    blocked_tries: int = 3
    #: Routings by RRT-Connect that may find no path before the first routed proposal that makes the plan
    #: better; after that many and none that did, proposals with a move that looked blocked are no longer
    #: checked (a cluttered world: the budget is left to the shortcuts).
    connect_probes: int = 1
    #: Proposals with a routed move that may fail to make the plan better, before the first that does (as
    #: :attr:`connect_probes`).
    routed_probes: int = 2
    #: Share of the budget one routing by RRT-Connect (and one lattice path replacing it) may spend at most.
    connect_share: float = 0.2
    #: Rounds of one routing by RRT-Connect at most.
    connect_steps: int = 1000
    #: The share of the budget one regrasp search on the lattice may take.
    regrasp_share: float = 0.35
    #: The share of the budget spent after which no regrasp search on the lattice starts (the rest is the
    #: shortcuts').
    regrasp_total_share: float = 0.6
    #: Tip angles tried around each grasp point when the first grasp is searched again on the lattice.
    first_grasp_approaches: int = 24
    #: Work units per node a Dijkstra search of :func:`clew_ros.planar.lattice.lattice_regrasp` expands (measured:
    #: 1.2 ms for 5,300 nodes of obstacles_32's lattice, 0.12 units a node at :attr:`work_per_second`).
    flood_work: float = 0.12
    #: Work units per release per round of :func:`clew_ros.planar.lattice.lattice_regrasp`: totalling the releases
    #: (compiled, :func:`clew_ros.planar.kernel.release_totals`, when a search changed) and picking the best not
    #: found blocked, with the round's Python (measured: 0.26 ms a round of about 5,000 releases on obstacles_16,
    #: 24 and 32, 0.027 units a release at :attr:`work_per_second`).
    release_work: float = 0.03
    #: A move whose ends both lie this close (rad, largest joint difference) to those of a move found blocked
    #: in the same mode is taken as blocked too.
    move_alike_rad: float = 0.1
    #: A partial shortcut spans at most this many pieces of the path.
    partial_pieces: int = 8
    #: Stream of the generator the proposals' inverse-kinematics restarts draw from (with ``planner.seed``): a
    #: stream of its own, so the run's stream stays the releases'.
    restart_stream: int = 19
    #: Joint travel below this (rad) counts as equal.
    travel_eps: float = 1e-9
    #: Work of one configuration of the final check at the validator's step, as a share of what a configuration
    #: checked costs (:attr:`batch_check_share` x ``check_work``). The final check of the segments changed so
    #: far is kept out of the budget, so that it fits in the budget too.
    dense_work: float = 0.5
    #: Work of one node expanded by the lattice's compiled A* (:func:`clew_ros.planar.kernel.lattice_search`), in
    #: work units (0.26 microseconds a node, measured on a 34^3 lattice with a wall).
    expansion_work: float = 0.2
    #: Configurations this close (rad, largest joint difference) count as the same where a transfer is put down
    #: and taken again (the pruning joins the two transfers).
    same_rad: float = 1e-12
    #: On arms of at least ``ManyJoints.straight_probe_joints`` joints the budget is multiplied by the joints over
    #: this many (count), to the power :attr:`many_budget_power`: a configuration check costs about the square of
    #: the joints (self-collision pairs, :func:`~clew_ros.planar.improve.budget.check_work`), so the default budget
    #: bought a 37-joint plan's solved postures (:mod:`clew_ros.planar.improve.many`) about one continuous check of
    #: each of its moves, and nothing after (the snake family's first plans of worlds 0-11 and 24-35 improved:
    #: median travel 1.04x the witness's and the longest 7.2x without it, 1.00x and 5.3x with it linearly).
    many_budget_joints: int = 10
    #: ...raised to this power (a number): a check of a many-joint plan's moves costs about the square of the
    #: joints, so a budget growing only linearly (power 1) ran out within the first solving again of the postures
    #: of some 32-joint plans, and the first plan was kept (snake worlds 70, 71, 73, 75, 77, seeds 0-1: median
    #: travel 1.50x the witness's, the longest 6.8x; with 2, 1.08x and 5.7x, the improvement 1-3 s of wall time).
    many_budget_power: float = 2.0
    #: Passes (count, at most) of the solving again of a many-joint plan's postures
    #: (:meth:`~clew_ros.planar.improve.many._ManyJointMoves.resolve_postures`), each from the plan the last one
    #: left, while one makes it shorter and work is left: a pass that stops at a piece it cannot join pulls the
    #: pieces before it back to the first plan's postures there, and the next pass, from those, shortens them
    #: (snake worlds 70, 71, 73, 75, 77, seeds 0-1: the longest plan 5.7x the witness's travel after one pass,
    #: 2.4x after up to three; snake_96 seed 1 108.9 rad -> 60.0 rad).
    many_resolve_passes: int = 3
    #: Goal shortcuts' moves checked in one compiled call on arms of at least ``ManyJoints.straight_probe_joints``
    #: joints (count), shortest first, the budget and the clock asked between calls: all of a 39-joint plan's
    #: candidates (its last transfer's waypoints) checked at once took 4 s near the slot, past the time limit.
    many_goal_batch: int = 4
    #: Error (m; the tip's angle counting 1 m per rad) left by the inverse kinematics of a posture solved again
    #: (:mod:`clew_ros.planar.improve.many`): the object is then held or put down where it was to within this, far
    #: below any tolerance of a world.
    resolve_error_m: float = 1e-9
    #: Sweep (m, ``sum_j |dq_j| R_j``) between the points of a path whose postures are solved again
    #: (:meth:`clew_ros.planar.improve.many._ManyJointMoves.resolve`): short enough that a straight move between two
    #: solved points keeps the tip near its old path.
    resolve_step_m: float = 0.05
    #: Work of one call of the inverse kinematics there (one point), besides its steps (:attr:`ik_work`), in work
    #: units: a one-row call from Python took 27 microseconds on 21 joints (14 units at :attr:`work_per_second`).
    resolve_call_work: float = 20.0
    #: Shares (from the solved posture towards the first plan's) of the seeds a point not joined clear is solved
    #: from again there; the first plan's own posture is tried last.
    resolve_pulls: tuple[float, ...] = (0.25, 0.5, 0.75)
    #: The proposals' tuning (:func:`clew_ros.planar.regrasp.propose`, and the goal shortcuts'
    #: :func:`clew_ros.planar.regrasp.goal_holds_near`).
    regrasp: RegraspSettings = RegraspSettings()
    #: The straight-move check of every move the improvement changes (its margin, a fraction of
    #: ``planner.clearance``; :func:`clew_ros.planar.continuous.straight_moves_clear`), also within its routings.
    moves: ContinuousSettings = ContinuousSettings()
    #: The routings of blocked moves by RRT-Connect (:func:`clew_ros.planar.connect.rrt_connect`).
    connect: ConnectSettings = ConnectSettings()
    #: The lattice's routings and regrasp searches (:mod:`clew_ros.planar.lattice`).
    lattice: LatticeSettings = LatticeSettings()
