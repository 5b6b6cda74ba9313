"""The arm in a real recording (issue 15): ``clew_planner`` in a subprocess plans and plays back; its
recording, read with independent readers (rosbags for every message, ``mcap`` + ``mcap_ros2`` for the
channels), holds the robot description, TF for every link at every joint state equal to the planner's
forward kinematics and the URDF's, the ``~/scene`` markers, the landmark outlines, and every topic with
the QoS its publisher offers.
"""

from __future__ import annotations

import json
import math
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml

pytest.importorskip("rclpy")
rosbags_rosbag2 = pytest.importorskip("rosbags.rosbag2")
urdf_lib = pytest.importorskip("urdf_parser_py.urdf")

from helpers.node_harness import HAVE_RECORDER, NodeProcess, Session, run_id_of, wait_until  # noqa: E402
from helpers.urdf_fk import urdf_fk  # noqa: E402
from mcap.reader import make_reader  # noqa: E402
from rosbags.typesys import Stores, get_typestore  # noqa: E402

from clew_ros.planar.kinematics import joint_positions, tip_poses  # noqa: E402
from clew_ros.planar.world import (  # noqa: E402
    World,
    read_parameter_file,
    world_from_parameters,
)
from clew_ros.ros import urdf  # noqa: E402
from clew_ros.ros.frames import OBJECT_FRAME  # noqa: E402
from clew_ros.ros.qos import GOAL_QOS  # noqa: E402
from clew_ros.ros.topics import TF_TOPICS, TOPICS  # noqa: E402

pytestmark = [pytest.mark.ros, pytest.mark.skipif(not HAVE_RECORDER, reason="the recorder needs mcap")]

QUICK = Path(__file__).parents[1] / "worlds" / "node_quick.yaml"
FAST = {"trajectory.max_velocity": 20.0, "trajectory.max_acceleration": 400.0, "playback.rate": 50.0}
#: The quick world with a 3-link arm of capsules, off the origin.
ARM3 = {
    "world.robot.base": [0.1, -0.2],
    "world.robot.link_lengths": [0.6, 0.6, 0.6],
    "world.robot.link_width": 0.04,
    "world.robot.joint_lower": [-3.1, -2.9, -2.9],
    "world.robot.joint_upper": [3.1, 2.9, 2.9],
    "world.robot.initial": [0.0, 0.0, 0.0],
}
TOLERANCE = 1e-9
TYPESTORE = get_typestore(Stores.ROS2_JAZZY)


@dataclass
class Recorded:
    world: World
    node: str  # the node's full name
    directory: Path
    messages: dict[str, list[tuple[int, Any]]]  # topic -> (log time ns, decoded message), in log order
    metadata: dict[str, Any]  # topic -> rosbag2 topic_metadata


def _world(overrides: dict[str, Any]) -> World:
    parameters = read_parameter_file(QUICK)
    for key, value in overrides.items():
        *path, last = key.split(".")
        tree = parameters
        for part in path:
            tree = tree[part]
        tree[last] = value
    return world_from_parameters(parameters)


@pytest.fixture(scope="module", params=[{}, ARM3], ids=["arm2", "arm3_capsules"])
def recorded(request: pytest.FixtureRequest, tmp_path_factory: pytest.TempPathFactory) -> Recorded:
    tmp = tmp_path_factory.mktemp("arm")
    overrides = dict(request.param)
    node = NodeProcess(tmp / "node.log", QUICK, {"record.directory": str(tmp / "rec"), **FAST, **overrides})
    session = Session(node)
    try:
        response = session.plan()
        assert response.success, f"{response.message}\n{node.output()}"
        run_id = run_id_of(response.message)
        session.wait_playback(run_id)
        directory = tmp / "rec" / run_id
        wait_until((directory / "metadata.yaml").is_file, 10.0, "the recording's metadata.yaml")
    finally:
        code = session.close()
    assert code == 0, node.output()
    messages: dict[str, list[tuple[int, Any]]] = {}
    with rosbags_rosbag2.Reader(directory) as reader:
        for connection, log_ns, data in reader.messages():
            decoded = TYPESTORE.deserialize_cdr(data, connection.msgtype)
            messages.setdefault(connection.topic, []).append((log_ns, decoded))
    info = yaml.safe_load((directory / "metadata.yaml").read_text())["rosbag2_bagfile_information"]
    metadata = {t["topic_metadata"]["name"]: t["topic_metadata"] for t in info["topics_with_message_count"]}
    return Recorded(_world(overrides), node.name, directory, messages, metadata)


