"""The timed form of a plan: trajectory points, grasp events and playback samples.

Pure NumPy over the core's :class:`~clew_ros.core.plan.Plan` and kinematics;
no rclpy, so it is tested without a ROS graph. ``messages`` turns a
:class:`Track` into a ``JointTrajectory``; the node samples it in time to
publish ``~/joint_states`` and ``~/object_pose``.

Timing (interface.md §3 leaves it to us, docs/ros.md documents it):

- the points are the plan's waypoints (interface.md §3), the first at ``t = 0``;
- a move between two points of one segment is the rest-to-rest quintic of
  :mod:`~clew_ros.motion.timing`: it starts and ends at rest (zero velocity
  and acceleration), all joints move together along the straight segment,
  and it lasts the shortest time in which no joint exceeds its
  ``max_velocity_rad_s`` or ``max_acceleration_rad_s2`` (one limit for every
  joint, or one per joint);
- a grasp or an ungrasp (two points with the same joints and a different
  ``gripper``) lasts ``grasp_dwell_s``, the arm at rest;
- every step lasts at least :data:`MIN_STEP_NS` so that ``time_from_start``
  increases strictly even between nearly equal points; durations are rounded
  up to the nanosecond, so the limits hold for the times as published.

:meth:`Track.state` gives the joints and their velocities at any time (what
``~/joint_states`` carries). Every point is at rest: its velocities and accelerations are zero,
and a controller that interpolates the points with quintic splines
(``joint_trajectory_controller``) moves exactly as :meth:`Track.sample`.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from clew_ros.core.parameters import PLAYBACK_PARAMETERS
from clew_ros.core.plan import Plan
from clew_ros.motion.timing import profile, rest_to_rest_duration_s
from clew_ros.planar.kinematics import compose, tip_poses
from clew_ros.planar.plan import replay
from clew_ros.planar.world import World

__all__ = [
    "GRIPPER_JOINT",
    "MIN_STEP_NS",
    "GripperEvent",
    "Track",
    "TrackState",
    "TrackTiming",
    "node_track",
    "track_from_plan",
]

#: The joint after the arm's in ~/trajectory and ~/joint_states: 1.0 while grasping
#: (the name clew_ros.recording.GRIPPER_JOINT reads back; the node needs no recording package).
GRIPPER_JOINT = "gripper"

#: Shortest time between two trajectory points (ns).
MIN_STEP_NS = 1_000_000


@dataclass(frozen=True)
class GripperEvent:
    """A grasp (gripper 0 -> 1) or ungrasp (1 -> 0) at ``time_s`` since the trajectory start."""

    kind: str  # "grasp" or "ungrasp"
    grasp: int
    time_s: float
    point: int  # index of the trajectory point at which the gripper has its new value


@dataclass(frozen=True)
class TrackState:
    """The played-back state at one time: ``joints`` (n,) rad and their ``velocities`` (n,) rad/s (from the
    same timing), ``gripper`` 0.0 / 1.0 and the object's pose ``object_pose`` (3,)."""

    joints: np.ndarray
    velocities: np.ndarray
    gripper: float
    object_pose: np.ndarray


