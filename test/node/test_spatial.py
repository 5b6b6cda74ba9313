"""Spatial worlds through the node (issue 45): ``clew_planner`` in a subprocess on the shipped Panda.

Two nodes, each started once: a motion-only query among the obstacles of a MoveIt scene file, and a box
moved from one table to another. Through ``~/plan`` each plans the plan the offline planner plans for the
same seed; the plan a client rebuilds from ``~/trajectory`` and the grasp events is valid
(``spatial.plan.validate_plan``); the trajectory names the URDF's planned joints only and keeps every
joint within the lower of its URDF velocity limit and ``trajectory.max_velocity``, and within
``trajectory.max_acceleration``. The recording decodes with rosbags and with ``mcap`` + ``mcap_ros2``;
its ``/tf`` (with ``/tf_static``) puts every link where the checker's forward kinematics does at every
recorded joint state, within 1 mm. ``~/goal_pose`` refuses a placement that is not stable, saying which
face and how far off the support, and a stable one starts a run that ``~/cancel`` stops within 100 ms.
"""

from __future__ import annotations

import itertools
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
pytest.importorskip("urdf_parser_py")
rosbags_rosbag2 = pytest.importorskip("rosbags.rosbag2")

from action_msgs.msg import GoalStatus  # noqa: E402
from geometry_msgs.msg import PoseStamped  # noqa: E402
from helpers.node_harness import HAVE_RECORDER, NodeProcess, Session, run_id_of, wait_until  # noqa: E402
from mcap.reader import make_reader  # noqa: E402
from mcap_ros2.decoder import DecoderFactory  # noqa: E402
from rosbags.typesys import Stores, get_typestore  # noqa: E402
from std_srvs.srv import Trigger  # noqa: E402

from clew_ros.core.plan import Plan  # noqa: E402
from clew_ros.core.settings import PlannerSettings  # noqa: E402
from clew_ros.motion.spatial import UrdfTree  # noqa: E402
from clew_ros.motion.timing import PEAK_ACCELERATION, PEAK_VELOCITY  # noqa: E402
from clew_ros.planar.plan import PlanSegment  # noqa: E402
from clew_ros.planar.world import read_parameter_file  # noqa: E402
from clew_ros.ros.qos import GOAL_QOS  # noqa: E402
from clew_ros.spatial.plan import make_plan, validate_plan  # noqa: E402
from clew_ros.spatial.space import plan as offline_plan  # noqa: E402
from clew_ros.spatial.transforms import quaternion_matrix  # noqa: E402
from clew_ros.spatial.world import SpatialWorld, spatial_world_from_parameters  # noqa: E402

pytestmark = [pytest.mark.ros, pytest.mark.skipif(not HAVE_RECORDER, reason="the recorder needs mcap")]

CONFIG = Path(__file__).resolve().parents[2] / "config" / "spatial"
#: Fast enough for a short test; high enough that the URDF's velocity limits bind for some joints.
LIMITS = {"trajectory.max_velocity": 2.4, "trajectory.max_acceleration": 30.0, "playback.rate": 50.0}
TYPESTORE = get_typestore(Stores.ROS2_JAZZY)
TF_TOLERANCE_M = 1e-3
#: The box of panda_table_to_table.yaml lying on its side on table_b: a stable placement no top-down grasp
#: reaches, so the planner works until its time limit (a run to cancel).
LYING = [0.5, -0.3, 0.14, math.pi / 2, 0.0, 0.0]


def _absolute(source: Path, target: Path, time_limit: float) -> Path:
    """``source`` with its robot, SRDF and scene file paths made absolute (the node reads relative paths
    from its working directory) and ``planner.time_limit`` set."""
    document = yaml.safe_load(source.read_text())
    parameters = document["clew_planner"]["ros__parameters"]
    world = parameters["world"]
    for key in ("urdf", "srdf"):
        world["robot"][key] = str((source.parent / world["robot"][key]).resolve())
    if "scene_file" in world:
        world["scene_file"] = str((source.parent / world["scene_file"]).resolve())
    parameters["planner"]["time_limit"] = time_limit
    target.write_text(yaml.safe_dump(document))
    return target


