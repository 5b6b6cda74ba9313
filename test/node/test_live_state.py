"""The world as it is now (interface.md section 3c, issue 54) through the node: ``clew_planner`` in a subprocess
on the shipped Panda moving a box between two tables, every ``state.*`` input on, and a client here.

In order, on one node: a run asked before any joint state is refused ``START_STATE_UNKNOWN`` naming the
joints; with a joint state, a perceived object pose a few millimetres off its table, an obstacle marker and
a point cloud (part of it on the arm), the run plans from the joint state (the trajectory's first point
equals it within 1e-6 rad), among the marker's obstacle and the cloud's cubes (none on the arm), with the
object snapped onto its table; its ``~/world_yaml`` is that snapshot, and ``clew_plan`` on it plans the same
plan with the same seed, valid (on the exact geometry too, where pinocchio and coal are installed). With
``state.advance`` the next run starts with the object where the last plan left it. A stale joint state is
refused ``START_STATE_UNKNOWN`` saying how old; a tilted object ``INVALID_WORLD`` naming the face, its tilt
and the table; a marker around the hand ``START_IN_COLLISION`` naming the marker (a cloud over
``state.max_points`` refused, the previous cubes kept); ``~/world_markers`` shows a marker deleted within
0.5 s; a ``PlannerClient`` goal carries its start state and object pose.
"""

from __future__ import annotations

import json
import time
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml

pytest.importorskip("rclpy")
pytest.importorskip("urdf_parser_py")

from builtin_interfaces.msg import Time
from geometry_msgs.msg import Point, Pose, PoseStamped, Quaternion, Vector3
from helpers.node_harness import HAVE_RECORDER, Client, NodeProcess, Session, run_id_of, wait_until
from rclpy.duration import Duration
from sensor_msgs.msg import JointState, PointCloud2, PointField
from std_msgs.msg import Header, String
from visualization_msgs.msg import Marker, MarkerArray

from clew_ros.cli.plan import main as clew_plan
from clew_ros.core.plan import Plan
from clew_ros.planar.world import read_parameter_file
from clew_ros.ros.qos import CLOUD_QOS, LATCHED_QOS, STATE_QOS
from clew_ros.spatial.exact import exact_available, exact_problems
from clew_ros.spatial.plan import validate_plan
from clew_ros.spatial.transforms import matrix_quaternion, rpy_matrix
from clew_ros.spatial.world import SpatialWorld, spatial_world_from_parameters

pytestmark = [pytest.mark.ros, pytest.mark.skipif(not HAVE_RECORDER, reason="the recorder needs mcap")]

WORLD = Path(__file__).resolve().parents[2] / "config" / "spatial" / "panda_table_to_table.yaml"
STATE = {
    "state.joint_states": True,
    "state.max_age": 30.0,
    "state.object_pose": True,
    "state.obstacles": True,
    "state.points": True,
    "state.advance": True,
    "state.max_points": 1500,
    "trajectory.max_velocity": 3.0,
    "trajectory.max_acceleration": 50.0,
    "playback.rate": 50.0,
}
#: state.voxel_m's default.
STATE_VOXEL_M = 0.02
#: The start the joint state gives: the world's initial configuration, moved a little.
OFFSET = np.array([0.05, -0.05, 0.05, 0.05, 0.0, -0.05, 0.1])
#: A finger joint (not planned) and the state the joint states give it (the world's: closed).
FINGER, FINGER_OPEN = "panda_finger_joint1", 0.03
#: A block of points behind the arm (a 0.1 m cube of points 1 cm apart).
BLOCK = np.stack(
    np.meshgrid(*(np.arange(10) * 0.01 + c for c in (-0.445, 0.405, 0.305)), indexing="ij"), axis=-1
).reshape(-1, 3)


