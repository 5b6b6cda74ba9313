"""Spatial plans checked on the exact geometry: pinocchio + coal on the URDF's own collision geometry.

The planner and :func:`~clew_ros.spatial.plan.validate_plan` test the conservative sphere model of the
robot and of the object. :func:`exact_problems` replays a plan on the geometry the contract names instead
(interface.md section 1b, "A spatial configuration is valid"): every ``<collision>`` of every link as
loaded (boxes, cylinders and spheres as such, meshes as coal triangle BVHs), the obstacles as coal
primitives, and the object as the box or cylinder the world gives, checking every configuration along every
straight piece at the validator's step (0.002 rad per revolute joint, 0.001 m per prismatic joint):

- every link (grown by ``world.robot.padding``: coal's security margin) against every obstacle and against
  the bounds (each face of ``bounds`` stands for the half-space outside it);
- every pair of links but those the sphere model exempts (``RobotModel.exempt``: a link and its parent,
  links on one frame, the SRDF's ``disable_collisions``);
- every link but ``world.robot.gripper_links`` against the object, resting where the previous transfer left
  it (during a transit) or attached to the tcp with the pose it had at the transfer's first waypoint (during
  a transfer);
- the object against the obstacles and the bounds, where it rests and all along a transfer; a support may
  be touched from above (the object no lower than its top face less ``world.placement_tolerance``).

The robot's kinematics are pinocchio's, built from the URDF text (``RobotModel.urdf``), independently of
the project's own; the constructor checks that both put every link at the same pose. pinocchio and coal
come with the ``spatial-ref`` extra (``pip install 'clew_ros[spatial-ref]'``) and are imported when a
:class:`ExactChecker` is made. The grasps held, the placements' stability and the goal are
:func:`~clew_ros.spatial.plan.validate_plan`'s; this module adds only the collisions on the exact geometry.
"""

from __future__ import annotations

import importlib
import itertools
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from clew_ros.core.plan import Plan
from clew_ros.spatial.placements import MovableObject, Support
from clew_ros.spatial.scene import Obstacle
from clew_ros.spatial.tier import coal_shape, outside_bounds
from clew_ros.spatial.transforms import pose_matrix
from clew_ros.spatial.validate import ValidationSettings, validation_samples
from clew_ros.spatial.world import SpatialWorld

__all__ = ["ExactChecker", "ExactSettings", "exact_available", "exact_problems"]

Matrix = NDArray[np.float64]


@dataclass(frozen=True)
class ExactSettings:
    """The exact checker's numbers."""

    #: How far (m) pinocchio's and the project's kinematics may put a link apart before the checker refuses
    #: to run (the two read one URDF; a gap means one of them folds it differently).
    kinematics_match_m: float = 1e-6


def exact_available() -> bool:
    """Whether pinocchio and coal (the ``spatial-ref`` extra) can be imported."""
    try:
        importlib.import_module("pinocchio")
        importlib.import_module("coal")
    except ImportError:
        return False
    return True


def _modules() -> tuple[Any, Any]:
    try:
        return importlib.import_module("pinocchio"), importlib.import_module("coal")
    except ImportError as error:
        raise ImportError(
            f"the exact checker needs pinocchio and coal ({error}): pip install 'clew_ros[spatial-ref]'"
        ) from None


def lowest_point(thing: MovableObject, pose: Matrix) -> float:
    """The object's lowest z (m) at ``pose`` (4x4), exactly: a box's lowest corner, a cylinder's lowest rim."""
    if thing.shape == "box":
        half = np.asarray(thing.size) / 2
        return float(pose[2, 3] - np.abs(pose[2, :3]) @ half)
    axis = pose[:3, 2]
    rim = thing.size[1] * float(np.sqrt(max(0.0, 1.0 - axis[2] ** 2)))
    return float(pose[2, 3] - abs(axis[2]) * thing.size[0] / 2 - rim)


@dataclass(frozen=True, eq=False)
class _Scene:
    """One geometry model and its data: the robot, the obstacles and the object as one mode places it."""

    model: Any
    data: Any
    names: tuple[str, ...]
    object_id: int  # the object's geometry index (-1: none)