@dataclass
class Served:
    """A node's run through ``~/plan``: the world (read here), what a client saw, and the recording."""

    world: SpatialWorld
    settings: PlannerSettings
    node: NodeProcess
    session: Session
    run_id: str
    trajectory: Any
    events: list[dict[str, Any]]
    recording: dict[str, list[tuple[int, Any]]]  # topic -> (log time, message), by rosbags
    directory: Path


def _serve(tmp: Path, world_file: Path) -> Served:
    params = _absolute(world_file, tmp / world_file.name, 20.0)
    tree = read_parameter_file(params)
    world = spatial_world_from_parameters(tree, params.parent)
    settings = PlannerSettings.from_parameters({"planner": tree["planner"]})
    node = NodeProcess(tmp / "node.log", params, {"record.directory": str(tmp / "rec"), **LIMITS})
    session = Session(node)
    try:
        response = session.plan(timeout_s=60.0)
        assert response.success, f"{response.message}\n{node.output()}"
        run_id = run_id_of(response.message)
        session.wait_playback(run_id, timeout_s=60.0)
        directory = tmp / "rec" / run_id
        wait_until((directory / "metadata.yaml").is_file, 10.0, "the recording's metadata.yaml")
    except BaseException:
        session.close()
        raise
    trajectory = session.trajectory.wait_for(lambda m: len(m.points) > 0)
    recording: dict[str, list[tuple[int, Any]]] = {}
    with rosbags_rosbag2.Reader(directory) as reader:
        for connection, log_ns, data in reader.messages():
            recording.setdefault(connection.topic, []).append(
                (log_ns, TYPESTORE.deserialize_cdr(data, connection.msgtype))
            )
    return Served(world, settings, node, session, run_id, trajectory, session.events_of(run_id), recording, directory)


@pytest.fixture(scope="module")
def motion(tmp_path_factory: pytest.TempPathFactory) -> Any:
    served = _serve(tmp_path_factory.mktemp("motion"), CONFIG / "panda_scene_motion.yaml")
    yield served
    assert served.session.close() == 0, served.node.output()


@pytest.fixture(scope="module")
def transfer(tmp_path_factory: pytest.TempPathFactory) -> Any:
    served = _serve(tmp_path_factory.mktemp("transfer"), CONFIG / "panda_table_to_table.yaml")
    yield served
    assert served.session.close() == 0, served.node.output()


def _seconds(duration: Any) -> float:
    return int(duration.sec) + int(duration.nanosec) * 1e-9


def _rebuilt_plan(served: Served) -> Plan:
    """The plan a client reads off ``~/trajectory`` and the grasp events: a grasp or an ungrasp is a
    repeated point at the event's time, where a segment ends and the next begins."""
    points = served.trajectory.points
    times = [_seconds(p.time_from_start) for p in points]
    cuts = []
    for event in (e for e in served.events if e["event"] in ("grasp", "ungrasp")):
        k = int(np.argmin(np.abs(np.array(times) - event["time"])))
        assert abs(times[k] - event["time"]) < 1e-6, "a grasp event's time is on the trajectory's clock"
        assert points[k].positions == points[k - 1].positions, "a grasp repeats the point"
        cuts.append((k, event))
    segments, start, grasp = [], 0, None
    for k, event in cuts:
        segments.append(PlanSegment("transfer" if grasp is not None else "transit", grasp, _rows(points[start:k])))
        start, grasp = k, event["grasp"] if event["event"] == "grasp" else None
    segments.append(PlanSegment("transfer" if grasp is not None else "transit", grasp, _rows(points[start:])))
    return make_plan(served.world, [(s.kind, s.grasp, s.waypoints) for s in segments])


def _rows(points: list[Any]) -> np.ndarray:
    return np.array([list(p.positions) for p in points], dtype=float)


