"""Reliability: ~/cancel in every state, and the time limit honoured.

README: ``~/cancel`` stops the planner within about 100 ms and answers once it
has stopped; during a playback it stops the playback (the run stays
succeeded); with nothing running it answers ``success: false``. The node
here serves ``config/behind_wall.yaml``: ``~/plan`` explores until canceled or
out of time (a wall hides its goal from the arm), a ``~/goal_pose`` above the
wall plans in about a second. Latencies are measured from the cancel request
to the receive time of the answer / status, and printed (``-s`` shows them).
The node's own figure (``canceled run ... in N ms``, from the request to the
stopped run) is held to :data:`CANCEL_BOUND_S`; end to end, DDS included, to
:data:`DDS_BOUND_S`.

Cancel "before the worker started" cannot be forced over DDS (the goal and
the cancel travel on different channels), so it is tested in-process: the
worker is held at its entry until the cancel has been requested.
"""

from __future__ import annotations

import json
import re
import threading
import time
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest

rclpy = pytest.importorskip("rclpy")


from action_msgs.msg import GoalStatus  # noqa: E402
from helpers.node_harness import NodeProcess, Session, kv, run_id_of, wait_future  # noqa: E402
from helpers.rel_node import goal_publisher, received_at, set_parameters, status_is, wait_event  # noqa: E402
from std_srvs.srv import Trigger  # noqa: E402

from clew_ros.core.settings import Outcome  # noqa: E402
from clew_ros.planar.world import read_parameter_file  # noqa: E402
from clew_ros.ros import messages  # noqa: E402
from clew_ros.ros.parameters import flatten  # noqa: E402

pytestmark = pytest.mark.ros

ROOT = Path(__file__).resolve().parents[2]
UNREACHABLE = ROOT / "config" / "behind_wall.yaml"
FAST_WORLD = ROOT / "test" / "worlds" / "rel_fast.yaml"
REACHABLE_GOAL = np.array([0.6, 1.1, 0.0])  # above the wall: plans in about a second
#: The contract's target is 100 ms, on an idle machine: the figures printed here (and docs/reliability.md)
#: show it. The test asserts the node's own figure ("... in N ms") against ten times that: on a loaded
#: 2-core machine CPU contention stretches the planner's step in progress and the switch to the service
#: thread several times over, and what the test must catch is a cancel nobody looks at (it would take the
#: run's 30 s), not a busy machine.
CANCEL_BOUND_S = 1.0
#: End to end (request sent -> answer or status received here): DDS delivery adds its own jitter,
#: now and then hundreds of ms on a busy machine (a reliable message repaired after a loss).
DDS_BOUND_S = 5.0
#: A run ends within planner.time_limit + this (s), measured by the planner: it looks at the clock between
#: steps of well under 0.1 s on an idle machine, which a loaded 2-core machine stretches several times.
TIME_LIMIT_SLACK_S = 1.0
#: ... and the ~/plan answer reaches the caller within time_limit + this (s), DDS included.
TIME_LIMIT_ROUND_TRIP_SLACK_S = TIME_LIMIT_SLACK_S + 1.0
MEASURED: dict[str, float] = {}


@pytest.fixture(scope="module")
def walled(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Session]:
    tmp = tmp_path_factory.mktemp("cancel")
    node = NodeProcess(
        tmp / "node.log",
        UNREACHABLE,
        {
            "record.directory": str(tmp / "recordings"),
            "planner.time_limit": 30.0,
            # a playback of several seconds, so that a cancel lands in it
            "trajectory.max_velocity": 0.5,
            "playback.rate": 50.0,
        },
    )
    session = Session(node)
    session.recordings = tmp / "recordings"
    try:
        yield session
    finally:
        code = session.close()
        assert code == 0, f"node exit code {code}; output:\n{node.output()}"
        if MEASURED:
            print(
                "\ncancel / time-limit figures (ms): " + ", ".join(f"{k} {1000 * v:.0f}" for k, v in MEASURED.items())
            )


def cancel(session: Session) -> tuple[Trigger.Response, float, float]:
    """Call ~/cancel; returns (response, sent time, answer time) in monotonic seconds."""
    future = session.client.call_async(session.srv("cancel"), Trigger)
    sent = time.monotonic()
    response = wait_future(future, 10.0, "~/cancel did not answer")
    return response, sent, time.monotonic()


def node_side_s(response: Trigger.Response) -> float:
    """The node's own figure in the answer (``... in N ms``), in seconds."""
    match = re.search(r" in (\d+) ms", response.message)
    assert match, f"no node-side figure in {response.message!r}"
    return float(match.group(1)) / 1000


def goal_pose_run(session: Session) -> str:
    """Send the reachable goal; return the run id once accepted."""
    publisher = goal_publisher(session)
    mark = len(session.events.messages)
    publisher.publish(messages.goal_pose_stamped(REACHABLE_GOAL, 0))
    accepted, _ = wait_event(session, mark, lambda e: e["event"] == "accepted" and e.get("source") == "goal_pose")
    return accepted["run_id"]