def _stamp(header: Any) -> int:
    return int(header.stamp.sec) * 10**9 + int(header.stamp.nanosec)


def _matrix(translation: Any, rotation: Any) -> np.ndarray:
    x, y, z, w = rotation.x, rotation.y, rotation.z, rotation.w
    out = np.eye(4)
    out[:3, :3] = [
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ]
    out[:3, 3] = [translation.x, translation.y, translation.z]
    return out


def _compose(edges: list[Any]) -> dict[str, np.ndarray]:
    """Every frame's pose in ``world`` from recorded TransformStamped edges."""
    poses = {"world": np.eye(4)}
    pending = list(edges)
    while pending:
        edge = next((e for e in pending if e.header.frame_id in poses), None)
        assert edge is not None, f"frames not connected to world: {[e.child_frame_id for e in pending]}"
        pending.remove(edge)
        transform = edge.transform
        poses[edge.child_frame_id] = poses[edge.header.frame_id] @ _matrix(transform.translation, transform.rotation)
    return poses


def _planar(pose: np.ndarray) -> np.ndarray:
    assert abs(pose[2, 3]) < TOLERANCE
    return np.array([pose[0, 3], pose[1, 3], math.atan2(pose[1, 0], pose[0, 0])])


def test_robot_description_is_the_worlds_urdf(recorded: Recorded) -> None:
    topic = f"{recorded.node}/robot_description"
    texts = {m.data for _t, m in recorded.messages[topic]}
    assert texts == {urdf.robot_urdf(recorded.world)}
    parsed = urdf_lib.URDF.from_xml_string(texts.pop())
    arm = [j.name for j in parsed.joints if j.type == "revolute" and j.mimic is None]
    assert arm == [*recorded.world.robot.joint_names, "gripper"]


def test_tf_at_every_joint_state_is_the_planners(recorded: Recorded) -> None:
    world, robot = recorded.world, recorded.world.robot
    statics = [e for _t, m in recorded.messages["/tf_static"] for e in m.transforms]
    assert {(e.header.frame_id, e.child_frame_id) for e in statics} == {
        ("world", urdf.BASE_LINK),
        (urdf.link_name(robot.dof), urdf.TOOL_FRAME),
    }
    tf_by_stamp: dict[int, list[Any]] = {}
    for _t, message in recorded.messages["/tf"]:
        stamps = {_stamp(e.header) for e in message.transforms}
        assert len(stamps) == 1
        tf_by_stamp.setdefault(stamps.pop(), []).extend(message.transforms)
    poses_by_stamp = {_stamp(m.header): m.pose for _t, m in recorded.messages[f"{recorded.node}/object_pose"]}
    parsed = urdf_lib.URDF.from_xml_string(urdf.robot_urdf(world))
    links = {link.name for link in parsed.links} - {"world"}

    states = [m for _t, m in recorded.messages[f"{recorded.node}/joint_states"]]
    assert len(states) >= 10
    q = np.array([list(m.position[: robot.dof]) for m in states])
    points, tips = joint_positions(robot, q), tip_poses(robot, q)
    for k, state in enumerate(states):
        stamp = _stamp(state.header)
        assert stamp in tf_by_stamp, f"no /tf at the joint state stamped {stamp}"
        frames = _compose(statics + tf_by_stamp[stamp])
        assert links <= set(frames), f"no TF for {links - set(frames)}"
        by_urdf = urdf_fk(parsed, dict(zip(state.name, state.position, strict=True)))
        phi = np.cumsum(q[k])
        for i in range(1, robot.dof + 1):
            name = urdf.link_name(i)
            x, y, theta = _planar(frames[name])
            assert np.allclose([x, y], points[k, i - 1], rtol=0, atol=TOLERANCE)
            assert abs(math.remainder(theta - phi[i - 1], 2 * math.pi)) < TOLERANCE
        tool = _planar(frames[urdf.TOOL_FRAME])
        assert np.allclose(tool[:2], tips[k, :2], rtol=0, atol=TOLERANCE)
        assert abs(math.remainder(tool[2] - tips[k, 2], 2 * math.pi)) < TOLERANCE
        for link in links:
            assert np.allclose(frames[link], by_urdf[link], rtol=0, atol=TOLERANCE), link
        pose = poses_by_stamp[stamp]
        obj = frames[OBJECT_FRAME]
        assert np.allclose(obj[:2, 3], [pose.position.x, pose.position.y], rtol=0, atol=TOLERANCE)


