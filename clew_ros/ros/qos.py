"""The QoS of each ``clew_planner`` topic (interface.md section 3), shared by the node and its clients."""

from __future__ import annotations

from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy

__all__ = ["CLOUD_QOS", "EVENTS_QOS", "GOAL_QOS", "LATCHED_QOS", "STATE_QOS", "STREAM_QOS", "TF_QOS", "TF_STATIC_QOS"]

#: Latched topics (~/status, ~/trajectory, ~/landmarks, ~/world_markers, ~/world_yaml, ~/robot_description):
#: a late subscriber gets the last message.
LATCHED_QOS = QoSProfile(
    depth=1,
    history=HistoryPolicy.KEEP_LAST,
    reliability=ReliabilityPolicy.RELIABLE,
    durability=DurabilityPolicy.TRANSIENT_LOCAL,
)
#: Streams (~/feedback, ~/joint_states, ~/object_pose, ~/scene).
STREAM_QOS = QoSProfile(
    depth=10,
    history=HistoryPolicy.KEEP_LAST,
    reliability=ReliabilityPolicy.RELIABLE,
    durability=DurabilityPolicy.VOLATILE,
)
#: ~/goal_pose: a burst of goals is queued, not dropped; each is answered (a run, or a BUSY refusal).
GOAL_QOS = QoSProfile(
    depth=100,
    history=HistoryPolicy.KEEP_LAST,
    reliability=ReliabilityPolicy.RELIABLE,
    durability=DurabilityPolicy.VOLATILE,
)
#: ~/events: every event of a run reaches a subscriber that keeps up.
EVENTS_QOS = QoSProfile(
    depth=100,
    history=HistoryPolicy.KEEP_LAST,
    reliability=ReliabilityPolicy.RELIABLE,
    durability=DurabilityPolicy.VOLATILE,
)
#: /tf, as tf2_ros's TransformBroadcaster offers it (DynamicBroadcasterQoS).
TF_QOS = QoSProfile(
    depth=100,
    history=HistoryPolicy.KEEP_LAST,
    reliability=ReliabilityPolicy.RELIABLE,
    durability=DurabilityPolicy.VOLATILE,
)
#: /tf_static, as tf2_ros's StaticTransformBroadcaster offers it (StaticBroadcasterQoS): latched.
TF_STATIC_QOS = QoSProfile(
    depth=1,
    history=HistoryPolicy.KEEP_LAST,
    reliability=ReliabilityPolicy.RELIABLE,
    durability=DurabilityPolicy.TRANSIENT_LOCAL,
)
#: The inputs of the world as it is now (joint_states, ~/object, ~/obstacles; interface.md section 3c): reliable,
#: as robot_state_publisher and RViz offer them, deep enough that a burst of obstacles is not dropped.
STATE_QOS = QoSProfile(
    depth=100,
    history=HistoryPolicy.KEEP_LAST,
    reliability=ReliabilityPolicy.RELIABLE,
    durability=DurabilityPolicy.VOLATILE,
)
#: ~/points: reliable, the latest only (a sensor that offers best effort only reaches it through a relay such as
#: topic_tools' relay with a reliable publisher: a cloud that a run plans among is never half lost).
CLOUD_QOS = QoSProfile(
    depth=1,
    history=HistoryPolicy.KEEP_LAST,
    reliability=ReliabilityPolicy.RELIABLE,
    durability=DurabilityPolicy.VOLATILE,
)