@dataclass(frozen=True)
class Track:
    """A plan as timed points; sampled by :meth:`sample` for playback.

    ``times_ns`` (P,), ``positions`` (P, n) rad, ``velocities`` (P, n) rad/s
    and ``accelerations`` (P, n) rad/s^2 (the profile at each point: zero,
    every point is at rest), ``gripper`` (P,) 0.0 / 1.0, ``object_poses``
    (P, 3) the object's pose at each point, ``segment`` (P,) the plan segment
    each point belongs to, ``grasp_rel`` the held object's
    pose in the end-effector frame per segment (``None`` for transit);
    ``max_velocity`` (n,) rad/s and ``max_acceleration`` (n,) rad/s^2 the
    limits it was timed with.
    """

    joint_names: list[str]
    times_ns: np.ndarray
    positions: np.ndarray
    velocities: np.ndarray
    accelerations: np.ndarray
    gripper: np.ndarray
    object_poses: np.ndarray
    segment: np.ndarray
    grasps: list[int | None]
    grasp_rel: list[np.ndarray | None]
    tip_pose_fn: Callable[[np.ndarray], np.ndarray]  # (N, n) -> (N, 3), the robot's tip poses
    max_velocity: np.ndarray
    max_acceleration: np.ndarray
    #: The held object's pose at joints ``q`` from ``grasp_rel`` (a spatial track's: 6 numbers); ``None``: the
    #: planar composition with ``tip_pose_fn``.
    held_pose_fn: Callable[[np.ndarray, np.ndarray], np.ndarray] | None = None
    #: Whether ``~/trajectory`` and ``~/joint_states`` carry the ``gripper`` joint after the arm's (planar
    #: worlds; a spatial world's trajectory carries the planned URDF joints only).
    gripper_joint: bool = True

    @property
    def duration_s(self) -> float:
        return float(self.times_ns[-1]) * 1e-9

    @property
    def times_s(self) -> np.ndarray:
        return self.times_ns * 1e-9

    def events(self) -> list[GripperEvent]:
        """Grasp and ungrasp events in time order (the plan's transfer segments, in order)."""
        out = []
        for k in range(1, len(self.gripper)):
            if self.gripper[k] == self.gripper[k - 1]:
                continue
            if self.gripper[k] > 0.5:
                out.append(GripperEvent("grasp", int(self.grasps[self.segment[k]]), self.times_s[k], k))
            else:
                out.append(GripperEvent("ungrasp", int(self.grasps[self.segment[k - 1]]), self.times_s[k], k))
        return out

    def joints_at(self, times_s: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(positions, velocities, accelerations)``, each (N, n), at ``times_s`` (N,) s (clamped to the track).

        Between two points the joints follow the rest-to-rest quintic of
        :mod:`~clew_ros.motion.timing` along the straight segment; before the
        first point and after the last the arm rests.
        """
        t_ns = np.clip(np.asarray(times_s, dtype=float).reshape(-1) * 1e9, 0.0, float(self.times_ns[-1]))
        last = len(self.times_ns) - 1
        k = np.clip(np.searchsorted(self.times_ns, t_ns, side="right") - 1, 0, max(last - 1, 0))
        if last == 0:
            zeros = np.zeros((len(t_ns), self.positions.shape[1]))
            return np.repeat(self.positions[:1], len(t_ns), axis=0), zeros, zeros.copy()
        span_s = (self.times_ns[k + 1] - self.times_ns[k]).astype(float) * 1e-9
        u = (t_ns - self.times_ns[k].astype(float)) * 1e-9 / span_s
        s, ds, dds = profile(u)
        delta = self.positions[k + 1] - self.positions[k]
        q = self.positions[k] + s[:, None] * delta
        dq = (ds / span_s)[:, None] * delta
        ddq = (dds / span_s**2)[:, None] * delta
        return q, dq, ddq

    def state(self, t_s: float) -> TrackState:
        """The state at ``t_s`` seconds (clamped to the track).

        Joints and velocities follow :meth:`joints_at`; the gripper holds the
        value of the last point reached; the object rests, or follows the end
        effector between two points of one transfer segment.
        """
        t_ns = float(np.clip(t_s * 1e9, 0.0, float(self.times_ns[-1])))
        k = int(np.searchsorted(self.times_ns, t_ns, side="right")) - 1
        if k >= len(self.times_ns) - 1:
            last = self.positions[-1]
            return TrackState(last.copy(), np.zeros_like(last), float(self.gripper[-1]), self.object_poses[-1].copy())
        joints, velocities, _ = self.joints_at(np.array([t_ns * 1e-9]))
        q = joints[0]
        same_transfer = self.segment[k] == self.segment[k + 1] and self.grasp_rel[self.segment[k]] is not None
        held = self.grasp_rel[self.segment[k]]
        if same_transfer and held is not None and self.held_pose_fn is not None:
            pose = self.held_pose_fn(q, held)
        elif same_transfer:
            pose = compose(self.tip_pose_fn(q[None])[0], held)
        else:
            pose = self.object_poses[k].copy()
        return TrackState(q, velocities[0], float(self.gripper[k]), pose)

    def sample(self, t_s: float) -> tuple[np.ndarray, float, np.ndarray]:
        """``(joints (n,), gripper, object_pose (3,))`` at ``t_s`` seconds: :meth:`state` without velocities."""
        state = self.state(t_s)
        return state.joints, state.gripper, state.object_pose


def track_from_plan(
    world: World,
    plan: Plan,
    *,
    max_velocity_rad_s: float | Sequence[float] = PLAYBACK_PARAMETERS.default("trajectory.max_velocity"),
    max_acceleration_rad_s2: float | Sequence[float] = PLAYBACK_PARAMETERS.default("trajectory.max_acceleration"),
    grasp_dwell_s: float = PLAYBACK_PARAMETERS.default("trajectory.grasp_dwell"),
) -> Track:
    """Time a successful plan (its ``segments``) for ``world``.

    ``max_velocity_rad_s`` and ``max_acceleration_rad_s2`` are one limit for
    every joint or one per joint. Raises ``ValueError`` for a plan without
    segments or a limit or dwell that is not > 0.
    """
    if not plan.segments:
        raise ValueError("a plan without segments has no trajectory")
    n = world.robot.dof
    try:
        max_velocity = np.broadcast_to(np.asarray(max_velocity_rad_s, dtype=float), (n,)).copy()
        max_acceleration = np.broadcast_to(np.asarray(max_acceleration_rad_s2, dtype=float), (n,)).copy()
    except ValueError:
        raise ValueError(f"the limits must be one number or one per joint ({n})") from None
    finite = np.all(np.isfinite(max_velocity)) and np.all(np.isfinite(max_acceleration))
    if not (finite and np.all(max_velocity > 0) and np.all(max_acceleration > 0) and grasp_dwell_s > 0):
        raise ValueError("the velocity and acceleration limits and grasp_dwell_s must be > 0")
    robot = world.robot

    def tips(q: np.ndarray) -> np.ndarray:
        return tip_poses(robot, q)

    positions: list[np.ndarray] = []
    poses: list[np.ndarray] = []
    gripper: list[float] = []
    seg_index: list[int] = []
    grasps: list[int | None] = []
    grasp_rel: list[np.ndarray | None] = []
    for motion in replay(world, plan, step_rad=None):
        transfer = motion.kind == "transfer"
        grasps.append(motion.grasp if transfer else None)
        grasp_rel.append(motion.grasp_rel)
        positions.extend(motion.configurations)
        gripper.extend([1.0 if transfer else 0.0] * len(motion.configurations))
        seg_index.extend([motion.index] * len(motion.configurations))
        poses.extend(np.array(motion.object_poses))

    positions_a = np.array(positions)
    gripper_a = np.array(gripper)
    times = np.zeros(len(positions_a), dtype=np.int64)
    for k in range(1, len(positions_a)):
        if gripper_a[k] != gripper_a[k - 1]:
            step_ns = round(grasp_dwell_s * 1e9)
        else:
            step_s = rest_to_rest_duration_s(positions_a[k] - positions_a[k - 1], max_velocity, max_acceleration)
            step_ns = math.ceil(step_s * 1e9)
        times[k] = times[k - 1] + max(MIN_STEP_NS, step_ns)
    return Track(
        joint_names=[*list(robot.joint_names), GRIPPER_JOINT],
        times_ns=times,
        positions=positions_a,
        velocities=np.zeros_like(positions_a),
        accelerations=np.zeros_like(positions_a),
        gripper=gripper_a,
        object_poses=np.array(poses),
        segment=np.array(seg_index),
        grasps=grasps,
        grasp_rel=grasp_rel,
        tip_pose_fn=tips,
        max_velocity=max_velocity,
        max_acceleration=max_acceleration,
    )


class TrackTiming(Protocol):
    """The ``trajectory.*`` settings a plan is timed with (the node's ``NodeSettings`` has them)."""

    @property
    def velocity_limit_rad_s(self) -> float | tuple[float, ...]: ...
    @property
    def max_acceleration_rad_s2(self) -> float | tuple[float, ...]: ...
    @property
    def grasp_dwell_s(self) -> float: ...


def node_track(world: World, plan: Plan, settings: TrackTiming) -> Track:
    """A successful plan timed as the node times it: with its ``trajectory.*`` settings."""
    return track_from_plan(
        world,
        plan,
        max_velocity_rad_s=settings.velocity_limit_rad_s,
        max_acceleration_rad_s2=settings.max_acceleration_rad_s2,
        grasp_dwell_s=settings.grasp_dwell_s,
    )
