"""``clew_planner`` end to end: a real node in a subprocess, a real client here.

A quick world (plans in about a second) for ~/plan, ~/goal_pose, late
subscribers and parameter changes; an unreachable world for a failing
~/plan. Every wait has a timeout; the node is stopped (SIGINT) at teardown
and must exit 0.
"""

from __future__ import annotations

import dataclasses
import itertools
import json
import math
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest
import yaml

rclpy = pytest.importorskip("rclpy")


from action_msgs.msg import GoalStatus, GoalStatusArray  # noqa: E402
from geometry_msgs.msg import PoseStamped  # noqa: E402
from helpers.node_harness import (  # noqa: E402
    HAVE_RECORDER,
    LATCHED,
    PLAN_TIMEOUT_S,
    Client,
    NodeProcess,
    Session,
    kv,
    recorded_topics,
    run_id_of,
    wait_until,
)
from rcl_interfaces.msg import Parameter as ParameterMsg  # noqa: E402
from rcl_interfaces.msg import ParameterType, ParameterValue  # noqa: E402
from rcl_interfaces.srv import SetParameters, SetParametersAtomically  # noqa: E402
from std_msgs.msg import String  # noqa: E402
from std_srvs.srv import Trigger  # noqa: E402
from trajectory_msgs.msg import JointTrajectory  # noqa: E402
from visualization_msgs.msg import Marker, MarkerArray  # noqa: E402

from clew_ros.planar.plan import validate_plan  # noqa: E402
from clew_ros.planar.world import load_world, read_parameter_file, world_from_parameters  # noqa: E402
from clew_ros.recording import trajectory_to_plan  # noqa: E402
from clew_ros.ros import messages  # noqa: E402

pytestmark = pytest.mark.ros

WORLDS = Path(__file__).parents[1] / "worlds"
QUICK = WORLDS / "node_quick.yaml"
UNREACHABLE = WORLDS / "node_unreachable.yaml"
# Fast playback so that a run (plan + playback) ends in about two seconds.
FAST = {"trajectory.max_velocity": 20.0, "trajectory.max_acceleration": 400.0, "playback.rate": 50.0}


@pytest.fixture(scope="module")
def quick(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Session]:
    tmp = tmp_path_factory.mktemp("quick")
    # the development switch: the tests change world.* at run time (else fixed at start: test/security)
    parameters = {"record.directory": str(tmp / "recordings"), "parameters.allow_runtime_changes": True, **FAST}
    node = NodeProcess(tmp / "node.log", QUICK, parameters)
    session = Session(node)
    session.recordings = tmp / "recordings"
    try:
        yield session
    finally:
        code = session.close()
        assert code == 0, f"node exit code {code}; output:\n{node.output()}"


@pytest.fixture(scope="module")
def quick_world():
    return load_world(QUICK)


def test_plan_succeeds_and_publishes_the_run(quick: Session, quick_world, tmp_path: Path) -> None:
    response = quick.plan()
    assert response.success, response.message
    run_id = run_id_of(response.message)
    assert "SUCCEEDED" in response.message
    assert "landmarks" in response.message
    quick.wait_status(run_id, GoalStatus.STATUS_SUCCEEDED)

    # the trajectory of this run: joint names, gripper values, strictly increasing times
    trajectory = quick.trajectory.wait_for(lambda m: True)
    assert list(trajectory.joint_names) == ["joint_1", "joint_2", "gripper"]
    times = [p.time_from_start.sec + 1e-9 * p.time_from_start.nanosec for p in trajectory.points]
    assert all(b > a for a, b in itertools.pairwise(times))
    assert {p.positions[-1] for p in trajectory.points} == {0.0, 1.0}
    plan = trajectory_to_plan(quick_world, trajectory, strict=True)
    assert validate_plan(quick_world, plan) == []

    # playback: joint_states end on the last point, the object ends at the goal
    quick.wait_playback(run_id)
    last = quick.joint_states.messages[-1]
    assert list(last.name) == list(trajectory.joint_names)
    assert np.allclose(last.position, trajectory.points[-1].positions)
    pose = quick.object_pose.messages[-1]
    assert pose.header.frame_id == "world"
    goal = quick_world.object.goal
    assert math.hypot(pose.pose.position.x - goal[0], pose.pose.position.y - goal[1]) <= quick_world.goal_tolerance

    # events: accepted first, succeeded, grasps in the order of the transfer segments
    events = quick.events_of(run_id)
    kinds = [e["event"] for e in events]
    assert kinds[0] == "accepted"
    assert "succeeded" in kinds
    assert "aborted" not in kinds
    succeeded = next(e for e in events if e["event"] == "succeeded")
    assert succeeded["code"] == "SUCCEEDED"
    assert succeeded["message"]
    transfers = [s.grasp for s in plan.segments if s.kind == "transfer"]
    assert [e["grasp"] for e in events if e["event"] == "grasp"] == transfers
    grasp_times = [e["time"] for e in events if e["event"] in ("grasp", "ungrasp")]
    assert grasp_times == sorted(grasp_times)
    assert all(0 < t <= times[-1] for t in grasp_times)

    # feedback while planning / at the end carries the run id
    assert any(kv(m).get("run_id") == run_id and kv(m).get("phase") == "SUCCEEDED" for m in quick.feedback.messages)

    if HAVE_RECORDER:
        recording = quick.recordings / run_id
        assert str(recording) in response.message
        wait_until((recording / "metadata.yaml").is_file, 10.0, "the recording's metadata.yaml")
        topics = recorded_topics(recording)
        name = quick.node.name
        expected = {
            f"{name}/{t}"
            for t in (
                "status",
                "feedback",
                "events",
                "landmarks",
                "trajectory",
                "joint_states",
                "object_pose",
                "world_markers",
                "world_yaml",
                "goal_pose",
            )
        }
        assert expected <= topics, f"missing {expected - topics}"