@pytest.mark.parametrize("which", ["motion", "transfer"])
def test_plans_what_the_offline_planner_plans_and_the_plan_is_valid(which: str, request: pytest.FixtureRequest) -> None:
    served: Served = request.getfixturevalue(which)
    rebuilt = _rebuilt_plan(served)
    assert validate_plan(served.world, rebuilt) == []
    offline = offline_plan(served.world, served.settings)
    assert [s.kind for s in rebuilt.segments] == [s.kind for s in offline.segments]
    for got, want in zip(rebuilt.segments, offline.segments, strict=True):
        assert got.grasp == want.grasp
        assert np.array_equal(got.waypoints, np.array(want.waypoints)), "same seed, same plan"
    accepted = next(e for e in served.events if e["event"] == "accepted")
    assert accepted["world"] == served.world.name
    outcomes = [e["event"] for e in served.events if e["event"] in ("succeeded", "aborted", "canceled")]
    assert outcomes == ["succeeded"]
    if which == "transfer":
        grasps = [e["grasp"] for e in served.events if e["event"] == "grasp"]
        assert grasps == [s.grasp for s in offline.segments if s.kind == "transfer"]


@pytest.mark.parametrize("which", ["motion", "transfer"])
def test_trajectory_names_the_planned_urdf_joints_within_their_limits(
    which: str, request: pytest.FixtureRequest
) -> None:
    served: Served = request.getfixturevalue(which)
    robot = served.world.robot
    trajectory = served.trajectory
    assert list(trajectory.joint_names) == list(robot.joint_names)
    urdf = UrdfTree(robot.urdf)
    velocity = np.minimum([urdf.velocity_of(name) for name in robot.joint_names], LIMITS["trajectory.max_velocity"])
    assert np.any(velocity < LIMITS["trajectory.max_velocity"]), "the URDF's limits bind for some joints"
    acceleration = LIMITS["trajectory.max_acceleration"]
    times = [_seconds(p.time_from_start) for p in trajectory.points]
    assert all(b > a for a, b in itertools.pairwise(times))
    peak_v = np.zeros(robot.dof)
    for a, b in zip(trajectory.points, trajectory.points[1:], strict=False):
        assert len(a.positions) == len(a.velocities) == len(a.accelerations) == robot.dof
        assert not any(a.velocities), "every point at rest"
        assert not any(a.accelerations), "every point at rest"
        span = _seconds(b.time_from_start) - _seconds(a.time_from_start)
        delta = np.abs(np.subtract(b.positions, a.positions))
        peak_v = np.maximum(peak_v, PEAK_VELOCITY * delta / span / velocity)
        assert np.all(PEAK_ACCELERATION * delta / span**2 <= acceleration * (1 + 1e-9))
    assert np.all(peak_v <= 1 + 1e-9)
    assert np.max(peak_v) > 0.5, "a move that limits bind"


def _stamp(header: Any) -> int:
    return int(header.stamp.sec) * 10**9 + int(header.stamp.nanosec)


def _matrix(transform: Any) -> np.ndarray:
    t, r = transform.translation, transform.rotation
    return quaternion_matrix([t.x, t.y, t.z], [r.x, r.y, r.z, r.w])


