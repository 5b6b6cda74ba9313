"""Security: the parameters that matter for safety are fixed at start (a real node, a peer in another process).

Started without the development switch, a node refuses a peer's
``~/set_parameters`` on ``world.*``, ``record.*``, ``trajectory.*`` and
``live.*`` (a declared one: read-only, refused by rclpy; a new one, such as
an obstacle: refused by the node), each with a reason naming the parameter,
and keeps planning and recording where it was told at start; ``planner.*``
stays settable within its range. Started with
``parameters.allow_runtime_changes: true``, the same changes go through,
within the caps (:data:`clew_ros.core.parameters.LIMITS`), and the switch
itself stays fixed. A ``~/goal_pose`` frame id is quoted short and printable.
"""

from __future__ import annotations

import json
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

rclpy = pytest.importorskip("rclpy")

from geometry_msgs.msg import PoseStamped  # noqa: E402
from helpers.node_harness import HAVE_RECORDER, Session, wait_until  # noqa: E402
from helpers.rel_node import get_parameters, goal_publisher, set_parameters, wait_event  # noqa: E402
from helpers.security_node import plan_and_wait, quick_session  # noqa: E402

from clew_ros.core.parameters import LIMITS  # noqa: E402

pytestmark = pytest.mark.ros

#: What a peer tries, and the value the node started with (rel_fast.yaml and FAST), where it has one.
ATTEMPTS: list[tuple[str, Any]] = [
    ("record.directory", "ELSEWHERE"),  # replaced by a folder of the test's
    ("record.enabled", False),
    ("record.max_runs", 0),
    ("world.robot.joint_upper", [6.0, 6.0]),
    ("world.obstacle_names", ["block", "extra"]),
    ("world.obstacles.block", [-0.1, -0.1, 0.1, -0.1, 0.1, 0.1]),
    ("world.obstacles.extra", [-0.1, -0.1, 0.1, -0.1, 0.1, 0.1]),  # not declared: a new obstacle
    ("world.object.goal", [1.8, -0.6, 0.0]),
    ("trajectory.max_velocity", 1000.0),
    ("trajectory.max_acceleration", 100000.0),
    ("trajectory.joint_speed", 500.0),
    ("live.foxglove_port", 8765),
    ("parameters.allow_runtime_changes", True),
]


def attempt(value: Any, elsewhere: Path) -> Any:
    return str(elsewhere) if value == "ELSEWHERE" else value


@pytest.fixture(scope="module")
def locked(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Session]:
    tmp = tmp_path_factory.mktemp("locked")
    with quick_session(tmp / "node.log", {"record.directory": str(tmp / "runs")}) as session:
        session.tmp = tmp  # type: ignore[attr-defined]
        yield session


@pytest.fixture(scope="module")
def unlocked(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Session]:
    tmp = tmp_path_factory.mktemp("unlocked")
    parameters = {"record.directory": str(tmp / "runs"), "parameters.allow_runtime_changes": True}
    with quick_session(tmp / "node.log", parameters) as session:
        session.tmp = tmp  # type: ignore[attr-defined]
        yield session


def test_a_peer_cannot_change_what_matters_for_safety(locked: Session) -> None:
    tmp: Path = locked.tmp  # type: ignore[attr-defined]
    elsewhere = tmp / "elsewhere"
    names = [name for name, _ in ATTEMPTS if name != "world.obstacles.extra"]
    before = get_parameters(locked, names)
    refused = 0
    for name, value in ATTEMPTS:
        [result] = set_parameters(locked, {name: attempt(value, elsewhere)})
        assert not result.successful, f"{name}: accepted"
        assert name in result.reason, f"{name}: the reason does not name it: {result.reason!r}"
        # declared: a read-only descriptor (rclpy's refusal); new: the node's own, saying how to allow it
        expected = "fixed at start" if name == "world.obstacles.extra" else "read-only"
        assert expected in result.reason, result.reason
        refused += 1
    # atomically, together with a settable parameter: nothing changes
    [result] = set_parameters(locked, {"planner.seed": 7, "world.robot.joint_upper": [6.0, 6.0]}, atomically=True)
    assert not result.successful
    assert "world.robot.joint_upper" in result.reason, result.reason
    assert get_parameters(locked, [*names, "planner.seed"]) == {**before, "planner.seed": 0}
    print(f"\n{refused + 1} changes by a peer refused, each naming its parameter; nothing changed")

    # the node keeps planning, in the world it started with, recording where it was told at start
    response, run_id = plan_and_wait(locked)
    assert response.success, response.message
    assert not elsewhere.exists()
    if HAVE_RECORDER:
        runs = (tmp / "runs").resolve()
        assert f"recording {runs / run_id}" in response.message, response.message
        wait_until((runs / run_id / "metadata.yaml").is_file, 10.0, "the closed recording")
    # planner.* stays settable, within its range
    [result] = set_parameters(locked, {"planner.time_limit": 5.0})
    assert result.successful, result.reason
    [result] = set_parameters(locked, {"planner.time_limit": 86400.0})
    assert not result.successful
    assert "planner.time_limit" in result.reason, result.reason