def test_late_subscriber_gets_the_latched_topics(quick: Session, quick_world) -> None:
    response = quick.plan()
    assert response.success, response.message
    run_id = run_id_of(response.message)
    late = Client("late")
    try:
        name = quick.node.name
        trajectory = late.inbox(f"{name}/trajectory", JointTrajectory, LATCHED).wait_for(timeout_s=10.0)
        landmarks = late.inbox(f"{name}/landmarks", MarkerArray, LATCHED).wait_for(timeout_s=10.0)
        world_markers = late.inbox(f"{name}/world_markers", MarkerArray, LATCHED).wait_for(timeout_s=10.0)
        world_yaml = late.inbox(f"{name}/world_yaml", String, LATCHED).wait_for(timeout_s=10.0)
        status = late.inbox(f"{name}/status", GoalStatusArray, LATCHED).wait_for(timeout_s=10.0)
    finally:
        late.close()

    # the trajectory received over DDS is a valid plan
    plan = trajectory_to_plan(quick_world, trajectory, strict=True)
    assert validate_plan(quick_world, plan) == []

    assert landmarks.markers[0].action == Marker.DELETEALL
    spheres = next(m for m in landmarks.markers if m.ns == "landmarks")
    assert len(spheres.points) >= 2
    assert all(m.header.frame_id == "world" for m in landmarks.markers[1:])
    assert {"bounds", "object_start", "object_goal"} <= {m.ns for m in world_markers.markers}

    # world_yaml is a parameter file holding the node's world
    tree = next(iter(yaml.safe_load(world_yaml.data).values()))["ros__parameters"]
    assert world_from_parameters(tree).name == quick_world.name
    assert any(
        bytes(s.goal_info.goal_id.uuid).hex() == run_id and s.status == GoalStatus.STATUS_SUCCEEDED
        for s in status.status_list
    )


def test_goal_pose_starts_a_run_to_that_goal(quick: Session, quick_world) -> None:
    goal = np.array([1.0, 0.7, 0.0])
    before = len(quick.events.messages)
    publisher = quick.client.publisher(f"{quick.node.name}/goal_pose", PoseStamped)
    publisher.publish(messages.goal_pose_stamped(goal, 0))
    accepted = quick.events.wait_for(
        lambda m: json.loads(m.data)["event"] == "accepted" and json.loads(m.data)["source"] == "goal_pose", 10.0
    )
    run_id = json.loads(accepted.data)["run_id"]
    assert quick.events.messages.index(accepted) >= before
    assert np.allclose(json.loads(accepted.data)["goal"], goal)
    quick.wait_status(run_id, GoalStatus.STATUS_SUCCEEDED, PLAN_TIMEOUT_S)
    quick.wait_playback(run_id)
    trajectory = quick.trajectory.messages[-1]
    world = dataclasses.replace(quick_world, object=dataclasses.replace(quick_world.object, goal=goal))
    assert validate_plan(world, trajectory_to_plan(world, trajectory, strict=True)) == []
    pose = quick.object_pose.messages[-1].pose
    assert math.hypot(pose.position.x - goal[0], pose.position.y - goal[1]) <= world.goal_tolerance
    # the latched world describes the run's problem: its goal
    world_yaml = quick.client.inbox(f"{quick.node.name}/world_yaml", String, LATCHED).wait_for(timeout_s=10.0)
    tree = next(iter(yaml.safe_load(world_yaml.data).values()))["ros__parameters"]
    assert np.allclose(tree["world"]["object"]["goal"], goal)