@pytest.mark.parametrize("which", ["motion", "transfer"])
def test_recording_decodes_and_its_tf_is_the_checkers_forward_kinematics(
    which: str, request: pytest.FixtureRequest
) -> None:
    served: Served = request.getfixturevalue(which)
    robot, name = served.world.robot, served.node.name
    with next(served.directory.glob("*.mcap")).open("rb") as stream:
        by_mcap: dict[str, int] = {}
        for _s, channel, _m, _decoded in make_reader(
            stream, decoder_factories=[DecoderFactory()]
        ).iter_decoded_messages():
            by_mcap[channel.topic] = by_mcap.get(channel.topic, 0) + 1
    assert by_mcap == {topic: len(messages) for topic, messages in served.recording.items()}
    assert {"/tf", "/tf_static", f"{name}/robot_description", f"{name}/trajectory"} <= set(by_mcap)

    description = served.recording[f"{name}/robot_description"][-1][1].data
    uris = re.findall(r'filename="([^"]+)"', description)
    assert uris
    assert all(uri.startswith("file:///") and Path(uri[len("file://") :]).is_file() for uri in uris)
    movable = UrdfTree(robot.urdf).movable_joint_names
    statics = [e for _t, m in served.recording["/tf_static"] for e in m.transforms]
    tf_by_stamp: dict[int, list[Any]] = {}
    for _t, message in served.recording["/tf"]:
        for edge in message.transforms:
            tf_by_stamp.setdefault(_stamp(edge.header), []).append(edge)
    states = [m for _t, m in served.recording[f"{name}/joint_states"]]
    assert len(states) >= 10
    for state in states:
        assert list(state.name) == movable  # every movable joint of the URDF, fingers too
        values = dict(zip(state.name, state.position, strict=True))
        q = [values[joint] for joint in robot.joint_names]
        frames = {"world": np.eye(4)}
        pending = statics + tf_by_stamp[_stamp(state.header)]
        while pending:
            edge = next((e for e in pending if e.header.frame_id in frames), None)
            assert edge is not None, f"frames not connected to world: {[e.child_frame_id for e in pending]}"
            pending.remove(edge)
            frames[edge.child_frame_id] = frames[edge.header.frame_id] @ _matrix(edge.transform)
        expected = robot.link_poses(q)
        assert expected
        for link, pose in expected.items():
            assert np.max(np.abs(frames[link][:3, 3] - pose[:3, 3])) <= TF_TOLERANCE_M, link
            assert np.max(np.abs(frames[link][:3, :3] - pose[:3, :3])) <= TF_TOLERANCE_M, link
        # world.robot.tcp is zero in these worlds: the tcp is tip_link's frame
        assert np.max(np.abs(frames[robot.tip_link] - robot.tcp_pose(q))) <= TF_TOLERANCE_M
    markers = served.recording[f"{name}/world_markers"][-1][1].markers
    solids = [m for m in markers if m.ns in ("obstacles", "supports")]
    assert len(solids) == len(served.world.obstacles)
    links = [m for m in markers if m.ns == "robot_links"]  # the arm drawn from the recording alone
    assert {m.header.frame_id for m in links} == {link.name for link in robot.links}
    assert all(m.frame_locked for m in links)
    assert sum(len(m.points) for m in links) > 1000


def test_parameters_change_as_for_a_planar_world_and_world_yaml_names_absolute_files(motion: Served) -> None:
    from rcl_interfaces.msg import Parameter as ParameterMsg
    from rcl_interfaces.msg import ParameterType, ParameterValue
    from rcl_interfaces.srv import SetParameters

    session = motion.session

    def set_parameter(name: str, value: ParameterValue) -> Any:
        request = SetParameters.Request(parameters=[ParameterMsg(name=name, value=value)])
        return session.client.call(session.srv("set_parameters"), SetParameters, request, timeout_s=20.0).results[0]

    # each given spatial world.* parameter is declared with its spec's descriptor: read-only, described
    from rcl_interfaces.srv import DescribeParameters

    from clew_ros.spatial.parameters import spatial_spec

    names = ["world.robot.base_link", "world.robot.initial", "world.scene_file"]
    request = DescribeParameters.Request(names=names)
    described = session.client.call(session.srv("describe_parameters"), DescribeParameters, request, timeout_s=20.0)
    for name, descriptor in zip(names, described.descriptors, strict=True):
        spec = spatial_spec(name)
        assert spec is not None
        assert descriptor.read_only, name
        assert descriptor.description == spec.description, name
    seed = set_parameter("planner.seed", ParameterValue(type=ParameterType.PARAMETER_INTEGER, integer_value=3))
    assert seed.successful, seed.reason
    initial = ParameterValue(type=ParameterType.PARAMETER_DOUBLE_ARRAY, double_array_value=[0.0] * 7)
    refused = set_parameter("world.robot.initial", initial)
    assert not refused.successful
    assert "world.robot.initial" in refused.reason
    (text,) = {m.data for _t, m in motion.recording[f"{motion.node.name}/world_yaml"]}
    world = next(iter(yaml.safe_load(text).values()))["ros__parameters"]["world"]
    assert world["kind"] == "spatial"
    for path in (world["robot"]["urdf"], world["robot"]["srdf"], world["scene_file"]):
        assert Path(path).is_absolute()
        assert Path(path).is_file()


def _goal_pose(pose: list[float], stamp_s: int) -> PoseStamped:
    from clew_ros.ros.spatial import pose_stamped

    return pose_stamped(pose, stamp_s * 10**9)  # frame world, the full orientation


