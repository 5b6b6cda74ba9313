"""``tf2_msgs/msg/TFMessage`` recorded without tf2_msgs: :func:`tf_message` (rosbags) gives bytes that
an independent decoder (``mcap_ros2``, from the recorded schema text) reads as the transforms given, its
schema text and type hash are rosbag2's, and a recording of it reads back with rosbags and with
``mcap`` + ``mcap_ros2``.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import yaml

pytest.importorskip("rclpy")
pytest.importorskip("rosbags.rosbag2")

from mcap.reader import make_reader
from mcap_ros2._dynamic import generate_dynamic
from mcap_ros2.decoder import DecoderFactory
from rosbags.rosbag2 import Reader
from rosbags.typesys import Stores, get_typestore

from clew_ros.recording import RunRecorder
from clew_ros.recording.cdr import TF_MESSAGE_TYPE, SerializedMessage, tf_message
from clew_ros.recording.msgdefs import message_definition, type_description_hash
from clew_ros.ros.frames import FrameTransform

TYPESTORE = get_typestore(Stores.ROS2_JAZZY)
EDGES = [
    FrameTransform("world", "base_link", 0.25, -1.5, 0.0),
    FrameTransform("base_link", "link_1", 0.0, 0.0, 2.5),
    FrameTransform("link_1", "a_frame_with_a_longer_name", 1.0, 0.0, -math.pi / 3),
]


def _rosbags_tf(edges: list[FrameTransform], stamp_ns: int):
    types = TYPESTORE.types
    header = types["std_msgs/msg/Header"]
    time = types["builtin_interfaces/msg/Time"]
    stamped = types["geometry_msgs/msg/TransformStamped"]
    transform = types["geometry_msgs/msg/Transform"]
    vector = types["geometry_msgs/msg/Vector3"]
    quaternion = types["geometry_msgs/msg/Quaternion"]
    sec, nanosec = divmod(stamp_ns, 10**9)
    return types[TF_MESSAGE_TYPE](
        transforms=[
            stamped(
                header=header(stamp=time(sec=sec, nanosec=nanosec), frame_id=e.parent),
                child_frame_id=e.child,
                transform=transform(translation=vector(*e.translation), rotation=quaternion(*e.rotation)),
            )
            for e in edges
        ]
    )


@pytest.mark.parametrize("count", [0, 1, 2, 3])
def test_tf_message_reads_back_with_an_independent_decoder(count: int) -> None:
    stamp_ns = 1_700_000_000_123_456_789
    message = tf_message(EDGES[:count], stamp_ns)
    assert message.type_name == "tf2_msgs/msg/TFMessage"
    assert message.data == bytes(TYPESTORE.serialize_cdr(_rosbags_tf(EDGES[:count], stamp_ns), TF_MESSAGE_TYPE))
    assert message.data == tf_message(EDGES[:count], stamp_ns).data  # same transforms, same bytes
    decoded = generate_dynamic(TF_MESSAGE_TYPE, message_definition(TF_MESSAGE_TYPE))[TF_MESSAGE_TYPE](message.data)
    assert len(decoded.transforms) == count
    for transform, edge in zip(decoded.transforms, EDGES[:count], strict=True):
        assert (transform.header.frame_id, transform.child_frame_id) == (edge.parent, edge.child)
        assert (transform.header.stamp.sec, transform.header.stamp.nanosec) == (1_700_000_000, 123_456_789)
        t, q = transform.transform.translation, transform.transform.rotation
        assert (t.x, t.y, t.z) == edge.translation
        assert (q.x, q.y, q.z, q.w) == edge.rotation
    strict = TYPESTORE.deserialize_cdr(message.data, TF_MESSAGE_TYPE)  # strict: no byte left over
    assert [t.child_frame_id for t in strict.transforms] == [e.child for e in EDGES[:count]]


def test_tf_schema_and_hash_are_rosbag2s() -> None:
    text = message_definition(TF_MESSAGE_TYPE)
    assert text.startswith("geometry_msgs/TransformStamped[] transforms\n")
    assert "MSG: geometry_msgs/TransformStamped\n" in text
    assert "MSG: builtin_interfaces/Time\n" in text
    # the hash of Jazzy's tf2_msgs, as rosbags computes it from the definitions (the same for the installed types)
    assert type_description_hash(TF_MESSAGE_TYPE) == TYPESTORE.hash_rihs01(TF_MESSAGE_TYPE)
    transform = "geometry_msgs/msg/TransformStamped"
    assert type_description_hash(transform) == TYPESTORE.hash_rihs01(transform)


def test_recorded_tf_reads_back(tmp_path: Path) -> None:
    recorder = RunRecorder(tmp_path, "0" * 32)
    for k in range(5):
        edges = [FrameTransform("world", "object", 0.1 * k, -0.2 * k, 0.3 * k), *EDGES]
        recorder.write("/tf", tf_message(edges, 10**18 + k), 10**18 + k)
    recorder.write("/tf_static", tf_message(EDGES[:1], 10**18), 10**18)
    recorder.write("/x", SerializedMessage("tf2_msgs/msg/TFMessage", tf_message([], 0).data), 10**18)
    path = recorder.close()
    assert recorder.error is None, recorder.error

    with Reader(path) as reader:
        connections = {c.topic: c for c in reader.connections}
        assert connections["/tf"].msgtype == TF_MESSAGE_TYPE
        assert connections["/tf"].msgcount == 5
        rosbags_read = [
            TYPESTORE.deserialize_cdr(data, TF_MESSAGE_TYPE)
            for _connection, _t, data in reader.messages(connections=[connections["/tf"]])
        ]
    with next(path.glob("*.mcap")).open("rb") as stream:
        mcap_read = [
            m
            for _s, c, _m, m in make_reader(stream, decoder_factories=[DecoderFactory()]).iter_decoded_messages()
            if c.topic == "/tf"
        ]
    for k, (a, b) in enumerate(zip(rosbags_read, mcap_read, strict=True)):
        for message in (a, b):
            first = message.transforms[0]
            assert (first.header.frame_id, first.child_frame_id) == ("world", "object")
            assert first.header.stamp.sec == 10**9
            assert first.header.stamp.nanosec == k
            assert np.allclose([first.transform.translation.x, first.transform.translation.y], [0.1 * k, -0.2 * k])
            assert first.transform.rotation.z == pytest.approx(math.sin(0.15 * k))
    info = yaml.safe_load((path / "metadata.yaml").read_text())["rosbag2_bagfile_information"]
    qos = {
        t["topic_metadata"]["name"]: t["topic_metadata"]["offered_qos_profiles"][0]
        for t in info["topics_with_message_count"]
    }
    assert qos["/tf_static"]["durability"] == "transient_local"
    assert (qos["/tf"]["durability"], qos["/tf"]["depth"]) == ("volatile", 100)
