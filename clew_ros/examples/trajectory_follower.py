"""Follow the planner's ``~/trajectory`` in time and publish joint states: a stand-in for
``joint_trajectory_controller``.

    python -m clew_ros.examples.trajectory_follower [--planner /clew_planner] [--count N] [--rate HZ]

Subscribes to ``<planner>/trajectory`` (transient-local, as the planner
offers it) and, for each trajectory, steps through its points in time and
publishes ``~/joint_states`` (the trajectory's joints: a planar arm's and
``gripper``, or a spatial world's planned URDF joints) at ``--rate``. Prints
``following <topic>`` once the planner is found, then one line per
trajectory followed, ``followed 12 points over 3.42 s, 2 grasps`` (a spatial
trajectory has no ``gripper``: its grasps are the planner's ``grasp`` events,
and the line ends at the time), and exits after ``--count`` trajectories
(0: runs until Ctrl-C). Between points it interpolates as
``joint_trajectory_controller`` does: quintic splines when the points carry
velocities and accelerations (the planner's do: every point at rest, so the
arm moves along the straight segment between them), linearly otherwise; the
``gripper`` switches at a point, it does not slide.
"""

from __future__ import annotations

import argparse
import sys

import numpy as np
import rclpy
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node
from sensor_msgs.msg import JointState
from trajectory_msgs.msg import JointTrajectory

from clew_ros.motion.playback import GRIPPER_JOINT
from clew_ros.motion.timing import quintic_spline
from clew_ros.ros.qos import LATCHED_QOS, STREAM_QOS


class TrajectoryFollower(Node):
    """Plays each received ``JointTrajectory`` on ``~/joint_states``, as a controller would execute it."""

    def __init__(self, planner: str = "/clew_planner", rate_hz: float = 50.0) -> None:
        super().__init__("clew_trajectory_follower")
        self.followed = 0
        self._trajectory: JointTrajectory | None = None
        self._times_s = np.zeros(0)
        self._positions = np.zeros((0, 0))
        self._rates: tuple[np.ndarray, np.ndarray] | None = None  # velocities, accelerations: quintic splines
        self._gripper = False  # the last joint is the planar gripper
        self._started_s = 0.0
        self._states = self.create_publisher(JointState, "~/joint_states", STREAM_QOS)
        self._subscription = self.create_subscription(
            JointTrajectory, f"{planner.rstrip('/')}/trajectory", self._on_trajectory, LATCHED_QOS
        )
        self._announced = False
        self.create_timer(1.0 / rate_hz, self._step)

    def _now_s(self) -> float:
        return self.get_clock().now().nanoseconds * 1e-9

    def _on_trajectory(self, msg: JointTrajectory) -> None:
        if not msg.points:
            return
        self._trajectory = msg
        self._times_s = np.array([p.time_from_start.sec + 1e-9 * p.time_from_start.nanosec for p in msg.points])
        self._positions = np.array([list(p.positions) for p in msg.points], dtype=float)
        self._gripper = bool(msg.joint_names) and msg.joint_names[-1] == GRIPPER_JOINT
        width = self._positions.shape[1]
        complete = all(len(p.velocities) == len(p.accelerations) == width for p in msg.points)
        self._rates = None
        if complete:
            velocities = np.array([list(p.velocities) for p in msg.points], dtype=float)
            self._rates = (velocities, np.array([list(p.accelerations) for p in msg.points], dtype=float))
        self._started_s = self._now_s()

    def _step(self) -> None:
        if not self._announced and self._subscription.get_publisher_count() > 0:
            self._announced = True
            print(f"following {self._subscription.topic_name}", flush=True)
        if self._trajectory is None:
            return
        t = self._now_s() - self._started_s
        k = int(np.searchsorted(self._times_s, t, side="right")) - 1
        if k >= len(self._times_s) - 1:
            positions = self._positions[-1]
        elif self._rates is not None:
            positions = quintic_spline(self._times_s, self._positions, *self._rates, np.array([t]))[0]
            if self._gripper:
                positions[-1] = self._positions[k][-1]  # the gripper switches, it does not slide
        else:
            alpha = (t - self._times_s[k]) / (self._times_s[k + 1] - self._times_s[k])
            positions = self._positions[k] + alpha * (self._positions[k + 1] - self._positions[k])
            if self._gripper:
                positions[-1] = self._positions[k][-1]  # the gripper switches, it does not slide
        state = JointState(name=list(self._trajectory.joint_names), position=positions.tolist())
        state.header.stamp = self.get_clock().now().to_msg()
        self._states.publish(state)
        if k >= len(self._times_s) - 1:
            text = f"followed {len(self._times_s)} points over {self._times_s[-1]:.2f} s"
            if self._gripper:
                text += f", {int(np.sum(np.diff(self._positions[:, -1]) > 0.5))} grasps"
            self.get_logger().info(text)
            print(text, flush=True)
            self.followed += 1
            self._trajectory = None


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="trajectory_follower", description=__doc__.splitlines()[0])
    parser.add_argument("--planner", default="/clew_planner", help="the planner node (default /clew_planner)")
    parser.add_argument("--count", type=int, default=0, help="exit after this many trajectories (0: never)")
    parser.add_argument("--rate", type=float, default=50.0, help="joint state rate (Hz, default 50)")
    args, ros_args = parser.parse_known_args(argv)
    rclpy.init(args=ros_args)
    node = TrajectoryFollower(args.planner, args.rate)
    try:
        while rclpy.ok() and (args.count == 0 or node.followed < args.count):
            rclpy.spin_once(node, timeout_sec=0.1)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        node.destroy_node()
        rclpy.try_shutdown()
    return 0


if __name__ == "__main__":
    sys.exit(main())
