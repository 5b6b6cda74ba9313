"""RunRecorder: write a run, read it back with two independent readers (rosbags; mcap + mcap_ros2).

Also: the schema text is rosbag2's, failed and canceled runs are complete, a
killed writer leaves a file readable up to its last chunk, and faults give
clear errors (RecordingError when creating; ``error`` while writing).
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import threading
import time
import uuid
from pathlib import Path

import pytest
import yaml

pytest.importorskip("rclpy")
rosbags_rosbag2 = pytest.importorskip("rosbags.rosbag2")

from helpers import rec_messages  # noqa: E402
from helpers.rec_plan import WORLD_PATH, quick_world  # noqa: E402
from mcap.reader import make_reader  # noqa: E402
from mcap.records import Message  # noqa: E402
from mcap.stream_reader import StreamReader  # noqa: E402
from mcap_ros2.decoder import DecoderFactory  # noqa: E402
from rclpy.serialization import deserialize_message, serialize_message  # noqa: E402
from rosbags.typesys import Stores, get_types_from_msg, get_typestore  # noqa: E402
from std_msgs.msg import String  # noqa: E402

from clew_ros.recording import Recording, RecordingError, RunRecorder, recover_recording  # noqa: E402
from clew_ros.recording.cdr import canonical_cdr  # noqa: E402
from clew_ros.recording.msgdefs import DELIMITER, learn_types, message_class, message_definition  # noqa: E402

WRITER = Path(__file__).parents[1] / "helpers" / "rec_writer.py"

#: A plan-shaped dict for the quick world (the recorder does not care whether it is valid).
PLAN = {
    "format": "clew-plan/1",
    "world": "rec_quick",
    "success": True,
    "message": "synthetic",
    "joint_names": ["joint_1", "joint_2"],
    "segments": [
        {"kind": "transit", "grasp": None, "waypoints": [[0.0, 0.0], [0.3, 0.0], [0.3, 0.9]]},
        {"kind": "transfer", "grasp": 2, "waypoints": [[0.3, 0.9], [-0.4, 0.9], [-0.4, 1.2]]},
        {"kind": "transit", "grasp": None, "waypoints": [[-0.4, 1.2], [0.0, 1.2]]},
    ],
    "final_object_pose": [1.0, -0.6, 0.0],
    "landmarks": [
        {"id": 0, "parent": None, "joints": [0.0, 0.0], "object_pose": [1.2, 0.6, 0.0], "grasp": None},
        {"id": 1, "parent": 0, "joints": [0.3, 0.9], "object_pose": [0.2, 1.0, 0.3], "grasp": 2},
        {"id": 2, "parent": 1, "joints": [-0.4, 1.2], "object_pose": [1.0, -0.6, 0.0], "grasp": 2},
    ],
    "stats": {},
}


def record(directory: Path, triples, run_id: str = "0" * 31 + "1") -> Path:
    recorder = RunRecorder(directory, run_id)
    for topic, msg, time_ns in triples:
        recorder.write(topic, msg, time_ns)
    path = recorder.close()
    assert recorder.error is None, recorder.error
    return path


@pytest.fixture(scope="module")
def run_triples():
    return rec_messages.sample_run(quick_world(), WORLD_PATH.read_text(), PLAN)


@pytest.fixture
def recording(tmp_path: Path, run_triples) -> Path:
    return record(tmp_path, run_triples)


def test_layout_and_metadata(recording: Path, run_triples) -> None:
    run_id = recording.name
    assert sorted(p.name for p in recording.iterdir()) == sorted(["metadata.yaml", f"{run_id}_0.mcap"])
    info = yaml.safe_load((recording / "metadata.yaml").read_text())["rosbag2_bagfile_information"]
    expected = rec_messages.counts(run_triples)
    assert info["version"] == 9
    assert info["storage_identifier"] == "mcap"
    assert info["relative_file_paths"] == [f"{run_id}_0.mcap"]
    assert info["message_count"] == sum(expected.values())
    assert info["files"][0]["path"] == f"{run_id}_0.mcap"
    assert info["files"][0]["message_count"] == sum(expected.values())
    times = [t for _topic, _msg, t in run_triples]
    assert info["starting_time"]["nanoseconds_since_epoch"] == min(times)
    assert info["duration"]["nanoseconds"] == max(times) - min(times)
    topics = {t["topic_metadata"]["name"]: t for t in info["topics_with_message_count"]}
    assert set(topics) == set(rec_messages.TOPIC_TYPES)
    for name, entry in topics.items():
        meta = entry["topic_metadata"]
        assert meta["type"] == rec_messages.TOPIC_TYPES[name]
        assert meta["serialization_format"] == "cdr"
        assert meta["type_description_hash"].startswith("RIHS01_")
        assert entry["message_count"] == expected[name]
        (qos,) = meta["offered_qos_profiles"]
        assert qos["durability"] == ("transient_local" if name in rec_messages.LATCHED else "volatile")
        assert qos["reliability"] == "reliable"
    assert info["custom_data"]["run_id"] == run_id


def test_rosbags_reads_every_topic(recording: Path, run_triples) -> None:
    typestore = get_typestore(Stores.ROS2_JAZZY)
    expected = rec_messages.counts(run_triples)
    with rosbags_rosbag2.Reader(recording) as reader:
        found = {c.topic: c for c in reader.connections}
        assert {t: c.msgtype for t, c in found.items()} == rec_messages.TOPIC_TYPES
        assert {t: c.msgcount for t, c in found.items()} == expected
        for connection in reader.connections:
            # the stored definition is rosbag2's ros2msg full text, and rosbags parses it
            assert connection.msgdef.format.name == "MSG"
            types = get_types_from_msg(connection.msgdef.data, connection.msgtype)
            assert connection.msgtype in types
            if connection.msgtype == "visualization_msgs/msg/MarkerArray":
                assert "MSG: visualization_msgs/Marker" in connection.msgdef.data
        decoded: dict[str, list] = {}
        for connection, _timestamp, raw in reader.messages():
            decoded.setdefault(connection.topic, []).append(typestore.deserialize_cdr(raw, connection.msgtype))
    events = [json.loads(m.data) for m in decoded["/clew_planner/events"]]
    assert next(e["event"] for e in events) == "accepted"
    assert events[-1]["event"] == "succeeded"
    assert [e["grasp"] for e in events if e["event"] == "grasp"] == [2]
    (trajectory,) = decoded["/clew_planner/trajectory"]
    assert list(trajectory.joint_names) == ["joint_1", "joint_2", "gripper"]
    assert len(trajectory.points) == 8
    assert decoded["/clew_planner/world_yaml"][0].data == WORLD_PATH.read_text()
    status = decoded["/clew_planner/status"][-1].status_list[0]
    assert status.status == 4
    assert bytes(status.goal_info.goal_id.uuid) == uuid.UUID(int=0x1234).bytes


def test_mcap_reader_decodes_every_topic(recording: Path, run_triples) -> None:
    expected = rec_messages.counts(run_triples)
    with (recording / f"{recording.name}_0.mcap").open("rb") as stream:
        reader = make_reader(stream, decoder_factories=[DecoderFactory()])
        assert reader.get_header().profile == "ros2"
        summary = reader.get_summary()
        assert summary is not None
        assert summary.statistics.message_count == sum(expected.values())
        assert {
            c.topic: summary.schemas[c.schema_id].name for c in summary.channels.values()
        } == rec_messages.TOPIC_TYPES
        for channel in summary.channels.values():
            assert channel.message_encoding == "cdr"
            assert summary.schemas[channel.schema_id].encoding == "ros2msg"
            qos = yaml.safe_load(channel.metadata["offered_qos_profiles"])
            assert qos[0]["durability"] in ("volatile", "transient_local")
            assert channel.metadata["topic_type_hash"].startswith("RIHS01_")
        counts: dict[str, int] = {}
        originals = iter(run_triples)
        for schema, channel, message, decoded in reader.iter_decoded_messages(log_time_order=True):
            topic, original, time_ns = next(originals)
            assert (channel.topic, message.log_time) == (topic, time_ns)
            counts[channel.topic] = counts.get(channel.topic, 0) + 1
            if channel.topic.endswith("/events"):
                assert decoded.data == original.data
            if channel.topic.endswith("/joint_states"):
                assert list(decoded.position) == list(original.position)
            # the bytes are rclpy's own serialisation, and rclpy reads them back unchanged
            assert deserialize_message(message.data, message_class(schema.name)) == original
    assert counts == expected


def test_schema_text_is_rosbag2s() -> None:
    text = message_definition("trajectory_msgs/msg/JointTrajectory")
    share = Path(sys.prefix) / "share"
    own = (share / "trajectory_msgs" / "msg" / "JointTrajectory.msg").read_text()
    assert text.startswith(own)
    blocks = text.split("\n" + DELIMITER)
    assert [b.splitlines()[0] for b in blocks[1:]] == [
        "MSG: std_msgs/Header",
        "MSG: builtin_interfaces/Time",
        "MSG: trajectory_msgs/JointTrajectoryPoint",
        "MSG: builtin_interfaces/Duration",
    ]
    assert DELIMITER == "=" * 80 + "\n"
    assert message_definition("std_msgs/msg/String") == (share / "std_msgs" / "msg" / "String.msg").read_text()


def test_recorded_bytes_are_rclpys_in_canonical_form(recording: Path, run_triples) -> None:
    """Each recorded message is rclpy's serialisation re-encoded by rosbags: rclpy reads back the original,
    and the bytes are rosbags' own encoding of it (exact length, zero padding), so equal messages are equal bytes."""
    typestore = get_typestore(Stores.ROS2_JAZZY)
    with (recording / f"{recording.name}_0.mcap").open("rb") as stream:
        records = [(c.topic, m.data) for _s, c, m in make_reader(stream).iter_messages(log_time_order=True)]
    assert len(records) == len(run_triples)
    for (topic, data), (topic_sent, original, _t) in zip(records, run_triples, strict=True):
        assert topic == topic_sent
        type_name = rec_messages.TOPIC_TYPES[topic]
        assert deserialize_message(data, type(original)) == original
        assert data == bytes(typestore.serialize_cdr(typestore.deserialize_cdr(data, type_name), type_name))
        assert data == canonical_cdr(type_name, serialize_message(original))