def assert_next_plan_works(session: Session) -> None:
    """A goal pose above the wall succeeds; its playback is then stopped (not needed here)."""
    before = {id(m) for m in session.joint_states.messages}
    run_id = goal_pose_run(session)
    session.status.wait_for(status_is(run_id, GoalStatus.STATUS_SUCCEEDED), 30.0)
    playback_started(session, before)
    response, _, _ = cancel(session)  # stops the playback
    assert response.success, response.message
    assert "stopped the playback" in response.message, response.message


def test_cancel_with_nothing_running(walled: Session) -> None:
    response, sent, answered = cancel(walled)
    MEASURED["nothing_running_answer"] = answered - sent
    assert not response.success, response.message
    assert response.message.startswith("nothing to cancel"), response.message
    assert answered - sent < DDS_BOUND_S
    assert_next_plan_works(walled)


def test_cancel_right_after_the_goal(walled: Session) -> None:
    """Over DDS: the cancel follows the ``accepted`` event at once (the worker has barely started)."""
    future_mark = len(walled.events.messages)
    plan_future = walled.client.call_async(walled.srv("plan"), Trigger)
    accepted, _ = wait_event(walled, future_mark, lambda e: e["event"] == "accepted", 10.0)
    run_id = accepted["run_id"]
    response, sent, answered = cancel(walled)
    canceled_at = received_at(walled.status, status_is(run_id, GoalStatus.STATUS_CANCELED), 5.0)
    plan_response = wait_future(plan_future, 5.0, "~/plan after the cancel")
    MEASURED["after_goal_answer"] = answered - sent
    MEASURED["after_goal_status"] = canceled_at - sent
    MEASURED["after_goal_node_side"] = node_side_s(response)
    assert response.success, response.message
    assert f"canceled run {run_id} in " in response.message, response.message
    assert not plan_response.success
    assert f"run {run_id}: CANCELED: " in plan_response.message
    assert node_side_s(response) < CANCEL_BOUND_S
    assert answered - sent < DDS_BOUND_S
    assert canceled_at - sent < DDS_BOUND_S
    outcome = [e for e in walled.events_of(run_id) if e["event"] in ("succeeded", "aborted", "canceled")]
    assert [e["code"] for e in outcome] == ["CANCELED"]
    assert_next_plan_works(walled)


def test_cancel_during_explore(walled: Session) -> None:
    mark = len(walled.events.messages)
    plan_future = walled.client.call_async(walled.srv("plan"), Trigger)
    accepted, _ = wait_event(walled, mark, lambda e: e["event"] == "accepted", 10.0)
    run_id = accepted["run_id"]
    wait_event(walled, mark, lambda e: e["run_id"] == run_id and e["event"] == "landmark", 15.0)  # EXPLORE runs
    response, sent, answered = cancel(walled)
    canceled_at = received_at(walled.status, status_is(run_id, GoalStatus.STATUS_CANCELED), 5.0)
    plan_response = wait_future(plan_future, 5.0, "~/plan after the cancel")
    MEASURED["explore_answer"] = answered - sent
    MEASURED["explore_status"] = canceled_at - sent
    MEASURED["explore_node_side"] = node_side_s(response)
    assert response.success, response.message
    assert f"canceled run {run_id} in " in response.message, response.message
    assert not plan_response.success
    assert "CANCELED" in plan_response.message
    assert node_side_s(response) < CANCEL_BOUND_S
    assert answered - sent < DDS_BOUND_S
    assert canceled_at - sent < DDS_BOUND_S
    walled.feedback.wait_for(lambda m: kv(m).get("run_id") == run_id and kv(m).get("phase") == "CANCELED", 2.0)
    # the recording is closed before the answer goes out
    assert (walled.recordings / run_id / "metadata.yaml").is_file()
    assert_next_plan_works(walled)


def playback_started(session: Session, before: set[int]) -> None:
    """Wait for a ``~/joint_states`` message not among ``before`` (ids of the messages seen before the
    run was sent): this run's playback is running (older messages belong to earlier playbacks)."""
    session.joint_states.wait_for(lambda m: id(m) not in before, 10.0)


def test_cancel_during_playback(walled: Session) -> None:
    before = {id(m) for m in walled.joint_states.messages}
    run_id = goal_pose_run(walled)
    walled.status.wait_for(status_is(run_id, GoalStatus.STATUS_SUCCEEDED), 30.0)
    playback_started(walled, before)
    response, sent, answered = cancel(walled)
    stopped_at = received_at(
        walled.feedback, lambda m: kv(m).get("run_id") == run_id and kv(m).get("phase") == "playback_stopped", 5.0
    )
    MEASURED["playback_answer"] = answered - sent
    MEASURED["playback_feedback"] = stopped_at - sent
    MEASURED["playback_node_side"] = node_side_s(response)
    assert response.success, response.message
    assert f"stopped the playback of run {run_id} in " in response.message, response.message
    assert node_side_s(response) < CANCEL_BOUND_S
    assert answered - sent < DDS_BOUND_S
    assert stopped_at - sent < DDS_BOUND_S
    assert walled.status_of(run_id) == GoalStatus.STATUS_SUCCEEDED  # the outcome stays
    # nothing is left to cancel
    assert not cancel(walled)[0].success
    assert_next_plan_works(walled)


