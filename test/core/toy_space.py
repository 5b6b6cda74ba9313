"""A toy space for the core alone: a point gripper in the unit square, one point object, two grasps.

Nothing here imports :mod:`clew_ros.planar` or :mod:`clew_ros.spatial`: the Ariadne's Clew Algorithm
(:func:`clew_ros.core.clew.plan`: EXPLORE, SEARCH) runs on this space as it runs on theirs. The gripper's two
joints are its x and y (m); the object rests at a point, or rides at the grasp's offset from the gripper. A
wall stands between the object's start and its goal, open above, so that a transfer must go over it: a
Manhattan path of more than one move. Free intervals are exact (axis-aligned moves among axis-aligned boxes).

``python test/core/toy_space.py`` plans and prints, as one JSON line, the outcome and which of clew_ros's
packages were imported (``test/core/test_toy_space.py`` runs it in a process of its own).
"""

from __future__ import annotations

import json
import sys
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from clew_ros.core import clew
from clew_ros.core.improve import joint_travel
from clew_ros.core.manhattan import Counters, ManhattanPaths, bounce
from clew_ros.core.search import SearchJob, local_search
from clew_ros.core.settings import Outcome, PlannerSettings
from clew_ros.core.space import Approach, Improvement, Mode, PathResult, PlanningContext, TransitRequest
from clew_ros.core.tree import Landmark, Segment

#: the wall (x_min, y_min, x_max, y_max, m) between the object's start and its goal; above it the way is open
WALL = np.array([0.45, 0.0, 0.55, 0.6])
#: the object's position in the gripper's frame for each grasp (m): beside the gripper, left or right
GRASPS = np.array([[0.05, 0.0], [-0.05, 0.0]])
#: a transit holds a grasp this close to it (m); a transfer reaches the goal this close (m)
HOLD_TOLERANCE_M = 1e-6
GOAL_TOLERANCE_M = 1e-3


def free_interval(points: np.ndarray, joint: int) -> tuple[np.ndarray, np.ndarray]:
    """The interval ``[low, high]`` (B,) each point (B, 2) may move along axis ``joint`` staying inside the
    unit square and out of :data:`WALL` (it is outside the wall to begin with)."""
    other = 1 - joint
    low, high = np.zeros(len(points)), np.ones(len(points))
    across = (points[:, other] > WALL[other]) & (points[:, other] < WALL[other + 2])
    before = across & (points[:, joint] <= WALL[joint])
    after = across & (points[:, joint] >= WALL[joint + 2])
    high = np.where(before, WALL[joint], high)
    low = np.where(after, WALL[joint + 2], low)
    return low, high


@dataclass
class ToyAims:
    """Regrasps in place are always worth a transit, by any approach, in the order given; no intermediate
    placements."""

    def retake(self, grasp: int, grasp_rel: np.ndarray) -> bool:
        return False

    def aim(self, landmark: Landmark, grasp: int) -> Approach | None:
        return np.ones(1, dtype=bool)

    def ranked(self, landmark: Landmark, grasps: list[int]) -> list[int]:
        return grasps

    def placements(self, landmark: Landmark, grasp: int, start: np.ndarray) -> list[np.ndarray]:
        return []