def test_canonical_cdr_zeroes_padding_and_keeps_values(run_triples) -> None:
    """Whatever rclpy leaves in the alignment padding, the canonical bytes are the same; any other byte stays."""
    typestore = get_typestore(Stores.ROS2_JAZZY)
    for topic, msg, _t in run_triples[:12]:
        type_name = rec_messages.TOPIC_TYPES[topic]
        canonical = canonical_cdr(type_name, serialize_message(msg))
        padding = 0
        for k in range(4, len(canonical)):
            stray = bytearray(canonical)
            stray[k] ^= 0xA5
            try:
                decoded = deserialize_message(bytes(stray), type(msg))
                again = canonical_cdr(type_name, bytes(stray))
            except Exception:  # noqa: BLE001 - the byte is a length or a string's: a library refuses the buffer
                continue
            if decoded == msg:  # padding: both libraries read the same message, and the canonical form drops it
                padding += 1
                assert again == canonical
            else:  # a value: it stays
                assert again != canonical
        typestore.deserialize_cdr(canonical, type_name)  # strict: no byte left over
        if topic.endswith("/world_markers"):
            assert padding > 0  # a Marker has padding (after its int32 and uint8 fields)


def test_learn_types_adds_unknown_types_and_refuses_a_different_definition() -> None:
    text = (
        "std_msgs/Header header\nfloat64[] values\nstring name\n"
        + DELIMITER
        + "MSG: std_msgs/Header\n"
        + message_definition("std_msgs/msg/Header")
    )
    assert learn_types("clew_test_msgs/msg/Reading", text)
    reading = get_typestore(Stores.ROS2_JAZZY)  # a fresh store does not know it
    assert "clew_test_msgs/msg/Reading" not in reading.fielddefs
    from clew_ros.recording.msgdefs import typestore

    store = typestore()
    types = store.types
    message = types["clew_test_msgs/msg/Reading"](
        header=types["std_msgs/msg/Header"](stamp=types["builtin_interfaces/msg/Time"](sec=1, nanosec=2), frame_id="w"),
        values=__import__("numpy").array([1.5, -2.0]),
        name="r",
    )
    data = bytes(store.serialize_cdr(message, "clew_test_msgs/msg/Reading"))
    assert canonical_cdr("clew_test_msgs/msg/Reading", data) == data
    # a known type defined otherwise (another distribution): rosbags must not re-encode rclpy's bytes with it
    assert not learn_types("std_msgs/msg/String", "int32 data\n")
    assert not learn_types("std_msgs/msg/String", "")
    assert learn_types("std_msgs/msg/String", message_definition("std_msgs/msg/String"))


