"""Send a planner the world as it is now before a goal (interface.md section 3c): the arm's start state on its
``joint_states`` and the object's pose on its ``~/object``, each taken before the goal that follows.

:class:`StateSender` makes its publishers on first use (a client that never sends a start state advertises
no ``joint_states``), waits until the planner listens, publishes, and waits until the planner has acknowledged
the message: the planner takes its inputs and its goals in one callback group, in order, so a goal sent after
that plans from this state.
"""

from __future__ import annotations

import math
import time
from collections.abc import Mapping, Sequence
from typing import Any, TypeAlias

from geometry_msgs.msg import PoseStamped
from rclpy.duration import Duration
from rclpy.node import Node
from sensor_msgs.msg import JointState

from clew_ros.client.run import PlannerNotFoundError
from clew_ros.ros.qos import STATE_QOS

__all__ = ["StartState", "StateSender"]

#: A start state: a ``JointState``, or joint name -> position (rad, or m for a prismatic joint).
StartState: TypeAlias = JointState | Mapping[str, float]


class StateSender:
    """Publishes start states on ``joint_states_topic`` and object poses on ``<planner>/object`` from ``node``;
    each send waits at most ``timeout_s`` for the planner to listen and to acknowledge."""

    def __init__(self, node: Node, planner: str, joint_states_topic: str, timeout_s: float = 5.0) -> None:
        self._node = node
        self._topics = {"joints": joint_states_topic, "object": f"{planner}/object"}
        self._publishers: dict[str, Any] = {}
        self.timeout_s = timeout_s

    def send_start(self, start: StartState, stamp_ns: int) -> None:
        """Publish ``start`` stamped ``stamp_ns`` (a ``JointState`` keeps its names and positions)."""
        if isinstance(start, JointState):
            names, positions = list(start.name), [float(v) for v in start.position]
        else:
            names, positions = list(start), [float(v) for v in start.values()]
        if len(names) != len(positions) or not all(math.isfinite(v) for v in positions):
            raise ValueError("start: expected a finite position for every joint named")
        msg = JointState(name=names, position=positions)
        msg.header.stamp.sec, msg.header.stamp.nanosec = divmod(stamp_ns, 10**9)
        self._send("joints", JointState, msg, "state.joint_states")

    def send_object(self, pose: Sequence[float] | PoseStamped, stamp_ns: int) -> None:
        """Publish the object's pose (``x, y, z, roll, pitch, yaw`` in ``world``, or a ``PoseStamped``)."""
        if isinstance(pose, PoseStamped):
            msg = pose
        else:
            from clew_ros.ros.spatial import pose_stamped

            values = [float(v) for v in pose]
            if len(values) != 6:
                raise ValueError(f"object_pose: expected (x, y, z, roll, pitch, yaw), got {pose!r}")
            msg = pose_stamped(values, stamp_ns)
        msg.header.stamp.sec, msg.header.stamp.nanosec = divmod(stamp_ns, 10**9)
        self._send("object", PoseStamped, msg, "state.object_pose")

    def _send(self, key: str, msg_type: Any, msg: Any, parameter: str) -> None:
        publisher = self._publishers.get(key)
        if publisher is None:
            publisher = self._publishers[key] = self._node.create_publisher(msg_type, self._topics[key], STATE_QOS)
        deadline = time.monotonic() + self.timeout_s
        while publisher.get_subscription_count() == 0:
            if time.monotonic() > deadline:
                raise PlannerNotFoundError(
                    f"nobody subscribes to {self._topics[key]} within {self.timeout_s} s: is the planner's "
                    f"{parameter} true?"
                )
            time.sleep(0.01)
        publisher.publish(msg)
        if not publisher.wait_for_all_acked(Duration(seconds=max(0.0, deadline - time.monotonic()))):
            raise PlannerNotFoundError(f"the planner did not acknowledge {self._topics[key]} within {self.timeout_s} s")

    def destroy(self) -> None:
        for publisher in self._publishers.values():
            self._node.destroy_publisher(publisher)
        self._publishers.clear()
