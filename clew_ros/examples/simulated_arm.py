"""A simulated arm for the closed loop: it follows the planner's ``~/trajectory`` and publishes ``joint_states``
at 50 Hz, always, as a robot's driver does.

    python -m clew_ros.examples.simulated_arm --joints NAME=VALUE[,NAME=VALUE ...] [--planner /clew_planner]
                                              [--rate 50] [--speed 1.0]

Starts at rest at ``--joints`` (the planned joints' names and start values, e.g. a spatial world's
``world.robot.initial``) and publishes ``joint_states`` (relative: ``/joint_states`` unless remapped) at
``--rate``, stamped with the node's clock: a planner with ``state.joint_states`` plans from it. Each
``~/trajectory`` stamped after the arm started is followed in time (``--speed`` x real time), as
``joint_trajectory_controller`` interpolates it (quintic splines through the points' positions, velocities
and accelerations), joints it does not name kept where they are; at its end the arm rests at the last point
and prints ``at rest after N points over T s``.
"""

from __future__ import annotations

import argparse
import sys

import numpy as np
import rclpy
from builtin_interfaces.msg import Duration
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node
from sensor_msgs.msg import JointState
from trajectory_msgs.msg import JointTrajectory

from clew_ros.motion.timing import quintic_spline
from clew_ros.ros.qos import LATCHED_QOS, STATE_QOS

__all__ = ["SimulatedArm", "main"]


def _seconds(duration: Duration) -> float:
    return int(duration.sec) + 1e-9 * int(duration.nanosec)


class SimulatedArm(Node):
    """Joint states of an arm that starts at ``joints`` and follows the planner's trajectories."""

    def __init__(
        self, joints: dict[str, float], planner: str = "/clew_planner", rate_hz: float = 50.0, speed: float = 1.0
    ) -> None:
        super().__init__("clew_simulated_arm")
        self.names = list(joints)
        self.positions = np.array(list(joints.values()), dtype=float)
        self.rests = 0  # trajectories followed to their end
        self._speed = speed
        self._started_ns = self.get_clock().now().nanoseconds
        self._trajectory: tuple[list[int], np.ndarray, np.ndarray, np.ndarray, np.ndarray] | None = None
        self._since_s = 0.0
        self._states = self.create_publisher(JointState, "joint_states", STATE_QOS)
        self.create_subscription(JointTrajectory, f"{planner.rstrip('/')}/trajectory", self._on_trajectory, LATCHED_QOS)
        self.create_timer(1.0 / rate_hz, self._step)

    def _now_s(self) -> float:
        return self.get_clock().now().nanoseconds * 1e-9

    def _on_trajectory(self, msg: JointTrajectory) -> None:
        stamp_ns = msg.header.stamp.sec * 10**9 + msg.header.stamp.nanosec
        if not msg.points or stamp_ns < self._started_ns:
            return  # empty, or a trajectory of a run before the arm started (latched)
        columns = [self.names.index(n) for n in msg.joint_names if n in self.names]
        own = [k for k, n in enumerate(msg.joint_names) if n in self.names]
        times = np.array([_seconds(p.time_from_start) for p in msg.points])
        rows = [(list(p.positions), list(p.velocities), list(p.accelerations)) for p in msg.points]
        positions = np.array([r[0] for r in rows])[:, own]
        width = len(msg.joint_names)
        complete = all(len(r[1]) == len(r[2]) == width for r in rows)
        velocities = np.array([r[1] for r in rows])[:, own] if complete else np.zeros_like(positions)
        accelerations = np.array([r[2] for r in rows])[:, own] if complete else np.zeros_like(positions)
        self._trajectory = (columns, times, positions, velocities, accelerations)
        self._since_s = self._now_s()

    def _step(self) -> None:
        if self._trajectory is not None:
            columns, times, positions, velocities, accelerations = self._trajectory
            t = min((self._now_s() - self._since_s) * self._speed, float(times[-1]))
            self.positions[columns] = quintic_spline(times, positions, velocities, accelerations, np.array([t]))[0]
            if t >= times[-1]:
                self.positions[columns] = positions[-1]  # exactly the last point
                self._trajectory = None
                self.rests += 1
                print(f"at rest after {len(times)} points over {times[-1]:.2f} s", flush=True)
        state = JointState(name=self.names, position=self.positions.tolist())
        state.header.stamp = self.get_clock().now().to_msg()
        self._states.publish(state)


def _joints(text: str) -> dict[str, float]:
    try:
        pairs = [item.split("=", 1) for item in text.split(",")]
        return {name.strip(): float(value) for name, value in pairs}
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected NAME=VALUE[,NAME=VALUE ...], got {text!r}") from None


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="simulated_arm", description=__doc__.splitlines()[0])
    parser.add_argument("--joints", type=_joints, required=True, help="NAME=VALUE,...: the joints and the start")
    parser.add_argument("--planner", default="/clew_planner", help="the planner node (default /clew_planner)")
    parser.add_argument("--rate", type=float, default=50.0, help="joint state rate (Hz, default 50)")
    parser.add_argument("--speed", type=float, default=1.0, help="trajectory time scale (default 1: real time)")
    args, ros_args = parser.parse_known_args(argv)
    rclpy.init(args=ros_args)
    node = SimulatedArm(args.joints, args.planner, args.rate, args.speed)
    try:
        rclpy.spin(node)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        node.destroy_node()
        rclpy.try_shutdown()
    return 0


if __name__ == "__main__":
    sys.exit(main())