@pytest.mark.parametrize("outcome", ["aborted", "canceled"])
def test_failed_and_canceled_runs_are_complete(tmp_path: Path, outcome: str) -> None:
    triples = rec_messages.sample_run(quick_world(), WORLD_PATH.read_text(), None, outcome=outcome)
    recorder = RunRecorder(tmp_path, f"run_{outcome}")
    for topic, msg, time_ns in triples:
        recorder.write(topic, msg, time_ns)
    paths = []
    closers = [threading.Thread(target=lambda: paths.append(recorder.close())) for _ in range(4)]
    for thread in closers:
        thread.start()
    for thread in closers:
        thread.join()
    assert paths == [recorder.path] * 4
    assert recorder.close() == recorder.path
    recorder.write("/clew_planner/events", String(data="after close"), 0)  # ignored, no error
    assert recorder.error is None
    assert recorder.dropped == 1
    recording = Recording(recorder.path)
    assert recording.complete
    assert {t: i.message_count for t, i in recording.topics.items()} == rec_messages.counts(triples)
    events = [json.loads(m.data) for m in recording.decoded("/clew_planner/events")]
    assert events[-1]["event"] == outcome
    info = yaml.safe_load((recorder.path / "metadata.yaml").read_text())["rosbag2_bagfile_information"]
    assert info["message_count"] == len(triples)
    with rosbags_rosbag2.Reader(recorder.path) as reader:
        assert reader.message_count == len(triples)
    assert "/clew_planner/trajectory" not in recording.topics