def test_scene_markers_follow_the_playback(recorded: Recorded) -> None:
    robot = recorded.world.robot
    scene = {_stamp(m.markers[0].header): m for _t, m in recorded.messages[f"{recorded.node}/scene"]}
    states = [m for _t, m in recorded.messages[f"{recorded.node}/joint_states"]]
    colors = set()
    for state in states:
        markers = {m.ns: m for m in scene[_stamp(state.header)].markers}
        assert set(markers) == {"arm", "arm_joints", "gripper", "object"}
        assert all(m.header.frame_id == "world" for m in markers.values())
        q = np.array(state.position[: robot.dof])
        expected = joint_positions(robot, q[None])[0]
        assert np.allclose([[p.x, p.y] for p in markers["arm"].points], expected, atol=1e-12)
        holding = state.position[-1] >= 0.5
        color = markers["gripper"].color
        assert (color.r > color.g) == holding  # red while holding, green while open
        colors.add(holding)
        assert len(markers["object"].points) == len(recorded.world.object.polygon) + 1
    assert colors == {False, True}, "the playback grasps and lets go"


def test_landmark_placements_are_outlined(recorded: Recorded) -> None:
    _t, last = recorded.messages[f"{recorded.node}/landmarks"][-1]
    spheres = next(m for m in last.markers if m.ns == "landmarks")
    outlines = [m for m in last.markers if m.ns == "landmark_outlines"]
    assert len(outlines) == len(spheres.points) >= 2
    for outline, center in zip(sorted(outlines, key=lambda m: m.id), spheres.points, strict=True):
        corners = np.array([[p.x, p.y] for p in outline.points[:-1]])
        assert np.allclose(corners.mean(axis=0), [center.x, center.y], atol=1e-9)  # the quick world's box


def _qos_fields(profile: Any) -> dict[str, Any]:
    return {
        "history": profile.history.name.lower(),
        "depth": profile.depth,
        "reliability": profile.reliability.name.lower(),
        "durability": profile.durability.name.lower(),
    }


def test_every_topic_is_recorded_with_its_offered_qos(recorded: Recorded) -> None:
    offered = {f"{recorded.node}/{name}": _qos_fields(qos) for name, (_type, qos) in TOPICS.items()}
    offered |= {topic: _qos_fields(qos) for topic, qos in TF_TOPICS.items()}
    offered[f"{recorded.node}/goal_pose"] = _qos_fields(GOAL_QOS)
    assert set(recorded.metadata) == set(offered), "every topic of the node is recorded"
    with next(recorded.directory.glob("*.mcap")).open("rb") as stream:
        channels = {c.topic: c for c in make_reader(stream).get_summary().channels.values()}
    for topic, meta in recorded.metadata.items():
        (in_metadata,) = meta["offered_qos_profiles"]
        (in_channel,) = yaml.safe_load(channels[topic].metadata["offered_qos_profiles"])
        for profile in (in_metadata, in_channel):
            assert {key: profile[key] for key in offered[topic]} == offered[topic], topic
    assert offered[f"{recorded.node}/status"]["durability"] == "transient_local"
    assert offered[f"{recorded.node}/events"]["depth"] == 100


def test_the_foxglove_layout_names_only_recorded_topics(recorded: Recorded) -> None:
    """config/foxglove_layout.json, opened on this recording, finds every topic it names (issue 15)."""
    layout = json.loads((Path(__file__).resolve().parents[2] / "config" / "foxglove_layout.json").read_text())
    panels = json.dumps(layout["configById"])
    named = set(re.findall(r"/clew_planner/[a-z_]+", panels))
    recorded_topics = {topic.replace(recorded.node, "/clew_planner", 1) for topic in recorded.messages}
    assert {"/clew_planner/robot_description", "/clew_planner/status", "/clew_planner/landmarks"} <= named
    assert named <= recorded_topics, named - recorded_topics
    scene = layout["configById"]["3D!clew_world"]
    urdf_layers = [layer for layer in scene["layers"].values() if layer["layerId"] == "foxglove.Urdf"]
    assert [layer["topic"] for layer in urdf_layers] == ["/clew_planner/robot_description"]
    assert scene["followTf"] == "world"
    assert {"/tf", "/tf_static"} <= recorded_topics  # the URDF's links are placed by the recorded TF
    # the status panel reads status_list[0]: the node lists the newest run first
    status = recorded.messages[f"{recorded.node}/status"][-1][1]
    assert status.status_list[0].status == 4  # this recording's own run, succeeded
