"""The node's topics (interface.md §3): each ``~/<name>`` with its message type and QoS, and the TF topics.

The node creates its publishers from :data:`TOPICS` and :data:`TF_TOPICS`; its recordings (made live or
offline, ``clew_batch --record``) record each topic with the QoS given here.
"""

from __future__ import annotations

from action_msgs.msg import GoalStatusArray
from diagnostic_msgs.msg import DiagnosticStatus
from geometry_msgs.msg import PoseStamped
from rclpy.qos import QoSProfile
from sensor_msgs.msg import JointState
from std_msgs.msg import String
from trajectory_msgs.msg import JointTrajectory
from visualization_msgs.msg import MarkerArray

from clew_ros.ros.qos import EVENTS_QOS, LATCHED_QOS, STREAM_QOS, TF_QOS, TF_STATIC_QOS

__all__ = ["TF_TOPICS", "TOPICS"]

#: The node's published topics (``~/<name>``): message type and QoS.
TOPICS: dict[str, tuple[type, QoSProfile]] = {
    "status": (GoalStatusArray, LATCHED_QOS),
    "feedback": (DiagnosticStatus, STREAM_QOS),
    "trajectory": (JointTrajectory, LATCHED_QOS),
    "joint_states": (JointState, STREAM_QOS),
    "object_pose": (PoseStamped, STREAM_QOS),
    "events": (String, EVENTS_QOS),
    "landmarks": (MarkerArray, LATCHED_QOS),
    "world_markers": (MarkerArray, LATCHED_QOS),
    "world_yaml": (String, LATCHED_QOS),
    "robot_description": (String, LATCHED_QOS),
    "scene": (MarkerArray, STREAM_QOS),
}
#: The TF topics (absolute names, as tf2 wants them) and their QoS; type ``tf2_msgs/msg/TFMessage``.
TF_TOPICS: dict[str, QoSProfile] = {"/tf": TF_QOS, "/tf_static": TF_STATIC_QOS}