def test_write_never_raises(tmp_path: Path) -> None:
    recorder = RunRecorder(tmp_path, "bad_message")
    recorder.write("/clew_planner/events", object(), 1)  # not a ROS message
    recorder.write("/clew_planner/events", String(data="ok"), 2)
    recorder.write("/clew_planner/events", String(data="ok"), "not a time")
    recorder.write("/clew_planner/events", String(data="ok"), -5)
    recorder.close()
    assert "cannot record a message on /clew_planner/events" in recorder.error
    assert str(recorder.mcap_path) in recorder.error
    assert Recording(recorder.path).topics["/clew_planner/events"].message_count == 1
    assert recorder.dropped == 3


def test_recording_errors_name_the_path(tmp_path: Path) -> None:
    missing = tmp_path / "missing"
    with pytest.raises(RecordingError, match=f"{missing} does not exist"):
        RunRecorder(missing, "run")
    a_file = tmp_path / "a_file"
    a_file.write_text("")
    with pytest.raises(RecordingError, match="a_file does not exist or is not a directory"):
        RunRecorder(a_file, "run")
    RunRecorder(tmp_path, "run").close()
    with pytest.raises(RecordingError, match=r"run exists already, not overwriting"):
        RunRecorder(tmp_path, "run")


@pytest.mark.parametrize("module", ["mcap.writer", "rosbags.typesys"])
def test_without_mcap_or_rosbags_nothing_is_created(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, module: str
) -> None:
    monkeypatch.setitem(sys.modules, module, None)  # any import of it raises ImportError
    with pytest.raises(RecordingError, match=f"the {module.partition('.')[0]} package is not installed"):
        RunRecorder(tmp_path, "run")
    assert list(tmp_path.iterdir()) == []


def test_read_only_directory_is_refused(tmp_path: Path) -> None:
    locked = tmp_path / "locked"
    locked.mkdir(mode=0o500)
    try:
        if os.access(locked, os.W_OK):  # root writes anywhere: nothing to refuse
            pytest.skip("running as root: a read-only directory is writable")
        with pytest.raises(RecordingError, match=f"{locked} is not writable"):
            RunRecorder(locked, "run")
    finally:
        locked.chmod(0o700)


def test_reading_something_else_fails_clearly(tmp_path: Path) -> None:
    (tmp_path / "empty").mkdir()
    (tmp_path / "empty" / "empty_0.mcap").write_bytes(b"")
    with pytest.raises(RecordingError, match=r"empty_0\.mcap is empty"):
        Recording(tmp_path / "empty")
    (tmp_path / "text.mcap").write_text("not an mcap file at all")
    with pytest.raises(RecordingError, match=r"text\.mcap is not an MCAP file"):
        Recording(tmp_path / "text.mcap")
    (tmp_path / "nothing").mkdir()
    with pytest.raises(RecordingError, match=r"exactly one \.mcap file, found 0"):
        Recording(tmp_path / "nothing")


