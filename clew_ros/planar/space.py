"""The planar world as the Ariadne's Clew Algorithm's space (:class:`clew_ros.core.space.Space`).

Every method hands the planar world and its compiled kernels to the generic
algorithm: Manhattan decoding (:mod:`clew_ros.planar.manhattan`), SEARCH's jobs
(:mod:`clew_ros.planar.search`), the approach cells that aim regrasps
(:mod:`clew_ros.planar.reach`), the infeasibility proof
(:mod:`clew_ros.planar.passage`) and the improvement (:mod:`clew_ros.planar.improve`).
:func:`plan` is the planar planner's entry point.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from clew_ros.core import clew
from clew_ros.core.manhattan import Counters, ManhattanPaths
from clew_ros.core.search import SearchJob
from clew_ros.core.settings import ManyJoints, Outcome, PlannerSettings, SearchSettings, Termination
from clew_ros.core.space import Approach, Improvement, Mode, PathResult, PlanningContext, TransitRequest
from clew_ros.core.tree import Landmark, Segment
from clew_ros.planar import search as planar_search
from clew_ros.planar.collision import is_placement_valid, is_valid
from clew_ros.planar.improve import ImproveSettings, improve
from clew_ros.planar.kinematics import compose, tip_poses
from clew_ros.planar.manhattan import run_manhattan, single_moves
from clew_ros.planar.passage import passage_refusal
from clew_ros.planar.reach import (
    ReachSettings,
    approach_cell,
    approach_cells,
    carry_cells,
    goal_approach_core,
    nearest_grasp_distance,
)
from clew_ros.planar.world import World

__all__ = ["PlanarAims", "PlanarSpace", "PlanarTuning", "landmark_features", "plan"]


@dataclass(frozen=True)
class PlanarTuning:
    """Every tuning value of a planar run beyond ``planner.*``, one frozen dataclass per stage: a benchmark or a
    test plans with a copy (``dataclasses.replace``), never by changing a module."""

    search: SearchSettings = field(default_factory=SearchSettings)
    many: ManyJoints = field(default_factory=ManyJoints)
    reach: ReachSettings = field(default_factory=ReachSettings)
    improve: ImproveSettings = field(default_factory=ImproveSettings)


def plan(
    world: World,
    settings: PlannerSettings | None = None,
    *,
    goal: np.ndarray | None = None,
    termination: Termination | None = None,
    progress: Callable[[clew.Progress], None] | None = None,
    tuning: PlanarTuning | None = None,
) -> clew.PlanResult:
    """:func:`clew_ros.core.clew.plan` in a planar world (``goal`` defaults to ``world.object.goal``), with
    ``tuning`` (default :class:`PlanarTuning` ())."""
    tuning = tuning or PlanarTuning()
    space = PlanarSpace(world, tuning.reach, tuning.improve)
    return clew.plan(
        space, settings, goal=goal, termination=termination, progress=progress, search=tuning.search, many=tuning.many
    )


def landmark_features(
    joints: np.ndarray, object_poses: np.ndarray, joint_weight: float, object_radius: float
) -> np.ndarray:
    """Embedding of (joints, object pose) where Euclidean distance is the landmark distance.

    Object position (m), orientation as a chord on a circle of the object's
    radius (m), joints weighted by ``joint_weight`` (m/rad) times ``sqrt(2 / n)``
    for ``n`` joints: the joints' part of the distance is then the weighted
    root mean square over the joints (scaled to a two-joint arm's), so that
    the angles of many joints do not swamp where the object lies.
    """
    theta = object_poses[:, 2]
    joint_weight = joint_weight * float(np.sqrt(2.0 / joints.shape[1]))
    return np.concatenate(
        [
            object_poses[:, :2],
            object_radius * np.stack([np.cos(theta), np.sin(theta)], axis=1),
            joint_weight * joints,
        ],
        axis=1,
    )


class PlanarAims:
    """SEARCH's regrasps in place aimed at the goal's approach core (:func:`goal_approach_core` of each
    grasp, computed when first asked): :class:`clew_ros.core.space.RegraspAims` for a planar world."""

    def __init__(self, world: World, goal: np.ndarray, settings: ReachSettings) -> None:
        self._world = world
        self._goal = goal
        self._settings = settings
        self._cores: dict[int, np.ndarray | None] = {}

    def core(self, grasp: int) -> np.ndarray | None:
        """The approach cells of ``grasp`` from which the arm reaches the goal in the most ways."""
        if grasp not in self._cores:
            self._cores[grasp] = goal_approach_core(self._world, self._goal, grasp, settings=self._settings)
        return self._cores[grasp]

    def retake(self, grasp: int, grasp_rel: np.ndarray) -> bool:
        """Held outside the goal's core: the same grasp is worth taking again, in the core."""
        core = self.core(grasp)
        return core is not None and not core[approach_cell(-grasp_rel[2], len(core))]

    def aim(self, landmark: Landmark, grasp: int) -> np.ndarray | None:
        """The approach cells a regrasp of ``grasp`` in place at ``landmark`` aims at: those of
        :meth:`regrasp_approaches` in the goal's core, or all of them when none is (``None``: none at all, or,
        for the landmark's own grasp, none in the core: it was just tried as it is held)."""
        approach = self.regrasp_approaches(landmark.object_pose, grasp)
        if not approach.any():
            return None  # no approach angle holds this grasp both here and at the goal: spare the transit
        core = self.core(grasp)
        if core is not None and (approach & core).any():
            aimed: np.ndarray = approach & core
            return aimed
        return None if grasp == landmark.grasp else approach

    def ranked(self, landmark: Landmark, grasps: list[int]) -> list[int]:
        return grasps  # the aim (approach cells) decides, not the order

    def placements(self, landmark: Landmark, grasp: int, start: np.ndarray) -> list[np.ndarray]:
        return []  # the planar planner proposes no intermediate placements (SearchSettings.via_placements 0)

    def regrasp_approaches(self, object_pose: np.ndarray, grasp: int) -> np.ndarray:
        """Approach cells that could hold ``grasp`` with the object at ``object_pose`` and at the goal (a
        rigid grasp keeps its approach during the transfer): a regrasp in place can end at the goal only
        with one of them."""
        world, goal = self._world, self._goal
        here = approach_cells(world, object_pose, grasp)
        there = approach_cells(
            world, goal, grasp, angle_spread=world.goal_angle_tolerance, position_slack=world.goal_tolerance
        )
        cells: np.ndarray = here & there & carry_cells(world, goal, grasp)
        return cells


@dataclass(frozen=True, eq=False)
class PlanarSpace:
    """A planar world (contract section 1) as the ACA's space, with the tuning of its own stages."""

    world: World
    reach_settings: ReachSettings = field(default_factory=ReachSettings)
    improve_settings: ImproveSettings = field(default_factory=ImproveSettings)

    @property
    def dof(self) -> int:
        return self.world.robot.dof

    @property
    def reach(self) -> float:
        return float(self.world.robot.reach)

    @property
    def grasp_count(self) -> int:
        return len(self.world.object.grasps)

    @property
    def initial_joints(self) -> np.ndarray:
        return self.world.robot.initial

    @property
    def initial_object_pose(self) -> np.ndarray:
        return self.world.object.initial

    @property
    def goal(self) -> np.ndarray:
        return np.asarray(self.world.object.goal, dtype=float)

    def manhattan(
        self,
        q0: np.ndarray,
        genes: np.ndarray,
        mode: Mode,
        *,
        margin_m: float,
        counters: Counters | None,
        should_stop: Callable[[], bool] | None,
        threads: int,
    ) -> ManhattanPaths:
        return run_manhattan(
            self.world,
            q0,
            genes,
            object_poses=mode.object_poses,
            grasp_rel=mode.grasp_rel,
            margin_m=margin_m,
            counters=counters,
            should_stop=should_stop,
            threads=threads,
        )

    def single_moves(
        self, q: np.ndarray, moves: np.ndarray, mode: Mode, *, margin_m: float, counters: Counters | None
    ) -> np.ndarray:
        return single_moves(
            self.world,
            q,
            moves,
            margin_m=margin_m,
            counters=counters,
            object_poses=mode.object_poses,
            grasp_rel=mode.grasp_rel,
        )

    def held_object_poses(self, q: np.ndarray, grasp_rel: np.ndarray) -> np.ndarray:
        return compose(tip_poses(self.world.robot, q), grasp_rel)

    def landmark_features(self, joints: np.ndarray, object_poses: np.ndarray, joint_weight: float) -> np.ndarray:
        return landmark_features(joints, object_poses, joint_weight, self.world.object.radius)

    def goal_distance(self, object_poses: np.ndarray, goal: np.ndarray) -> np.ndarray:
        distance: np.ndarray = np.linalg.norm(planar_search.goal_error(self.world, object_poses, goal), axis=1)
        return distance

    def search_transits(self, ctx: PlanningContext, requests: list[TransitRequest]) -> list[PathResult]:
        return planar_search.search_transits(self.world, ctx, requests)

    def search_transfer(
        self, ctx: PlanningContext, q0: np.ndarray, grasp_rel: np.ndarray, goal: np.ndarray
    ) -> PathResult:
        return planar_search.search_transfer(self.world, ctx, q0, grasp_rel, goal)

    def straight_probe(
        self,
        ctx: PlanningContext,
        jobs: list[SearchJob],
        q: np.ndarray,
        best: np.ndarray,
        waypoints: list[list[np.ndarray]],
    ) -> None:
        planar_search.straight_probe(self.world, ctx, jobs, q, best, waypoints=waypoints)

    def approach_allows(self, approach: Approach, grasp_rel: np.ndarray) -> bool:
        # the last link's direction in the object frame is -grasp_rel[2]
        return bool(approach[approach_cell(-grasp_rel[2], len(approach))])

    def regrasp_aims(self, goal: np.ndarray) -> PlanarAims:
        return PlanarAims(self.world, goal, self.reach_settings)

    def quick_refusal(self, goal: np.ndarray) -> tuple[Outcome, str] | None:
        """A colliding start or goal, a goal beyond reach, a proof that none exists."""
        world = self.world
        if not np.all(np.isfinite(goal)) or goal.shape != (3,):
            return Outcome.INVALID_WORLD, "goal: expected three finite numbers (x, y, theta)"
        if not is_placement_valid(world, goal[None])[0]:
            return Outcome.GOAL_IN_COLLISION, f"goal placement {goal.tolist()} collides or leaves world.bounds"
        if not is_valid(world, world.robot.initial[None], world.object.initial[None])[0]:
            return Outcome.START_IN_COLLISION, "the start configuration is not valid"
        nearest = nearest_grasp_distance(world, goal)
        if nearest > world.robot.reach + world.grasp_tolerance:
            message = (
                f"goal placement out of reach: its nearest grasp is {nearest:.3f} m "
                f"from the base, the arm reaches {world.robot.reach:.3f} m"
            )
            return Outcome.GOAL_OUT_OF_REACH, message
        reason = passage_refusal(world, goal)
        if reason is not None:
            return Outcome.NO_PATH_AT_RESOLUTION, reason
        return None

    def improve(
        self, ctx: PlanningContext, segments: list[Segment], object_pose: np.ndarray, goal: np.ndarray
    ) -> Improvement:
        return improve(self.world, ctx, segments, object_pose, goal, settings=self.improve_settings)
