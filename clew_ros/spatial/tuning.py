"""The spatial planner's tuning beyond ``planner.*`` (:class:`SpatialTuning`)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from clew_ros.core.settings import ManyJoints, SearchSettings
from clew_ros.spatial.checker import IntervalSettings
from clew_ros.spatial.lift import LiftSettings
from clew_ros.spatial.regrasps import RegraspSettings

__all__ = ["SpatialTuning"]


@dataclass(frozen=True)
class SpatialTuning:
    """Every tuning value of a spatial run beyond ``planner.*``; a benchmark or a test plans with a copy."""

    #: SEARCH's tuning: core's, but SEARCH runs from the start before the first EXPLORE, goes by way of up to 3
    #: intermediate placements where a goal grasp can take the object (:mod:`clew_ros.spatial.regrasps`), and
    #: the resolution criterion proves nothing (the run goes on to its time limit)
    search: SearchSettings = field(
        default_factory=lambda: SearchSettings(search_from_start=True, via_placements=3, resolution_proves=False)
    )
    #: how a transfer that drags the object at its ends is mended (:mod:`clew_ros.spatial.lift`)
    lift: LiftSettings = field(default_factory=LiftSettings)
    #: how intermediate placements are drawn (:class:`~clew_ros.spatial.regrasps.RegraspSettings`)
    regrasp: RegraspSettings = field(default_factory=RegraspSettings)
    #: how core adapts the search to arms of many joints, from 6 joints here (a UR5, a Panda): Manhattan
    #: paths of order 1 (``planner.manhattan_order`` lowered to it) and at most 4 generations of EXPLORE's GA:
    #: a free interval costs 0.13-0.25 ms on the Panda, and with them the pick-and-place problems of
    #: benchmarks/spatial_plan.py planned in a median 0.44-0.7 s instead of 0.8-2.0 s, as often; the GA rounds
    #: are kept when a job has ``straight`` targets (they miss behind any obstacle)
    many: ManyJoints = field(
        default_factory=lambda: ManyJoints(
            straight_probe_joints=6, transit_ga=True, transfer_ga=True, manhattan_order=1, explore_generations=4
        )
    )
    #: how the Manhattan decoding's free intervals step (the checker's defaults: coarser steps measured no
    #: faster on the Panda, 130-250 us an interval either way)
    intervals: IntervalSettings = field(default_factory=IntervalSettings)
    #: largest joint move (rad, max over joints) of the step that sets a carried object down: beyond it
    #: the linearised inverse kinematics from the decoded end rarely lands near it, and the move sweeps far
    settle_max_rad: float = 0.8
    #: highest (m) a carried object may be above a support and still be set down on it by that step; a
    #: little above (``settle_rise_m``) is allowed too (the object's face a few mm below the top)
    settle_drop_m: float = 0.3
    settle_rise_m: float = 0.01
    #: a transit holds its grasp when the tcp is this close (m, rad) to it: the object then rides on the
    #: nominal grasp within the plan file's 1e-4 replay tolerance
    hold_tolerance_m: float = 1e-5
    hold_tolerance_rad: float = 1e-5
    #: a transfer reaches the goal when the object's face is this close (rad) to the goal's face down,
    #: besides world.goal_tolerance on the centre and world.goal_angle_tolerance on the yaw
    face_tolerance_rad: float = 1e-3
    #: SEARCH's straight moves to a target also go by way of its approach: the tcp backed off this far (m)
    #: along its own -z (a grasp) or the object lifted this far (a placement), and from the start's own such
    #: retreat (0: direct moves only); a gripper's approach, as MoveIt Task Constructor's stages have it
    approach_m: float = 0.1
    #: SEARCH_TRANSFER's goal configurations hold the object at the goal turned about world z by each of these
    #: (rad) within world.goal_angle_tolerance: any of them reaches the goal, and an arm holding a grasp often
    #: reaches only some (with the goal's own yaw only, 1 run in 5 of the on_side problem needed a regrasp)
    goal_yaws: tuple[float, ...] = (0.0, math.pi / 2, -math.pi / 2, math.pi)
    #: whether SEARCH_TRANSFER gives up at once with a grasp that holds the object at the goal in no
    #: configuration its inverse kinematics finds (the start and SearchSettings.goal_seeds random starts, at
    #: every yaw of goal_yaws): its GA could only bring the object near, never place it
    hopeless_transfers: bool = True
    #: straight moves (count, nearest first) SEARCH tries to the targets inverse kinematics found
    straight_probes: int = 8
    #: a straight move is checked first at every this-many-th sample of the validator's (cheap refusals),
    #: then at every sample
    coarse_every: int = 16
    #: weight (m/rad) of the tcp's and the object's angles against their positions in SEARCH's objectives
    angle_weight_m: float = 0.1
    #: iterations of the inverse kinematics that sets a decoded end down on its support, from that end alone
    #: (no other seeds): the end is already near the placement, and each settle is paid per GA evaluation
    settle_iterations: int = 40
    #: the improvement's straight plan tries this many (hold, goal configuration) pairs per grasp, least
    #: straight-line joint travel first (each costs up to a few straight moves checked at 0.002 rad)
    straight_pairs: int = 16
    #: shortcuts tried per segment of a found plan (the improvement's work, deterministic): each is one
    #: straight move checked at 0.002 rad (0.1-1 ms on the Panda); 48 left the Manhattan detours about twice
    #: as long as 200 did on benchmarks/spatial_plan.py
    shortcut_tries: int = 200
    #: configurations this close (rad, largest joint difference) count as the same where the improvement joins
    #: a transfer put down and taken again by the same grasp (the arm did not move: nothing to check)
    same_rad: float = 1e-12
    #: motion-only queries: weight (m/rad) of the joint distance to the goal in SEARCH_TRANSIT's objective
    motion_weight: float = 0.1
    #: motion-only queries: landmarks (count) EXPLORE places at most (each followed by a SEARCH_TRANSIT
    #: to the goal) before the run gives up with NO_PATH_AT_RESOLUTION; 0: no such cap, the run goes on to its
    #: time limit (a cap is no proof that no motion exists)
    motion_landmarks: int = 0
    # -- motion-only queries (clew_ros.spatial.motion_plan); measured on the motion benchmark's scene seeds
    # -- 10-15 (python -m benchmarks spatial_motion --seed 10 ...), not on the reported seeds 0-2
    #: whether EXPLORE grows a tree from the goal as well as one from the start, in turn, each new landmark's
    #: SEARCH going to the other tree (RRT-Connect's two trees; False: the start's only): a goal in a shelf or
    #: a cage is hard to thread into from outside, easy to explore out of
    motion_bidirectional: bool = True
    #: EXPLORE's GA per landmark (population, generations), instead of planner.population and
    #: planner.generations: with theirs (24, 12) a landmark cost about 0.3 s on the cages and shelves
    motion_explore_population: int = 8
    motion_explore_generations: int = 3
    #: SEARCH_TRANSIT's do-while rounds and GA (population, generations), instead of planner.*: its straight
    #: moves and greedy probe do most of the joining; without the GA the development problems took as long
    motion_search_rounds: int = 1
    motion_search_population: int = 8
    motion_search_generations: int = 3
    #: weight (m/m) of the tcp's position beside the weighted joints in EXPLORE's landmark distance: on the
    #: UR5 (joints of +-2 pi) the joints alone spread landmarks over wrist turns that lead nowhere; with the
    #: tcp (and motion_keep_gain_rad) the mean CPU time of seeds 10-15 fell from 0.13 to 0.10 s, the median
    #: unchanged (weight 2: about as good)
    motion_tcp_weight: float = 1.0
    #: landmarks (count, nearest first) of the other tree SEARCH aims at (2 and 8 measured the same)
    motion_connect_targets: int = 4
    #: a failed SEARCH's end becomes a landmark of its tree when it got nearer the other tree by more than this
    #: (rad, joint distance; negative: never), as RRT-Connect keeps its extensions: with the tcp weight, one
    #: failure (bookshelf_ur5_18) of seeds 16-19 without it, none with
    motion_keep_gain_rad: float = 0.1
    #: shortcuts tried on the found path at most (as shortcut_tries for a plan's segments), in rounds of
    #: motion_shortcut_round tries, stopping after a round that took none: a path with long detours gets
    #: more tries, a simple one fewer (200 fixed tries took about a third of a run)
    motion_shortcut_tries: int = 400
    motion_shortcut_round: int = 20
    #: shortcuts (of a motion-only path, of a plan's segments) stop once the exact geometry has decided this
    #: many contacts per second of ``planner.improve_time`` (near contact every shortcut costs such checks; a
    #: count, so the plan does not depend on the machine)
    shortcut_exact_rate: float = 10_000.0
    #: a motion-only query's ``world.robot.goal_pose``: random IK seeds (count, after the start
    #: configuration) whose distinct valid solutions are the goal tree's roots, each a goal the search may
    #: reach (a 6-joint arm has up to 8 for one pose, a 7-joint one a continuum)
    goal_pose_ik_seeds: int = 64
    #: ... of which at most this many (count, nearest the start first, joint travel) become roots
    goal_pose_roots: int = 16

    # -- pick-and-place where the whole pose is out of reach (arms of 4-5 joints, joint limits) and the
    # -- goal out of sight of the placements (spatial_shelf, spatial_narrow)
    #: whether a decoded end whose placement's whole pose no configuration near it holds (an arm of 4-5
    #: joints reaches a full pose only on a thin set; joint limits) sets the object down level at the
    #: support's height instead, its x, y and yaw where the arm can put them (False: such an end is no move)
    level_settle: bool = True
    #: whether an approach no configuration near holds in its whole pose (an arm of 4-5 joints) is taken
    #: with the tcp at its position alone, turned as the arm turns it there (False: no approach then)
    position_approach: bool = True
    #: a carried object's approach where lifting it ``approach_m`` is out of reach: lifted this far (m) and
    #: backed off ``approach_m`` along the tcp's -z (a side grasp slides it out of a shelf); 0: no such approach
    slide_lift_m: float = 0.015
    #: SEARCH's straight moves try that slide (lifted, then slid out, as two moves) to at most this many of
    #: their targets (count) where the straight lift is blocked: each costs a few checked moves
    slide_targets: int = 2
    #: ... the slide in this many straight moves (count), each to inverse kinematics' configuration seeded at
    #: the one before: a straight joint move over the whole slide sags into a ceiling a few mm above
    slide_steps: int = 8
    #: a transit's way in from a grasp's approach, where the straight joint move sags into a cubby's wall, in
    #: this many short moves (count) along the tcp's line, each seeded at the one further in
    approach_steps: int = 8
    #: ... and from that retreat to that approach, where the straight move between them is blocked, over the
    #: top: both raised this much (m)
    carry_raise_m: float = 0.2
    #: whether SEARCH_TRANSFER's Manhattan paths end with the object in the air, where their moves take it
    #: (scored by its distance to the goal; the do-while loop goes on from there; refinement and the straight
    #: moves to the goal configurations set it down at the goal; a search that does not reach the goal sets
    #: its end down where it is, else is cut back to its last resting point): the GA then has a slope to
    #: follow to a goal it cannot see from ends that set the object down, and no settling to pay for each
    #: (False: every end is set down or is no move, as in EXPLORE)
    search_in_air: bool = True
    #: landmarks (count, both trees together) of the two trees a SEARCH_TRANSFER grows when its GA did not
    #: reach the goal (EXPLORE for transfer paths: the motion-only search, the object carried, from the
    #: landmark and from the nearest goal configuration); 0: none
    transfer_tree_landmarks: int = 8
    #: goal configurations (count) a goal tree is rooted at: the first SEARCH_TRANSFER's best goal
    #: configuration (:func:`~clew_ros.spatial.targets.goal_configurations`: the way out carrying the object farthest,
    #: then the nearest), then each later one's best where it is at least ``transfer_goal_apart_rad`` (largest
    #: joint difference) from every root (its inverse kinematics found a posture the first did not)
    transfer_goal_roots: int = 3
    transfer_goal_apart_rad: float = 1.0
    #: how far (m) those trees' first landmarks carry the object out from the landmark and from the goal
    #: along its approach, in steps of ``approach_m`` while they are clear: out of a shelf deeper than one
    #: approach
    transfer_way_out_m: float = 0.3
    #: a transit's holding configurations (count, nearest first) whose way out (:func:`~clew_ros.spatial.ways.way_out`)
    #: is measured when the nearest's does not carry the object ``approach_m``: in a cubby, a posture whose
    #: arm meets a wall as it slides the object out holds it where no transfer can start; those measured so
    #: are dropped where one measured carries it out (0: no measuring)
    hold_way_out_checks: int = 6
    #: where SEARCH_TRANSFER's GA stops short, the object carried out and in (ways out at both ends) through
    #: one of this many random configurations (count; 0: none) where no straight move joins the two ways out
    carry_vias: int = 24
    #: whether a transfer's Manhattan moves may start near a contact (free intervals sampled on the exact
    #: geometry where the spheres refuse the row); False: a carried object leaves a tight spot by its straight
    #: way out and set-down moves only, and the GA's moves stay where the spheres clear them (a search of
    #: transfers near a table crawled in millimetre steps)
    transfer_band_intervals: bool = False
    #: a motion-only query's way out of a tight spot: the tcp backed off along its own -z from the start and
    #: from the goal this far (m), in straight steps of ``motion_way_out_step_m`` (inverse kinematics seeded
    #: at the step before, each step clear), as a gripper leaves a bin or a grasp; both trees' first landmark
    #: (0: none)
    motion_way_out_m: float = 0.1
    motion_way_out_step_m: float = 0.01
