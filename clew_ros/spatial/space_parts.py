"""What every part of the spatial space shares (:class:`SpaceParts`): the world and its tuning, the checker of
each mode (cached by pose), the tcp's forward and inverse kinematics, the grasps, and the straight-move check
at the validator's resolution."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from clew_ros.core.space import Mode
from clew_ros.core.tree import LandmarkTree
from clew_ros.spatial.checker import Held, SpatialChecker
from clew_ros.spatial.inverse import IKSettings, InverseKinematics
from clew_ros.spatial.scene import make_obstacle
from clew_ros.spatial.straight import straight_samples_clear
from clew_ros.spatial.transforms import inverse_matrix, matrices, poses
from clew_ros.spatial.tuning import SpatialTuning
from clew_ros.spatial.turns import nearest_turns, turnable
from clew_ros.spatial.validate import ValidationSettings
from clew_ros.spatial.world import SpatialWorld

__all__ = ["SpaceParts", "cache_key"]

Array = NDArray[np.float64]


def cache_key(*parts: Array) -> bytes:
    """A cache key of poses (a checker's, a goal tree's): their numbers rounded to 1e-9."""
    return np.round(np.concatenate([np.asarray(p, dtype=float).reshape(-1) for p in parts]), 9).tobytes()


class SpaceParts:
    """A spatial world's checkers, kinematics and grasps, and the caches one run keeps of them."""

    def __init__(self, world: SpatialWorld, tuning: SpatialTuning) -> None:
        self.world = world
        self.tuning = tuning
        self.validation = ValidationSettings()
        self._ik: dict[int, InverseKinematics] = {}
        #: the inverse kinematics seeded only where it is asked to start (settling, approaches, the tcp's poses)
        self.settle_ik = InverseKinematics(world.robot, IKSettings(seeds=0, max_iterations=tuning.settle_iterations))
        self._transit_checkers: dict[bytes, SpatialChecker] = {}
        self._transfer_checkers: dict[bytes, SpatialChecker] = {}
        #: the goal trees of the failed SEARCH_TRANSFERs (:func:`clew_ros.spatial.search.transfer_trees`), by held
        #: pose and goal: each grows over the run, as the ACA's landmarks do
        self.goal_trees: dict[bytes, LandmarkTree] = {}
        #: how far (m) the object gets by its way out at a goal pose, by (grasp, goal, goal pose)
        #: (:func:`clew_ros.spatial.targets.goal_configurations`)
        self.way_out_lengths: dict[bytes, float] = {}
        thing = world.object
        #: the grasps: the tcp's 4x4 pose in the object's frame (G, 4, 4)
        self.grasps = matrices(thing.grasps) if thing is not None else np.zeros((0, 4, 4))
        #: the object's size scale (m): its half diagonal, the radius of the orientation's chord
        self.object_radius = float(np.linalg.norm(thing.shape.size) / 2) if thing is not None else 0.1
        robot = world.robot
        origin_steps = np.linalg.norm(robot.origins[1:, :3, 3], axis=1).sum()
        travel = float(np.sum(np.maximum(np.abs(robot.lower), np.abs(robot.upper))[robot.prismatic]))
        #: an upper bound (m) of the tcp's distance from the first joint's origin, whatever the joints
        self.reach = float(origin_steps + np.linalg.norm(robot.tcp[:3, 3]) + travel)
        #: the first joint's origin (m, world frame)
        self.shoulder = (robot.base @ robot.origins[0])[:3, 3].copy()

    def transit_checker(self, object_pose: Array) -> SpatialChecker:
        """The checker with the object resting at ``object_pose`` (6 numbers); the world's own without one."""
        thing = self.world.object
        if thing is None:
            return self.world.checker
        key = cache_key(object_pose)
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
        key = cache_key(grasp_rel)
        checker = self._transfer_checkers.get(key)
        if checker is None:
            world = self.world
            held = Held(
                thing.shape,
                inverse_matrix(matrices(grasp_rel)[0]),
                world.supports,
                world.tolerances["placement_tolerance"],
            )
            checker = SpatialChecker(
                world.robot, world.spheres, world.obstacles, world.bounds, held=held, exact=world.checker.exact,
                band_intervals=self.tuning.transfer_band_intervals,
            )  # fmt: skip
            self._transfer_checkers[key] = checker
        return checker

    def checker_of(self, mode: Mode) -> SpatialChecker:
        """The checker of a mode of one pose ``(1, 6)``: the object resting there, or held so."""
        if mode.transfer:
            return self.transfer_checker(mode.poses.reshape(-1)[:6])
        return self.transit_checker(mode.poses.reshape(-1)[:6])

    @property
    def validation_steps(self) -> Array:
        """The validator's step per planned joint (rad, m for a prismatic one)."""
        robot = self.world.robot
        return np.where(robot.prismatic, self.validation.step_m, self.validation.step_rad)

    @property
    def exact_checks(self) -> int:
        """Contacts the exact geometry has decided for these checkers so far (deterministic work)."""
        checkers = [self.world.checker, *self._transit_checkers.values(), *self._transfer_checkers.values()]
        return sum(c.exact_checks for c in checkers)

    def ik(self, seeds: int) -> InverseKinematics:
        """The tcp's inverse kinematics with ``seeds`` random starts per target."""
        if seeds not in self._ik:
            self._ik[seeds] = InverseKinematics(self.world.robot, IKSettings(seeds=seeds))
        return self._ik[seeds]

    def tcp(self, q: Array) -> Array:
        """The tcp's 4x4 poses (B, 4, 4) at configurations ``q`` (B, n)."""
        return self.settle_ik.tcp_poses(np.asarray(q, dtype=float).reshape(-1, self.world.robot.dof))

    def clear(self, checker: SpatialChecker, starts: Array, ends: Array) -> NDArray[np.bool_]:
        """Whether each straight move is valid at the validator's resolution."""
        return straight_samples_clear(
            checker, starts, ends, coarse_every=self.tuning.coarse_every, settings=self.validation
        )

    def grasp_rel(self, grasp: int) -> Array:
        """The object's nominal pose in the tcp's frame while it holds ``grasp``."""
        rel: Array = poses(inverse_matrix(self.grasps[grasp])[None])[0]
        return rel

    def held_object_poses(self, q: Array, grasp_rel: Array) -> Array:
        """Where the object held as ``grasp_rel`` is (B, 6) at configurations ``q`` (B, n)."""
        q = np.asarray(q, dtype=float).reshape(-1, self.world.robot.dof)
        rel = matrices(np.broadcast_to(np.asarray(grasp_rel, dtype=float).reshape(-1, 6), (len(q), 6)))
        return poses(self.tcp(q) @ rel)

    def nearest_turns(self, q0: Array, found: Array) -> Array:
        """IK solutions with each joint whose limits span a turn (:func:`~clew_ros.spatial.turns.turnable`)
        moved by whole turns the short way from ``q0`` (within the limits): the same postures, nearest."""
        robot = self.world.robot
        return nearest_turns(q0, found, robot.lower, robot.upper, turnable(robot.prismatic, robot.lower, robot.upper))