@pytest.mark.parametrize(
    ("frame", "x", "w", "reason"),
    [
        ("map", 1.0, 1.0, "frame_id"),
        ("world", float("nan"), 1.0, "finite"),
        ("world", 1.0, 0.5, "unit quaternion"),
        ("world", 9.0, 1.0, "outside world.bounds"),
    ],
)
def test_bad_goal_pose_is_refused(quick: Session, frame: str, x: float, w: float, reason: str) -> None:
    publisher = quick.client.publisher(f"{quick.node.name}/goal_pose", PoseStamped)
    msg = PoseStamped()
    msg.header.frame_id = frame
    msg.pose.position.x, msg.pose.position.y, msg.pose.orientation.w = x, 0.5, w
    before = len(quick.events.messages)
    publisher.publish(msg)
    refused = quick.events.wait_for(
        lambda m: quick.events.messages.index(m) >= before and json.loads(m.data)["event"] == "aborted", 10.0
    )
    event = json.loads(refused.data)
    assert reason in event["message"]
    assert event["code"] == "INVALID_WORLD"
    quick.wait_status(event["run_id"], GoalStatus.STATUS_ABORTED)


def _set(session: Session, name: str, value: ParameterValue) -> tuple[bool, str]:
    request = SetParameters.Request(parameters=[ParameterMsg(name=name, value=value)])
    response = session.client.call(session.srv("set_parameters"), SetParameters, request, timeout_s=10.0)
    return response.results[0].successful, response.results[0].reason


def _doubles(values: list[float]) -> ParameterValue:
    return ParameterValue(type=ParameterType.PARAMETER_DOUBLE_ARRAY, double_array_value=values)


def test_bad_parameters_are_rejected_and_good_ones_republish(quick: Session) -> None:
    ok, reason = _set(quick, "world.robot.initial", _doubles([9.0, 0.0]))
    assert not ok
    assert "world.robot.initial" in reason
    ok, reason = _set(
        quick, "planner.population", ParameterValue(type=ParameterType.PARAMETER_STRING, string_value="many")
    )
    assert not ok
    assert "planner.population" in reason
    ok, reason = _set(
        quick, "world.goal_tolerence", ParameterValue(type=ParameterType.PARAMETER_DOUBLE, double_value=0.1)
    )
    assert not ok
    assert "world.goal_tolerence" in reason

    # a valid change is taken and ~/world_markers shows the new goal
    count = len(quick.world_markers.messages)
    ok, reason = _set(quick, "world.object.goal", _doubles([1.1, 0.9, 0.0]))
    assert ok, reason
    markers = quick.world_markers.wait_for(lambda m: quick.world_markers.messages.index(m) >= count, 10.0)
    outline = next(m for m in markers.markers if m.ns == "object_goal")
    assert abs(np.mean([p.x for p in outline.points[:-1]]) - 1.1) < 1e-6
    ok, reason = _set(quick, "world.object.goal", _doubles([0.6, 1.1, 0.0]))  # back for the other tests
    assert ok, reason

    # an obstacle is added with one atomic set of its name and its polygon, and retired by its name
    names = ParameterMsg(
        name="world.obstacle_names",
        value=ParameterValue(type=ParameterType.PARAMETER_STRING_ARRAY, string_array_value=["pillar"]),
    )
    pillar = ParameterMsg(name="world.obstacles.pillar", value=_doubles([-1.8, -1.8, -1.6, -1.8, -1.6, -1.6]))
    ok, reason = _set(quick, "world.obstacle_names", names.value)
    assert not ok
    assert "world.obstacles.pillar" in reason
    count = len(quick.world_markers.messages)
    ok, reason = _set(quick, "world.obstacles.pillar", pillar.value)  # not listed yet: accepted, ignored
    assert ok, reason
    markers = quick.world_markers.wait_for(lambda m: quick.world_markers.messages.index(m) >= count, 10.0)
    assert "obstacles" not in [m.ns for m in markers.markers]
    count = len(quick.world_markers.messages)
    result = quick.client.call(
        quick.srv("set_parameters_atomically"),
        SetParametersAtomically,
        SetParametersAtomically.Request(parameters=[names, pillar]),
        timeout_s=10.0,
    ).result
    assert result.successful, result.reason
    markers = quick.world_markers.wait_for(lambda m: quick.world_markers.messages.index(m) >= count, 10.0)
    assert [m.ns for m in markers.markers].count("obstacles") == 1
    ok, reason = _set(quick, "world.obstacle_names", ParameterValue(type=ParameterType.PARAMETER_STRING_ARRAY))
    assert ok, reason
    markers = quick.world_markers.wait_for(lambda m: quick.world_markers.messages.index(m) >= count + 1, 10.0)
    assert "obstacles" not in [m.ns for m in markers.markers]

    # parameters the node does not know are refused
    ok, reason = _set(quick, "colour", ParameterValue(type=ParameterType.PARAMETER_STRING, string_value="red"))
    assert not ok
    assert "colour" in reason


