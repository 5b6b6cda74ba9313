"""The timed form of a plan: trajectory points, grasp events and playback samples.

Pure NumPy over the core's :class:`~clew_ros.core.plan.Plan` and kinematics;
no rclpy, so it is tested without a ROS graph. ``messages`` turns a
:class:`Track` into a ``JointTrajectory``; the node samples it in time to
publish ``~/joint_states`` and ``~/object_pose``.

Timing (interface.md §3 leaves it to us, README documents it):

- the first point is at ``t = 0``;
- a move between two points of one segment lasts
  ``max_i |dq_i| / joint_speed_rad_s`` (every joint moves at most at that
  speed, all joints arrive together);
- a grasp or an ungrasp (two points with the same joints and a different
  ``gripper``) lasts ``grasp_dwell_s``;
- every step lasts at least :data:`MIN_STEP_NS` so that ``time_from_start``
  increases strictly even between nearly equal points.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from clew_ros.core.kinematics import compose, tip_poses
from clew_ros.core.plan import Plan, replay
from clew_ros.core.world import World

__all__ = ["GRIPPER_JOINT", "MIN_STEP_NS", "GripperEvent", "Track", "track_from_plan"]

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
class Track:
    """A plan as timed points; sampled by :meth:`sample` for playback.

    ``times_ns`` (P,), ``positions`` (P, n) rad, ``gripper`` (P,) 0.0 / 1.0,
    ``object_poses`` (P, 3) the object's pose at each point, ``segment`` (P,)
    the plan segment each point belongs to, ``grasp_rel`` the held object's
    pose in the end-effector frame per segment (``None`` for transit).
    """

    joint_names: list[str]
    times_ns: np.ndarray
    positions: np.ndarray
    gripper: np.ndarray
    object_poses: np.ndarray
    segment: np.ndarray
    grasps: list[int | None]
    grasp_rel: list[np.ndarray | None]
    tip_pose_fn: Callable[[np.ndarray], np.ndarray]  # (N, n) -> (N, 3), the robot's tip poses

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

    def sample(self, t_s: float) -> tuple[np.ndarray, float, np.ndarray]:
        """``(joints (n,), gripper, object_pose (3,))`` at ``t_s`` seconds (clamped to the track).

        Joints move linearly between points; the gripper holds the value of the
        last point reached; the object rests, or follows the end effector
        between two points of one transfer segment.
        """
        t_ns = float(np.clip(t_s * 1e9, 0.0, float(self.times_ns[-1])))
        k = int(np.searchsorted(self.times_ns, t_ns, side="right")) - 1
        if k >= len(self.times_ns) - 1:
            return self.positions[-1].copy(), float(self.gripper[-1]), self.object_poses[-1].copy()
        span = float(self.times_ns[k + 1] - self.times_ns[k])
        alpha = (t_ns - float(self.times_ns[k])) / span
        q = self.positions[k] + alpha * (self.positions[k + 1] - self.positions[k])
        same_transfer = self.segment[k] == self.segment[k + 1] and self.grasp_rel[self.segment[k]] is not None
        if same_transfer:
            pose = compose(self.tip_pose_fn(q[None])[0], self.grasp_rel[self.segment[k]])
        else:
            pose = self.object_poses[k].copy()
        return q, float(self.gripper[k]), pose


def track_from_plan(world: World, plan: Plan, *, joint_speed_rad_s: float = 1.0, grasp_dwell_s: float = 0.2) -> Track:
    """Time a successful plan (its ``segments``) for ``world``.

    Raises ``ValueError`` for a plan without segments.
    """
    if joint_speed_rad_s <= 0 or grasp_dwell_s <= 0:
        raise ValueError("joint_speed_rad_s and grasp_dwell_s must be > 0")
    if not plan.segments:
        raise ValueError("a plan without segments has no trajectory")
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
            step_s = grasp_dwell_s
        else:
            step_s = float(np.max(np.abs(positions_a[k] - positions_a[k - 1]))) / joint_speed_rad_s
        times[k] = times[k - 1] + max(MIN_STEP_NS, round(step_s * 1e9))
    return Track(
        joint_names=[*list(robot.joint_names), GRIPPER_JOINT],
        times_ns=times,
        positions=positions_a,
        gripper=gripper_a,
        object_poses=np.array(poses),
        segment=np.array(seg_index),
        grasps=grasps,
        grasp_rel=grasp_rel,
        tip_pose_fn=tips,
    )
