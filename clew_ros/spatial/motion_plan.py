"""Motion-only queries on a spatial world (``world.robot.goal``, no object): the ACA's transit search.

As the paper's closing section suggests, EXPLORE runs for transit paths too: landmarks are collision-free
configurations, each reached from an earlier one by a Manhattan path (bounced into the free intervals,
:meth:`~clew_ros.spatial.space.SpatialSpace.manhattan`) that the genetic algorithm
(:func:`clew_ros.core.genetic.minimize`, the landmark a category gene) places as far as possible from every
landmark of its tree (the joints, weighted as the manipulation landmarks' joints are, and the tcp's
position, :attr:`SpatialTuning.motion_tcp_weight`).

Two trees of landmarks grow, one rooted at the start and one at the goal (RRT-Connect's two trees; a
departure from the paper, whose landmarks all grow from the start): SEARCH_TRANSIT
(:func:`clew_ros.core.search.local_search`) runs first from the start to the goal, then, in turn, EXPLORE
places a landmark in one tree and SEARCH_TRANSIT goes from it to the other tree, minimising the joint
distance to the nearest of that tree's landmarks (:attr:`SpatialTuning.motion_connect_targets`, nearest
first): straight moves to them checked at the validator's 0.002 rad (directly or by way of the approaches),
the greedy Manhattan probe, a small GA, and from where it ends straight moves again. The first search that
reaches the other tree ends the run; a search that fails but ends nearer the other tree leaves its end as
a landmark of its own tree (:attr:`SpatialTuning.motion_keep_gain_rad`, as RRT-Connect keeps its
extensions), which the other tree's next SEARCH aims at. The path (the start tree's landmarks' paths, the
search's, the goal tree's walked back to the goal) is shortcut (:func:`clew_ros.core.improve.shortcut_path`) in rounds
until a round takes none. EXPLORE's and SEARCH's GAs are small (SpatialTuning's motion block, instead of
``planner.population``, ``planner.generations`` and ``planner.search_rounds``): a landmark is worth more
as a place to search from than as the farthest one a long GA finds. Paths have ``planner.manhattan_order``
as set: unlike manipulation, it is not lowered for 7-joint arms (:attr:`SpatialTuning.many`); with order 1
or 3 for EXPLORE the benchmark's development problems (scene seeds 10-15) took longer on average (mean CPU
0.15-0.16 s against 0.12 s).
"""

from __future__ import annotations

import dataclasses
import math
import traceback
from collections.abc import Callable, Sequence
from functools import partial
from typing import Any, Protocol

import numpy as np
from numpy.typing import NDArray

from clew_ros.core import clew
from clew_ros.core.genetic import minimize
from clew_ros.core.improve import shortcut_path
from clew_ros.core.manhattan import Counters
from clew_ros.core.search import SearchJob, local_search
from clew_ros.core.settings import Outcome, PlannerSettings, Termination
from clew_ros.core.space import Mode, PlanningContext, Space
from clew_ros.core.tree import Landmark, LandmarkTree, Segment
from clew_ros.spatial.checker import SpatialChecker
from clew_ros.spatial.inverse import IKSettings, InverseKinematics, distinct
from clew_ros.spatial.tuning import SpatialTuning
from clew_ros.spatial.turns import goal_turns, joint_features, joint_gaps
from clew_ros.spatial.world import SpatialWorld

__all__ = ["add_branch", "connect", "plan_motion"]

#: The improvement draws from its own generator seeded with (planner.seed, this), as core's.
IMPROVE_STREAM = clew.IMPROVE_STREAM
#: The IK of ``world.robot.goal_pose`` draws its seeds from its own generator seeded with (planner.seed, this).
GOAL_POSE_STREAM = 0x60A1
#: Goal configurations this close (rad, largest joint difference) are one goal tree root.
SAME_GOAL_RAD = 1e-9
#: a configuration landmark's object pose: none (the trees of configurations carry no object pose)
_NO_POSE = np.zeros(6)


class MotionSpace(Space, Protocol):
    """What the motion-only search asks of a spatial space (:class:`clew_ros.spatial.space.SpatialSpace`)."""

    @property
    def world(self) -> SpatialWorld: ...

    @property
    def tuning(self) -> SpatialTuning: ...

    def clear(self, checker: SpatialChecker, starts: np.ndarray, ends: np.ndarray) -> NDArray[np.bool_]: ...

    def tcp(self, q: np.ndarray) -> np.ndarray: ...

    def backed_off(self, checker: SpatialChecker, q: np.ndarray) -> np.ndarray | None: ...

    @property
    def validation_steps(self) -> np.ndarray: ...


