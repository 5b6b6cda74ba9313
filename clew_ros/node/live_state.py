"""The world as it is now (interface.md section 3c): the node's ``state.*`` inputs and each run's snapshot.

:class:`LiveState` subscribes to the inputs its ``state.*`` parameters turn on (``joint_states``,
``~/object``, ``~/obstacles``, ``~/points``), keeps the latest of each, and :meth:`LiveState.snapshot` turns
them into the configuration a run plans in: the parameters' world tree with the start configuration, the
object's pose and the obstacles of the moment written in (:func:`~clew_ros.spatial.snapshot.snapshot_tree`),
read back into a world. The run publishes that tree as its ``~/world_yaml``, so ``clew_plan`` on it plans
the same plan. A state that cannot be planned from is a :class:`StateRefusalError` (``START_STATE_UNKNOWN``,
``START_IN_COLLISION``, ``INVALID_WORLD``) with a message saying why.

With ``state.advance`` a run starts where the previous one ended (its last waypoint and final object pose
after a success, else where it started); ``joint_states`` overrides the arm, and an ``~/object`` received
after the previous run was accepted overrides the object.

Threads: the subscriptions share the callback group of ``~/goal_pose`` (mutually exclusive, created first,
so that an input sent before a goal is taken before it); ``self._lock`` guards the inputs; a timer
republishes ``~/world_markers`` within :attr:`LiveState.markers_period_s` of a change.
"""

from __future__ import annotations

import dataclasses
import threading
import time
from collections.abc import Callable
from typing import TYPE_CHECKING

import numpy as np
from geometry_msgs.msg import PoseStamped
from sensor_msgs.msg import JointState, PointCloud2
from visualization_msgs.msg import MarkerArray

from clew_ros.core.errors import WorldError
from clew_ros.core.settings import Outcome
from clew_ros.node.run_recording import NO_RECORDING
from clew_ros.ros import spatial as spatial_messages
from clew_ros.ros.qos import CLOUD_QOS, STATE_QOS
from clew_ros.ros.state_messages import (
    StateInputError,
    apply_markers,
    cloud_xyz,
    joint_positions,
    object_matrix,
    stamp_ns,
)
from clew_ros.spatial.scene import make_obstacle
from clew_ros.spatial.snapshot import AddedObstacle, SnapError, WorldState, snap_object_pose
from clew_ros.spatial.transforms import pose_matrix
from clew_ros.spatial.voxels import occupied_cubes

if TYPE_CHECKING:
    from rclpy.callback_groups import CallbackGroup
    from rclpy.node import Node

    from clew_ros.node.publishing import Publishing
    from clew_ros.node.run import Run
    from clew_ros.ros.parameters import Configuration, NodeSettings
    from clew_ros.spatial.robot import RobotModel
    from clew_ros.spatial.scene import Obstacle
    from clew_ros.spatial.spheres import SphereModel
    from clew_ros.spatial.world import SpatialWorld

__all__ = ["LiveState", "StateRefusalError", "describe_inputs"]


class StateRefusalError(Exception):
    """A run that cannot start from the state of the moment: its outcome ``code`` and the message."""

    def __init__(self, code: Outcome, message: str) -> None:
        super().__init__(message)
        self.code = code
        self.message = message


def _enabled(settings: NodeSettings) -> bool:
    return any(
        (
            settings.state_joint_states,
            settings.state_object_pose,
            settings.state_obstacles,
            settings.state_points,
            settings.state_advance,
        )
    )


