"""Security: ``use_sim_time`` fixed at start unless ``parameters.allow_sim_time_changes``, ``planner.*`` fixed
as a whole with ``parameters.lock_planner``, and the refused requests recorded in the current run's recording
capped at ``Limits.max_recorded_refusals`` (a real node, a peer in another process)."""

from __future__ import annotations

import json
from collections.abc import Iterator
from pathlib import Path

import pytest

rclpy = pytest.importorskip("rclpy")

from geometry_msgs.msg import PoseStamped  # noqa: E402
from helpers.node_harness import HAVE_RECORDER, Session, run_id_of, wait_until  # noqa: E402
from helpers.rel_node import get_parameters, goal_publisher, set_parameters  # noqa: E402
from helpers.security_node import quick_session  # noqa: E402

from clew_ros.core.parameters import LIMITS  # noqa: E402

pytestmark = pytest.mark.ros


@pytest.fixture(scope="module")
def planner_locked(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Session]:
    tmp = tmp_path_factory.mktemp("planner_locked")
    parameters = {"record.directory": str(tmp / "runs"), "parameters.lock_planner": True}
    with quick_session(tmp / "node.log", parameters) as session:
        session.tmp = tmp  # type: ignore[attr-defined]
        yield session


def test_use_sim_time_is_fixed_at_start(planner_locked: Session) -> None:
    [result] = set_parameters(planner_locked, {"use_sim_time": True})
    assert not result.successful
    assert "use_sim_time" in result.reason, result.reason
    assert "parameters.allow_sim_time_changes" in result.reason, result.reason
    assert get_parameters(planner_locked, ["use_sim_time"]) == {"use_sim_time": False}


def test_the_planner_parameters_are_fixed_as_a_whole(planner_locked: Session) -> None:
    for name, value in (("planner.seed", 7), ("planner.time_limit", 5.0), ("planner.threads", 1)):
        [result] = set_parameters(planner_locked, {name: value})
        assert not result.successful, name
        assert name in result.reason, result.reason
    [result] = set_parameters(planner_locked, {"playback.rate": 40.0})  # the rest of the settable ones stay so
    assert result.successful, result.reason
    assert get_parameters(planner_locked, ["planner.seed"]) == {"planner.seed": 0}


@pytest.mark.skipif(not HAVE_RECORDER, reason="needs the rosbag2 recorder")
def test_refusals_recorded_in_the_current_run_are_capped(tmp_path: Path) -> None:
    """Goals refused while a run plays back (slowly: it stays open) are recorded up to the cap; the rest are
    published and not recorded, and the node warns once."""
    from std_srvs.srv import Trigger

    from clew_ros.recording import Recording

    slow = {"trajectory.max_velocity": 0.05, "trajectory.max_acceleration": 0.5}
    with quick_session(tmp_path / "node.log", {"record.directory": str(tmp_path / "runs"), **slow}) as session:
        response = session.plan()
        assert response.success, response.message
        run_id = run_id_of(response.message)
        publisher = goal_publisher(session)
        extra = 30
        mark = len(session.events.messages)

        def refused() -> int:
            events = (json.loads(msg.data) for msg in session.events.messages[mark:])
            return sum(1 for e in events if e.get("source") == "goal_pose" and e.get("event") == "aborted")

        for sent in range(1, LIMITS.max_recorded_refusals + extra + 1):  # each refused before the next is sent
            goal = PoseStamped()
            goal.header.frame_id = "not_world"
            goal.pose.orientation.w = 1.0
            publisher.publish(goal)
            wait_until(lambda sent=sent: refused() >= sent, 10.0, f"refusal {sent} published")
        warned = "Limits.max_recorded_refusals"
        wait_until(lambda: warned in session.node.output(), 10.0, "the warning")
        assert session.node.output().count(warned) == 1
        session.client.call(session.srv("cancel"), Trigger, Trigger.Request())  # ends the playback and its recording
        folder = tmp_path / "runs" / run_id
        wait_until((folder / "metadata.yaml").is_file, 20.0, "the closed recording")
    recording = Recording(folder)
    [topic] = [name for name in recording.topics if name.endswith("/clew_planner/events")]
    events = [json.loads(m.data) for m in recording.decoded(topic)]
    recorded = [e for e in events if e.get("source") == "goal_pose" and e.get("event") == "aborted"]
    assert len(recorded) == LIMITS.max_recorded_refusals


def test_use_sim_time_changes_when_the_switch_allows(tmp_path: Path) -> None:
    parameters = {"record.enabled": False, "parameters.allow_sim_time_changes": True}
    with quick_session(tmp_path / "node.log", parameters) as session:
        [result] = set_parameters(session, {"use_sim_time": True})
        assert result.successful, result.reason
        [result] = set_parameters(session, {"use_sim_time": False})
        assert result.successful, result.reason
        [result] = set_parameters(session, {"planner.seed": 3})  # not locked without parameters.lock_planner
        assert result.successful, result.reason