def plan_motion(
    space: MotionSpace,
    settings: PlannerSettings | None = None,
    *,
    goal: np.ndarray | None = None,
    termination: Termination | None = None,
    progress: Callable[[clew.Progress], None] | None = None,
) -> clew.PlanResult:
    """A collision-free motion in ``space.world`` from ``world.initial`` to ``goal`` (joints; default
    ``world.robot.goal``), as one transit segment; never raises for planning failures."""
    settings = settings or PlannerSettings()
    termination = termination or Termination(settings.time_limit)
    world = space.world
    run = _MotionRun(space, settings, termination, resolution_stop=space.tuning.search.resolution_proves)
    refusal = _refusal(world, world.goal if goal is None else goal)
    if goal is None and world.goal is None and world.goal_pose is not None:
        refusal = _pose_goals(space, settings)
    if isinstance(refusal, tuple):
        return run.finish(*refusal)
    try:
        goal_tree = run.rooted_at(refusal)
        for tree in (run.tree, goal_tree):  # out of a tight spot: the tcp backed off along its approach
            for root in [k for k in range(len(tree)) if tree[k].parent is None]:
                way = space.backed_off(run.checker, tree[root].joints)
                if way is not None:
                    add_branch(tree, root, way)
        return run.search_all(refusal, progress, goal_tree)
    except Exception as problem:  # noqa: BLE001 - a bug: reported as an outcome so a node keeps running
        return run.finish(Outcome.INTERNAL_ERROR, f"internal error: {problem!r}\n{traceback.format_exc(limit=4)}")


def connect(
    space: MotionSpace,
    ctx: PlanningContext,
    start: np.ndarray,
    goal: np.ndarray,
    *,
    mode: Mode,
    checker: SpatialChecker,
    landmarks: int,
    rng: np.random.Generator,
    goal_tree: LandmarkTree | None = None,
    start_ways: Sequence[np.ndarray] = (),
) -> np.ndarray | None:
    """A path (m, n) from ``start`` to ``goal`` (joints) in ``mode`` (``Mode.held``: the object
    carried), each piece checked by ``checker``: the motion-only search's two trees (rooted at ``start`` and at
    ``goal``, or ``goal_tree``'s root: a goal tree an earlier call grew, grown further in place) given at most
    ``landmarks`` EXPLORE steps and new landmarks, on ``ctx``'s settings, stop test and counters and on ``rng``;
    ``start_ways``: paths from ``start`` whose ends are landmarks of the start's tree from the outset; a
    landmark nearer the others than ``planner.resolution`` is dropped (no claim is made); the path is not
    shortcut (a plan's improvement does that). ``None`` when the trees did not meet within that budget, which
    proves nothing."""
    run = _MotionRun(
        space,
        ctx.settings,
        ctx.termination,
        start=start,
        mode=mode,
        checker=checker,
        rng=rng,
        counters=ctx.counters,
        landmarks=landmarks,
        shortcuts=False,
        resolution_stop=False,
    )
    for way in start_ways:
        add_branch(run.tree, 0, way)
    target = goal if goal_tree is None else goal_tree[0].joints
    result = run.search_all(target, None, goal_tree)
    if result.outcome is not Outcome.SUCCEEDED:
        return None
    return np.asarray(result.segments[0].waypoints, dtype=float)


def add_branch(tree: LandmarkTree, parent: int, way: np.ndarray) -> Landmark:
    """A configuration landmark (no object pose, no grasp) at the end of ``way``, a path from landmark
    ``parent`` of ``tree``, added to it."""
    return tree.add(
        parent=parent, joints=way[-1].copy(), object_pose=_NO_POSE, grasp=None, grasp_rel=None, transit=way,
        transfer=None,
    )  # fmt: skip


