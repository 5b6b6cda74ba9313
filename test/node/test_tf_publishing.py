"""``/tf``: one message for the recording and the live topic.

:meth:`Publishing.publish_tf` encodes the transforms once (:func:`clew_ros.recording.cdr.tf_message`,
rosbags) and hands the same bytes to the run's recording and to the ``/tf`` publisher, which rclpy
publishes as they are (the PyPI wheels have no ``tf2_msgs``; where it is installed the publisher is a
``TFMessage`` one). The mechanism is checked end to end with a type the wheels have: bytes made by
rosbags, published by rclpy, arrive as the message.
"""

from __future__ import annotations

import threading
from pathlib import Path

import pytest

rclpy = pytest.importorskip("rclpy")
pytest.importorskip("mcap")
pytest.importorskip("rosbags.typesys")

from helpers.node_harness import wait_until  # noqa: E402
from mcap.reader import make_reader  # noqa: E402
from rclpy.executors import SingleThreadedExecutor  # noqa: E402
from rclpy.qos import QoSDurabilityPolicy, QoSProfile, QoSReliabilityPolicy  # noqa: E402
from rosbags.typesys import Stores, get_typestore  # noqa: E402
from std_msgs.msg import String  # noqa: E402

from clew_ros.node.publishing import Publishing  # noqa: E402
from clew_ros.node.run_recording import BagRecording  # noqa: E402
from clew_ros.recording import RunRecorder  # noqa: E402
from clew_ros.recording.cdr import TF_MESSAGE_TYPE, tf_message  # noqa: E402
from clew_ros.ros.frames import FrameTransform  # noqa: E402

pytestmark = pytest.mark.ros

EDGES = [FrameTransform("world", "base_link", 0.5, -0.25, 0.0), FrameTransform("base_link", "link_1", 0.0, 0.0, 1.0)]


@pytest.fixture
def context():
    context = rclpy.Context()
    rclpy.init(context=context)
    try:
        yield context
    finally:
        context.try_shutdown()


class _Publisher:
    """Stands in for the ``TFMessage`` publisher where ``tf2_msgs`` is not installed: keeps what it is given."""

    def __init__(self) -> None:
        self.published: list[object] = []

    def publish(self, msg: object) -> None:
        self.published.append(msg)


def test_publish_tf_records_and_publishes_the_same_bytes(context, tmp_path: Path) -> None:
    node = rclpy.create_node("tf_publishing", context=context)
    try:
        publishing = Publishing(node, threading.Event())
        publisher = _Publisher()
        publishing._tf_publishers = {"/tf": publisher}  # noqa: SLF001 - what have_tf2_msgs() would have made
        recorder = RunRecorder(tmp_path, "run")
        failures: list[str] = []
        recording = BagRecording(recorder, failures.append)
        publishing.publish_tf(EDGES, 1_700_000_000_000_000_007, recording)
        recording.close()
    finally:
        node.destroy_node()
    assert failures == []
    with (recorder.path / "run_0.mcap").open("rb") as stream:
        recorded = [(c.topic, m.data) for _s, c, m in make_reader(stream).iter_messages()]
    expected = tf_message(EDGES, 1_700_000_000_000_000_007).data
    assert recorded == [("/tf", expected)]
    assert publisher.published == [expected]
    assert type(publisher.published[0]) is bytes  # rclpy's Publisher.publish takes bytes as a serialized message


def test_rclpy_publishes_rosbags_bytes_as_the_message(context) -> None:
    typestore = get_typestore(Stores.ROS2_JAZZY)
    data = bytes(
        typestore.serialize_cdr(typestore.types["std_msgs/msg/String"](data="from rosbags"), "std_msgs/msg/String")
    )
    node = rclpy.create_node("raw_bytes", context=context)
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(node)
    received: list[str] = []
    qos = QoSProfile(depth=1, reliability=QoSReliabilityPolicy.RELIABLE, durability=QoSDurabilityPolicy.TRANSIENT_LOCAL)
    try:
        publisher = node.create_publisher(String, "raw_bytes", qos)
        node.create_subscription(String, "raw_bytes", lambda msg: received.append(msg.data), qos)
        publisher.publish(data)

        def arrived() -> bool:
            executor.spin_once(timeout_sec=0.05)
            return bool(received)

        wait_until(arrived, 20.0, "the String published as bytes")
    finally:
        executor.shutdown()
        node.destroy_node()
    assert received == ["from rosbags"]
    assert TF_MESSAGE_TYPE in typestore.types  # what tf_message encodes: rosbags knows it without tf2_msgs