def test_time_limit_is_honoured_by_the_node(walled: Session) -> None:
    """config/behind_wall.yaml, planner.time_limit 2 (default tuning): the run ends by the limit plus
    :data:`TIME_LIMIT_SLACK_S`."""
    limit = 2.0
    assert set_parameters(walled, {"planner.time_limit": limit})[0].successful
    try:
        mark = len(walled.events.messages)
        sent = time.monotonic()
        response = walled.plan(timeout_s=limit + 10.0)
        round_trip = time.monotonic() - sent
        run_id = run_id_of(response.message)
        outcome, _ = wait_event(walled, mark, lambda e: e["run_id"] == run_id and e["event"] == "aborted", 2.0)
        MEASURED["time_limit_planner"] = outcome["time_s"]
        MEASURED["time_limit_round_trip"] = round_trip
        assert outcome["code"] in ("TIME_LIMIT", "NO_PATH_AT_RESOLUTION"), outcome
        assert f"run {run_id}: {outcome['code']}: " in response.message
        assert outcome["time_s"] <= limit + TIME_LIMIT_SLACK_S, outcome
        assert round_trip <= limit + TIME_LIMIT_ROUND_TRIP_SLACK_S, f"~/plan answered after {round_trip:.3f} s"
    finally:
        assert set_parameters(walled, {"planner.time_limit": 30.0})[0].successful


def test_every_run_had_exactly_one_outcome(walled: Session) -> None:
    events = [json.loads(m.data) for m in walled.events.messages]
    runs = {e["run_id"] for e in events if e["event"] == "accepted"}
    assert runs
    for run_id in runs:
        outcomes = [e for e in events if e["run_id"] == run_id and e["event"] in ("succeeded", "aborted", "canceled")]
        assert len(outcomes) == 1, outcomes
        assert outcomes[0]["code"]
        assert outcomes[0]["message"]
        assert isinstance(outcomes[0]["code_value"], int)
        # README: `time` is wall-clock seconds, `time_s` the planning time
        assert abs(outcomes[0]["time"] - time.time()) < 600, outcomes[0]
        assert 0 <= outcomes[0]["time_s"] < 60, outcomes[0]


# --------------------------------------------------------------------------- in-process: before the worker


@pytest.fixture
def local_node(tmp_path: Path):
    """A PlannerNode in this process (own context, no executor), recording to ``tmp_path / "recordings"``.

    Its public entry points (``request_plan``, ``cancel``) are called directly.
    """
    from rclpy.parameter import Parameter

    from clew_ros.node.planner_node import PlannerNode

    context = rclpy.Context()
    rclpy.init(context=context)
    values = flatten(read_parameter_file(FAST_WORLD))
    values.update(
        {
            "record.directory": str(tmp_path / "recordings"),
            "trajectory.max_velocity": 50.0,
            "trajectory.max_acceleration": 1000.0,
        }
    )
    overrides = [Parameter(name, value=value) for name, value in values.items()]
    node = PlannerNode(context=context, parameter_overrides=overrides, namespace=f"/rel{id(tmp_path) % 10**6}")
    try:
        yield node
    finally:
        node.shutdown_runs()
        node.destroy_node()
        context.try_shutdown()


def test_cancel_before_the_worker_started(local_node, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    from clew_ros.node.run import Phase
    from clew_ros.node.worker import RunWorker

    node = local_node
    original = RunWorker.execute
    held = threading.Event()

    def execute_after_cancel(worker: RunWorker, run) -> None:  # the worker's first act waits for the cancel
        held.set()
        deadline = time.monotonic() + 10.0
        while not run.is_cancel_requested and time.monotonic() < deadline:
            time.sleep(0.005)
        original(worker, run)

    monkeypatch.setattr(RunWorker, "execute", execute_after_cancel)
    run, refusal = node.request_plan("plan")
    assert run is not None, refusal
    assert held.wait(5.0)
    assert run.phase is Phase.ACCEPTED  # accepted, its planning not begun
    sent = time.monotonic()
    success, message = node.cancel()
    latency = time.monotonic() - sent
    MEASURED["before_worker_answer"] = latency
    print(f"\ncancel before the worker started: answered in {1000 * latency:.0f} ms")
    assert success, message
    assert f"canceled run {run.hex}" in message, message
    assert run.outcome is Outcome.CANCELED
    assert run.wait_outcome(0.0)
    assert latency < CANCEL_BOUND_S
    assert run.wait_finished(5.0)
    assert (tmp_path / "recordings" / run.hex / "metadata.yaml").is_file()

    monkeypatch.setattr(RunWorker, "execute", original)  # the next plan works
    following, refusal = node.request_plan("plan")
    assert following is not None, refusal
    assert following.wait_outcome(20.0), following.message
    assert following.outcome is Outcome.SUCCEEDED, following.message
    assert following.wait_finished(10.0)
