"""Core values <-> ROS 2 messages (clew_ros.ros.messages), without a ROS graph."""

from __future__ import annotations

import itertools
import json
import math
import uuid
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("rclpy")

from geometry_msgs.msg import PoseStamped
from rclpy.serialization import deserialize_message, serialize_message
from sensor_msgs.msg import JointState
from trajectory_msgs.msg import JointTrajectory
from visualization_msgs.msg import Marker

from clew_ros.core.plan import Plan
from clew_ros.core.settings import PlannerSettings
from clew_ros.core.tree import LandmarkTree
from clew_ros.motion.playback import track_from_plan
from clew_ros.motion.timing import quintic_spline
from clew_ros.planar.plan import validate_plan
from clew_ros.planar.space import plan
from clew_ros.planar.world import load_world, world_from_parameters
from clew_ros.recording import trajectory_to_plan
from clew_ros.ros import messages

WORLDS = Path(__file__).parents[1] / "worlds"
RING = Path(__file__).parents[2] / "config" / "unreachable.yaml"  # four obstacles


@pytest.fixture(scope="module")
def quick():
    return load_world(WORLDS / "node_quick.yaml")


@pytest.fixture(scope="module")
def quick_plan(quick) -> Plan:
    result = plan(quick, PlannerSettings(seed=0, time_limit=20.0))
    assert result.success, result.message
    return Plan.from_result(quick, result)


def test_trajectory_round_trips_to_a_valid_plan(quick, quick_plan) -> None:
    track = track_from_plan(quick, quick_plan)
    msg = messages.joint_trajectory(track, 5_000_000_123)
    msg = deserialize_message(serialize_message(msg), JointTrajectory)  # as it travels over DDS
    assert (msg.header.stamp.sec, msg.header.stamp.nanosec) == (5, 123)
    rebuilt = trajectory_to_plan(quick, msg, strict=True)
    assert validate_plan(quick, rebuilt) == []
    assert [(s.kind, s.grasp) for s in rebuilt.segments] == [(s.kind, s.grasp) for s in quick_plan.segments]
    for a, b in zip(rebuilt.segments, quick_plan.segments, strict=True):
        assert np.allclose(a.waypoints, b.waypoints, atol=0, rtol=0)
    assert np.allclose(rebuilt.final_object_pose, quick_plan.final_object_pose, atol=1e-9)


def test_trajectory_points_hold_the_contract(quick, quick_plan) -> None:
    msg = messages.joint_trajectory(track_from_plan(quick, quick_plan), 0)
    assert msg.joint_names == ["joint_1", "joint_2", "gripper"]
    waypoints = [w.tolist() for s in quick_plan.segments for w in s.waypoints]
    assert [list(p.positions[:2]) for p in msg.points] == waypoints
    gripper = [1.0 if s.kind == "transfer" else 0.0 for s in quick_plan.segments for _ in s.waypoints]
    assert [p.positions[2] for p in msg.points] == gripper
    times = [p.time_from_start.sec * 10**9 + p.time_from_start.nanosec for p in msg.points]
    assert all(b > a for a, b in itertools.pairwise(times))


def test_trajectory_points_carry_velocities_and_accelerations(quick, quick_plan) -> None:
    """Every point has positions, velocities and accelerations of every joint, as joint_trajectory_controller
    expects; a controller that runs them as quintic splines moves exactly as the node's playback."""
    track = track_from_plan(quick, quick_plan, max_velocity_rad_s=1.5, max_acceleration_rad_s2=3.0)
    msg = deserialize_message(serialize_message(messages.joint_trajectory(track, 0)), JointTrajectory)
    for point in msg.points:
        assert len(point.positions) == len(point.velocities) == len(point.accelerations) == 3
        assert list(point.velocities) == [0.0, 0.0, 0.0]  # every waypoint is at rest; gripper: always 0
        assert list(point.accelerations) == [0.0, 0.0, 0.0]
    times = np.array([p.time_from_start.sec + 1e-9 * p.time_from_start.nanosec for p in msg.points])
    assert np.array_equal(np.round(times * 1e9).astype(np.int64), track.times_ns)
    columns = [
        np.array([list(getattr(p, f))[:2] for p in msg.points]) for f in ("positions", "velocities", "accelerations")
    ]
    t = np.linspace(0.0, track.duration_s, 4001)
    assert np.allclose(quintic_spline(times, *columns, t), track.joints_at(t)[0], atol=1e-7)
    assert np.allclose(quintic_spline(times, *columns, t), [track.sample(s)[0] for s in t], atol=1e-7)