@dataclass
class ToySpace:
    """The toy world as the ACA's space (:class:`clew_ros.core.space.Space`)."""

    initial: np.ndarray = field(default_factory=lambda: np.array([0.2, 0.9]))
    object_initial: np.ndarray = field(default_factory=lambda: np.array([0.2, 0.3]))
    object_goal: np.ndarray = field(default_factory=lambda: np.array([0.8, 0.3]))

    dof = 2
    reach = 1.0
    grasp_count = len(GRASPS)

    @property
    def initial_joints(self) -> np.ndarray:
        return self.initial

    @property
    def initial_object_pose(self) -> np.ndarray:
        return self.object_initial

    @property
    def goal(self) -> np.ndarray:
        return self.object_goal

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
        count, order, n = genes.shape
        q = np.array(q0, dtype=float).reshape(count, n)
        rel = np.broadcast_to(np.asarray(mode.poses, dtype=float), (count, 2)) if mode.transfer else None
        way = np.empty((count, order * n + 1, n))
        way[:, 0] = q
        for step in range(order * n):
            r, j = divmod(step, n)
            low, high = self._interval(q, j, rel)
            q[:, j] = bounce(q[:, j] + genes[:, r, j], low, high)
            way[:, step + 1] = q
            if counters is not None:
                counters.clearance_checks += count
        if rel is None:
            return ManhattanPaths(way, np.array(np.broadcast_to(mode.poses, (count, 2)), dtype=float))
        return ManhattanPaths(way, q + rel)

    def _interval(self, q: np.ndarray, joint: int, rel: np.ndarray | None) -> tuple[np.ndarray, np.ndarray]:
        """The gripper's free interval along ``joint``; carrying, the object's too (shifted to the gripper's)."""
        low, high = free_interval(q, joint)
        if rel is not None:
            held_low, held_high = free_interval(q + rel, joint)
            low = np.maximum(low, held_low - rel[:, joint])
            high = np.minimum(high, held_high - rel[:, joint])
        return low, high

    def single_moves(
        self, q: np.ndarray, moves: np.ndarray, mode: Mode, *, margin_m: float, counters: Counters | None
    ) -> np.ndarray:
        rel = mode.grasp_rel
        current = np.array(q, dtype=float)
        out = [current.copy()]
        for j in np.flatnonzero(moves):
            low, high = self._interval(current[None], int(j), None if rel is None else rel.reshape(1, 2))
            current[j] = float(np.clip(current[j] + moves[j], low[0], high[0]))
            out.append(current.copy())
        return np.array(out)

    def held_object_poses(self, q: np.ndarray, grasp_rel: np.ndarray) -> np.ndarray:
        return np.asarray(np.asarray(q, dtype=float).reshape(-1, 2) + grasp_rel)

    def landmark_features(self, joints: np.ndarray, object_poses: np.ndarray, joint_weight: float) -> np.ndarray:
        return np.concatenate([object_poses, joint_weight * joints], axis=1)

    def goal_distance(self, object_poses: np.ndarray, goal: np.ndarray) -> np.ndarray:
        distance: np.ndarray = np.linalg.norm(object_poses - goal, axis=1)
        return distance

    def search_transits(self, ctx: PlanningContext, requests: list[TransitRequest]) -> list[PathResult]:
        jobs = []
        for start, resting, grasp, _approach in requests:
            target = np.asarray(resting) - GRASPS[grasp]

            def error(q: np.ndarray, target: np.ndarray = target) -> np.ndarray:
                return np.asarray(q - target)

            def objective(q: np.ndarray, _poses: np.ndarray, target: np.ndarray = target) -> np.ndarray:
                distance: np.ndarray = np.linalg.norm(q - target, axis=1)
                return distance

            mode = Mode.resting(np.asarray(resting, dtype=float)[None])
            jobs.append(SearchJob(np.asarray(start, dtype=float), objective, error, 1e-9, mode, toward=target))
        results = []
        for (_, _, grasp, _), (waypoints, distance) in zip(requests, local_search(ctx, jobs), strict=True):
            success = distance <= HOLD_TOLERANCE_M
            results.append(PathResult(success, waypoints, distance, GRASPS[grasp].copy() if success else None))
        return results

    def search_transfer(
        self, ctx: PlanningContext, q0: np.ndarray, grasp_rel: np.ndarray, goal: np.ndarray
    ) -> PathResult:
        def error(q: np.ndarray) -> np.ndarray:
            return np.asarray(q + grasp_rel - goal)

        def objective(_q: np.ndarray, object_poses: np.ndarray) -> np.ndarray:
            return self.goal_distance(object_poses, goal)

        mode = Mode.held(np.asarray(grasp_rel, dtype=float)[None])
        job = SearchJob(np.asarray(q0, dtype=float), objective, error, 1e-9, mode, toward=goal - grasp_rel)
        waypoints, distance = local_search(ctx, [job])[0]
        success = distance <= GOAL_TOLERANCE_M
        return PathResult(success, waypoints, distance, object_pose=waypoints[-1] + grasp_rel)

    def straight_probe(
        self,
        ctx: PlanningContext,
        jobs: list[SearchJob],
        q: np.ndarray,
        best: np.ndarray,
        waypoints: list[list[np.ndarray]],
    ) -> None:
        """No straight moves: two joints are the Manhattan paths' own."""

    def approach_allows(self, approach: Approach, grasp_rel: np.ndarray) -> bool:
        return True

    def regrasp_aims(self, goal: np.ndarray) -> ToyAims:
        return ToyAims()

    def quick_refusal(self, goal: np.ndarray) -> tuple[Outcome, str] | None:
        inside = np.all(goal >= WALL[:2]) and np.all(goal <= WALL[2:])
        return (Outcome.GOAL_IN_COLLISION, "the goal is inside the wall") if inside else None

    def improve(
        self, ctx: PlanningContext, segments: list[Segment], object_pose: np.ndarray, goal: np.ndarray
    ) -> Improvement:
        travel = joint_travel(segments)
        transfers = sum(s.kind == "transfer" for s in segments)
        return Improvement(segments, object_pose, travel, transfers, travel, transfers, 0, 0, False)


def main() -> int:
    """Plan in the toy space (seed 0) and print the outcome, the plan's transfers and the modules imported."""
    result = clew.plan(ToySpace(), PlannerSettings(seed=0, time_limit=30.0))
    loaded = sorted({name.split(".")[1] for name in sys.modules if name.startswith("clew_ros.")})
    report = {
        "outcome": result.outcome.name,
        "message": result.message,
        "landmarks": len(result.tree),
        "segments": [[s.kind, s.grasp, np.asarray(s.waypoints).tolist()] for s in result.segments],
        "final_object_pose": None if result.final_object_pose is None else result.final_object_pose.tolist(),
        "packages": loaded,
    }
    print(json.dumps(report))
    return 0 if result.success else 1


if __name__ == "__main__":
    sys.exit(main())