def _start_writer(*args: str) -> subprocess.Popen:
    return subprocess.Popen(
        [sys.executable, str(WRITER), *args],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=os.environ.copy(),
    )


def test_killed_writer_leaves_a_readable_recording(tmp_path: Path) -> None:
    writer = _start_writer("loop", str(tmp_path), "killed")
    mcap_path = tmp_path / "killed" / "killed_0.mcap"
    try:
        assert writer.stdout.readline().strip() == "ready", writer.stderr.read()
        deadline = time.monotonic() + 20.0
        while time.monotonic() < deadline and mcap_path.stat().st_size < 12_000:
            time.sleep(0.05)
    finally:
        writer.send_signal(signal.SIGKILL)
        writer.wait()
    assert mcap_path.stat().st_size >= 12_000, "the writer did not get far enough"
    assert not (tmp_path / "killed" / "metadata.yaml").exists()

    # The mcap stream reader reads every complete chunk, then meets the cut.
    numbers = []

    def read_every_chunk() -> None:
        with mcap_path.open("rb") as stream:
            numbers.extend(
                json.loads(deserialize_message(record.data, String).data)["n"]
                for record in StreamReader(stream).records
                if isinstance(record, Message)
            )

    with pytest.raises(Exception):  # noqa: B017, PT011 - mcap raises one of several errors at a cut
        read_every_chunk()
    assert len(numbers) > 20
    assert numbers == list(range(len(numbers)))

    recording = Recording(tmp_path / "killed")
    assert not recording.complete
    assert len(recording.messages()) == len(numbers)

    recover_recording(tmp_path / "killed")
    assert (tmp_path / "killed" / "killed_0.mcap.truncated").is_file()
    with rosbags_rosbag2.Reader(tmp_path / "killed") as reader:
        assert reader.message_count == len(numbers)
        assert [c.msgtype for c in reader.connections] == ["std_msgs/msg/String"]
    assert Recording(tmp_path / "killed").complete


def test_recorder_left_open_is_closed_at_exit(tmp_path: Path) -> None:
    writer = _start_writer("exit", str(tmp_path), "left_open")
    _out, err = writer.communicate(timeout=30)
    assert writer.returncode == 0, err
    recording = Recording(tmp_path / "left_open")
    assert recording.complete
    assert (tmp_path / "left_open" / "metadata.yaml").is_file()
    assert [m.data for m in recording.decoded("/clew_planner/events")] == [str(n) for n in range(10)]


def test_disk_full_sets_error_without_raising(tmp_path: Path) -> None:
    writer = _start_writer("fsize", str(tmp_path), "full", str(48 * 1024))
    out, err = writer.communicate(timeout=40)
    assert writer.returncode == 0, err
    result = json.loads(out.strip().splitlines()[-1])
    assert result["raised"] is None
    assert result["error"]
    assert "full_0.mcap" in result["error"]
    assert "File too large" in result["error"]
    assert result["dropped"] >= 10
    info = yaml.safe_load((tmp_path / "full" / "metadata.yaml").read_text())["rosbag2_bagfile_information"]
    assert info["custom_data"]["error"] == result["error"]
    readable = Recording(tmp_path / "full")
    assert not readable.complete
    assert 0 < info["message_count"] <= len(readable.messages())


def test_foxglove_layout_names_recorded_topics() -> None:
    layout = json.loads((Path(__file__).resolve().parents[2] / "config" / "foxglove_layout.json").read_text())
    panels = layout["configById"]

    def leaves(node):
        if isinstance(node, str):
            yield node
        else:
            yield from leaves(node["first"])
            yield from leaves(node["second"])

    assert sorted(leaves(layout["layout"])) == sorted(panels)
    text = json.dumps(panels)
    mentioned = {t for t in rec_messages.TOPIC_TYPES if f'"{t}' in text or f"{t}." in text}
    assert {
        "/clew_planner/world_markers",
        "/clew_planner/landmarks",
        "/clew_planner/joint_states",
        "/clew_planner/events",
    } <= mentioned
    assert panels["3D!clew_world"]["followTf"] == "world"