def test_joint_states_carry_velocities_for_every_name() -> None:
    names = ["joint_1", "joint_2", "gripper"]
    msg = messages.joint_state(names, np.array([0.1, -0.2]), 1.0, 5, np.array([0.5, -1.5]))
    msg = deserialize_message(serialize_message(msg), JointState)
    assert list(msg.name) == names
    assert list(msg.position) == pytest.approx([0.1, -0.2, 1.0])
    assert list(msg.velocity) == [0.5, -1.5, 0.0]  # the gripper: 0.0
    assert list(msg.effort) == []
    assert list(messages.joint_state(names, np.array([0.1, -0.2]), 0.0, 5).velocity) == []


def goal_msg(x=0.5, y=0.5, yaw=0.0, frame="world") -> PoseStamped:
    msg = messages.goal_pose_stamped(np.array([x, y, yaw]), 0)
    msg.header.frame_id = frame
    return msg


@pytest.mark.parametrize("yaw", [0.0, 1.0, -2.5, math.pi - 1e-9])
def test_goal_pose_yaw_round_trips(quick, yaw: float) -> None:
    goal = messages.goal_from_pose_stamped(goal_msg(0.3, -0.4, yaw), quick)
    assert np.allclose(goal, [0.3, -0.4, yaw])


def test_goal_pose_accepts_an_empty_frame_and_the_bounds_edge(quick) -> None:
    assert np.allclose(messages.goal_from_pose_stamped(goal_msg(2.0, -2.0, frame=""), quick)[:2], [2.0, -2.0])


@pytest.mark.parametrize(
    ("change", "reason"),
    [
        (lambda m: setattr(m.header, "frame_id", "map"), "frame_id"),
        (lambda m: setattr(m.pose.position, "y", math.inf), "finite"),
        (lambda m: setattr(m.pose.orientation, "w", 0.0), "unit quaternion"),
        (lambda m: (setattr(m.pose.orientation, "x", 0.6), setattr(m.pose.orientation, "w", 0.8)), "about z"),
        (lambda m: setattr(m.pose.position, "x", 2.01), "outside world.bounds"),
    ],
)
def test_goal_pose_refusals_say_why(quick, change, reason: str) -> None:
    msg = goal_msg()
    change(msg)
    with pytest.raises(messages.GoalPoseError, match=reason):
        messages.goal_from_pose_stamped(msg, quick)


def test_world_markers() -> None:
    world = load_world(RING)
    markers = messages.world_markers(world, 7).markers
    assert markers[0].action == Marker.DELETEALL
    assert all(m.header.frame_id == "world" for m in markers)
    by_ns: dict[str, list[Marker]] = {}
    for m in markers[1:]:
        by_ns.setdefault(m.ns, []).append(m)
    assert len(by_ns["obstacles"]) == len(world.obstacles) == 4
    assert all(len(m.points) == 6 and m.type == Marker.TRIANGLE_LIST for m in by_ns["obstacles"])  # 2 triangles
    bounds = by_ns["bounds"][0]
    assert bounds.type == Marker.LINE_STRIP
    assert bounds.points[0] == bounds.points[-1]
    assert len(bounds.points) == 5
    goal = by_ns["object_goal"][0]
    centre = np.mean([[p.x, p.y] for p in goal.points[:-1]], axis=0)
    assert np.allclose(centre, world.object.goal[:2])
    # another goal (a ~/goal_pose run) moves the goal outline
    moved = messages.world_markers(world, 7, goal=np.array([0.5, 0.5, 0.0])).markers
    outline = next(m for m in moved if m.ns == "object_goal")
    assert np.allclose(np.mean([[p.x, p.y] for p in outline.points[:-1]], axis=0), [0.5, 0.5])


def test_concave_obstacles_are_filled_inside_only(quick) -> None:
    import dataclasses

    import shapely

    from clew_ros.planar.world import Obstacle

    u_shape = np.array([[0, 0], [3, 0], [3, 3], [2, 3], [2, 1], [1, 1], [1, 3], [0, 3]], dtype=float)
    world = dataclasses.replace(quick, obstacles=(Obstacle("u", u_shape),))
    filled = next(m for m in messages.world_markers(world, 0).markers if m.ns == "obstacles")
    points = filled.points
    assert len(points) % 3 == 0
    area = sum(shapely.Polygon([(p.x, p.y) for p in points[i : i + 3]]).area for i in range(0, len(points), 3))
    assert area == pytest.approx(shapely.Polygon(u_shape).area)