class Live:
    """The node, a session on it, the world read here, and publishers of its inputs."""

    def __init__(self, tmp: Path) -> None:
        document = yaml.safe_load(WORLD.read_text())
        parameters = document["clew_planner"]["ros__parameters"]
        robot = parameters["world"]["robot"]
        for key in ("urdf", "srdf"):
            robot[key] = str((WORLD.parent / robot[key]).resolve())
        parameters["planner"]["time_limit"] = 30.0
        params = tmp / "world.yaml"
        params.write_text(yaml.safe_dump(document))
        self.world: SpatialWorld = spatial_world_from_parameters(read_parameter_file(params), tmp)
        self.node = NodeProcess(tmp / "node.log", params, {"record.directory": str(tmp / "rec"), **STATE})
        self.session = Session(self.node)
        client: Client = self.session.client
        name = self.node.name
        self.world_yaml = client.inbox(f"{name}/world_yaml", String, LATCHED_QOS)
        self.joints = client.publisher(f"{self.node.namespace}/joint_states", JointState, STATE_QOS)
        self.object = client.publisher(f"{name}/object", PoseStamped, STATE_QOS)
        self.obstacles = client.publisher(f"{name}/obstacles", MarkerArray, STATE_QOS)
        self.points = client.publisher(f"{name}/points", PointCloud2, CLOUD_QOS)

    def now(self, age_s: float = 0.0) -> Time:
        sec, nanosec = divmod(time.time_ns() - int(age_s * 1e9), 10**9)
        return Time(sec=sec, nanosec=nanosec)

    def send(self, publisher: Any, msg: Any) -> None:
        publisher.publish(msg)
        assert publisher.wait_for_all_acked(Duration(seconds=5.0))

    def send_joints(self, q: np.ndarray, age_s: float = 0.0, fixed: dict[str, float] | None = None) -> None:
        names = [*self.world.robot.joint_names, *(fixed or {})]
        values = [*q, *(fixed or {}).values()]
        self.send(self.joints, JointState(header=Header(stamp=self.now(age_s)), name=names, position=values))

    def send_object(self, pose: list[float]) -> None:
        x, y, z, w = matrix_quaternion(rpy_matrix(*pose[3:]))
        msg = PoseStamped(
            header=Header(stamp=self.now(), frame_id="world"),
            pose=Pose(position=Point(x=pose[0], y=pose[1], z=pose[2]), orientation=Quaternion(x=x, y=y, z=z, w=w)),
        )
        self.send(self.object, msg)

    def send_marker(self, ns: str, key: int, action: int, center: list[float] | None = None, size: float = 0.1) -> None:
        marker = Marker(header=Header(frame_id="world"), ns=ns, id=key, type=Marker.CUBE, action=action)
        if center is not None:
            marker.pose.position = Point(x=center[0], y=center[1], z=center[2])
            marker.pose.orientation.w = 1.0
            marker.scale = Vector3(x=size, y=size, z=size)
        self.send(self.obstacles, MarkerArray(markers=[marker]))

    def send_cloud(self, points: np.ndarray) -> None:
        data = np.asarray(points, dtype=np.float32)
        padded = np.zeros((len(data), 4), dtype=np.float32)  # x y z and 4 bytes of padding: point_step 16
        padded[:, :3] = data
        fields = [PointField(name=n, offset=4 * k, datatype=PointField.FLOAT32, count=1) for k, n in enumerate("xyz")]
        msg = PointCloud2(
            header=Header(stamp=self.now(), frame_id="world"),
            height=1,
            width=len(data),
            fields=fields,
            is_bigendian=False,
            point_step=16,
            row_step=16 * len(data),
            data=padded.tobytes(),
            is_dense=True,
        )
        self.send(self.points, msg)

    def obstacle_markers(self) -> list[Any]:
        """The obstacles the latest ``~/world_markers`` draws: each marker of ``obstacles`` and ``supports``, and
        each cube of the ``points`` CUBE_LIST."""
        latest = self.session.world_markers.messages[-1]
        cubes = [p for m in latest.markers if m.ns == "points" and m.type == Marker.CUBE_LIST for p in m.points]
        return [m for m in latest.markers if m.ns in ("obstacles", "supports")] + cubes

    def wait_marker_count(self, count: int, since_ns: int) -> float:
        """Wait until the latest ``~/world_markers`` holds ``count`` obstacles; how long after ``since_ns`` (wall
        clock) the node stamped it (the node's clock is the wall clock), in seconds."""
        wait_until(lambda: len(self.obstacle_markers()) == count, 10.0, f"{count} obstacle markers")
        stamp = self.session.world_markers.messages[-1].markers[0].header.stamp
        return (stamp.sec * 10**9 + stamp.nanosec - since_ns) * 1e-9

    def run_world(self) -> dict[str, Any]:
        """The last ``~/world_yaml``: the last accepted run's (a run publishes its own as it is accepted)."""
        return yaml.safe_load(self.world_yaml.messages[-1].data)

    def close(self) -> int | None:
        return self.session.close()


@pytest.fixture(scope="module")
def live(tmp_path_factory: pytest.TempPathFactory) -> Any:
    served = Live(tmp_path_factory.mktemp("live"))
    yield served
    assert served.close() == 0, served.node.output()


def _outcome(live: Live, run_id: str) -> dict[str, Any]:
    wait_until(
        lambda: any(e["event"] in ("succeeded", "aborted", "canceled") for e in live.session.events_of(run_id)),
        60.0,
        f"run {run_id}'s outcome",
    )
    return next(e for e in live.session.events_of(run_id) if e["event"] in ("succeeded", "aborted", "canceled"))


def test_a_run_before_any_joint_state_is_refused_start_state_unknown(live: Live) -> None:
    response = live.session.plan()
    assert not response.success
    event = _outcome(live, run_id_of(response.message))
    assert event["event"] == "aborted"
    assert event["code"] == "START_STATE_UNKNOWN"
    assert "panda_joint1" in event["message"], event["message"]
    assert "joint_states" in event["message"], event["message"]