def test_goal_pose_refuses_an_unstable_placement_and_a_run_is_canceled_quickly(transfer: Served) -> None:
    session, name = transfer.session, transfer.node.name
    publisher = session.client.publisher(f"{name}/goal_pose", PoseStamped, GOAL_QOS)

    def aborted(stamp_s: int) -> dict[str, Any]:
        wait_until(
            lambda: any(json.loads(m.data).get("goal_stamp_ns") == stamp_s * 10**9 for m in session.events.messages),
            10.0,
            f"the answer to goal {stamp_s}",
        )
        return next(
            e
            for e in (json.loads(m.data) for m in session.events.messages)
            if e.get("goal_stamp_ns") == stamp_s * 10**9
        )

    publisher.publish(_goal_pose([0.5, -0.3, 0.17, 0.3, 0.0, 0.0], 101))  # tilted 0.3 rad
    refused = aborted(101)
    assert refused["event"] == "aborted"
    assert refused["code"] == "INVALID_WORLD"
    assert "not a stable placement" in refused["message"]
    assert "face -z" in refused["message"]
    assert "tilted 0.3000 rad" in refused["message"]
    publisher.publish(_goal_pose([0.5, -0.3, 0.22, 0.0, 0.0, 0.0], 102))  # 5 cm above table_b
    refused = aborted(102)
    assert refused["event"] == "aborted"
    assert "0.0500 m off support table_b's top face" in refused["message"]

    publisher.publish(_goal_pose(LYING, 103))
    accepted = aborted(103)
    assert accepted["event"] == "accepted"
    assert accepted["source"] == "goal_pose"
    assert np.allclose(accepted["goal"], LYING, atol=1e-9)
    session.wait_status(accepted["run_id"], GoalStatus.STATUS_EXECUTING)
    response = session.client.call(session.srv("cancel"), Trigger)
    assert response.success, response.message
    took = re.search(r"canceled run ([0-9a-f]{32}) in (\d+) ms", response.message)
    assert took, response.message
    assert took.group(1) == accepted["run_id"], response.message
    assert int(took.group(2)) < 100, response.message
    session.wait_status(accepted["run_id"], GoalStatus.STATUS_CANCELED)


def test_planner_client_sends_a_3d_goal_and_rebuilds_a_valid_plan(transfer: Served) -> None:
    import rclpy

    from clew_ros.client import PlannerClient
    from clew_ros.ros.spatial import with_goal

    goal = (0.45, -0.25, 0.17, 0.0, 0.0, 1.0)  # on table_b, turned 1 rad
    context = rclpy.Context()
    rclpy.init(context=context)
    node = rclpy.create_node("clew_spatial_client", context=context)
    try:
        client = PlannerClient(node, transfer.node.name)
        client.wait_for_planner(timeout_s=20.0)
        result = client.send_goal(goal).wait(timeout_s=60.0)
        assert result.succeeded, result.message
        assert result.plan is not None
        assert result.plan.world_kind == "spatial"
        assert result.plan.grasp_count == 1
        assert validate_plan(with_goal(transfer.world, goal), result.plan) == []
        refused = client.send_goal((0.45, -0.25, 0.2, 0.0, 0.0, 1.0)).wait(timeout_s=20.0)  # 3 cm up
        assert refused.outcome.name == "INVALID_WORLD"
        assert "0.0300 m off support table_b's top face" in refused.message
        client.destroy()
    finally:
        node.destroy_node()
        rclpy.try_shutdown(context=context)


def test_the_trajectory_follower_follows_a_spatial_trajectory(transfer: Served) -> None:
    import subprocess
    import sys

    latest = transfer.session.trajectory.messages[-1]
    follower = subprocess.run(
        [
            sys.executable,
            "-m",
            "clew_ros.examples.trajectory_follower",
            "--planner",
            transfer.node.name,
            "--count",
            "1",
            "--rate",
            "100",
        ],
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
    )
    assert follower.returncode == 0, follower.stdout + follower.stderr
    duration = _seconds(latest.points[-1].time_from_start)
    assert f"followed {len(latest.points)} points over {duration:.2f} s\n" in follower.stdout, follower.stdout