def _refusal(world: SpatialWorld, goal: Any) -> tuple[Outcome, str] | np.ndarray:
    """The goal configurations (m, n): ``goal`` (joints, or several rows: any of them), each with its values
    modulo 2 pi on the continuous joints within the limits (:func:`~clew_ros.spatial.turns.goal_turns`), or
    the outcome and reason of a query answered at once."""
    robot = world.robot
    if goal is None:
        return Outcome.INVALID_WORLD, "world.robot.goal: missing (a motion-only query needs the goal joints)"
    target = np.atleast_2d(np.asarray(goal, dtype=float))
    if target.ndim != 2 or target.shape[1:] != (robot.dof,) or not len(target) or not np.all(np.isfinite(target)):
        return Outcome.INVALID_WORLD, f"world.robot.goal: expected {robot.dof} finite joint values"
    if np.any(target < robot.lower) or np.any(target > robot.upper):
        return Outcome.INVALID_WORLD, "world.robot.goal: outside the joint limits"
    if not world.checker.valid(world.initial[None])[0]:
        return Outcome.START_IN_COLLISION, "the start configuration is not valid"
    target = target[world.checker.valid(target)]
    if not len(target):
        return Outcome.GOAL_IN_COLLISION, "the goal configuration is not valid"
    turns = np.concatenate([goal_turns(q, robot.lower, robot.upper, robot.continuous) for q in target])
    return distinct(turns, SAME_GOAL_RAD)  # an IK solution and another's turn may be one configuration


def _pose_goals(space: MotionSpace, settings: PlannerSettings) -> tuple[Outcome, str] | np.ndarray:
    """The goal configurations of ``world.robot.goal_pose``: the distinct valid solutions of the planner's
    own IK (the start configuration and :attr:`SpatialTuning.goal_pose_ik_seeds` random seeds drawn from
    ``planner.seed``'s own stream), at most :attr:`SpatialTuning.goal_pose_roots`, nearest the start first;
    or the outcome and reason when there is none."""
    world, tuning = space.world, space.tuning
    assert world.goal_pose is not None
    if not world.checker.valid(world.initial[None])[0]:
        return Outcome.START_IN_COLLISION, "the start configuration is not valid"
    kinematics = InverseKinematics(world.robot, IKSettings(seeds=tuning.goal_pose_ik_seeds))
    rng = np.random.default_rng([settings.seed, GOAL_POSE_STREAM])
    found = kinematics.solve(list(world.goal_pose), rng, seeds=world.initial[None])
    if not len(found):
        seeds = 1 + tuning.goal_pose_ik_seeds
        why = f"the inverse kinematics found no configuration that puts the tcp there ({seeds} seeds)"
        return Outcome.GOAL_OUT_OF_REACH, f"world.robot.goal_pose: {why}"
    valid = found[world.checker.valid(found)]
    if not len(valid):
        return (
            Outcome.GOAL_IN_COLLISION,
            f"world.robot.goal_pose: every configuration found that puts the tcp there ({len(found)}) is in collision",
        )
    travel = joint_gaps(valid, world.initial, world.robot.continuous).sum(axis=1)
    return _refusal(world, valid[np.argsort(travel, kind="stable")[: tuning.goal_pose_roots]])


