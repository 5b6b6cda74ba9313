"""Per-joint trajectory limits and ``~/joint_states`` velocities on a running ``clew_planner``.

The node starts with a limit per joint (joint_2 much slower than joint_1);
``~/trajectory`` is timed with each joint's own limits, ``~/joint_states``
carries velocities within them; set-parameters refuses a list of the wrong
length or a non-positive limit, naming the parameter, and the node serves
on; a valid change applies from the next run.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest

rclpy = pytest.importorskip("rclpy")

from helpers.node_harness import PLAN_TIMEOUT_S, NodeProcess, Session, run_id_of  # noqa: E402
from rcl_interfaces.msg import Parameter as ParameterMsg  # noqa: E402
from rcl_interfaces.msg import ParameterType, ParameterValue  # noqa: E402
from rcl_interfaces.srv import GetParameters, SetParameters  # noqa: E402
from trajectory_msgs.msg import JointTrajectory  # noqa: E402

from clew_ros.motion.playback import track_from_plan  # noqa: E402
from clew_ros.planar.plan import validate_plan  # noqa: E402
from clew_ros.planar.world import load_world  # noqa: E402
from clew_ros.recording import trajectory_to_plan  # noqa: E402

pytestmark = pytest.mark.ros

QUICK = Path(__file__).parents[1] / "worlds" / "node_quick.yaml"
VELOCITY = [8.0, 1.5]  # rad/s, joint_1 then joint_2
ACCELERATION = [80.0, 6.0]  # rad/s^2
DWELL_S = 0.05


@pytest.fixture(scope="module")
def node(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Session]:
    tmp = tmp_path_factory.mktemp("joint_limits")
    parameters = {
        "record.enabled": False,
        "trajectory.max_velocity": VELOCITY,
        "trajectory.max_acceleration": ACCELERATION,
        "trajectory.grasp_dwell": DWELL_S,
        "playback.rate": 100.0,
        "parameters.allow_runtime_changes": True,  # the limits' checks at run time (else fixed at start)
    }
    process = NodeProcess(tmp / "node.log", QUICK, parameters)
    session = Session(process)
    try:
        yield session
    finally:
        code = session.close()
        assert code == 0, f"node exit code {code}; output:\n{process.output()}"


def _plan_and_play(session: Session) -> tuple[str, JointTrajectory]:
    """Plan to the node's goal and wait until the plan is played back; the run id and its ~/trajectory."""
    response = session.plan(PLAN_TIMEOUT_S)
    assert response.success, response.message
    run_id = run_id_of(response.message)
    session.wait_playback(run_id, timeout_s=60.0)
    accepted = next(e for e in session.events_of(run_id) if e["event"] == "accepted")
    trajectory = session.trajectory.wait_for(
        lambda m: m.header.stamp.sec * 10**9 + m.header.stamp.nanosec >= _stamp_ns(session, run_id),
        timeout_s=10.0,
    )
    assert accepted["world"] == "node_quick"
    return run_id, trajectory


def _stamp_ns(session: Session, run_id: str) -> int:
    for msg in reversed(session.status.messages):
        for entry in msg.status_list:
            if bytes(entry.goal_info.goal_id.uuid).hex() == run_id:
                return entry.goal_info.stamp.sec * 10**9 + entry.goal_info.stamp.nanosec
    raise AssertionError(f"run {run_id} not in ~/status")


def _times_ns(trajectory: JointTrajectory) -> list[int]:
    return [p.time_from_start.sec * 10**9 + p.time_from_start.nanosec for p in trajectory.points]


def _set(session: Session, name: str, value: ParameterValue) -> tuple[bool, str]:
    request = SetParameters.Request(parameters=[ParameterMsg(name=name, value=value)])
    response = session.client.call(session.srv("set_parameters"), SetParameters, request, timeout_s=10.0)
    return response.results[0].successful, response.results[0].reason


def _doubles(values: list[float]) -> ParameterValue:
    return ParameterValue(type=ParameterType.PARAMETER_DOUBLE_ARRAY, double_array_value=values)


