"""A spatial world as the Ariadne's Clew Algorithm's space (:class:`clew_ros.core.space.Space`).

The generic algorithm (EXPLORE, SEARCH's do-while loop, the genetic algorithm, the landmark tree) runs
unchanged; :class:`SpatialSpace` hands it the spatial world's parts (docs/spatial.md, "Planning"):

- *poses*: an object pose is 6 numbers ``[x, y, z, roll, pitch, yaw]`` (section 1b); a held pose
  ``grasp_rel`` is the object's pose in the tcp's frame, always the *nominal* one of the grasp (the inverse
  of ``world.object.grasps[g]``): a transit succeeds only when the tcp holds the grasp within
  :attr:`SpatialTuning.hold_tolerance_m` / ``_rad``, so the object rides on the grasp as the plan says.
- what every part shares (the checker of each mode, the kinematics, the straight-move check):
  :mod:`~clew_ros.spatial.space_parts`;
- *Manhattan decoding*, each move bounced into its joint's free interval: :mod:`~clew_ros.spatial.manhattan`;
- *stable ends*: a decoded transfer ends with the object **set down** (:mod:`~clew_ros.spatial.settle`) or
  counts as no move at all: the placement search is inside the optimisation, as the paper suggests, and
  every landmark's object rests on a support;
- EXPLORE's landmark distance and SEARCH_TRANSFER's goal distance: :mod:`~clew_ros.spatial.distances`;
- *SEARCH*: its jobs (:mod:`~clew_ros.spatial.search`), the configurations they aim at
  (:mod:`~clew_ros.spatial.targets`) and the straight moves to them (:mod:`~clew_ros.spatial.ways`);
- the answers knowable at once: :mod:`~clew_ros.spatial.refusals`; the improvement:
  :mod:`~clew_ros.spatial.improvement`.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

from clew_ros.core import clew
from clew_ros.core.manhattan import Counters, ManhattanPaths
from clew_ros.core.search import SearchJob
from clew_ros.core.settings import Outcome, PlannerSettings, Termination
from clew_ros.core.space import Approach, Improvement, Mode, PathResult, PlanningContext, TransitRequest
from clew_ros.core.tree import Segment
from clew_ros.spatial import distances, improvement, manhattan, search
from clew_ros.spatial.checker import SpatialChecker
from clew_ros.spatial.inverse import InverseKinematics
from clew_ros.spatial.motion_plan import plan_motion
from clew_ros.spatial.refusals import quick_refusal
from clew_ros.spatial.regrasps import SpatialAims
from clew_ros.spatial.space_parts import SpaceParts
from clew_ros.spatial.straight import straight_samples_clear
from clew_ros.spatial.transforms import matrices, poses
from clew_ros.spatial.tuning import SpatialTuning
from clew_ros.spatial.turns import split_turns
from clew_ros.spatial.validate import ValidationSettings
from clew_ros.spatial.ways import backed_off
from clew_ros.spatial.world import SpatialWorld

__all__ = ["SpatialSpace", "SpatialTuning", "matrices", "plan", "poses", "straight_samples_clear"]

Array = NDArray[np.float64]


class SpatialSpace:
    """A spatial world (contract section 1b) with an object, as the ACA's space; motion-only worlds use
    it for their transit checks (their mode's pose is ignored)."""

    def __init__(self, world: SpatialWorld, tuning: SpatialTuning | None = None) -> None:
        self.world = world
        self.tuning = tuning or SpatialTuning()
        self.parts = SpaceParts(world, self.tuning)
        #: whether decoded transfers end where their moves take them, the object in the air, unsettled
        #: (inside SEARCH_TRANSFER: :attr:`SpatialTuning.search_in_air`); else each sets it down or stays at
        #: its start
        self.in_air = False

    # -- the protocol -----------------------------------------------------------------------------------
    @property
    def dof(self) -> int:
        return self.world.robot.dof

    @property
    def reach(self) -> float:
        return self.parts.reach

    @property
    def grasp_count(self) -> int:
        return len(self.parts.grasps)

    @property
    def initial_joints(self) -> np.ndarray:
        return self.world.initial

    @property
    def initial_object_pose(self) -> np.ndarray:
        thing = self.world.object
        return np.asarray(thing.initial if thing is not None else np.zeros(6), dtype=float)

    @property
    def goal(self) -> np.ndarray:
        thing = self.world.object
        return np.asarray(thing.goal if thing is not None else np.zeros(6), dtype=float)

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
        """:func:`clew_ros.spatial.manhattan.decode` (the clearance is the checker's, one thread)."""
        return manhattan.decode(
            self.parts,
            q0,
            genes,
            mode,
            counters=counters,
            should_stop=should_stop,
            in_air=self.in_air,
        )

    def single_moves(
        self, q: np.ndarray, moves: np.ndarray, mode: Mode, *, margin_m: float, counters: Counters | None
    ) -> np.ndarray:
        return manhattan.single_moves(q, moves, checker=self.parts.checker_of(mode), counters=counters)

    def held_object_poses(self, q: np.ndarray, grasp_rel: np.ndarray) -> np.ndarray:
        return self.parts.held_object_poses(q, grasp_rel)

    def landmark_features(self, joints: np.ndarray, object_poses: np.ndarray, joint_weight: float) -> np.ndarray:
        return distances.landmark_features(self.parts, joints, object_poses, joint_weight)

    def goal_distance(self, object_poses: np.ndarray, goal: np.ndarray) -> np.ndarray:
        return distances.goal_distance(self.parts, object_poses, goal)

    def search_transits(self, ctx: PlanningContext, requests: list[TransitRequest]) -> list[PathResult]:
        return search.search_transits(self, ctx, requests)

    def search_transfer(
        self, ctx: PlanningContext, q0: np.ndarray, grasp_rel: np.ndarray, goal: np.ndarray
    ) -> PathResult:
        return search.search_transfer(self, ctx, q0, grasp_rel, goal)

    def straight_probe(
        self,
        ctx: PlanningContext,
        jobs: list[SearchJob],
        q: np.ndarray,
        best: np.ndarray,
        waypoints: list[list[np.ndarray]],
    ) -> None:
        search.straight_probe(self.parts, ctx, jobs, q, best, waypoints=waypoints)

    def approach_allows(self, approach: Approach, grasp_rel: np.ndarray) -> bool:
        return True  # no aiming: every approach is allowed

    def regrasp_aims(self, goal: np.ndarray) -> SpatialAims:
        return SpatialAims(self, goal, self.tuning.regrasp)

    def quick_refusal(self, goal: np.ndarray) -> tuple[Outcome, str] | None:
        return quick_refusal(self.parts, goal)

    def improve(
        self, ctx: PlanningContext, segments: list[Segment], object_pose: np.ndarray, goal: np.ndarray
    ) -> Improvement:
        """:func:`clew_ros.spatial.improvement.improved`, mended and checked by the plan validator's checks
        (:func:`clew_ros.spatial.improvement.checked`)."""
        better = improvement.improved(self, ctx, segments, object_pose, goal)
        return improvement.checked(self, segments, object_pose, better)

    # -- what the motion-only search, the lift and the regrasps' aims ask (spatial.views) ---------------
    @property
    def validation_steps(self) -> Array:
        return self.parts.validation_steps

    def transit_checker(self, object_pose: Array) -> SpatialChecker:
        return self.parts.transit_checker(object_pose)

    def transfer_checker(self, grasp_rel: Array) -> SpatialChecker:
        return self.parts.transfer_checker(grasp_rel)

    def grasp_rel(self, grasp: int) -> Array:
        return self.parts.grasp_rel(grasp)

    def ik(self, seeds: int) -> InverseKinematics:
        return self.parts.ik(seeds)

    def tcp(self, q: Array) -> Array:
        return self.parts.tcp(q)

    def clear(self, checker: SpatialChecker, starts: Array, ends: Array) -> NDArray[np.bool_]:
        return self.parts.clear(checker, starts, ends)

    def backed_off(self, checker: SpatialChecker, q: Array) -> Array | None:
        return backed_off(self.parts, checker, q)

    def nearest_turns(self, q0: Array, found: Array) -> Array:
        return self.parts.nearest_turns(q0, found)


def plan(
    world: SpatialWorld,
    settings: PlannerSettings | None = None,
    *,
    goal: np.ndarray | None = None,
    termination: Termination | None = None,
    progress: Callable[[clew.Progress], None] | None = None,
    tuning: SpatialTuning | None = None,
) -> clew.PlanResult:
    """Plan in a spatial world: :func:`clew_ros.core.clew.plan` on :class:`SpatialSpace` with an object
    (``goal`` defaults to ``world.object.goal``), the motion-only ACA
    (:func:`clew_ros.spatial.motion_plan.plan_motion`) without one (``goal``: joints, default
    ``world.robot.goal``)."""
    tuning = tuning or SpatialTuning()
    if world.object is None:
        result = plan_motion(
            SpatialSpace(world, tuning), settings, goal=goal, termination=termination, progress=progress
        )
    else:
        space = SpatialSpace(world, tuning)
        result = clew.plan(
            space,
            settings,
            goal=goal,
            termination=termination,
            progress=progress,
            search=tuning.search,
            many=tuning.many,
        )
    steps = np.where(world.robot.prismatic, ValidationSettings().step_m, ValidationSettings().step_rad)
    return _short_turns(result, world.robot.continuous, steps)


def _short_turns(result: clew.PlanResult, continuous: NDArray[np.bool_], steps: Array) -> clew.PlanResult:
    """``result`` with every piece that turns a continuous joint by pi or more cut into straight parts at its
    own validator samples (:func:`clew_ros.spatial.turns.split_turns`: the same motion, read the same the
    short way round, checked at the same configurations)."""
    if not continuous.any():
        return result
    result.segments = [
        Segment(s.kind, s.grasp, list(split_turns(np.asarray(s.waypoints, dtype=float), continuous, steps=steps)))
        for s in result.segments
    ]
    return result