class LiveState:
    """The ``state.*`` inputs of ``node`` (module docstring); inert when none is on."""

    #: How often (s) a change is looked for and ``~/world_markers`` republished (interface.md: within 0.5 s).
    markers_period_s = 0.2
    #: How far (rad, or m) a fixed joint's state may lie from the world's value and the world's arm model be kept
    #: (another value reloads the arm's model, which takes seconds; a gripper's jitter must not).
    fixed_tolerance = 1e-4

    def __init__(
        self,
        node: Node,
        config: Configuration,
        out: Publishing,
        group: CallbackGroup,
        current_run: Callable[[], Run | None] = lambda: None,
    ) -> None:
        self._node = node
        self._current_run = current_run  # the node's last accepted run: where state.advance left the arm
        self._config = config
        self._out = out
        self._logger = node.get_logger()
        self._lock = threading.Lock()
        self._joints: dict[str, tuple[float, int]] = {}  # name -> (position, stamp ns on the node's clock)
        self._object: tuple[np.ndarray, float] | None = None  # (4x4 pose, received at time.monotonic())
        self._obstacles: dict[str, AddedObstacle] = {}
        self._cubes: np.ndarray | None = None
        self._models: dict[tuple[tuple[str, int], ...], tuple[RobotModel, SphereModel]] = {}  # by fixed joints
        self._dirty = False
        settings = config.node
        self.enabled = _enabled(settings)  # only in a spatial world (ros.parameters checks it)
        if settings.state_joint_states:
            node.create_subscription(JointState, "joint_states", self._on_joints, STATE_QOS, callback_group=group)
        if settings.state_object_pose:
            node.create_subscription(PoseStamped, "~/object", self._on_object, STATE_QOS, callback_group=group)
        if settings.state_obstacles:
            node.create_subscription(MarkerArray, "~/obstacles", self._on_obstacles, STATE_QOS, callback_group=group)
        if settings.state_points:
            node.create_subscription(PointCloud2, "~/points", self._on_points, CLOUD_QOS, callback_group=group)
        if settings.state_object_pose or settings.state_obstacles or settings.state_points:
            node.create_timer(self.markers_period_s, self._on_timer, callback_group=group)

    @property
    def _world(self) -> SpatialWorld:
        return self._config.world  # type: ignore[return-value]  # a spatial world (checked at start)

    # ------------------------------------------------------------------ inputs

    def _on_joints(self, msg: JointState) -> None:
        stamp = stamp_ns(msg.header) or self._out.now_ns()
        positions = joint_positions(msg)
        with self._lock:
            for name, value in positions.items():
                self._joints[name] = (value, stamp)

    def _on_object(self, msg: PoseStamped) -> None:
        try:
            pose = object_matrix(msg)
        except StateInputError as error:
            self._logger.warning(f"{error}; the previous object pose stays")
            return
        with self._lock:
            self._object = (pose, time.monotonic())
            self._dirty = True

    def _on_obstacles(self, msg: MarkerArray) -> None:
        reserved = frozenset(o.name for o in self._world.obstacles)
        with self._lock:
            self._obstacles, refused = apply_markers(msg, self._obstacles, reserved)
            self._dirty = True
        for line in refused:
            self._logger.warning(f"{line}; refused (the other markers apply)")

    def _on_points(self, msg: PointCloud2) -> None:
        settings = self._config.node
        try:
            points = cloud_xyz(msg, settings.state_max_points)
        except StateInputError as error:  # one line a refused message (at most one every 5 s)
            self._logger.warning(f"{error}; the previous cloud stays", throttle_duration_sec=5.0)
            return
        world, previous = self._world, self._current_run()
        with self._lock:
            joints = self._start_joints(previous)
            thing = self._object_obstacle(self._object_pose_now(previous))
            added = [_as_obstacle(o) for o in self._obstacles.values()]
        cubes = occupied_cubes(
            points,
            voxel_m=settings.state_voxel_m,
            grow_m=settings.state_self_filter_m,
            sphere_centers=world.checker.sphere_positions(joints.tolist()),
            sphere_radii=world.spheres.radii,
            solids=[*world.obstacles, *added, *([thing] if thing is not None else [])],
            bounds=world.bounds,
        )
        with self._lock:
            self._cubes = cubes
            self._dirty = True

    def _on_timer(self) -> None:
        with self._lock:
            dirty, self._dirty = self._dirty, False
        if not dirty:
            return
        try:
            config = self._build(self._config, self._state(self._current_run(), strict=False))
        except (StateRefusalError, WorldError) as error:
            self._logger.warning(f"~/world_markers: the current state cannot be shown: {error}")
            return
        markers = spatial_messages.world_markers(config.world, self._out.now_ns())  # type: ignore[arg-type]
        self._out.publish("world_markers", markers, NO_RECORDING)

    # ------------------------------------------------------------------ the snapshot

    def snapshot(self, config: Configuration, previous: Run | None) -> Configuration:
        """The configuration a run accepted now plans in (``config`` itself when no input is on); raises
        :class:`StateRefusalError` when the state cannot be planned from."""
        if not self.enabled:
            return config
        return self._build(config, self._state(previous, strict=True))

    def _state(self, previous: Run | None, *, strict: bool) -> WorldState:
        with self._lock:
            initial = self._start_joints(previous, strict=strict)
            fixed = self._fixed_joints()
            pose = self._object_pose_now(previous)
            obstacles = tuple(self._obstacles.values())
            cubes = self._cubes
        settings = self._config.node
        snapped: tuple[float, ...] | None = None
        world = self._world
        if pose is not None and world.object is not None:
            try:
                snapped = snap_object_pose(
                    world.object.shape,
                    pose,
                    world.supports,
                    snap_m=settings.state_snap_m,
                    snap_rad=settings.state_snap_rad,
                )
            except SnapError as error:
                if strict:
                    raise StateRefusalError(
                        Outcome.INVALID_WORLD, f"object: not near a stable placement: {error}"
                    ) from None
        return WorldState(
            initial=tuple(float(v) for v in initial),
            fixed=fixed,
            object_pose=snapped,
            obstacles=obstacles,
            cubes=cubes,
            cube_m=settings.state_voxel_m,
        )

    def _start_joints(self, previous: Run | None, *, strict: bool = False) -> np.ndarray:
        """The planned joints at the start (under the lock): joint_states, else where ``previous`` left the arm
        (state.advance), else world.robot.initial."""
        world, settings = self._world, self._config.node
        if settings.state_joint_states:
            names = world.robot.joint_names
            now = self._out.now_ns()
            missing = [n for n in names if n not in self._joints]
            if not missing:
                age = max((now - self._joints[n][1]) * 1e-9 for n in names)
                if age <= settings.state_max_age_s or not strict:
                    return np.array([self._joints[n][0] for n in names])
                raise StateRefusalError(
                    Outcome.START_STATE_UNKNOWN,
                    f"the latest joint state is {age:.3f} s old (state.max_age {settings.state_max_age_s} s)",
                )
            if strict:
                heard = "no joint state has come" if not self._joints else "the joint states lack them"
                raise StateRefusalError(
                    Outcome.START_STATE_UNKNOWN,
                    f"no state of joints {', '.join(missing)} on {self._joint_topic()} ({heard})",
                )
        end = _run_end(previous) if settings.state_advance else None
        return np.asarray(world.initial if end is None else end[0], dtype=float)

    def _joint_topic(self) -> str:
        namespace = self._node.get_namespace().rstrip("/")
        return f"{namespace}/joint_states"

    def _fixed_joints(self) -> dict[str, float]:
        """The fixed joints' positions joint_states gives that differ from the world's by more than
        :attr:`fixed_tolerance`, rounded to a multiple of it (under the lock)."""
        fixed, step = self._world.robot.fixed_positions, self.fixed_tolerance
        # on a grid of fixed_tolerance: the arm's model kept for a value is the model of the value written
        changed = {n: p for n, (p, _) in self._joints.items() if n in fixed and abs(p - fixed[n]) > step}
        return {n: round(p / step) * step for n, p in changed.items()}

    def _object_pose_now(self, previous: Run | None) -> np.ndarray | None:
        """The object's pose (4x4) at the start, ``None``: the parameters' (under the lock): ~/object, unless
        state.advance and ``previous`` was accepted after it came."""
        end = _run_end(previous) if self._config.node.state_advance else None
        if self._object is not None and (end is None or previous is None or self._object[1] > previous.start_s):
            return self._object[0]
        if end is not None and end[1] is not None:
            return pose_matrix(list(end[1]))
        return None

    def _object_obstacle(self, pose: np.ndarray | None) -> Obstacle | None:
        thing = self._world.object
        if thing is None:
            return None
        where = pose if pose is not None else pose_matrix(list(thing.initial))
        return make_obstacle("object", thing.shape.shape, thing.shape.size, where, "world.object")

    def _build(self, config: Configuration, state: WorldState) -> Configuration:
        """``config`` with the world of ``state`` written into its parameter tree (module docstring)."""
        from clew_ros.spatial.snapshot import snapshot_tree
        from clew_ros.spatial.world import spatial_world_from_parameters

        setup, world = config.spatial, self._world
        assert setup is not None  # a spatial world (checked at start)
        robot = world.robot
        q = np.asarray(state.initial, dtype=float)
        outside = (q < robot.lower) | (q > robot.upper)
        if np.any(outside):
            j = int(np.argmax(outside))
            raise StateRefusalError(
                Outcome.START_IN_COLLISION,
                f"the start configuration is not valid: joint {robot.joint_names[j]} = {q[j]:.6g} is outside its "
                f"limits [{robot.lower[j]:.6g}, {robot.upper[j]:.6g}]",
            )
        tree = snapshot_tree(setup.tree, state)
        key = tuple(sorted((n, round(v / self.fixed_tolerance)) for n, v in state.fixed.items()))
        prepared = (robot, world.spheres) if not key else self._models.get(key)
        try:
            snapshot = spatial_world_from_parameters(tree, setup.folder, prepared=prepared)
        except WorldError as error:
            raise StateRefusalError(Outcome.INVALID_WORLD, f"the world as it is now is not valid: {error}") from None
        if key and prepared is None:  # the arm with these fixed joints: kept for the next runs (the last one only)
            self._models = {key: (snapshot.robot, snapshot.spheres)}
        return dataclasses.replace(config, world=snapshot, spatial=dataclasses.replace(setup, tree=tree))


def _run_end(run: Run | None) -> tuple[np.ndarray, tuple[float, ...] | None] | None:
    """Where ``run`` left the arm and the object: its plan's end after a success, else its start."""
    if run is None:
        return None
    if run.end_state is not None:
        return run.end_state
    world: SpatialWorld = run.config.world  # type: ignore[assignment]  # state.* needs a spatial world
    return np.asarray(world.initial), None if world.object is None else tuple(world.object.initial)


def _as_obstacle(added: AddedObstacle) -> Obstacle:
    return make_obstacle(added.name, added.shape, added.size, pose_matrix(list(added.pose)), "obstacles")


def describe_inputs(settings: NodeSettings) -> str:
    """The inputs on, for the node's start log line ("" when none)."""
    names = [
        name
        for name, on in (
            ("joint_states", settings.state_joint_states),
            ("~/object", settings.state_object_pose),
            ("~/obstacles", settings.state_obstacles),
            ("~/points", settings.state_points),
            ("state.advance", settings.state_advance),
        )
        if on
    ]
    return f"; planning from the world as it is now ({', '.join(names)})" if names else ""