def test_the_development_switch_lets_them_change(unlocked: Session) -> None:
    tmp: Path = unlocked.tmp  # type: ignore[attr-defined]
    elsewhere = tmp / "elsewhere"
    for name, value in ATTEMPTS:
        if name in ("parameters.allow_runtime_changes", "live.foxglove_port", "world.obstacle_names"):
            continue  # the switch and the live view are read at start only; the names are set with the polygon
        if name.startswith("world.obstacles."):
            continue
        [result] = set_parameters(unlocked, {name: attempt(value, elsewhere)})
        assert result.successful, f"{name}: {result.reason}"
    [result] = set_parameters(
        unlocked,
        {
            "world.obstacle_names": ["block", "extra"],
            "world.obstacles.extra": [-2.4, 2.1, -2.1, 2.1, -2.1, 2.4, -2.4, 2.4],
        },
        atomically=True,
    )
    assert result.successful, result.reason
    got = get_parameters(unlocked, ["record.directory", "world.robot.joint_upper", "trajectory.max_velocity"])
    assert got == {
        "record.directory": str(elsewhere),
        "world.robot.joint_upper": [6.0, 6.0],
        "trajectory.max_velocity": 1000.0,
    }
    for name in ("parameters.allow_runtime_changes", "live.foxglove_port"):  # read only, switch or not
        [result] = set_parameters(unlocked, {name: False if name.startswith("parameters") else 8765})
        assert not result.successful
        assert name in result.reason, result.reason
    # record.enabled was switched off above: on again, and the next run records into the new directory
    [result] = set_parameters(unlocked, {"record.enabled": True, "record.max_runs": 100}, atomically=True)
    assert result.successful, result.reason
    response, run_id = plan_and_wait(unlocked)
    assert response.success, response.message
    if HAVE_RECORDER:
        assert f"recording {elsewhere.resolve() / run_id}" in response.message, response.message
    assert "allow_runtime_changes is true" in unlocked.node.output()  # the node warns at start


def test_caps_are_refused_by_a_running_node(unlocked: Session) -> None:
    """Even with the switch on, a peer cannot add parameters beyond the caps."""
    long_name = "world.obstacles." + "o" * LIMITS.max_name_chars
    [result] = set_parameters(unlocked, {long_name: [0.0, 0.0, 0.1, 0.0, 0.1, 0.1]})
    assert not result.successful
    assert "Limits.max_name_chars" in result.reason, result.reason
    many = {f"world.obstacles.flood_{i}": [0.0, 0.0, 0.1, 0.0, 0.1, 0.1] for i in range(LIMITS.max_parameters)}
    [result] = set_parameters(unlocked, many, atomically=True, timeout_s=60.0)
    assert not result.successful
    assert "Limits.max_parameters" in result.reason, result.reason
    assert not get_parameters(unlocked, ["world.obstacles.flood_0"])["world.obstacles.flood_0"]
    response, _run_id = plan_and_wait(unlocked)
    assert response.success, response.message


def test_a_goal_frame_id_is_quoted_short_and_printable(locked: Session) -> None:
    publisher = goal_publisher(locked)
    frame = "\x1b[31m" + "f" * 10_000
    goal = PoseStamped()
    goal.header.frame_id = frame
    goal.pose.orientation.w = 1.0
    mark = len(locked.events.messages)
    publisher.publish(goal)
    event, _ = wait_event(locked, mark, lambda e: "header.frame_id" in str(e.get("message", "")))
    message = event["message"]
    assert "\x1b" not in message, message
    assert "f" * (LIMITS.max_quoted_chars + 1) not in message, message
    assert f"({len(frame)} characters)" in message, message
    assert len(json.dumps(event)) < 1000
    assert "f" * (LIMITS.max_quoted_chars + 1) not in locked.node.output()