def test_a_new_request_or_cancel_stops_a_playback(quick: Session) -> None:
    quick.wait_idle()
    # a playback of many seconds; set through the deprecated alias trajectory.joint_speed, which wins when set
    slow = ParameterValue(type=ParameterType.PARAMETER_DOUBLE, double_value=0.2)
    assert _set(quick, "trajectory.joint_speed", slow)[0]
    try:
        first = run_id_of(quick.plan().message)
        quick.feedback.wait_for(lambda m: kv(m).get("run_id") == first and kv(m).get("phase") == "SUCCEEDED", 5.0)
        second = quick.plan()
        assert second.success, second.message
        quick.feedback.wait_for(
            lambda m: kv(m).get("run_id") == first and kv(m).get("phase") == "playback_stopped", 5.0
        )
        assert quick.status_of(first) == GoalStatus.STATUS_SUCCEEDED  # the outcome stays
        cancel = quick.client.call(quick.srv("cancel"), Trigger, timeout_s=5.0)
        assert cancel.success
        assert "playback" in cancel.message
        assert run_id_of(second.message) in cancel.message
    finally:
        assert _set(
            quick,
            "trajectory.joint_speed",
            ParameterValue(type=ParameterType.PARAMETER_DOUBLE, double_value=FAST["trajectory.max_velocity"]),
        )[0]


def test_cancel_with_nothing_running_says_so(quick: Session) -> None:
    quick.wait_idle()
    response = quick.client.call(quick.srv("cancel"), Trigger, timeout_s=10.0)
    assert not response.success
    assert "nothing to cancel" in response.message


# --------------------------------------------------------------------------- unreachable goal


@pytest.fixture(scope="module")
def unreachable(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Session]:
    tmp = tmp_path_factory.mktemp("unreachable")
    node = NodeProcess(tmp / "node.log", UNREACHABLE, {"record.directory": str(tmp / "recordings")})
    session = Session(node)
    session.recordings = tmp / "recordings"
    try:
        yield session
    finally:
        code = session.close()
        assert code == 0, f"node exit code {code}; output:\n{node.output()}"


def test_plan_fails_on_an_unreachable_goal(unreachable: Session) -> None:
    response = unreachable.plan()
    assert not response.success
    assert "GOAL_OUT_OF_REACH" in response.message
    run_id = run_id_of(response.message)
    unreachable.wait_status(run_id, GoalStatus.STATUS_ABORTED)
    aborted = unreachable.events.wait_for(lambda m: json.loads(m.data)["event"] == "aborted", 10.0)
    event = json.loads(aborted.data)
    assert event["run_id"] == run_id
    assert event["code"] == "GOAL_OUT_OF_REACH"
    assert "reach" in event["message"]
    assert not unreachable.trajectory.messages, "a failed run publishes no trajectory"
    if HAVE_RECORDER:
        # without a playback, the recording is complete when the answer comes
        assert (unreachable.recordings / run_id / "metadata.yaml").is_file()
        assert f"{unreachable.node.name}/status" in recorded_topics(unreachable.recordings / run_id)


def test_call_plan_client_reports_the_failure(unreachable: Session) -> None:
    done = subprocess.run(
        [sys.executable, "-m", "clew_ros.client.call_plan", "--node", unreachable.node.name, "--timeout", "20"],
        capture_output=True,
        text=True,
        timeout=40,
        check=False,
    )
    assert done.returncode == 1, done.stdout + done.stderr
    assert "success: False" in done.stdout
    assert "GOAL_OUT_OF_REACH" in done.stdout


def test_world_yaml_round_trips_the_world_file(unreachable: Session) -> None:
    world_yaml = unreachable.client.inbox(f"{unreachable.node.name}/world_yaml", String, LATCHED)
    tree = next(iter(yaml.safe_load(world_yaml.wait_for(timeout_s=10.0).data).values()))
    expected = world_from_parameters(read_parameter_file(UNREACHABLE))
    world = world_from_parameters(tree["ros__parameters"])
    assert world.name == expected.name
    assert np.allclose(world.object.goal, expected.object.goal)
