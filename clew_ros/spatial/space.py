"""A spatial world as the Ariadne's Clew Algorithm's space (:class:`clew_ros.core.space.Space`).

The generic algorithm (EXPLORE, SEARCH's do-while loop, the genetic algorithm, the landmark tree) runs
unchanged; this module gives it the spatial world (docs/spatial.md, "Planning"):

- *poses*: an object pose is 6 numbers ``[x, y, z, roll, pitch, yaw]`` (section 1b); a held pose
  ``grasp_rel`` is the object's pose in the tcp's frame, always the *nominal* one of the grasp (the inverse
  of ``world.object.grasps[g]``): a transit succeeds only when the tcp holds the grasp within
  :attr:`SpatialTuning.hold_tolerance_m` / ``_rad``, so the object rides on the grasp as the plan says.
- *Manhattan decoding*: each move bounced (:func:`clew_ros.core.manhattan.bounce`) into its joint's free
  interval from :meth:`SpatialChecker.free_intervals` (one compiled call per joint move and per distinct
  mode in the batch: a resting pose in transit, a grasp in transfer, each with its own checker, cached).
- *stable ends*: a decoded transfer ends with the object **set down** (:meth:`SpatialSpace.settle`): the
  face most nearly down is rested on the highest support under the object's centre (within
  :attr:`SpatialTuning.settle_drop_m` below it), the configuration holding it there found by inverse
  kinematics seeded at the decoded end, and the straight move to it checked at the validator's
  resolution. An end that cannot be set down counts as no move at all (the path stays at its start,
  where the object rests): the placement search is inside the optimisation, as the paper suggests, and
  every landmark's object rests on a support.
- *SEARCH*: SEARCH_TRANSIT minimises the tcp's pose error to the grasp; SEARCH_TRANSFER the object's
  distance to the goal placement (:meth:`SpatialSpace.goal_distance`). Both get configurations meeting
  their target from inverse kinematics (holds of the grasp; configurations holding the object at the goal)
  as ``toward`` (the greedy Manhattan probe) and ``straight`` (straight joint-space moves, checked at the
  validator's 0.002 rad) targets, and try those straight moves again from where the search ended.
- *improvement*: first the pruning that needs no checking (:func:`clew_ros.core.improve.pruned_path`: repeats,
  loops and collinear waypoints; :func:`clew_ros.core.improve.joined_regrasps`: a transfer put down and taken
  again by the same grasp without the arm moving made one), then shortcuts between waypoints of a segment, each
  straight move checked at 0.002 rad, taken only when shorter (:func:`clew_ros.core.improve.shortcut_path`).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from functools import partial
from typing import Any

import numpy as np
from numpy.typing import NDArray

from clew_ros.core import clew
from clew_ros.core.improve import WorkBudget, WorkCosts, joined_regrasps, joint_travel, pruned_path, shortcut_path
from clew_ros.core.manhattan import Counters, ManhattanPaths, bounce
from clew_ros.core.search import SearchJob, local_search, object_at, own_generator
from clew_ros.core.settings import Outcome, PlannerSettings, Termination
from clew_ros.core.space import Improvement, PathResult, PlanningContext, TransitRequest
from clew_ros.core.tree import Landmark, LandmarkTree, Segment
from clew_ros.spatial.checker import Held, SpatialChecker
from clew_ros.spatial.enclosure import enclosure_refusal
from clew_ros.spatial.inverse import IKSettings, InverseKinematics, pose_rows
from clew_ros.spatial.lift import drag_free, lifted_segments
from clew_ros.spatial.motion_plan import add_branch, connect, plan_motion
from clew_ros.spatial.placements import Support, face_down, object_extent, placement_pose, resting_on
from clew_ros.spatial.plan import make_plan, path_problems
from clew_ros.spatial.regrasps import SpatialAims
from clew_ros.spatial.scene import make_obstacle
from clew_ros.spatial.tier import object_touches
from clew_ros.spatial.transforms import rpy_matrix
from clew_ros.spatial.tuning import SpatialTuning
from clew_ros.spatial.turns import joint_features, nearest_turns, split_turns, turnable
from clew_ros.spatial.validate import ValidationSettings, validation_samples
from clew_ros.spatial.world import SpatialWorld

__all__ = [
    "SpatialSpace",
    "SpatialTuning",
    "matrices",
    "plan",
    "poses",
    "rotation_angle",
]

Array = NDArray[np.float64]

#: The holding configurations' inverse kinematics draws from a generator seeded with (planner.seed, this,
#: the request): the same request gets the same sample, and the run's stream is left as it was.
HOLD_STREAM = 21
#: The goal configurations' inverse kinematics: its own stream too.
GOAL_STREAM = 22
#: A failed SEARCH_TRANSFER's two trees (:meth:`SpatialSpace.transfer_trees`): their own stream too.
TRANSFER_TREES_STREAM = 23
#: The improvement's shortcuts draw from the run's improvement generator (core's IMPROVE_STREAM).

#: a level face at a height: the pose error's z and its rotation's x and y (the object's x, y and yaw free)
_LEVEL_ROWS = pose_rows(("z", "rx", "ry"))

#: a position: the pose error's x, y and z (the orientation free)
_POSITION_ROWS = pose_rows(("x", "y", "z"))


def matrices(poses: Array) -> Array:
    """4x4 transforms (B, 4, 4) of poses (B, 6) ``[x, y, z, roll, pitch, yaw]`` (vectorised
    :func:`~clew_ros.spatial.transforms.pose_matrix`)."""
    poses = np.asarray(poses, dtype=float).reshape(-1, 6)
    cr, sr = np.cos(poses[:, 3]), np.sin(poses[:, 3])
    cp, sp = np.cos(poses[:, 4]), np.sin(poses[:, 4])
    cy, sy = np.cos(poses[:, 5]), np.sin(poses[:, 5])
    out = np.zeros((len(poses), 4, 4))
    out[:, 0, 0], out[:, 0, 1], out[:, 0, 2] = cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr
    out[:, 1, 0], out[:, 1, 1], out[:, 1, 2] = sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr
    out[:, 2, 0], out[:, 2, 1], out[:, 2, 2] = -sp, cp * sr, cp * cr
    out[:, :3, 3] = poses[:, :3]
    out[:, 3, 3] = 1.0
    return out


def poses(transforms: Array) -> Array:
    """Poses (B, 6) of 4x4 transforms (B, 4, 4) (vectorised :func:`~clew_ros.spatial.transforms.matrix_pose`)."""
    r = np.asarray(transforms, dtype=float).reshape(-1, 4, 4)
    pitch = np.arcsin(np.clip(-r[:, 2, 0], -1.0, 1.0))
    flat = np.abs(np.cos(pitch)) < 1e-9
    roll = np.where(flat, 0.0, np.arctan2(r[:, 2, 1], r[:, 2, 2]))
    yaw = np.where(flat, np.arctan2(-r[:, 0, 1], r[:, 1, 1]), np.arctan2(r[:, 1, 0], r[:, 0, 0]))
    return np.column_stack([r[:, 0, 3], r[:, 1, 3], r[:, 2, 3], roll, pitch, yaw])


def _rotation_vectors(rotations: Array) -> Array:
    """Rotation vectors (B, 3) (axis times angle, rad) of rotations (B, 3, 3)."""
    vec = 0.5 * np.stack(
        [
            rotations[:, 2, 1] - rotations[:, 1, 2],
            rotations[:, 0, 2] - rotations[:, 2, 0],
            rotations[:, 1, 0] - rotations[:, 0, 1],
        ],
        axis=1,
    )
    sine = np.linalg.norm(vec, axis=1)
    cosine = np.clip((np.trace(rotations, axis1=1, axis2=2) - 1.0) / 2.0, -1.0, 1.0)
    angle = np.arctan2(sine, cosine)
    scale = np.where(sine > 1e-12, angle / np.maximum(sine, 1e-300), 1.0)
    out: Array = vec * scale[:, None]
    return out


def rotation_angle(rotations: Array) -> Array:
    """The angle (rad) of each rotation (B, 3, 3)."""
    cosine = np.clip((np.trace(rotations, axis1=1, axis2=2) - 1.0) / 2.0, -1.0, 1.0)
    return np.asarray(np.arccos(cosine))


def _inverse(transform: Array) -> Array:
    out = np.eye(4)
    out[:3, :3] = transform[:3, :3].T
    out[:3, 3] = -transform[:3, :3].T @ transform[:3, 3]
    return out


def _pose_errors(transforms: Array, target: Array, weight: float) -> Array:
    """(B, 6): position error (m) and ``weight`` x rotation vector (m) of transforms (B, 4, 4) to ``target``."""
    dp = transforms[:, :3, 3] - target[:3, 3]
    rv = _rotation_vectors(np.einsum("ji,bjk->bik", target[:3, :3], transforms[:, :3, :3]))
    return np.concatenate([dp, weight * rv], axis=1)


def straight_samples_clear(
    checker: SpatialChecker,
    starts: Array,
    ends: Array,
    *,
    coarse_every: int,
    settings: ValidationSettings,
    refine: int = 2,
) -> NDArray[np.bool_]:
    """Whether each straight joint-space move ``starts[i] -> ends[i]`` is valid at every configuration the
    validator checks (steps of at most 0.002 rad per revolute joint, 0.001 m per prismatic one): first at
    every ``coarse_every``-th of those samples (cheap refusals), then at all of them; where two neighbouring
    samples lie near a contact (the sphere model does not clear both), ``refine - 1`` more between them (the
    middle), so
    that a move the validator accepts does not graze between its samples either (another planner's samples,
    or a part of the move, fall elsewhere)."""
    robot = checker.robot
    steps = np.where(robot.prismatic, settings.step_m, settings.step_rad)
    samples = [validation_samples(a, b, steps) for a, b in zip(starts, ends, strict=True)]
    clear = np.ones(len(samples), dtype=bool)
    near: list[NDArray[np.bool_]] = [np.zeros(0, dtype=bool)] * len(samples)
    for stride in (coarse_every, 1):
        pick = np.flatnonzero(clear)
        if not len(pick):
            break
        parts = [samples[i][::stride] if stride > 1 else samples[i] for i in pick]
        if stride > 1:
            parts = [np.vstack([p, samples[i][-1:]]) for p, i in zip(parts, pick, strict=True)]
        owners = np.repeat(pick, [len(p) for p in parts])
        valid, spheres = checker.valid_and_on_spheres(np.vstack(parts), groups=owners)
        bounds = np.cumsum([0, *(len(p) for p in parts)])
        for a, i in enumerate(pick):
            clear[i] = bool(valid[bounds[a] : bounds[a + 1]].all())
            near[i] = ~spheres[bounds[a] : bounds[a + 1]]
    pick = np.flatnonzero(clear)
    if refine > 1 and checker.exact and len(pick):
        # neighbouring samples either of which the spheres do not clear: refine - 1 more between them
        firsts = [np.flatnonzero(near[i][:-1] | near[i][1:]) for i in pick]
        owner = np.repeat(pick, [len(f) for f in firsts])
        if len(owner):
            lows = np.vstack([samples[i][f] for i, f in zip(pick, firsts, strict=True)])
            highs = np.vstack([samples[i][f + 1] for i, f in zip(pick, firsts, strict=True)])
            share = (np.arange(1, refine) / refine)[None, :, None]
            between = (lows[:, None, :] + share * (highs - lows)[:, None, :]).reshape(-1, robot.dof)
            valid, _ = checker.valid_and_on_spheres(between, groups=np.repeat(owner, refine - 1))
            fine = valid.reshape(len(lows), refine - 1).all(axis=1)
            clear[np.unique(owner[~fine])] = False
    return clear


def _footprint_inside(world: SpatialWorld, support: Support, face: str, pose: Array) -> bool:
    assert world.object is not None
    thing = world.object.shape
    if thing.shape == "cylinder":
        return bool(support.contains(pose[None, :2, 3], inset=thing.size[1])[0])
    corners = thing.face_points(face) @ pose[:3, :3].T + pose[:3, 3]
    return bool(support.contains(corners[:, :2]).all())


class SpatialSpace:
    """A spatial world (contract section 1b) with an object, as the ACA's space; motion-only worlds use
    it for their transit checks (their mode's pose is ignored)."""

    def __init__(self, world: SpatialWorld, tuning: SpatialTuning | None = None) -> None:
        self.world = world
        self.tuning = tuning or SpatialTuning()
        self.validation = ValidationSettings()
        self._ik: dict[int, InverseKinematics] = {}
        self._settle_ik = InverseKinematics(
            world.robot, IKSettings(seeds=0, max_iterations=self.tuning.settle_iterations)
        )
        self._transit_checkers: dict[bytes, SpatialChecker] = {}
        self._transfer_checkers: dict[bytes, SpatialChecker] = {}
        #: the goal trees of the failed SEARCH_TRANSFERs (:meth:`transfer_trees`), by held pose and goal: each
        #: grows over the run, as the ACA's landmarks do
        self._goal_trees: dict[bytes, LandmarkTree] = {}
        self._way_out_lengths: dict[bytes, float] = {}  # (grasp, goal, goal pose) -> m (_way_out_m)
        thing = world.object
        self._grasps = matrices(thing.grasps) if thing is not None else np.zeros((0, 4, 4))
        #: the object's size scale (m): its half diagonal, the radius of the orientation's chord
        self.object_radius = float(np.linalg.norm(thing.shape.size) / 2) if thing is not None else 0.1
        robot = world.robot
        origin_steps = np.linalg.norm(robot.origins[1:, :3, 3], axis=1).sum()
        travel = float(np.sum(np.maximum(np.abs(robot.lower), np.abs(robot.upper))[robot.prismatic]))
        #: an upper bound (m) of the tcp's distance from the first joint's origin, whatever the joints
        self._reach = float(origin_steps + np.linalg.norm(robot.tcp[:3, 3]) + travel)
        first = robot.base @ robot.origins[0]
        self._shoulder = first[:3, 3].copy()
        #: whether decoded transfers end where their moves take them, the object in the air, unsettled
        #: (inside SEARCH_TRANSFER: :attr:`SpatialTuning.search_in_air`); else each sets it down or stays at
        #: its start
        self._in_air = False

    # -- the protocol's properties --------------------------------------------------------------------
    @property
    def dof(self) -> int:
        return self.world.robot.dof

    @property
    def reach(self) -> float:
        return self._reach

    @property
    def grasp_count(self) -> int:
        return len(self._grasps)

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

    # -- checkers -------------------------------------------------------------------------------------
    def transit_checker(self, object_pose: Array) -> SpatialChecker:
        """The checker with the object resting at ``object_pose`` (6 numbers); the world's own without one."""
        thing = self.world.object
        if thing is None:
            return self.world.checker
        key = _key(object_pose)
        checker = self._transit_checkers.get(key)
        if checker is None:
            resting = make_obstacle(
                "object", thing.shape.shape, thing.shape.size, matrices(object_pose)[0], "world.object"
            )
            world = self.world
            checker = SpatialChecker(
                world.robot, world.spheres, world.obstacles, world.bounds, resting_object=resting,
                exact=world.checker.exact,
            )  # fmt: skip
            self._transit_checkers[key] = checker
        return checker

    def transfer_checker(self, grasp_rel: Array) -> SpatialChecker:
        """The checker with the object held as ``grasp_rel`` (its pose in the tcp's frame, 6 numbers)."""
        thing = self.world.object
        assert thing is not None  # transfers carry the object
        key = _key(grasp_rel)
        checker = self._transfer_checkers.get(key)
        if checker is None:
            world = self.world
            held = Held(
                thing.shape,
                _inverse(matrices(grasp_rel)[0]),
                world.supports,
                world.tolerances["placement_tolerance"],
            )
            checker = SpatialChecker(
                world.robot, world.spheres, world.obstacles, world.bounds, held=held, exact=world.checker.exact,
                band_intervals=self.tuning.transfer_band_intervals,
            )  # fmt: skip
            self._transfer_checkers[key] = checker
        return checker

    @property
    def validation_steps(self) -> Array:
        """The validator's step per planned joint (rad, m for a prismatic one)."""
        robot = self.world.robot
        return np.where(robot.prismatic, self.validation.step_m, self.validation.step_rad)

    @property
    def exact_checks(self) -> int:
        """Contacts the exact geometry has decided for this space's checkers so far (deterministic work)."""
        checkers = [self.world.checker, *self._transit_checkers.values(), *self._transfer_checkers.values()]
        return sum(c.exact_checks for c in checkers)

    def checker_of(self, mode: dict[str, np.ndarray]) -> SpatialChecker:
        """The checker of a mode ``{"object_poses": (1, 6)}`` or ``{"grasp_rel": (1, 6)}``."""
        if mode.get("grasp_rel") is not None:
            return self.transfer_checker(mode["grasp_rel"].reshape(-1)[:6])
        return self.transit_checker(mode["object_poses"].reshape(-1)[:6])

    def ik(self, seeds: int) -> InverseKinematics:
        """The tcp's inverse kinematics with ``seeds`` random starts per target."""
        if seeds not in self._ik:
            self._ik[seeds] = InverseKinematics(self.world.robot, IKSettings(seeds=seeds))
        return self._ik[seeds]

    def tcp(self, q: Array) -> Array:
        """The tcp's 4x4 poses (B, 4, 4) at configurations ``q`` (B, n)."""
        return self._settle_ik.tcp_poses(np.asarray(q, dtype=float).reshape(-1, self.dof))

    def clear(self, checker: SpatialChecker, starts: Array, ends: Array) -> NDArray[np.bool_]:
        """Whether each straight move is valid at the validator's resolution."""
        return straight_samples_clear(
            checker, starts, ends, coarse_every=self.tuning.coarse_every, settings=self.validation
        )

    # -- Manhattan paths ------------------------------------------------------------------------------
    def _groups(self, rows: Array, transfer: bool) -> list[tuple[SpatialChecker, np.ndarray]]:
        """The batch's rows grouped by their mode's pose, each with its checker (first-seen order)."""
        keys = np.round(rows, 9)
        _, first, inverse = np.unique(keys, axis=0, return_index=True, return_inverse=True)
        inverse = inverse.reshape(-1)
        out = []
        for u in np.argsort(first):
            idx = np.flatnonzero(inverse == u)
            pose = rows[idx[0]]
            out.append((self.transfer_checker(pose) if transfer else self.transit_checker(pose), idx))
        return out

    def manhattan(
        self,
        q0: np.ndarray,
        genes: np.ndarray,
        *,
        margin_m: float,
        counters: Counters | None,
        should_stop: Callable[[], bool] | None,
        threads: int,
        object_poses: np.ndarray | None = None,
        grasp_rel: np.ndarray | None = None,
    ) -> ManhattanPaths:
        """Genes (B, k, n) decoded from ``q0`` (B, n): each move bounced into its joint's free interval; a
        transfer then sets the object down (:meth:`settle`). The waypoints are (B, k n + 2, n): the moves,
        then the settled end (a repeat of the last move's in transit)."""
        genes = np.asarray(genes, dtype=float)
        count, order, n = genes.shape
        q = np.array(q0, dtype=float).reshape(count, n)
        transfer = grasp_rel is not None
        modes = np.asarray(grasp_rel if transfer else object_poses, dtype=float).reshape(-1, 6)
        modes = np.broadcast_to(modes, (count, 6))
        groups = self._groups(modes, transfer)
        way = np.empty((count, order * n + 2, n))
        way[:, 0] = q
        for step in range(order * n):
            r, j = divmod(step, n)
            if j == 0 and r > 0 and should_stop is not None and should_stop():
                way[:, step + 1 :] = q[:, None]
                break
            for checker, idx in groups:
                move = genes[idx, r, j]
                # searched only as far as the move and its fold reach: the same fold as over the whole interval,
                # unless a path folds twice (then it folds inside the reach, as free)
                lo, hi, ok = checker.free_intervals(
                    q[idx], j, self.tuning.intervals, move=move + np.copysign(1e-9, move)
                )
                moved = bounce(q[idx, j] + move, lo, hi)
                q[idx, j] = np.where(ok, moved, q[idx, j])
            if counters is not None:
                counters.clearance_checks += count
            way[:, step + 1] = q
        way[:, -1] = way[:, -2]
        if transfer:
            for checker, idx in groups:
                if self._in_air:
                    break  # SEARCH_TRANSFER's ends stay in the air: search_transfer sets its last one down
                settled, ok = self.settle(checker, modes[idx[0]], way[idx, -2])
                way[idx[ok], -1] = settled[ok]
                way[idx[~ok]] = way[idx[~ok], :1]  # no stable end: the path stays where the object rests
            held = self.held_object_poses(way[:, -1], modes)
            return ManhattanPaths(way, held)
        return ManhattanPaths(way, np.array(modes, dtype=float))

    def rest_below(self, object_pose: Array) -> Array | None:
        """The stable placement (4x4) under a carried object at ``object_pose`` (4x4): its face most nearly
        down, on the highest support under its centre at most :attr:`SpatialTuning.settle_drop_m` below
        that face, at the same x, y and yaw, its footprint inside the support's top; ``None`` if none."""
        thing = self.world.object
        assert thing is not None
        center = object_pose[:3, 3]
        face, yaw = face_down(thing.shape, object_pose[:3, :3])
        bottom = float(center[2]) - thing.shape.height(face)
        tuning = self.tuning
        under = [
            s
            for s in self.world.supports
            if -tuning.settle_rise_m <= bottom - s.top <= tuning.settle_drop_m and s.contains(center[None, :2])[0]
        ]
        for support in sorted(under, key=lambda s: -s.top):
            placed = placement_pose(thing.shape, support, face, x=float(center[0]), y=float(center[1]), yaw=yaw)
            if _footprint_inside(self.world, support, face, placed):
                return placed
        return None

    def settle(self, checker: SpatialChecker, grasp_rel: Array, ends: Array) -> tuple[Array, NDArray[np.bool_]]:
        """Configurations (B, n) near ``ends`` (B, n) that set the object held as ``grasp_rel`` down on a
        support (:meth:`rest_below`), and whether each was found with a clear straight move to it."""
        rel = matrices(grasp_rel)[0]
        back = _inverse(rel)
        held = self.tcp(ends) @ rel
        out = ends.copy()
        ok = np.zeros(len(ends), dtype=bool)
        targets, rows = [], []
        for b, pose in enumerate(held):
            placed = self.rest_below(pose)
            if placed is not None:
                targets.append(placed @ back)
                rows.append(b)
        if not rows:
            return out, ok
        found = self._settle_ik.solve_many(
            targets, np.random.default_rng(0), seeds=[ends[b][None] for b in rows]
        )  # no random seeds: the generator is never drawn from
        reach = self.tuning.settle_max_rad
        moves = [
            (b, solutions[0])
            for b, solutions in zip(rows, found, strict=True)
            if len(solutions) and np.max(np.abs(solutions[0] - ends[b])) <= reach
        ]
        if self.tuning.level_settle:
            missed = [k for k, b in enumerate(rows) if b not in {m for m, _ in moves}]
            moves += self._level_settle(rel, ends, [rows[k] for k in missed], [targets[k] for k in missed])
            moves.sort(key=lambda move: move[0])
        if not moves:
            return out, ok
        index = np.array([b for b, _ in moves])
        goals = np.array([s for _, s in moves])
        clear = self.clear(checker, ends[index], goals)
        out[index[clear]] = goals[clear]
        ok[index[clear]] = True
        return out, ok

    def _level_settle(self, rel: Array, ends: Array, rows: list[int], targets: list[Array]) -> list[tuple[int, Array]]:
        """Where the whole placement's pose is out of reach (an arm of 4-5 joints, joint limits): the object
        set down level at the support's height, its x, y and yaw left free (:meth:`InverseKinematics.solve_rows`
        seeded at the decoded end), kept where it then rests inside a support's top within
        :attr:`SpatialTuning.settle_max_rad` of that end. ``(row, configuration)`` pairs."""
        if not rows:
            return []
        object_targets = np.array([target @ rel for target in targets])
        reached, ok = self._settle_ik.solve_rows(object_targets, ends[rows], _LEVEL_ROWS, frame=rel)
        thing = self.world.object
        assert thing is not None
        tolerance = self.world.tolerances["placement_tolerance"]
        out = []
        for k in np.flatnonzero(ok):
            b = rows[int(k)]
            if np.max(np.abs(reached[k] - ends[b])) > self.tuning.settle_max_rad:
                continue
            pose = self.tcp(reached[k][None])[0] @ rel
            found = resting_on(thing.shape, pose, self.world.supports, tolerance)
            if found is not None and _footprint_inside(self.world, found[0], found[1], pose):
                out.append((b, reached[k]))
        return out

    def single_moves(
        self, q: np.ndarray, moves: np.ndarray, *, margin_m: float, counters: Counters | None, **mode: np.ndarray
    ) -> np.ndarray:
        checker = self.checker_of(mode)
        current = np.array(q, dtype=float)
        out = [current.copy()]
        for j in np.flatnonzero(np.abs(moves) > 0.0):
            lo, hi, ok = checker.free_intervals(current[None], int(j), reach=abs(float(moves[j])) + 1e-9)
            if counters is not None:
                counters.clearance_checks += 1
            if not ok[0]:
                break
            current[j] = float(np.clip(current[j] + moves[j], lo[0], hi[0]))
            out.append(current.copy())
        return np.array(out)

    def held_object_poses(self, q: np.ndarray, grasp_rel: np.ndarray) -> np.ndarray:
        q = np.asarray(q, dtype=float).reshape(-1, self.dof)
        rel = matrices(np.broadcast_to(np.asarray(grasp_rel, dtype=float).reshape(-1, 6), (len(q), 6)))
        return poses(self.tcp(q) @ rel)

    # -- distances ------------------------------------------------------------------------------------
    def landmark_features(self, joints: np.ndarray, object_poses: np.ndarray, joint_weight: float) -> np.ndarray:
        """Object position (m); orientation as its rotation matrix times the object's radius over sqrt 2
        (distances are then chords, m, of a circle of that radius: the face down and the yaw both count);
        joints times ``joint_weight`` (m/rad) times ``sqrt(2 / n)``, as the planar space weighs them (a
        continuous joint on the unit circle: :func:`~clew_ros.spatial.turns.joint_features`)."""
        rot = matrices(object_poses)[:, :3, :3].reshape(len(object_poses), 9)
        weight = joint_weight * float(np.sqrt(2.0 / joints.shape[1]))
        turned = joint_features(joints, self.world.robot.continuous)  # continuous joints modulo 2 pi
        return np.concatenate(
            [np.asarray(object_poses)[:, :3], self.object_radius / math.sqrt(2.0) * rot, weight * turned], axis=1
        )

    def goal_parts(self, object_poses: Array, goal: Array) -> tuple[Array, Array, Array]:
        """Per pose: the centre's distance to the goal's (m), the angle (rad) between the world's up seen
        from the object and from the goal (0: the same face down), and the yaw error beyond
        ``world.goal_angle_tolerance`` (rad)."""
        mats = matrices(object_poses)
        target = matrices(goal)[0]
        distance = np.linalg.norm(mats[:, :3, 3] - target[:3, 3], axis=1)
        up_here = mats[:, 2, :3]  # world z in the object's frame: row 2 of R
        up_goal = target[2, :3]
        tilt = np.arccos(np.clip(up_here @ up_goal, -1.0, 1.0))
        relative = mats[:, :3, :3] @ target[:3, :3].T  # about world z when the faces agree
        yaw = np.abs(np.arctan2(relative[:, 1, 0], relative[:, 0, 0]))
        excess = np.maximum(yaw - self.world.tolerances["goal_angle_tolerance"], 0.0)
        return distance, tilt, excess

    def goal_distance(self, object_poses: np.ndarray, goal: np.ndarray) -> np.ndarray:
        """The centre's distance (m) plus ``SpatialTuning.angle_weight_m`` x (the face's tilt + the yaw beyond
        its tolerance): 0 at the goal."""
        distance, tilt, excess = self.goal_parts(object_poses, goal)
        out: np.ndarray = distance + self.tuning.angle_weight_m * (tilt + excess)
        return out

    def at_goal(self, object_pose: Array, goal: Array) -> bool:
        """Whether the object rests at ``object_pose`` within the goal's tolerances (section 1b)."""
        distance, tilt, excess = self.goal_parts(object_pose[None], goal)
        tol = self.world.tolerances
        return bool(
            distance[0] <= tol["goal_tolerance"]
            and tilt[0] <= self.tuning.face_tolerance_rad
            and excess[0] <= 0.0
            and self.rests(object_pose)
        )

    def rests(self, object_pose: Array) -> bool:
        """Whether the object at ``object_pose`` (6 numbers) is at a stable placement."""
        thing = self.world.object
        assert thing is not None
        tolerance = self.world.tolerances["placement_tolerance"]
        return resting_on(thing.shape, matrices(object_pose)[0], self.world.supports, tolerance) is not None

    # -- SEARCH ---------------------------------------------------------------------------------------
    def holds(self, ctx: PlanningContext, q0: Array, object_pose: Array, grasp: int) -> Array:
        """Configurations (m, n) holding ``grasp`` with the object at ``object_pose``, valid in transit and
        in transfer, nearest ``q0`` first (joint travel)."""
        target = matrices(object_pose)[0] @ self._grasps[grasp]
        rng = own_generator(ctx, HOLD_STREAM, q0, np.r_[object_pose, grasp])
        found = self.ik(ctx.hold_samples).solve(target, rng, seeds=q0[None], checker=self.transit_checker(object_pose))
        if len(found):
            found = self.nearest_turns(q0, found[self.transfer_checker(self.grasp_rel(grasp)).valid(found)])
        return found[np.argsort(np.abs(found - q0).sum(axis=1), kind="stable")]

    def grasp_rel(self, grasp: int) -> Array:
        """The object's nominal pose in the tcp's frame while it holds ``grasp``."""
        rel: Array = poses(_inverse(self._grasps[grasp])[None])[0]
        return rel

    def search_transits(self, ctx: PlanningContext, requests: list[TransitRequest]) -> list[PathResult]:
        results: list[PathResult | None] = []
        jobs: list[SearchJob] = []
        slots: list[int] = []
        targets: list[Array] = []
        weight = self.tuning.angle_weight_m
        for start, resting, grasp, _approach in requests:
            q0 = np.asarray(start, dtype=float)
            object_pose = np.asarray(resting, dtype=float)
            holds = self.holds(ctx, q0, object_pose, grasp)
            if not len(holds):
                results.append(PathResult(False, q0[None], math.inf))
                continue
            target = matrices(object_pose)[0] @ self._grasps[grasp]

            def error(q: Array, target: Array = target) -> Array:
                return _pose_errors(self.tcp(q), target, weight)

            def objective(q: Array, _poses: Array, error: Callable[[Array], Array] = error) -> Array:
                e = error(q)
                out: Array = np.linalg.norm(e[:, :3], axis=1) + np.linalg.norm(e[:, 3:], axis=1)
                return out

            slots.append(len(results))
            results.append(None)
            targets.append(holds)
            jobs.append(
                SearchJob(
                    q0,
                    objective,
                    error,
                    accept=1e-7,
                    mode={"object_poses": object_pose[None]},
                    toward=holds[0],
                    straight=holds[: self.tuning.straight_probes],
                )
            )
        if jobs:
            answers = local_search(ctx, jobs)
            for slot, job, holds, (searched, _value) in zip(slots, jobs, targets, answers, strict=True):
                waypoints = self._finish(ctx, job, searched, holds)
                grasp = requests[slot][2]
                e = job.error(waypoints[-1:])[0]
                success = bool(
                    np.linalg.norm(e[:3]) <= self.tuning.hold_tolerance_m
                    and np.linalg.norm(e[3:]) / weight <= self.tuning.hold_tolerance_rad
                )
                distance = float(np.linalg.norm(e))
                results[slot] = PathResult(
                    success, waypoints, distance, grasp_rel=self.grasp_rel(grasp) if success else None
                )
        return [r for r in results if r is not None]

    def _finish(self, ctx: PlanningContext, job: SearchJob, waypoints: Array, targets: Array) -> Array:
        """A search's waypoints, ended by straight moves (:meth:`way`) to the nearest target they reach from its
        end (none: as they were)."""
        end = waypoints[-1]
        if ctx.termination() or not len(targets):
            return waypoints
        if np.min(np.max(np.abs(targets - end), axis=1)) < 1e-9:
            return waypoints
        order = np.argsort(np.abs(targets - end).sum(axis=1), kind="stable")
        found = self.way(job.mode, end, targets[order])
        return waypoints if found is None else np.vstack([waypoints, found])

    def search_transfer(
        self, ctx: PlanningContext, q0: np.ndarray, grasp_rel: np.ndarray, goal: np.ndarray
    ) -> PathResult:
        q0 = np.asarray(q0, dtype=float)
        rel = np.asarray(grasp_rel, dtype=float)
        goal = np.asarray(goal, dtype=float)
        found = self.goal_configurations(ctx, q0, rel, goal)
        if not len(found) and self.tuning.hopeless_transfers:
            start = self.held_object_poses(q0[None], rel)
            return PathResult(False, q0[None], float(self.goal_distance(start, goal)[0]), object_pose=start[0])
        weight = self.tuning.angle_weight_m
        target = matrices(goal)[0]

        def error(q: Array) -> Array:
            return _pose_errors(self.tcp(q) @ matrices(rel)[0], target, weight)

        def objective(_q: Array, object_poses: Array) -> Array:
            return self.goal_distance(object_poses, goal)

        job = SearchJob(
            q0,
            objective,
            error,
            accept=1e-7,
            mode={"grasp_rel": rel[None]},
            toward=found[0] if len(found) else None,
            straight=found[: self.tuning.straight_probes] if len(found) else None,
        )
        self._in_air = self.tuning.search_in_air
        try:
            waypoints, _ = local_search(ctx, [job])[0]
        finally:
            self._in_air = False
        waypoints = self._finish(ctx, job, waypoints, found)
        held = self.held_object_poses(waypoints, rel)
        if not self.at_goal(held[-1], goal):
            joined = self.transfer_trees(ctx, q0, rel, goal, found, searched=waypoints)
            if joined is not None:
                waypoints, held = joined, self.held_object_poses(joined, rel)
        if not self.at_goal(held[-1], goal) and not self.rests(held[-1]):
            settled, ok = self.settle(self.transfer_checker(rel), rel, waypoints[-1:])
            if ok[0]:  # the search's end set down where it got to (the closest attempt, for SEARCH's chain)
                waypoints = np.vstack([waypoints, settled])
                held = self.held_object_poses(waypoints, rel)
        if not self.at_goal(held[-1], goal):
            resting = [i for i in range(len(waypoints)) if self.rests(held[i])]
            last = resting[-1] if resting else 0  # (the start rests)
            waypoints, held = waypoints[: last + 1], held[: last + 1]
        success = self.at_goal(held[-1], goal)
        distance = float(self.goal_distance(held[-1:], goal)[0])
        return PathResult(success, waypoints, 0.0 if success else distance, object_pose=held[-1])

    def transfer_trees(
        self,
        ctx: PlanningContext,
        q0: Array,
        grasp_rel: Array,
        goal: Array,
        found: Array,
        *,
        searched: Array | None = None,
    ) -> Array | None:
        """When SEARCH_TRANSFER's GA did not reach the goal: the motion-only search's two trees of landmarks
        (:func:`clew_ros.spatial.motion_plan.connect`: EXPLORE for transfer paths, the object carried as
        ``grasp_rel``) given :attr:`SpatialTuning.transfer_tree_landmarks` steps; the path from ``q0`` to the
        goal, or ``None``. One tree is rooted at ``q0``, with the GA's path ``searched`` (from ``q0``, the
        object in the air) and the object's way out from there (:meth:`way_out`) as landmarks; the other at the
        goal configuration nearest ``q0`` (``found``: :meth:`goal_configurations`), with its way out as a
        landmark, and kept for the later SEARCH_TRANSFERs of the same grasp and goal, which grow it further:
        where the object rests in a shelf, single-joint moves from the root barely move it."""
        budget = self.tuning.transfer_tree_landmarks
        if budget <= 0 or not len(found) or ctx.termination():
            return None
        rel = np.asarray(grasp_rel, dtype=float)
        rng = own_generator(ctx, TRANSFER_TREES_STREAM, q0, np.r_[rel, goal])
        mode = {"grasp_rel": rel[None]}
        checker = self.transfer_checker(rel)
        tree = self.goal_tree(rel, goal)
        if tree is None:
            tree = self._goal_trees[_key(rel, goal)] = LandmarkTree(found[0], np.zeros(6))
            root: Landmark | None = tree[0]
        else:  # a goal configuration with a way in that the tree's roots may lack
            roots = [k for k in range(len(tree)) if tree[k].parent is None]
            apart = self.tuning.transfer_goal_apart_rad
            root = None
            if len(roots) < self.tuning.transfer_goal_roots and all(
                np.max(np.abs(found[0] - tree[k].joints)) >= apart for k in roots
            ):
                root = tree.add(
                    parent=None, joints=found[0].copy(), object_pose=np.zeros(6), grasp=None, grasp_rel=None,
                    transit=None, transfer=None,
                )  # fmt: skip
        if root is not None:
            out_of_goal = self.way_out(checker, mode, found[0])
            if out_of_goal is not None:
                add_branch(tree, root.id, out_of_goal)
        ways = [self.way_out(checker, mode, q0)]
        if searched is not None and len(searched) > 1 and np.max(np.abs(searched[-1] - q0)) > 0:
            ways.append(searched)
        return connect(
            self,
            ctx,
            q0,
            found[0],
            mode=mode,
            checker=checker,
            landmarks=budget,
            rng=rng,
            goal_tree=tree,
            start_ways=[w for w in ways if w is not None],
        )

    def goal_tree(self, grasp_rel: Array, goal: Array) -> LandmarkTree | None:
        """The goal tree :meth:`transfer_trees` keeps for the object held as ``grasp_rel`` and set down at
        ``goal`` (``None``: none grown yet)."""
        return self._goal_trees.get(_key(np.asarray(grasp_rel, dtype=float), np.asarray(goal, dtype=float)))

    def way_out(self, checker: SpatialChecker, mode: dict[str, Array], q: Array) -> Array | None:
        """The carried object's way out from ``q`` (k + 1, n), along the first of its approaches (:meth:`offsets`:
        lifted, or lifted a little and slid back along the tcp's -z, the slide in
        :attr:`SpatialTuning.slide_steps` short moves) whose first step is clear, repeated step by
        step (each ``approach_m`` further, inverse kinematics seeded at the step before, each straight move
        clear) up to :attr:`SpatialTuning.transfer_way_out_m` while they stay clear: out of a shelf deeper than
        one approach; ``None`` if no first step is clear."""
        steps = max(1, math.ceil(self.tuning.transfer_way_out_m / self.tuning.approach_m - 1e-9))
        for kind, (first, along) in enumerate(self._approach_poses(mode, q[None])):
            way, done = [q], 0
            if kind == 1:  # lifted a little, then slid out in short moves (one straight joint move sags)
                raised = self.tcp(q[None])
                raised[:, 2, 3] += self.tuning.slide_lift_m
                lifted = self._approach_joints(raised, q[None])
                for step in [lifted[0], *self._slide_steps(raised, along, lifted)[:, 0]]:
                    if np.isnan(step).any() or not self.clear(checker, way[-1][None], step[None])[0]:
                        break
                    way.append(step)
                done = 1 if len(way) == self.tuning.slide_steps + 2 else steps
            for k in range(done, steps):
                target = first[0].copy()
                target[:3, 3] += k * along[0]
                step = self._approach_joints(target[None], way[-1][None])
                if np.isnan(step).any() or not self.clear(checker, way[-1][None], step)[0]:
                    break
                way.append(step[0])
            if len(way) > 1:
                out: Array = np.array(way)
                return out
        return None

    def backed_off(self, checker: SpatialChecker, q: Array) -> Array | None:
        """The tcp's way back from ``q`` along its own -z (k + 1, n): steps of
        :attr:`SpatialTuning.motion_way_out_step_m` up to :attr:`SpatialTuning.motion_way_out_m`, inverse
        kinematics seeded at the step before, while each straight move is clear (``checker``); ``None`` if
        the first step is not."""
        tuning = self.tuning
        if tuning.motion_way_out_m <= 0 or tuning.motion_way_out_step_m <= 0:
            return None
        pose = self.tcp(q[None])[0]
        way = [q]
        for k in range(1, math.ceil(tuning.motion_way_out_m / tuning.motion_way_out_step_m - 1e-9) + 1):
            target = pose.copy()
            target[:3, 3] -= k * tuning.motion_way_out_step_m * pose[:3, 2]
            step = self._approach_joints(target[None], way[-1][None])
            if np.isnan(step).any() or not self.clear(checker, way[-1][None], step)[0]:
                break
            way.append(step[0])
        return np.array(way) if len(way) > 1 else None

    def goal_configurations(self, ctx: PlanningContext, q0: Array, grasp_rel: Array, goal: Array) -> Array:
        """Valid configurations (m, n) holding the object (as ``grasp_rel``) at the goal (:meth:`goal_poses`),
        nearest ``q0`` first: inverse kinematics seeded at ``q0`` and ``SearchSettings.goal_seeds`` random
        starts drawn from a generator of the request's own."""
        rng = own_generator(ctx, GOAL_STREAM, q0, np.r_[grasp_rel, goal])
        back = _inverse(matrices(grasp_rel)[0])
        tcp_goals = [pose @ back for pose in self.goal_poses(goal)]
        checker = self.transfer_checker(grasp_rel)
        solutions = self.ik(ctx.search.goal_seeds).solve_many(
            tcp_goals, rng, seeds=[q0[None]] * len(tcp_goals), checker=checker
        )
        found = self.nearest_turns(q0, np.vstack(solutions))
        travel = np.abs(found - q0).sum(axis=1)
        pose_of = np.repeat(np.arange(len(solutions)), [len(s) for s in solutions])
        way_out = np.zeros(len(solutions))
        for k in np.unique(pose_of).tolist():
            rows = np.flatnonzero(pose_of == k)
            way_out[k] = self._way_out_m(checker, grasp_rel, goal, k, found[rows[np.argmin(travel[rows])]])
        order = np.lexsort((travel, -np.round(way_out[pose_of], 2)))
        ordered: Array = found[order]
        return ordered

    def _way_out_m(self, checker: SpatialChecker, grasp_rel: Array, goal: Array, pose: int, q: Array) -> float:
        """How far (m) the object held as ``grasp_rel`` at the goal pose ``pose`` (:meth:`goal_poses`' index) gets
        by its way out (:meth:`way_out`) from ``q``, once per grasp, goal and pose: a hand that can only lift
        its object a little in a cubby (its slide out meets a wall) comes in that way no more."""
        key = _key(grasp_rel, goal, np.array([float(pose)]))
        if key not in self._way_out_lengths:
            rel = np.asarray(grasp_rel, dtype=float)
            way = self.way_out(checker, {"grasp_rel": rel[None]}, q)
            held = self.held_object_poses(np.vstack([q[None], q[None] if way is None else way[-1:]]), rel)
            self._way_out_lengths[key] = float(np.linalg.norm(held[1, :3] - held[0, :3]))
        return self._way_out_lengths[key]

    def nearest_turns(self, q0: Array, found: Array) -> Array:
        """IK solutions with each joint whose limits span a turn (:func:`~clew_ros.spatial.turns.turnable`)
        moved by whole turns the short way from ``q0`` (within the limits): the same postures, nearest."""
        robot = self.world.robot
        return nearest_turns(q0, found, robot.lower, robot.upper, turnable(robot.prismatic, robot.lower, robot.upper))

    def goal_poses(self, goal: Array) -> list[Array]:
        """The goal placement (4x4) turned about world z through its centre by each of
        :attr:`SpatialTuning.goal_yaws` within ``world.goal_angle_tolerance`` (the goal's own first): every
        one of them reaches the goal."""
        base = matrices(goal)[0]
        tolerance = self.world.tolerances["goal_angle_tolerance"]
        out = []
        for yaw in self.tuning.goal_yaws:
            if abs(yaw) <= tolerance + 1e-12:
                turned = base.copy()
                turned[:3, :3] = rpy_matrix(0.0, 0.0, yaw) @ base[:3, :3]
                out.append(turned)
        return out

    def straight_probe(
        self,
        ctx: PlanningContext,
        jobs: list[SearchJob],
        q: np.ndarray,
        best: np.ndarray,
        waypoints: list[list[np.ndarray]],
    ) -> None:
        """Each job with ``straight`` targets tries straight moves to them (:meth:`way`); kept where it gets
        closer."""
        for i, job in enumerate(jobs):
            if job.straight is None or not len(job.straight) or ctx.termination():
                continue
            found = self.way(job.mode, q[i], job.straight)
            if found is None:
                continue
            reached = found[-1]
            value = float(job.objective(reached[None], object_at(ctx, reached[None], job.mode))[0])
            if value < best[i]:
                waypoints[i].append(found.copy())
                q[i] = reached
                best[i] = value

    def offsets(self, mode: dict[str, np.ndarray], qs: Array) -> Array:
        """Configurations (m, n) near ``qs`` (m, n) with the tcp moved :attr:`SpatialTuning.approach_m` away
        along its own -z (transit: backed off a grasp's approach) or up (transfer: the object lifted; where
        that is out of reach, lifted :attr:`SpatialTuning.slide_lift_m` and backed off along the tcp's -z, as
        a gripper slides an object out of a shelf); where no configuration near holds that whole pose, one
        with the tcp at its position (:attr:`SpatialTuning.position_approach`); a row is NaN where inverse
        kinematics seeded at it found none within its joint limits."""
        out = np.full(qs.shape, np.nan)
        for targets, _ in self._approach_poses(mode, qs):
            missed = np.flatnonzero(np.isnan(out).any(axis=1))
            if not len(missed):
                break
            out[missed] = self._approach_joints(targets[missed], qs[missed])
        return out

    def _approach_poses(self, mode: dict[str, np.ndarray], qs: Array) -> list[tuple[Array, Array]]:
        """The tcp's approach poses (m, 4, 4) for configurations ``qs`` (m, n), first choice first (:meth:`offsets`):
        backed off along its -z (transit); the object lifted, then lifted a little and slid out (transfer). Each
        with the move (m, 3) that takes it one approach further the same way (:meth:`way_out`)."""
        here = self.tcp(qs)
        tuning = self.tuning
        shift = tuning.approach_m
        back = -shift * here[:, :3, 2]
        backed = here.copy()
        backed[:, :3, 3] += back
        if mode.get("grasp_rel") is None:
            return [(backed, back)]
        up = np.broadcast_to([0.0, 0.0, shift], back.shape)
        lifted = here.copy()
        lifted[:, :3, 3] += up
        moves = [(lifted, up)]
        if tuning.slide_lift_m > 0:
            backed[:, 2, 3] += tuning.slide_lift_m
            moves.append((backed, back))
        return moves

    def _approach_joints(self, targets: Array, qs: Array) -> Array:
        """Configurations (m, n) near ``qs`` (m, n) with the tcp at ``targets`` (m, 4, 4) (:meth:`offsets`), NaN
        rows where none is found."""
        out = np.full(qs.shape, np.nan)
        found = self._settle_ik.solve_many(list(targets), np.random.default_rng(0), seeds=[q[None] for q in qs])
        for k, solutions in enumerate(found):
            if len(solutions):
                out[k] = solutions[0]
        missed = np.flatnonzero(np.isnan(out).any(axis=1))
        if len(missed) and self.tuning.position_approach:
            reached, ok = self._settle_ik.solve_rows(targets[missed], qs[missed], _POSITION_ROWS)
            out[missed[ok]] = reached[ok]
        return out

    def way(self, mode: dict[str, np.ndarray], q: Array, targets: Array) -> Array | None:
        """Waypoints (without ``q``) of straight joint-space moves from ``q`` to the first of ``targets``
        (nearest first) it reaches, each move checked at the validator's 0.002 rad in ``mode``: directly, or by
        way of the target's approach (:meth:`offsets`: the tcp backed off, the object lifted), or from ``q``'s
        own retreat; ``None`` if none is clear."""
        checker = self.checker_of(mode)
        targets = targets[: self.tuning.straight_probes]
        count = len(targets)
        starts = np.broadcast_to(q, targets.shape)
        clear = self.clear(checker, starts, targets)
        if clear.any():
            direct: Array = targets[int(np.argmax(clear))][None]
            return direct
        if self.tuning.approach_m <= 0:
            return None
        vias = self.offsets(mode, targets)
        retreat = self.offsets(mode, q[None])[0]
        fine = [k for k in range(count) if not np.isnan(vias[k]).any()]
        ways = [[vias[k], targets[k]] for k in fine]
        if not np.isnan(retreat).any():
            ways += [[retreat, vias[k], targets[k]] for k in fine]
            ways += [[retreat, targets[k]] for k in range(count)]
        for path in ways:
            points = np.array([q, *path])
            if self.clear(checker, points[:-1], points[1:]).all():
                via: Array = points[1:]
                return via
        return self._other_ways(mode, checker, q, targets, ways)

    def _other_ways(
        self, mode: dict[str, np.ndarray], checker: SpatialChecker, q: Array, targets: Array, tried: list[list[Array]]
    ) -> Array | None:
        """:meth:`way`'s moves by way of a carried object's other approach (:meth:`_approach_poses`: lifted
        :attr:`SpatialTuning.slide_lift_m` and slid out along the tcp's -z, where lifting it straight up is
        blocked by a shelf's lid or a cubby's ceiling), which :meth:`offsets` passes over when the first is
        within reach; the lift and the slide as two moves (one straight joint move sags between them); between
        the retreat and the approach, directly or over the top (both raised :attr:`SpatialTuning.carry_raise_m`)."""
        kinds = self._approach_poses(mode, np.vstack([q[None], targets]))
        if len(kinds) < 2:
            return None
        rows = np.vstack([q[None], targets])
        slid = self._approach_joints(kinds[1][0], rows)
        raised = self.tcp(rows)
        raised[:, 2, 3] += self.tuning.slide_lift_m
        lifted = self._approach_joints(raised, rows)
        steps = self._slide_steps(raised, kinds[1][1], lifted)  # (steps, rows, n): the slide in short moves
        del tried
        retreats = [[lifted[0], *steps[:, 0]], [lifted[0], slid[0]], [slid[0]], []]
        retreats = [r for r in retreats if self._path_clear(checker, [q, *r])]
        high: dict[bytes, Array] = {}
        for k in range(min(len(targets), self.tuning.slide_targets)):
            comings = [[*steps[::-1, k + 1], lifted[k + 1]], [slid[k + 1], lifted[k + 1]], [slid[k + 1]], []]
            comings = [c for c in comings if self._path_clear(checker, [*c, targets[k]])]
            for retreat in retreats:
                for coming in comings:
                    if not retreat and not coming:
                        continue  # way()'s direct move
                    a, b = (retreat[-1] if retreat else q), (coming[0] if coming else targets[k])
                    for middle in ([], [self._raised(a, high), self._raised(b, high)]):
                        if self._path_clear(checker, [a, *middle, b]):
                            found: Array = np.array([*retreat, *middle, *coming, targets[k]])
                            return found
        return None

    def _slide_steps(self, raised: Array, along: Array, lifted: Array) -> Array:
        """Configurations (steps, m, n) sliding the lifted tcps ``raised`` (m, 4, 4) out along ``along`` (m, 3), in
        :attr:`SpatialTuning.slide_steps` equal steps, each seeded at the one before (NaN: out of reach)."""
        count = self.tuning.slide_steps
        out = np.full((count, *lifted.shape), np.nan)
        last = lifted
        for i in range(count):
            rows = np.flatnonzero(~np.isnan(last).any(axis=1))
            if not len(rows):
                break
            target = raised[rows].copy()
            target[:, :3, 3] += along[rows] * (i + 1) / count
            out[i, rows] = self._approach_joints(target, last[rows])
            last = out[i]
        return out

    def _raised(self, q: Array, cache: dict[bytes, Array]) -> Array:
        """The configuration near ``q`` with the tcp :attr:`SpatialTuning.carry_raise_m` higher (NaN: none)."""
        key = q.tobytes()
        if key not in cache:
            target = self.tcp(q[None])
            target[:, 2, 3] += self.tuning.carry_raise_m
            cache[key] = self._approach_joints(target, q[None])[0]
        return cache[key]

    def _path_clear(self, checker: SpatialChecker, path: Sequence[Array]) -> bool:
        """Whether every straight move of ``path`` (a list of configurations; NaN: none) is valid."""
        if any(np.isnan(p).any() for p in path):
            return False
        if len(path) < 2:
            return True
        points = np.asarray(path)
        return bool(self.clear(checker, points[:-1], points[1:]).all())

    # -- regrasps, refusals, improvement --------------------------------------------------------------
    def approach_allows(self, approach: Any, grasp_rel: np.ndarray) -> bool:
        return True  # no aiming: every approach is allowed

    def regrasp_aims(self, goal: np.ndarray) -> SpatialAims:
        return SpatialAims(self, goal, self.tuning.regrasp)

    def quick_refusal(self, goal: np.ndarray) -> tuple[Outcome, str] | None:
        """A goal that is no stable placement or that collides, a start in collision, a goal no grasp can
        reach (the tcp's distance from the first joint beyond the arm's reach: a proof), a goal the object
        cannot get to (closed off by obstacles: :func:`~clew_ros.spatial.enclosure.enclosure_refusal`)."""
        world = self.world
        thing = world.object
        assert thing is not None
        goal = np.asarray(goal, dtype=float)
        if goal.shape != (6,) or not np.all(np.isfinite(goal)):
            return Outcome.INVALID_WORLD, "goal: expected a pose of six finite numbers [x, y, z, roll, pitch, yaw]"
        if not self.rests(goal):
            names = ", ".join(s.name for s in world.supports) or "none"
            return (
                Outcome.INVALID_WORLD,
                (
                    f"goal {np.round(goal, 6).tolist()} is not a stable placement: no flat face of the "
                    f"{thing.shape.shape} lies within {world.tolerances['placement_tolerance']} m of a support's "
                    f"top face with its centre above it (supports: {names})"
                ),
            )
        hit = self._object_collides(goal)
        if hit:
            return Outcome.GOAL_IN_COLLISION, f"the object at its goal placement touches {hit}"
        if not self.transit_checker(self.initial_object_pose).valid(world.initial[None])[0]:
            return Outcome.START_IN_COLLISION, "the start configuration is not valid (object resting at initial)"
        tcps = matrices(goal)[0] @ self._grasps
        nearest = float(np.min(np.linalg.norm(tcps[:, :3, 3] - self._shoulder, axis=1)))
        if nearest > self._reach:
            return (
                Outcome.GOAL_OUT_OF_REACH,
                (
                    f"goal placement out of reach: its nearest grasp is {nearest:.3f} m from the first joint, "
                    f"the arm reaches at most {self._reach:.3f} m"
                ),
            )
        closed = enclosure_refusal(world, goal, self.initial_object_pose)
        return (Outcome.NO_PATH_AT_RESOLUTION, f"no plan exists: {closed}") if closed else None

    def _object_collides(self, object_pose: Array) -> str:
        """The obstacles (names) the object at ``object_pose`` touches, its support but from above allowed,
        or the bounds it leaves; "" if none (on its exact box or cylinder)."""
        world = self.world
        thing = world.object
        assert thing is not None
        pose = matrices(object_pose)[0]
        found = resting_on(thing.shape, pose, world.supports, world.tolerances["placement_tolerance"])
        support = found[0].name if found is not None else ""
        hits = object_touches(thing.shape, pose, [o for o in world.obstacles if o.name != support])
        if world.bounds is not None:
            low, high = object_extent(thing.shape, pose)
            if np.any(low < world.bounds[:3]) or np.any(high > world.bounds[3:]):
                hits.append("the world's bounds")
        return ", ".join(hits)

    def improve(
        self, ctx: PlanningContext, segments: list[Segment], object_pose: np.ndarray, goal: np.ndarray
    ) -> Improvement:
        """:meth:`improved`, returned only if the plan validator's checks of every segment
        (:func:`clew_ros.spatial.plan.path_problems`, the grasps and placements included) pass it; else the
        first plan, with what was refused (the planner's own checks sample the moves where the validator's
        samples may fall elsewhere: an improved move grazing a support within its tolerance is not kept)."""
        better = self.improved(ctx, segments, object_pose, goal)
        mended = lifted_segments(self, better.segments, self.tuning.lift)
        if not _same_waypoints(mended, better.segments):
            better = replace(better, segments=mended, travel=joint_travel(mended))
        if _same_waypoints(better.segments, segments):
            return better  # nothing changed: the first plan, checked by the planner as it was found
        built = [(s.kind, s.grasp, np.asarray(s.waypoints, dtype=float)) for s in better.segments]
        problems = path_problems(self.world, make_plan(self.world, built))
        if not problems:
            return better
        return Improvement(
            segments,
            object_pose,
            better.first_travel,
            better.first_transfers,
            better.first_travel,
            better.first_transfers,
            0,
            better.work,
            better.stopped,
            refused="; ".join(problems[:2]),
        )

    def improved(
        self, ctx: PlanningContext, segments: list[Segment], object_pose: np.ndarray, goal: np.ndarray
    ) -> Improvement:
        """Shortcuts (:func:`_shortcut_segments`); then the straight plan (:meth:`straight_plan`) where it is
        shorter; then a plan still of several transfers is tried as one, from the start: each grasp's transit
        at the initial placement, then SEARCH_TRANSFER to the goal, shortcut; the one-transfer plan replaces it
        where it is no longer."""
        better = _shortcut_segments(self, ctx, segments, object_pose)
        if ctx.settings.improve_time <= 0 or better.stopped:
            return better
        straight = self.straight_plan(ctx, goal)
        if straight is not None:
            single, pose = straight
            direct = _shortcut_segments(self, ctx, single, pose)
            if direct.travel < better.travel:
                better = Improvement(
                    direct.segments,
                    pose,
                    better.first_travel,
                    better.first_transfers,
                    direct.travel,
                    direct.transfers,
                    better.shortcuts + direct.shortcuts,
                    better.work + direct.work + 1,
                    direct.stopped,
                )
        if better.transfers <= 1 or better.stopped:
            return better
        for grasp in range(self.grasp_count):
            if ctx.termination():
                break
            if not len(self.goal_configurations(ctx, self.initial_joints, self.grasp_rel(grasp), goal)):
                continue  # no configuration holds the object at the goal with this grasp: spare its searches
            pose = self.initial_object_pose
            transit = self.search_transits(ctx, [(self.initial_joints, pose, grasp, None)])[0]
            if not transit.success or transit.grasp_rel is None:
                continue
            carried = self.search_transfer(ctx, transit.waypoints[-1], transit.grasp_rel, goal)
            if not carried.success or carried.object_pose is None:
                continue
            single = [
                Segment("transit", None, list(transit.waypoints)),
                Segment("transfer", grasp, list(carried.waypoints)),
            ]
            direct = _shortcut_segments(self, ctx, single, carried.object_pose)
            if direct.travel <= better.travel:
                return Improvement(
                    direct.segments,
                    direct.final_object_pose,
                    better.first_travel,
                    better.first_transfers,
                    direct.travel,
                    direct.transfers,
                    better.shortcuts + direct.shortcuts,
                    better.work + direct.work + 1,
                    direct.stopped,
                )
        return better

    def straight_plan(self, ctx: PlanningContext, goal: Array) -> tuple[list[Segment], Array] | None:
        """The shortest plan of one transfer made of straight moves (:meth:`way`: direct or by way of the
        approaches) from the start to a hold and from it to a goal configuration, over every grasp: for each,
        the :attr:`SpatialTuning.straight_pairs` (hold, goal configuration) pairs of least joint travel in
        straight lines, the first whose moves are clear; ``None`` if none is."""
        start, pose = self.initial_joints, self.initial_object_pose
        best: tuple[float, list[Segment], Array] | None = None
        for grasp in range(self.grasp_count):
            if ctx.termination():
                break
            rel = self.grasp_rel(grasp)
            goals = self.goal_configurations(ctx, start, rel, goal)
            holds = self.holds(ctx, start, pose, grasp) if len(goals) else goals
            if not len(holds):
                continue
            cost = np.abs(holds - start).sum(axis=1)[:, None] + np.abs(holds[:, None] - goals[None]).sum(axis=2)
            for flat in np.argsort(cost, axis=None, kind="stable")[: self.tuning.straight_pairs]:
                i, j = np.unravel_index(flat, cost.shape)
                if best is not None and cost[i, j] >= best[0]:
                    break
                reach = self.way({"object_poses": pose[None]}, start, holds[i][None])
                carry = None if reach is None else self.way({"grasp_rel": rel[None]}, holds[i], goals[j][None])
                if reach is None or carry is None:
                    continue
                segments = [
                    Segment("transit", None, [start, *reach]),
                    Segment("transfer", grasp, [holds[i], *carry]),
                ]
                travel = joint_travel(segments)
                if best is None or travel < best[0]:
                    best = (travel, segments, self.held_object_poses(goals[j][None], rel)[0])
                break
        return None if best is None else (best[1], best[2])


def _key(*parts: Array) -> bytes:
    """A cache key of poses (a checker's, a goal tree's): their numbers rounded to 1e-9."""
    return np.round(np.concatenate([np.asarray(p, dtype=float).reshape(-1) for p in parts]), 9).tobytes()


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


def _same_waypoints(a: Sequence[Segment], b: Sequence[Segment]) -> bool:
    """Whether two plans are the same segments through the same waypoints."""
    return len(a) == len(b) and all(
        x.kind == y.kind and x.grasp == y.grasp and np.array_equal(np.asarray(x.waypoints), np.asarray(y.waypoints))
        for x, y in zip(a, b, strict=True)
    )


@dataclass
class _Piece:
    """A segment as the pruning sees it (:class:`clew_ros.core.improve.JoinablePiece`): a spatial transfer's held
    pose is its grasp's nominal one, so kind, grasp and waypoints are all there is."""

    kind: str
    grasp: int | None
    waypoints: Array

    def with_waypoints(self, waypoints: Array) -> _Piece:
        return _Piece(self.kind, self.grasp, waypoints)


def _pruned(segments: list[Segment], same_rad: float) -> list[_Piece]:
    """The plan's segments pruned without checking (the module's docstring): each path's repeats, loops and
    collinear waypoints dropped, then each transfer put down and taken again in place joined to the one before."""
    pieces = [_Piece(s.kind, s.grasp, pruned_path(np.array(s.waypoints, dtype=float))) for s in segments]
    return joined_regrasps(pieces, same_rad)


def _clear_lifted(
    space: SpatialSpace, checker: SpatialChecker, rel: Array, starts: Array, ends: Array
) -> NDArray[np.bool_]:
    """A transfer's shortcuts: clear, and not dragging the object over a support (:func:`lift.drag_free`)."""
    clear = space.clear(checker, starts, ends)
    if clear.any():
        clear[clear] = drag_free(space, starts[clear], ends[clear], rel, space.tuning.lift.drag)
    return clear


def _shortcut_segments(
    space: SpatialSpace, ctx: PlanningContext, segments: list[Segment], object_pose: Array
) -> Improvement:
    """The plan's segments pruned and shortcut (the module's docstring); ``object_pose``: where the object
    ends. The work is the shortcuts' tries (a fixed number per segment), counted by a
    :class:`~clew_ros.core.improve.WorkBudget` without a total: only the clock, and the exact contacts they cost
    (:attr:`SpatialTuning.shortcut_exact_rate`), stop it early."""
    first_travel = joint_travel(segments)
    first_transfers = sum(s.kind == "transfer" for s in segments)
    if ctx.settings.improve_time <= 0:
        return Improvement(
            segments, object_pose, first_travel, first_transfers, first_travel, first_transfers, 0, 0, False
        )
    budget = WorkBudget(math.inf, WorkCosts(), ctx.termination)
    exact_limit = space.exact_checks + space.tuning.shortcut_exact_rate * ctx.settings.improve_time

    def stop() -> bool:
        return budget.stop() or space.exact_checks >= exact_limit

    pieces = _pruned(segments, space.tuning.same_rad)
    transfers = sum(p.kind == "transfer" for p in pieces)
    resting = space.initial_object_pose
    out: list[Segment] = []
    shortcuts = 0
    for segment in pieces:
        path = segment.waypoints
        if segment.kind == "transfer":
            assert segment.grasp is not None
            rel = space.grasp_rel(segment.grasp)
            checker = space.transfer_checker(rel)
        else:
            rel = None
            checker = space.transit_checker(resting)
        if not budget.stopped:
            clear = partial(space.clear, checker) if rel is None else partial(_clear_lifted, space, checker, rel)
            path, taken, spent, _ = shortcut_path(
                clear,
                path,
                tries=space.tuning.shortcut_tries,
                rng=ctx.rng,
                stop=stop,
                steps=space.validation_steps,
            )
            shortcuts += taken
            budget.spend(spent)
        out.append(Segment(segment.kind, segment.grasp, list(path)))
        if rel is not None:
            resting = space.held_object_poses(path[-1:], rel)[0]
    travel = joint_travel(out)
    if travel > first_travel:  # (never: pruning and shortcuts only shorten)
        return Improvement(
            segments,
            object_pose,
            first_travel,
            first_transfers,
            first_travel,
            first_transfers,
            0,
            budget.spent,
            budget.stopped,
        )
    return Improvement(
        out, object_pose, first_travel, first_transfers, travel, transfers, shortcuts, budget.spent, budget.stopped
    )