def test_plans_from_the_joint_state_among_markers_and_cubes_and_clew_plan_replans_it(
    live: Live, tmp_path: Path
) -> None:
    world = live.world
    q = world.initial + OFFSET
    live.send_joints(q, fixed={FINGER: FINGER_OPEN})
    assert world.object is not None
    off = [*world.object.initial]
    off[2] += 0.004  # 4 mm above its table, tilted 0.02 rad: snapped
    off[3] += 0.02
    live.send_object(off)
    live.session.world_markers.wait_for(timeout_s=10.0)
    before = len(live.obstacle_markers())
    since = time.time_ns()
    live.send_marker("test", 1, Marker.ADD, [-0.5, -0.5, 0.6])
    live.wait_marker_count(before + 1, since)  # (a publisher's first message may wait for the match: not timed)
    spheres = world.checker.sphere_positions(q.tolist())
    on_arm = spheres + 0.5 * world.spheres.radii[:, None] * np.array([0.0, 0.0, 1.0])
    live.send_cloud(np.concatenate([BLOCK, on_arm]))
    cells = {tuple(c) for c in np.floor(BLOCK / STATE_VOXEL_M).astype(int).tolist()}
    live.wait_marker_count(before + 1 + len(cells), time.time_ns())

    response = live.session.plan(timeout_s=90.0)
    assert response.success, f"{response.message}\n{live.node.output()}"
    run_id = run_id_of(response.message)
    trajectory = live.session.trajectory.wait_for(lambda m: len(m.points) > 0, 10.0)
    first = np.array(trajectory.points[0].positions)
    assert np.max(np.abs(first - q)) <= 1e-6, "the plan starts at the joint state"

    snapshot = live.run_world()
    tree = next(iter(snapshot.values()))["ros__parameters"]
    assert np.allclose(tree["world"]["robot"]["initial"], q, atol=0.0, rtol=0.0)
    robot = tree["world"]["robot"]
    assert robot["fixed_joint_positions"][robot["fixed_joint_names"].index(FINGER)] == pytest.approx(FINGER_OPEN)
    start = tree["world"]["object"]["initial"]
    assert start[2] == pytest.approx(world.object.initial[2], abs=1e-9), "snapped onto the table"
    assert abs(start[3]) < 1e-9, "snapped level"
    assert abs(start[4]) < 1e-9, "snapped level"
    names = tree["world"]["obstacle_names"]
    assert "test/1" in names
    assert tree["world"]["obstacles"]["test/1"]["size"] == [0.1, 0.1, 0.1]
    cubes = np.array([tree["world"]["obstacles"][n]["pose"][:3] for n in names if n.startswith("points/")])
    assert len(cubes) == len(cells), "one cube per cell of the block, none on the arm"
    assert {tuple(c) for c in np.floor(cubes / STATE_VOXEL_M).astype(int).tolist()} == cells

    # clew_plan on the run's world_yaml: the same plan with the same seed, valid
    world_file = tmp_path / "snapshot.yaml"
    world_file.write_text(yaml.safe_dump(snapshot))
    assert clew_plan([str(world_file), "--output", str(tmp_path / "plan.json")]) == 0
    offline = Plan.read(tmp_path / "plan.json")
    replanned = np.concatenate([np.asarray(s.waypoints) for s in offline.segments])
    played = np.array([p.positions for p in trajectory.points])
    assert replanned.shape == played.shape
    assert np.array_equal(replanned, played), "same seed, same plan"
    snapshot_world = spatial_world_from_parameters(tree, tmp_path)
    assert validate_plan(snapshot_world, offline) == []
    if exact_available():  # and on the exact geometry: the links' own, the marker, the cubes
        assert exact_problems(snapshot_world, offline) == []
    live.session.wait_playback(run_id, timeout_s=60.0)
    live.final_pose = list(offline.final_object_pose)  # type: ignore[attr-defined]
    live.last_waypoint = replanned[-1]  # type: ignore[attr-defined]


def test_the_next_run_starts_where_the_last_plan_left_the_object(live: Live) -> None:
    world = live.world
    assert world.object is not None
    live.send_joints(live.last_waypoint)  # type: ignore[attr-defined]  # the arm followed the plan
    back = PoseStamped(header=Header(frame_id="world"))
    initial = world.object.initial
    back.pose.position = Point(x=initial[0], y=initial[1], z=initial[2])
    back.pose.orientation = Quaternion(w=1.0)
    goal = live.session.client.publisher(f"{live.node.name}/goal_pose", PoseStamped)
    accepted_before = len([e for e in _events(live) if e["event"] == "accepted"])
    goal.publish(back)
    wait_until(
        lambda: len([e for e in _events(live) if e["event"] == "accepted"]) > accepted_before, 20.0, "a run accepted"
    )
    run_id = [e for e in _events(live) if e["event"] == "accepted"][-1]["run_id"]
    _outcome(live, run_id)
    tree = next(iter(live.run_world().values()))["ros__parameters"]
    assert np.allclose(tree["world"]["object"]["initial"], live.final_pose, atol=1e-6)  # type: ignore[attr-defined]
    live.session.wait_idle(60.0)


