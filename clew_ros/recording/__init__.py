"""Recordings of planning runs (interface.md section 4).

Each run is a rosbag2 directory ``<record dir>/<run id>/`` holding
``metadata.yaml`` (rosbag2 version 9, as ROS 2 Jazzy writes it) and one MCAP
file ``<run id>_0.mcap``: schema encoding ``ros2msg`` with the full dependency
text, message encoding ``cdr``, each topic with the QoS it was offered with.
Foxglove, ``ros2 bag``, ``rosbags`` and the ``mcap`` readers open it. The
messages are encoded by rclpy's serializer and ``rosbags``
(:mod:`~clew_ros.recording.cdr`); the schema texts are rosbag2's
(:mod:`~clew_ros.recording.msgdefs`). ``/tf`` and ``/tf_static``
(``tf2_msgs/msg/TFMessage``) are recorded without ``tf2_msgs`` installed:
rosbags knows the type (:func:`~clew_ros.recording.cdr.tf_message`).

- :class:`RunRecorder` writes a run from the node without ever blocking it
  (the node holds it through :mod:`clew_ros.node.run_recording`, which
  records nothing when recording is off or cannot be done).
- :class:`Recording` reads one back (also one cut short by a killed writer);
  :func:`recover_recording` rewrites such a file whole.
- :func:`trajectory_to_plan` rebuilds the plan from a recorded trajectory.

Importing this package needs no rclpy; :class:`RunRecorder` needs rclpy,
``mcap`` and ``rosbags`` (without them the node plans but does not record).
"""

from clew_ros.recording.errors import RecordingError, TrajectoryError
from clew_ros.recording.reader import (
    RecordedMessage,
    Recording,
    RecordingLimits,
    TopicInfo,
    find_mcap,
    recover_recording,
)
from clew_ros.recording.recorder import (
    ROSBAG2_VERSION,
    TRANSIENT_LOCAL_TOPICS,
    RunRecorder,
    default_offered_qos,
)
from clew_ros.recording.trajectory import GRIPPER_JOINT, spatial_trajectory_plan, trajectory_to_plan

__all__ = [
    "GRIPPER_JOINT",
    "ROSBAG2_VERSION",
    "TRANSIENT_LOCAL_TOPICS",
    "RecordedMessage",
    "Recording",
    "RecordingError",
    "RecordingLimits",
    "RunRecorder",
    "TopicInfo",
    "TrajectoryError",
    "default_offered_qos",
    "find_mcap",
    "recover_recording",
    "spatial_trajectory_plan",
    "trajectory_to_plan",
]