def test_landmark_markers() -> None:
    tree = LandmarkTree(np.zeros(2), np.array([0.0, 1.0, 0.0]))
    tree.add(
        parent=0,
        joints=np.ones(2),
        object_pose=np.array([1.0, 1.0, 0.0]),
        grasp=1,
        grasp_rel=None,
        transit=None,
        transfer=None,
    )
    tree.add(
        parent=1,
        joints=np.ones(2),
        object_pose=np.array([1.0, 0.0, 0.0]),
        grasp=0,
        grasp_rel=None,
        transit=None,
        transfer=None,
    )
    markers = messages.landmark_markers(tree, 0).markers
    assert markers[0].action == Marker.DELETEALL
    spheres = next(m for m in markers if m.ns == "landmarks")
    assert [(p.x, p.y) for p in spheres.points] == [(0.0, 1.0), (1.0, 1.0), (1.0, 0.0)]
    edges = next(m for m in markers if m.ns == "tree_edges")
    assert edges.type == Marker.LINE_LIST
    assert len(edges.points) == 4
    texts = [m for m in markers if m.ns == "landmark_ids"]
    assert [(m.id, m.text) for m in texts] == [(0, "0"), (1, "1"), (2, "2")]
    assert not [m for m in markers if m.ns == "landmark_outlines"]  # no polygon given

    # every landmark's placement drawn as the object's outline
    square = np.array([[-0.1, -0.1], [0.1, -0.1], [0.1, 0.1], [-0.1, 0.1]])
    outlines = [m for m in messages.landmark_markers(tree, 0, square).markers if m.ns == "landmark_outlines"]
    assert [m.id for m in outlines] == [0, 1, 2]
    assert all(m.type == Marker.LINE_STRIP and len(m.points) == 5 for m in outlines)
    assert (outlines[1].points[0].x, outlines[1].points[0].y) == pytest.approx((0.9, 0.9))


def test_scene_markers(quick) -> None:
    joints = np.array([math.pi / 2, -math.pi / 2])
    resting = {m.ns: m for m in messages.scene_markers(quick, joints, 0.0, quick.object.initial, 7).markers}
    assert set(resting) == {"arm", "arm_joints", "gripper", "object"}
    arm = resting["arm"]
    assert arm.type == Marker.LINE_STRIP
    assert np.allclose([(p.x, p.y) for p in arm.points], [(0.0, 0.0), (0.0, 1.0), (0.8, 1.0)])
    assert (resting["gripper"].pose.position.x, resting["gripper"].pose.position.y) == pytest.approx((0.8, 1.0))
    held = {m.ns: m for m in messages.scene_markers(quick, joints, 1.0, np.array([0.8, 1.05, 0.0]), 7).markers}
    assert resting["gripper"].color.g > resting["gripper"].color.r  # open: green
    assert held["gripper"].color.r > held["gripper"].color.g  # holding: red, and larger
    assert held["gripper"].scale.x > resting["gripper"].scale.x
    assert held["object"].color != resting["object"].color
    assert len(held["object"].points) == len(quick.object.polygon) + 1
    assert all(m.header.frame_id == "world" and m.header.stamp.nanosec == 7 for m in held.values())


def test_robot_description_message(quick) -> None:
    text = messages.robot_description_message(quick).data
    assert text.startswith("<?xml")
    assert '<joint name="joint_2" type="revolute">' in text
    assert '<joint name="gripper" type="revolute">' in text


def test_status_feedback_and_events() -> None:
    run_id = uuid.uuid4()
    status = messages.goal_status_array([(run_id, 1_500_000_000, 2)], 0)
    assert bytes(status.status_list[0].goal_info.goal_id.uuid) == run_id.bytes
    assert status.status_list[0].goal_info.stamp.sec == 1
    assert status.status_list[0].status == 2
    feedback = messages.feedback_status(run_id, landmarks=3, best_distance=math.inf, elapsed_s=1.25, phase="planning")
    values = {kv.key: kv.value for kv in feedback.values}
    assert values["run_id"] == run_id.hex
    assert values["landmarks"] == "3"
    assert values["elapsed"] == "1.250"
    event = json.loads(
        messages.event_message(run_id, "aborted", 12.5, code="BUSY", best=math.nan, pose=np.array([1.0, np.inf])).data
    )
    assert event == {
        "run_id": run_id.hex,
        "event": "aborted",
        "time": 12.5,
        "code": "BUSY",
        "best": None,
        "pose": [1.0, None],
    }


def test_world_yaml_is_a_parameter_file_for_the_same_world(tmp_path: Path) -> None:
    from clew_ros.planar.world import read_parameter_file

    world = load_world(WORLDS / "node_behind_wall.yaml")
    settings = PlannerSettings(seed=4, time_limit=3.0)
    path = tmp_path / "world.yaml"
    path.write_text(messages.world_yaml_message(world, settings).data)
    tree = read_parameter_file(path)
    again = world_from_parameters(tree)
    assert again.name == world.name
    assert [o.name for o in again.obstacles] == [o.name for o in world.obstacles]
    assert np.allclose(again.object.polygon, world.object.polygon)
    assert PlannerSettings.from_parameters(tree) == settings