def _events(live: Live) -> list[dict[str, Any]]:
    return [json.loads(m.data) for m in live.session.events.messages]


def test_a_stale_joint_state_is_refused_saying_how_old(live: Live) -> None:
    live.send_joints(live.world.initial, age_s=100.0)
    response = live.session.plan()
    assert not response.success
    event = _outcome(live, run_id_of(response.message))
    assert event["code"] == "START_STATE_UNKNOWN"
    assert "s old" in event["message"], event["message"]
    assert "state.max_age" in event["message"], event["message"]


def test_an_object_far_from_a_stable_placement_is_refused_naming_the_face(live: Live) -> None:
    world = live.world
    assert world.object is not None
    live.send_joints(world.initial)
    tilted = [*world.object.initial]
    tilted[3] = 0.3
    live.send_object(tilted)
    response = live.session.plan()
    assert not response.success
    event = _outcome(live, run_id_of(response.message))
    assert event["code"] == "INVALID_WORLD"
    assert "face -z" in event["message"], event["message"]
    assert "0.3000 rad" in event["message"], event["message"]
    assert "table_a" in event["message"], event["message"]
    live.send_object(list(world.object.initial))


def test_a_start_in_collision_names_the_marker_it_touches(live: Live) -> None:
    world = live.world
    live.send_joints(world.initial)
    hand = world.checker.sphere_positions(world.initial.tolist())[-1]
    live.send_marker("block", 7, Marker.ADD, hand.tolist(), size=0.05)
    live.send_cloud(np.zeros((1501, 3)))  # over state.max_points: refused, the block's cubes stay
    wait_until(lambda: "1501 points exceed state.max_points 1500" in live.node.output(), 10.0, "the warning")
    response = live.session.plan()
    assert not response.success
    event = _outcome(live, run_id_of(response.message))
    assert event["code"] == "START_IN_COLLISION"
    assert "block/7" in event["message"], event["message"]
    tree = next(iter(live.run_world().values()))["ros__parameters"]
    cubes = [n for n in tree["world"]["obstacle_names"] if n.startswith("points/")]
    assert len(cubes) == len({tuple(c) for c in np.floor(BLOCK / STATE_VOXEL_M).astype(int).tolist()})


def test_world_markers_show_a_deleted_marker_gone_within_half_a_second(live: Live) -> None:
    count = len(live.obstacle_markers())
    since = time.time_ns()
    live.send_marker("block", 7, Marker.DELETE)
    assert 0.0 < live.wait_marker_count(count - 1, since) < 0.5
    since = time.time_ns()
    live.send_marker("", 0, Marker.DELETEALL)
    assert 0.0 < live.wait_marker_count(count - 2, since) < 0.5


def test_a_client_sends_a_goal_with_its_start_state_and_object_pose(live: Live) -> None:
    from clew_ros.client import PlannerClient

    world = live.world
    assert world.object is not None
    client = PlannerClient(live.session.client.node, live.node.name)
    try:
        client.wait_for_planner(timeout_s=20.0)
        q = world.initial - 0.5 * OFFSET
        moved = [*world.object.initial]
        moved[0] += 0.02  # 2 cm along its table
        result = client.plan(
            tuple(world.object.goal),
            start=dict(zip(world.robot.joint_names, q.tolist(), strict=True)),
            object_pose=moved,
            timeout_s=90.0,
        )
        assert result.succeeded, result.message
        assert result.trajectory is not None
        assert np.max(np.abs(np.array(result.trajectory.points[0].positions) - q)) <= 1e-6
        tree = next(iter(live.run_world().values()))["ros__parameters"]
        assert tree["world"]["object"]["initial"] == pytest.approx(moved, abs=1e-9)
    finally:
        client.destroy()


def test_the_state_parameters_are_fixed_while_the_node_runs(live: Live) -> None:
    from rcl_interfaces.msg import Parameter, ParameterType, ParameterValue
    from rcl_interfaces.srv import SetParameters

    request = SetParameters.Request(
        parameters=[Parameter(name="state.points", value=ParameterValue(type=ParameterType.PARAMETER_BOOL))]
    )
    response = live.session.client.call(live.session.srv("set_parameters"), SetParameters, request)
    assert not response.results[0].successful
    assert "state.points" in response.results[0].reason, response.results[0].reason