def test_each_joint_is_timed_and_played_back_within_its_own_limits(node: Session) -> None:
    world = load_world(QUICK)
    count = len(node.joint_states.messages)
    _, trajectory = _plan_and_play(node)
    planned = trajectory_to_plan(world, trajectory)
    assert validate_plan(world, planned) == []
    # ~/trajectory: exactly the timing of the per-joint limits (each piece as short as its slowest joint allows)
    expected = track_from_plan(
        world, planned, max_velocity_rad_s=VELOCITY, max_acceleration_rad_s2=ACCELERATION, grasp_dwell_s=DWELL_S
    )
    assert _times_ns(trajectory) == expected.times_ns.tolist()
    one_limit = track_from_plan(
        world, planned, max_velocity_rad_s=VELOCITY[0], max_acceleration_rad_s2=ACCELERATION[0], grasp_dwell_s=DWELL_S
    )
    assert expected.duration_s > one_limit.duration_s  # joint_2's own, lower limits are what make it longer

    # ~/joint_states of the playback (over: _plan_and_play waited for it): a velocity for every name, each
    # joint within its own limits
    played = node.joint_states.messages[count:]
    assert played, "no ~/joint_states during the playback"
    velocities = np.array([list(m.velocity) for m in played])
    assert all(list(m.name) == ["joint_1", "joint_2", "gripper"] for m in played)
    assert velocities.shape == (len(played), 3)
    assert np.all(velocities[:, 2] == 0.0)  # the gripper
    assert np.all(np.abs(velocities[:, :2]) <= np.array(VELOCITY) * (1 + 1e-9))
    assert np.any(np.abs(velocities[:, :2]) > 0.0)  # the arm does move
    assert np.all(velocities[-1] == 0.0)  # the last message is the last point, at rest
    assert list(played[-1].position[:2]) == pytest.approx(planned.segments[-1].waypoints[-1].tolist())


def test_bad_limits_are_refused_naming_the_parameter_and_the_node_serves_on(node: Session) -> None:
    per_joint = "expected a number for every joint or a list with one per joint (2: joint_1, joint_2)"
    for name, value, reason in [
        (
            "trajectory.max_velocity",
            _doubles([1.0, 2.0, 3.0]),
            f"trajectory.max_velocity: {per_joint}, got a list of 3",
        ),
        ("trajectory.max_acceleration", _doubles([2.0]), f"trajectory.max_acceleration: {per_joint}, got a list of 1"),
        (
            "trajectory.max_velocity",
            _doubles([1.0, 0.0]),
            "trajectory.max_velocity: expected a value in [0.001, 1000.0] for joint_2, got 0.0",
        ),
        (  # one number out of range: rclpy's own range check (the descriptor's) answers first
            "trajectory.max_acceleration",
            ParameterValue(type=ParameterType.PARAMETER_DOUBLE, double_value=-1.0),
            "Parameter trajectory.max_acceleration out of range Min: 0.001, Max: 100000.0, value: -1.0",
        ),
        (
            "trajectory.max_velocity",
            ParameterValue(type=ParameterType.PARAMETER_STRING_ARRAY, string_array_value=["fast", "slow"]),
            "trajectory.max_velocity: expected a number for joint_1, got 'fast'",
        ),
    ]:
        ok, why = _set(node, name, value)
        assert not ok, name
        assert why == reason
    response = node.client.call(
        node.srv("get_parameters"),
        GetParameters,
        GetParameters.Request(names=["trajectory.max_velocity", "trajectory.max_acceleration"]),
        timeout_s=10.0,
    )
    assert [list(v.double_array_value) for v in response.values] == [VELOCITY, ACCELERATION]  # kept

    # a valid change (integers, one per joint) applies from the next run
    new_velocity = ParameterValue(type=ParameterType.PARAMETER_INTEGER_ARRAY, integer_array_value=[2, 6])
    ok, why = _set(node, "trajectory.max_velocity", new_velocity)
    assert ok, why
    _, trajectory = _plan_and_play(node)
    world = load_world(QUICK)
    planned = trajectory_to_plan(world, trajectory)
    expected = track_from_plan(
        world, planned, max_velocity_rad_s=[2.0, 6.0], max_acceleration_rad_s2=ACCELERATION, grasp_dwell_s=DWELL_S
    )
    assert _times_ns(trajectory) == expected.times_ns.tolist()
    assert math.isfinite(expected.duration_s)