class _MotionRun:
    """One motion-only run: its space, contexts, and two landmark trees (from the start, from the goal)."""

    def __init__(
        self,
        space: MotionSpace,
        settings: PlannerSettings,
        termination: Termination,
        *,
        start: np.ndarray | None = None,
        mode: Mode | None = None,
        checker: SpatialChecker | None = None,
        rng: np.random.Generator | None = None,
        counters: Counters | None = None,
        landmarks: int | None = None,
        shortcuts: bool = True,
        resolution_stop: bool = True,
    ) -> None:
        self.world = space.world
        self.settings = settings
        tuning = self.tuning = space.tuning
        self.termination = termination
        self.space = space
        rng = np.random.default_rng(settings.seed) if rng is None else rng
        self.ctx = PlanningContext(
            self.space,
            settings,
            rng,
            termination,
            counters=Counters() if counters is None else counters,
            search=tuning.search,
            many=tuning.many,
        )
        #: both trees' landmarks (count) after which the run stops
        self.landmarks = (tuning.motion_landmarks or math.inf) if landmarks is None else landmarks
        #: whether the path found is shortcut (else left to the plan's improvement)
        self.shortcuts = shortcuts
        #: whether a new landmark nearer the others than ``planner.resolution`` ends the run with
        #: NO_PATH_AT_RESOLUTION (the paper's criterion), else is dropped and the run goes on
        self.resolution_stop = resolution_stop
        # SEARCH's and EXPLORE's own sizes (SpatialTuning's motion block), on the run's generator and counters
        self.search_ctx = dataclasses.replace(
            self.ctx,
            settings=dataclasses.replace(
                settings,
                search_rounds=tuning.motion_search_rounds,
                population=tuning.motion_search_population,
                generations=tuning.motion_search_generations,
            ),
        )
        self.explore_ctx = dataclasses.replace(
            self.ctx,
            settings=dataclasses.replace(
                settings,
                population=tuning.motion_explore_population,
                generations=tuning.motion_explore_generations,
            ),
        )
        self.none = np.zeros(6)
        #: the Manhattan decoding's mode (the arm alone, or carrying the object) and its checker
        self.mode = Mode.resting(self.none[None]) if mode is None else mode
        self.checker = self.world.checker if checker is None else checker
        self.tree = LandmarkTree(self.world.initial if start is None else start, self.none)
        self.goal_tree: LandmarkTree | None = None

    def finish(self, outcome: Outcome, message: str, waypoints: np.ndarray | None = None) -> clew.PlanResult:
        stats: dict[str, Any] = {
            "time_s": round(self.termination.elapsed, 4),
            "landmarks": len(self.tree),
            "goal_landmarks": 0 if self.goal_tree is None else len(self.goal_tree),
            "collision_checks": self.ctx.counters.clearance_checks,
            "evaluations": self.ctx.counters.evaluations,
            "seed": self.settings.seed,
        }
        segments = [Segment("transit", None, list(waypoints))] if waypoints is not None else []
        return clew.PlanResult(outcome, message, segments, None, self.tree, stats)

    def search(self, q0: np.ndarray, targets: np.ndarray) -> tuple[np.ndarray, int]:
        """SEARCH_TRANSIT from ``q0`` to the nearest of ``targets`` (m, n) it reaches: its waypoints and the
        target's index (-1 when it reached none; the waypoints then end where it stopped)."""
        weight = self.tuning.motion_weight
        order = np.argsort(np.abs(targets - q0).sum(axis=1), kind="stable")[: self.tuning.motion_connect_targets]
        near = targets[order]

        def objective(q: np.ndarray, _poses: np.ndarray) -> np.ndarray:
            out: np.ndarray = weight * np.min(np.linalg.norm(q[:, None] - near[None], axis=2), axis=1)
            return out

        def error(q: np.ndarray) -> np.ndarray:
            nearest = near[np.argmin(np.linalg.norm(q[:, None] - near[None], axis=2), axis=1)]
            out: np.ndarray = weight * (q - nearest)
            return out

        job = SearchJob(q0, objective, error, 1e-9, self.mode, toward=near[0], straight=near)
        waypoints, _ = local_search(self.search_ctx, [job])[0]
        end = waypoints[-1]
        gaps = np.max(np.abs(near - end), axis=1)
        if np.min(gaps) <= 1e-9:
            return waypoints, int(order[int(np.argmin(gaps))])
        ranked = np.argsort(np.abs(near - end).sum(axis=1), kind="stable")
        for k in ranked:
            if self.termination():
                break
            if self.space.clear(self.checker, end[None], near[k][None])[0]:
                return np.vstack([waypoints, near[k][None]]), int(order[k])
        return waypoints, -1

    def rooted_at(self, target: np.ndarray) -> LandmarkTree:
        """A goal tree whose roots are the goal configurations ``target`` ((n,) or (k, n)): the search may
        reach any of them."""
        roots = np.atleast_2d(target)
        goal_tree = LandmarkTree(roots[0], self.none)
        for root in roots[1:]:
            goal_tree.add(
                parent=None, joints=root.copy(), object_pose=self.none, grasp=None, grasp_rel=None, transit=None,
                transfer=None,
            )  # fmt: skip
        return goal_tree

    def search_all(
        self,
        target: np.ndarray,
        progress: Callable[[clew.Progress], None] | None,
        goal_tree: LandmarkTree | None = None,
    ) -> clew.PlanResult:
        """SEARCH from the start to the goal; then, in turn from each end (a tree of landmarks rooted at
        the start, one at the goal), EXPLORE places a landmark and SEARCH goes from it to the other tree's
        landmarks, until one reaches them. ``goal_tree``: a goal tree grown by an earlier run (rooted at
        ``target``), grown further; its landmarks do not count against this run's."""
        best = math.inf
        tree = self.tree
        if goal_tree is None:
            goal_tree = self.rooted_at(target)
        self.goal_tree = goal_tree
        earlier = len(goal_tree) - 1
        trees = (tree, goal_tree)
        weight = self.tuning.motion_weight * math.sqrt(2.0 / self.world.robot.dof)
        side, landmark, steps = 0, tree[0], 0
        while True:
            reason = self.termination.reason()
            if reason is not None:
                stopped = (
                    "canceled" if reason is Outcome.CANCELED else f"time limit of {self.settings.time_limit} s reached"
                )
                return self.finish(
                    reason,
                    f"{stopped} after {len(tree) + len(goal_tree)} landmarks; no motion found; the nearest search "
                    f"ended {best:.4g} rad (largest joint difference) from the other tree",
                )
            other = trees[1 - side]
            found, reached = self.search(landmark.joints, other.joints())
            gap = 0.0 if reached >= 0 else float(np.min(np.max(np.abs(other.joints() - found[-1]), axis=1)))
            best = min(best, gap)
            if progress is not None:
                progress(clew.Progress(len(tree), best, self.termination.elapsed, tree))
            if reached >= 0:
                if side == 0:
                    return self.success(landmark.id, found, reached, target)
                return self.success(reached, found[::-1], landmark.id, target)
            self.keep_end(trees[side], landmark, found, other.joints())
            steps += 1
            if len(tree) + len(goal_tree) - earlier >= self.landmarks or (
                not self.resolution_stop and steps >= self.landmarks
            ):
                return self.finish(
                    Outcome.NO_PATH_AT_RESOLUTION,
                    f"no motion found after {len(tree) + len(goal_tree)} landmarks; best {best:.4g} rad from the "
                    "other tree",
                )
            if self.tuning.motion_bidirectional:
                side = 1 - side
            explored = _explore(self.explore_ctx, self.space, trees[side], weight, self.mode)
            if explored is None or (explored[2] < self.settings.resolution and not self.resolution_stop):
                landmark = trees[side][-1]  # no new place: SEARCH again from this tree's newest landmark
                continue
            parent, path, distance = explored
            landmark = add_branch(trees[side], parent, path)
            if distance < self.settings.resolution:
                return self.finish(
                    Outcome.NO_PATH_AT_RESOLUTION,
                    f"no path at resolution {self.settings.resolution}: the new landmark lies {distance:.4g} from "
                    f"the others after {len(tree) + len(goal_tree)} landmarks",
                )

    def keep_end(self, tree: LandmarkTree, landmark: Landmark, found: np.ndarray, others: np.ndarray) -> None:
        """A failed SEARCH's end becomes a landmark of ``tree`` (``landmark``'s child, reached by SEARCH's path)
        when it ended nearer the other tree's landmarks ``others`` than ``landmark`` is, by more than
        :attr:`SpatialTuning.motion_keep_gain_rad` (joint distance): the next SEARCH from the other tree aims at
        it, as RRT-Connect's trees grow towards each other."""
        if self.tuning.motion_keep_gain_rad < 0:
            return
        before = float(np.min(np.linalg.norm(others - landmark.joints, axis=1)))
        after = float(np.min(np.linalg.norm(others - found[-1], axis=1)))
        if after < before - self.tuning.motion_keep_gain_rad:
            add_branch(tree, landmark.id, found)

    def _branch(self, tree: LandmarkTree, landmark_id: int) -> np.ndarray:
        """The path from the landmark's root (``tree``'s first, or another goal configuration) to it, through
        the landmarks' transit paths."""
        lineage = tree.lineage(landmark_id)
        pieces = [lm.transit for lm in lineage[1:] if lm.transit is not None]
        return np.vstack([lineage[0].joints[None], *(p[1:] for p in pieces)])

    def shortcut(self, path: np.ndarray) -> tuple[np.ndarray, int]:
        """``path`` shortcut (:func:`~clew_ros.spatial.shortcut.shortcut_path`) in rounds of
        :attr:`SpatialTuning.motion_shortcut_round` tries, until a round takes none,
        :attr:`SpatialTuning.motion_shortcut_tries` are spent or the exact geometry has decided
        :attr:`SpatialTuning.shortcut_exact_rate` x ``planner.improve_time`` contacts; the path and the
        shortcuts taken."""
        rng = np.random.default_rng([self.settings.seed, IMPROVE_STREAM])
        clear = partial(self.space.clear, self.checker)
        left, shortcuts = self.tuning.motion_shortcut_tries, 0
        exact = self.checker.exact_checks + self.tuning.shortcut_exact_rate * self.settings.improve_time
        while left > 0 and self.checker.exact_checks < exact:
            tries = min(left, self.tuning.motion_shortcut_round)
            path, taken, _, stopped = shortcut_path(
                clear, path, tries=tries, rng=rng, stop=self.termination, steps=self.space.validation_steps
            )
            shortcuts += taken
            left -= tries
            if stopped or taken == 0 or len(path) <= 2:
                break
        return path, shortcuts

    def success(self, start_id: int, found: np.ndarray, goal_id: int, target: np.ndarray) -> clew.PlanResult:
        """The start tree's path to its landmark, SEARCH's path between the trees, the goal tree's path from
        its landmark back to the goal; shortcut."""
        assert self.goal_tree is not None
        back = self._branch(self.goal_tree, goal_id)[::-1]
        path = np.vstack([self._branch(self.tree, start_id), found[1:], back[1:]])
        path[-1] = self.goal_tree.lineage(goal_id)[0].joints  # the goal configuration reached, exactly
        first = float(np.abs(np.diff(path, axis=0)).sum())
        shortcuts = 0
        if self.shortcuts and self.settings.improve_time > 0:
            path, shortcuts = self.shortcut(path)
        travel = float(np.abs(np.diff(path, axis=0)).sum())
        result = self.finish(
            Outcome.SUCCEEDED,
            f"motion found with {len(self.tree)} + {len(self.goal_tree)} landmarks, joint travel {travel:.2f} rad "
            f"(first: {first:.2f} rad)",
            path,
        )
        result.stats.update(
            {
                "joint_travel_rad": round(travel, 6),
                "first_joint_travel_rad": round(first, 6),
                "transfers": 0,
                "shortcuts": shortcuts,
            }
        )
        return result