class ExactChecker:
    """The exact collision test of one spatial world (see the module docstring)."""

    def __init__(self, world: SpatialWorld, settings: ExactSettings | None = None) -> None:
        self.settings = settings or ExactSettings()
        self.pin, self.coal = _modules()
        pin, coal = self.pin, self.coal
        self.world = world
        robot = world.robot
        self.model = pin.buildModelFromXML(robot.urdf)
        self.data = self.model.createData()
        self.neutral: NDArray[np.float64] = np.asarray(pin.neutral(self.model), dtype=np.float64)
        for name, value in robot.fixed_positions.items():
            self._set(self.neutral, name, value)
        pin.forwardKinematics(self.model, self.data, self.neutral)
        pin.updateFramePlacements(self.model, self.data)
        base_in_universe = self.data.oMf[self._frame(robot.base_link)].homogeneous
        #: ``world`` <- pinocchio's universe (the URDF's root link): the base's pose over its pose in the root.
        self.universe: Matrix = robot.base @ np.linalg.inv(np.asarray(base_in_universe, dtype=np.float64))
        self.to_universe: Matrix = np.asarray(np.linalg.inv(self.universe), dtype=np.float64)
        self.tip = self._frame(robot.tip_link)
        q0 = np.clip(np.zeros(robot.dof), robot.lower, robot.upper).tolist()
        self.tcp_in_tip: Matrix = np.linalg.inv(self.universe @ self._tip(q0)) @ robot.tcp_pose(q0)
        self._check_kinematics()
        self.link_geometries = [
            [(coal_shape(coal, g.kind, g.size, g), g.origin) for g in link.geometries] for link in robot.links
        ]
        self.obstacle_shapes = [(o, coal_shape(coal, o.shape, o.size)) for o in world.obstacles]
        self.slabs = self._slabs()
        self.object_shape = (
            None if world.object is None else coal_shape(coal, world.object.shape.shape, world.object.shape.size)
        )
        self.gripper = {i for i, link in enumerate(robot.links) if link.name in robot.gripper_links}
        self.self_pairs = [
            (i, j)
            for i in range(len(robot.links))
            for j in range(i + 1, len(robot.links))
            if (i, j) not in robot.exempt
        ]
        self._alone: _Scene | None = None

    # -- kinematics -------------------------------------------------------------------------------------

    def _frame(self, name: str) -> int:
        return int(self.model.getFrameId(name, self.pin.FrameType.BODY))

    def _set(self, q: NDArray[np.float64], joint: str, value: float) -> None:
        """Joint ``joint`` of pinocchio's configuration ``q`` at ``value`` (a continuous joint as cos, sin)."""
        if not self.model.existJointName(joint):
            return
        jmodel = self.model.joints[self.model.getJointId(joint)]
        if jmodel.nq == 2:
            q[jmodel.idx_q : jmodel.idx_q + 2] = [np.cos(value), np.sin(value)]
        else:
            q[jmodel.idx_q] = value

    def full(self, q: Any) -> NDArray[np.float64]:
        """pinocchio's configuration of the planned joints at ``q``, the others at their fixed positions."""
        out = self.neutral.copy()
        for name, value in zip(self.world.robot.joint_names, q, strict=True):
            self._set(out, name, float(value))
        return out

    def _tip(self, q: Any) -> Matrix:
        """``tip_link``'s pose in pinocchio's universe at ``q``."""
        self.pin.framesForwardKinematics(self.model, self.data, self.full(q))
        return np.asarray(self.data.oMf[self.tip].homogeneous, dtype=np.float64)

    def tcp_pose(self, q: Any) -> Matrix:
        """The tcp's pose in ``world`` at ``q``, by pinocchio's kinematics."""
        pose: Matrix = self.universe @ self._tip(q) @ self.tcp_in_tip
        return pose

    def _check_kinematics(self) -> None:
        """pinocchio and the project's kinematics put every link (and the tcp) at one pose (a fixed draw)."""
        robot = self.world.robot
        q = np.random.default_rng(0).uniform(robot.lower, robot.upper).tolist()
        ours = robot.link_poses(q)
        self.pin.framesForwardKinematics(self.model, self.data, self.full(q))
        worst = float(np.max(np.abs(self.tcp_pose(q) - robot.tcp_pose(q))))
        for name, pose in ours.items():
            theirs = self.universe @ self.data.oMf[self._frame(name)].homogeneous
            worst = max(worst, float(np.max(np.abs(theirs - pose))))
        if worst > self.settings.kinematics_match_m:
            raise ValueError(
                f"world.robot: pinocchio's kinematics of the URDF differ from the planner's by {worst:.3g} "
                "(a link's pose); the exact check would test other poses than the plan's"
            )

    # -- scenes -----------------------------------------------------------------------------------------

    def _slabs(self) -> list[tuple[str, Any, Matrix]]:
        """The outside of ``bounds``: a half-space beyond each face (in ``world``)."""
        bounds = self.world.bounds
        if bounds is None:
            return []
        names = [f"the bounds ({side} {'xyz'[axis]})" for axis in range(3) for side in ("min", "max")]
        return [
            (name, shape, np.eye(4))
            for name, shape in zip(names, outside_bounds(self.coal, bounds.tolist()), strict=True)
        ]

    def _scene(self, resting: Matrix | None = None, held: Matrix | None = None) -> _Scene:
        """The robot among the obstacles, the bounds' slabs and the object: ``resting`` at that pose in
        ``world``, or ``held`` with that pose in the tcp's frame, or absent."""
        pin = self.pin
        robot = self.world.robot
        geometry = pin.GeometryModel()
        names: list[str] = []

        def add(name: str, joint: int, placement: Matrix, shape: Any) -> int:
            names.append(name)
            return int(geometry.addGeometryObject(pin.GeometryObject(name, joint, pin.SE3(placement), shape)))

        owned = []
        for link, shapes in zip(robot.links, self.link_geometries, strict=True):
            frame = self.model.frames[self._frame(link.name)]
            owned.append(
                [
                    add(f"link {link.name!r}", frame.parentJoint, frame.placement.homogeneous @ origin, shape)
                    for shape, origin in shapes
                ]
            )
        statics = [add(f"obstacle {o.name!r}", 0, self.to_universe @ o.pose, s) for o, s in self.obstacle_shapes]
        statics += [add(name, 0, self.to_universe @ pose, shape) for name, shape, pose in self.slabs]
        object_id = -1
        if self.object_shape is not None and resting is not None:
            object_id = add("the object (resting)", 0, self.to_universe @ resting, self.object_shape)
        elif self.object_shape is not None and held is not None:
            tip = self.model.frames[self.tip]
            placement = tip.placement.homogeneous @ self.tcp_in_tip @ held
            object_id = add("the object (held)", tip.parentJoint, placement, self.object_shape)
        pairs = [(g, s) for mine in owned for g in mine for s in statics]
        pairs += [(g, h) for i, j in self.self_pairs for g in owned[i] for h in owned[j]]
        if object_id >= 0:
            pairs += [(g, object_id) for i, mine in enumerate(owned) if i not in self.gripper for g in mine]
        if object_id >= 0 and held is not None:  # resting: tested once, where it rests (resting_problem)
            supports = {s.name for s in self.world.supports}
            obstacles = [k for k, (o, _) in enumerate(self.obstacle_shapes) if o.name not in supports]
            pairs += [(object_id, statics[k]) for k in obstacles]
            pairs += [(object_id, s) for s in statics[len(self.obstacle_shapes) :]]
        for first, second in pairs:
            geometry.addCollisionPair(pin.CollisionPair(first, second))
        data = pin.GeometryData(geometry)
        links = {g for mine in owned for g in mine}
        for k, (first, second) in enumerate(pairs):  # world.robot.padding: each link grown by it
            grown = robot.padding * ((first in links) + (second in links))
            if grown > 0:
                data.collisionRequests[k].security_margin = grown
        return _Scene(geometry, data, tuple(names), object_id)

    def _collides(self, scene: _Scene, q: Sequence[float]) -> str:
        """What collides at ``q`` in ``scene`` (the first pair pinocchio finds), "" for nothing."""
        pin = self.pin
        if not pin.computeCollisions(self.model, self.data, scene.model, scene.data, self.full(q), True):
            return ""
        for k, result in enumerate(scene.data.collisionResults):
            if result.isCollision():
                pair = scene.model.collisionPairs[k]
                return f"{scene.names[pair.first]} touches {scene.names[pair.second]}"
        return "a collision"  # pragma: no cover - computeCollisions said so

    def configuration_problem(self, q: Sequence[float]) -> str:
        """What the robot at ``q`` touches (an obstacle, the bounds, itself; the object left out), "" for
        nothing: the reference answer for one configuration."""
        if self._alone is None:
            self._alone = self._scene()
        return self._collides(self._alone, q)

    def _touches(self, shape: Any, pose: Matrix, other: Any, other_pose: Matrix) -> bool:
        coal = self.coal
        request, result = coal.CollisionRequest(), coal.CollisionResult()
        a = coal.Transform3s(pose[:3, :3], pose[:3, 3])
        b = coal.Transform3s(other_pose[:3, :3], other_pose[:3, 3])
        return bool(coal.collide(shape, a, other, b, request, result) > 0)

    def object_problem(self, pose: Matrix) -> str:
        """What the object at ``pose`` (4x4, ``world``) touches: an obstacle, a support from below its top face
        (less ``world.placement_tolerance``), the bounds; "" for nothing."""
        world = self.world
        assert world.object is not None
        assert self.object_shape is not None
        supports = {s.name: s for s in world.supports}
        tolerance = world.tolerances["placement_tolerance"]
        low = lowest_point(world.object.shape, pose)
        for obstacle, shape in self.obstacle_shapes:
            support = supports.get(obstacle.name)
            if support is not None and low >= support.top - tolerance:
                continue  # on it from above, or beside it and above its top
            if self._touches(self.object_shape, pose, shape, obstacle.pose):
                what = "sinks below the top of support" if support is not None else "touches obstacle"
                return f"the object {what} {obstacle.name!r}"
        for name, shape, slab in self.slabs:
            if self._touches(self.object_shape, pose, shape, slab):
                return f"the object crosses {name}"
        return ""

    def _support_problem(
        self, supports: Sequence[tuple[Support, Obstacle, Any]], q: Sequence[float], held: Matrix
    ) -> str:
        """The held object (its pose ``held`` in the tcp's frame) at ``q`` against the supports, touched only
        from above (see :meth:`object_problem`)."""
        world = self.world
        assert world.object is not None
        pose = self.tcp_pose(q) @ held
        low = lowest_point(world.object.shape, pose)
        tolerance = world.tolerances["placement_tolerance"]
        for support, obstacle, shape in supports:
            if low < support.top - tolerance and self._touches(self.object_shape, pose, shape, obstacle.pose):
                return f"the object (held) sinks below the top of support {obstacle.name!r}"
        return ""

    # -- paths and plans ---------------------------------------------------------------------------------

    def path_problems(
        self,
        waypoints: Any,
        *,
        resting: Matrix | None = None,
        held: Matrix | None = None,
        settings: ValidationSettings | None = None,
    ) -> list[str]:
        """The problems of the straight pieces through ``waypoints`` (k, n) on the exact geometry, the object
        ``resting`` at that pose or ``held`` with that pose in the tcp's frame: one per piece with a colliding
        configuration (checked at ``settings``' step), naming the first."""
        settings = settings or ValidationSettings()
        robot = self.world.robot
        path = np.asarray(waypoints, dtype=np.float64).reshape(-1, robot.dof)
        steps = np.where(robot.prismatic, settings.step_m, settings.step_rad)
        scene = self._scene(resting=resting, held=held)
        supports = []
        if held is not None:
            by_name = {o.name: (o, shape) for o, shape in self.obstacle_shapes}
            supports = [(s, *by_name[s.name]) for s in self.world.supports if s.name in by_name]
        pieces = (
            [path[:1]] if len(path) == 1 else [validation_samples(a, b, steps) for a, b in itertools.pairwise(path)]
        )
        problems = []
        for i, samples in enumerate(pieces):
            for k, q in enumerate(samples):
                what = self._collides(scene, q)
                if not what and held is not None:
                    what = self._support_problem(supports, q, held)
                if what:
                    where = "waypoint 0" if len(path) == 1 else f"piece {i} (waypoints {i} -> {i + 1})"
                    share = k / max(1, len(samples) - 1)
                    problems.append(
                        f"{where}: configuration {np.round(q, 6).tolist()} at {share:.1%} collides on the exact "
                        f"geometry: {what}"
                    )
                    break
        return problems

    def plan_problems(self, plan: Plan, settings: ValidationSettings | None = None) -> list[str]:
        """The collisions of a successful ``plan`` on the exact geometry (empty: none), the object carried
        as the plan says: resting where it lies during a transit, attached to the tcp (pinocchio's) from the
        transfer's first waypoint during a transfer."""
        world = self.world
        pose = None if world.object is None else pose_matrix(world.object.initial)
        problems: list[str] = []
        for index, segment in enumerate(plan.segments):
            head = f"segment {index} ({segment.kind})"
            waypoints = np.asarray(segment.waypoints, dtype=np.float64)
            if pose is None:
                found = self.path_problems(waypoints, settings=settings)
            elif segment.kind == "transit":
                resting = self.object_problem(pose)
                if resting:
                    problems.append(f"{head}: where it rests, {resting}")
                found = self.path_problems(waypoints, resting=pose, settings=settings)
            else:
                held = np.linalg.inv(self.tcp_pose(waypoints[0])) @ pose
                found = self.path_problems(waypoints, held=held, settings=settings)
                pose = self.tcp_pose(waypoints[-1]) @ held
            problems += [f"{head}: {problem}" for problem in found]
        return problems


def exact_problems(world: SpatialWorld, plan: Plan, settings: ValidationSettings | None = None) -> list[str]:
    """:meth:`ExactChecker.plan_problems` of a new checker of ``world``: the plan's collisions on the URDF's
    exact geometry at the validator's step (empty: none). ``ImportError`` without pinocchio and coal."""
    return ExactChecker(world).plan_problems(plan, settings)
