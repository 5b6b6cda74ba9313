"""A run's handle: its phases, cancel and stop, its outcome and answer, and the ~/status table (no ROS graph)."""

from __future__ import annotations

import threading
import types
import uuid
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("action_msgs")

from action_msgs.msg import GoalStatus

from clew_ros.core.settings import Outcome
from clew_ros.node.run import CancelKind, Phase, Run, StatusTable
from clew_ros.node.run_recording import RunRecording
from clew_ros.planar.world import read_parameter_file
from clew_ros.ros.parameters import configuration_from_values, flatten, initial_values

QUICK = Path(__file__).parents[1] / "worlds" / "node_quick.yaml"
#: Stands in for the timed plan of a success (only its duration is read).
TRACK = types.SimpleNamespace(duration_s=1.5)


@pytest.fixture(scope="module")
def config():
    return configuration_from_values(initial_values(flatten(read_parameter_file(QUICK))))


def planned(run: Run, outcome: Outcome = Outcome.SUCCEEDED, *, cancel_before_end: bool = False) -> bool:
    """Move ``run`` through planning to its outcome; return what end_planning said."""
    run.begin_planning()
    if cancel_before_end:
        run.request_cancel()
    canceled = run.end_planning()
    run.conclude(outcome, "message", 0.25, TRACK if outcome is Outcome.SUCCEEDED else None)
    return canceled


def test_a_success_goes_through_every_phase(config) -> None:
    run = Run("plan", None, config, accepted_ns=7)
    assert np.allclose(run.goal, config.world.object.goal)
    assert np.allclose(run.world.object.goal, run.goal)
    assert run.phase is Phase.ACCEPTED
    assert run.is_busy
    assert run.status == GoalStatus.STATUS_ACCEPTED
    run.begin_planning()
    assert run.phase is Phase.PLANNING
    assert run.is_busy
    assert run.status == GoalStatus.STATUS_EXECUTING
    assert run.end_planning() is False
    assert run.phase is Phase.PUBLISHING
    assert run.is_busy
    run.conclude(Outcome.SUCCEEDED, "found", 0.25, TRACK)
    assert run.status == GoalStatus.STATUS_SUCCEEDED
    assert not run.wait_outcome(0.0)
    run.outcome_published()
    assert run.phase is Phase.PLAYBACK
    assert not run.is_busy
    assert run.wait_outcome(0.0)
    assert not run.wait_finished(0.0)
    run.finish()
    assert run.phase is Phase.FINISHED
    assert run.wait_finished(0.0)


@pytest.mark.parametrize(
    ("outcome", "status"),
    [
        (Outcome.TIME_LIMIT, GoalStatus.STATUS_ABORTED),
        (Outcome.INTERNAL_ERROR, GoalStatus.STATUS_ABORTED),
        (Outcome.CANCELED, GoalStatus.STATUS_CANCELED),
    ],
)
def test_without_a_plan_the_run_finishes_at_its_outcome(config, outcome: Outcome, status: int) -> None:
    run = Run("goal_pose", np.array([0.5, 0.5, 0.0]), config, accepted_ns=0)
    planned(run, outcome)
    run.outcome_published()
    assert run.phase is Phase.FINISHED
    assert run.status == status
    assert run.track is None
    assert np.allclose(run.world.object.goal, [0.5, 0.5, 0.0])


def test_a_cancel_stops_the_planning_until_the_plan_is_known_then_the_playback(config) -> None:
    run = Run("plan", None, config, accepted_ns=0)
    assert run.request_cancel() is CancelKind.PLAN  # accepted: the planner will not even start
    assert run.is_cancel_requested
    assert run.termination().reason() is Outcome.CANCELED
    assert not run.is_stop_requested

    run = Run("plan", None, config, accepted_ns=0)
    assert planned(run, cancel_before_end=True) is True  # the worker sees the cancel that came in time
    assert run.request_cancel() is CancelKind.PLAYBACK
    assert run.is_stop_requested
    run.outcome_published()
    assert run.request_cancel() is CancelKind.PLAYBACK
    run.finish()
    assert run.request_cancel() is None  # nothing left to cancel


def test_one_outcome_per_run_and_no_going_back(config) -> None:
    run = Run("plan", None, config, accepted_ns=0)
    planned(run)
    run.conclude(Outcome.INTERNAL_ERROR, "replaced before it is out", 0.3)  # still allowed
    assert run.track is None
    run.outcome_published()
    with pytest.raises(RuntimeError, match="is out already"):
        run.conclude(Outcome.SUCCEEDED, "again", 0.3, TRACK)
    with pytest.raises(RuntimeError, match="cannot go back"):
        run.begin_planning()


def test_the_answer_names_the_outcome_and_the_recording(config) -> None:
    class Open(RunRecording):
        @property
        def is_open(self) -> bool:
            return True

    run = Run("plan", None, config, accepted_ns=0)
    run.recording = Open("recording /tmp/x")
    planned(run)
    run.landmarks = 4
    assert run.result_text() == (
        f"run {run.hex}: SUCCEEDED: message; landmarks 4; time 0.25 s; recording /tmp/x"
        " (complete when the 1.5 s playback ends)"
    )
    run.recording = RunRecording("recording off (record.enabled is false)")
    assert run.result_text().endswith("; recording off (record.enabled is false)")


def test_waits_return_when_the_worker_gets_there(config) -> None:
    run = Run("plan", None, config, accepted_ns=0)
    assert not run.wait_stop(0.0)
    threading.Timer(0.05, run.stop).start()
    assert run.wait_stop(5.0)
    assert run.is_cancel_requested
    threading.Timer(0.05, run.finish).start()  # a worker that failed before its outcome still lets waiters go
    assert run.wait_outcome(5.0)
    assert run.wait_finished(5.0)


def test_status_table_keeps_the_last_runs_newest_first() -> None:
    table = StatusTable(history=3)
    ids = [uuid.uuid4() for _ in range(5)]
    for k, run_id in enumerate(ids):
        table.set(run_id, k, GoalStatus.STATUS_ACCEPTED)
    table.set(ids[2], 2, GoalStatus.STATUS_SUCCEEDED)  # an update keeps the run's place
    assert table.entries() == [  # newest first
        (ids[4], 4, GoalStatus.STATUS_ACCEPTED),
        (ids[3], 3, GoalStatus.STATUS_ACCEPTED),
        (ids[2], 2, GoalStatus.STATUS_SUCCEEDED),
    ]
    table.set(ids[3], 3, GoalStatus.STATUS_EXECUTING, current=True)
    table.set(uuid.uuid4(), 5, GoalStatus.STATUS_ABORTED)  # a request refused while ids[3] runs
    assert table.entries()[0] == (ids[3], 3, GoalStatus.STATUS_EXECUTING)  # the current run first
    assert table.entries()[1][2] == GoalStatus.STATUS_ABORTED  # then the others, newest first
    assert len(table) == 3


def test_a_fault_before_planning_still_ends_the_run(config) -> None:
    run = Run("plan", None, config, accepted_ns=0)
    run.conclude(Outcome.INTERNAL_ERROR, "internal error in the node: ...", 0.0)  # the worker failed at once
    assert run.status == GoalStatus.STATUS_ABORTED
    run.outcome_published()
    assert run.phase is Phase.FINISHED
    assert not run.is_busy