def _explore(
    ctx: PlanningContext, space: MotionSpace, tree: LandmarkTree, weight: float, mode: Mode
) -> tuple[int, np.ndarray, float] | None:
    """EXPLORE for transit: the landmark (a category gene) and Manhattan genes whose decoded end lies
    farthest from every landmark of ``tree``: the distance between the joints times ``weight`` and the tcp's
    positions times :attr:`SpatialTuning.motion_tcp_weight`, together (:func:`_features`); its parent, path
    and that distance."""
    n = space.dof
    k = ctx.settings.manhattan_order
    joints = tree.joints()
    landmarks = _features(space, joints, weight)

    def decode(population: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        index = np.clip(population[:, 0].astype(int), 0, len(joints) - 1)
        genes = population[:, 1:].reshape(-1, k, n)
        paths = ctx.manhattan(joints[index], genes, mode.with_poses(np.repeat(mode.poses, len(population), axis=0)))
        return index, paths.waypoints

    def evaluate(population: np.ndarray) -> np.ndarray:
        _, waypoints = decode(population)
        ctx.counters.evaluations += len(population)
        ends = _features(space, waypoints[:, -1], weight)
        nearest: np.ndarray = np.min(np.linalg.norm(ends[:, None] - landmarks[None], axis=2), axis=1)
        return -nearest

    size = ctx.settings.population
    initial = np.empty((size, 1 + k * n))
    initial[:, 0] = ctx.rng.integers(0, len(joints), size=size)
    initial[:, 1:] = ctx.initial_genes(size).reshape(size, -1)
    genetic = ctx.settings.genetic
    result = minimize(evaluate, initial, ctx.rng, genetic, categories=len(joints), should_stop=ctx.termination)
    if not np.isfinite(result.fitness):
        return None
    index, waypoints = decode(result.genes[None])
    return int(index[0]), waypoints[0], -result.fitness


def _features(space: MotionSpace, joints: np.ndarray, weight: float) -> np.ndarray:
    """Points (B, n + c + 3) whose distances are EXPLORE's landmark distances: the joints (B, n; each of the c
    continuous ones as a point on the unit circle) times ``weight`` (m/rad), then the tcp's position (m)
    times :attr:`SpatialTuning.motion_tcp_weight`."""
    scale = space.tuning.motion_tcp_weight
    tcp = space.tcp(joints)[:, :3, 3] if scale > 0 else np.zeros((len(joints), 3))
    turned = joint_features(joints, space.world.robot.continuous)  # continuous joints modulo 2 pi
    out: np.ndarray = np.concatenate([weight * turned, scale * tcp], axis=1)
    return out
