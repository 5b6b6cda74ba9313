"""What a client knows of one run: its status, latest feedback and, when it ends, a typed result.

Plain values and one thread-safe handle; no rclpy here, so they can be
built and read anywhere (the :class:`~clew_ros.client.PlannerClient` feeds
the handle from its subscriptions).
"""

from __future__ import annotations

import argparse
import enum
import threading
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Protocol

from trajectory_msgs.msg import JointTrajectory

from clew_ros.core.plan import Plan
from clew_ros.core.settings import Outcome

__all__ = [
    "Feedback",
    "PlannerNotFoundError",
    "RunHandle",
    "RunResult",
    "RunStatus",
    "RunTimeoutError",
    "goal_argument",
]


def goal_argument(text: str) -> tuple[float, ...]:
    """An object goal ``X,Y,YAW`` (m, m, rad, frame ``world``), or a spatial world's ``X,Y,Z,ROLL,PITCH,YAW``,
    typed on a command line: an ``argparse`` type."""
    try:
        values = tuple(float(v) for v in text.split(","))
    except ValueError:
        values = ()
    if len(values) not in (3, 6):
        raise argparse.ArgumentTypeError(
            f"expected X,Y,YAW (three numbers) or X,Y,Z,ROLL,PITCH,YAW (six), got {text!r}"
        ) from None
    return values


class PlannerNotFoundError(RuntimeError):
    """No planner answers on ``<planner>/goal_pose`` and ``<planner>/events`` within the timeout."""


class RunTimeoutError(TimeoutError):
    """A run did not end (or was not answered) within the time the caller gave."""


class Follower(Protocol):
    """What a handle asks of the client that follows its run."""

    def wait_until(self, predicate: Callable[[], bool], timeout_s: float | None) -> bool: ...

    def cancel(self, handle: RunHandle) -> None: ...


class RunStatus(enum.Enum):
    """Where a run stands, as ``~/status`` and ``~/events`` say (``SENT``: the goal is on its way)."""

    SENT = "sent"
    ACCEPTED = "accepted"
    EXECUTING = "executing"
    SUCCEEDED = "succeeded"
    CANCELED = "canceled"
    ABORTED = "aborted"

    @property
    def done(self) -> bool:
        return self in (RunStatus.SUCCEEDED, RunStatus.CANCELED, RunStatus.ABORTED)


@dataclass(frozen=True)
class Feedback:
    """One ``~/feedback`` message of the run: ``phase`` is ``planning``, an outcome name, ``playback``,
    ``playback_done`` or ``playback_stopped``."""

    phase: str
    landmarks: int
    best_distance_m: float
    elapsed_s: float


@dataclass(frozen=True)
class RunResult:
    """How a run ended.

    ``outcome`` tells every case apart (``SUCCEEDED``, ``BUSY``, ``TIME_LIMIT``,
    ``GOAL_IN_COLLISION``, ...); ``plan`` and ``trajectory`` are set on
    success (the plan rebuilt from ``~/trajectory`` in the run's world);
    ``recording`` is the run's recording directory, ``None`` when the run is
    not recorded (``recording_note`` says why).
    """

    run_id: str
    outcome: Outcome
    message: str
    landmarks: int = 0
    time_s: float = 0.0
    plan: Plan | None = None
    trajectory: JointTrajectory | None = None
    recording: str | None = None
    recording_note: str = ""

    @property
    def succeeded(self) -> bool:
        return self.outcome is Outcome.SUCCEEDED


class RunHandle:
    """One goal sent to a planner, followed until it ends.

    Read ``status``, ``run_id``, ``feedback`` and ``result`` at any time;
    :meth:`wait` blocks until the result (see :class:`~clew_ros.client.PlannerClient`
    for where it may be called); :meth:`add_done_callback` and
    ``on_feedback`` call back from the executor that spins the client's node.
    """

    def __init__(
        self,
        client: Follower,
        goal: tuple[float, ...] | None,
        stamp_ns: int,
        on_feedback: Callable[[RunHandle, Feedback], None] | None = None,
    ) -> None:
        self._client = client
        self.goal = goal
        self.stamp_ns = stamp_ns
        self._on_feedback = on_feedback
        self._lock = threading.Lock()
        self._done = threading.Event()
        self._playback_over = threading.Event()
        self._callbacks: list[Callable[[RunHandle], None]] = []
        self._status = RunStatus.SENT
        self._run_id: str | None = None
        self._feedback: Feedback | None = None
        self._result: RunResult | None = None
        self._playback: str | None = None
        # kept by the client while the run goes on
        self.accepted_stamp_ns: int | None = None  # the run's ~/status stamp (the planner's clock)
        self.cancel_requested = False  # cancel() before the planner answered: sent once it accepts the run
        self.recording: tuple[str | None, str] = (None, "")  # (directory, note) from the accepted event
        self.outcome_event: RunResult | None = None  # a success waiting for its ~/trajectory
        #: The outcome event's fields (a spatial success says how the trajectory splits into segments).
        self.outcome_fields: dict[str, Any] = {}

    # -- what the caller reads ----------------------------------------------------------------------

    @property
    def run_id(self) -> str | None:
        """The run's UUID as 32 hex digits (``~/status``, ``~/events``), once the planner answered."""
        return self._run_id

    @property
    def status(self) -> RunStatus:
        return self._status

    @property
    def feedback(self) -> Feedback | None:
        return self._feedback

    @property
    def result(self) -> RunResult | None:
        return self._result

    @property
    def playback(self) -> str | None:
        """``playback_done`` or ``playback_stopped`` once the planner has played the plan back."""
        return self._playback

    def done(self) -> bool:
        return self._done.is_set()

    def wait(self, timeout_s: float | None = None, *, playback: bool = False) -> RunResult:
        """The result, waiting at most ``timeout_s`` (``None``: no limit); with ``playback`` also until a
        successful plan has been played back (its recording is then complete).

        Raises :class:`RunTimeoutError` when the time is up.
        """
        client = self._client
        ready = self._playback_ready if playback else self.done
        if not client.wait_until(ready, timeout_s):
            what = "played back" if self.done() else "answered"
            raise RunTimeoutError(f"run {self._run_id or '(not accepted yet)'} was not {what} within {timeout_s} s")
        assert self._result is not None
        return self._result

    def cancel(self) -> bool:
        """Ask the planner to cancel this run (``~/cancel``); ``False`` when it has already ended.

        The run then ends with outcome ``CANCELED`` (or the one it reached at the same moment).
        """
        if self.done():
            return False
        self._client.cancel(self)
        return True

    def add_done_callback(self, callback: Callable[[RunHandle], None]) -> None:
        """Call ``callback(handle)`` when the run ends (at once if it has)."""
        with self._lock:
            if not self._done.is_set():
                self._callbacks.append(callback)
                return
        callback(self)

    def _playback_ready(self) -> bool:
        if not self._done.is_set():
            return False
        return self._result is None or not self._result.succeeded or self._playback_over.is_set()

    # -- what the client that follows the run feeds (not for users) -----------------------------------

    def mark_accepted(self, run_id: str) -> None:
        with self._lock:
            self._run_id = run_id
            if self._status is RunStatus.SENT:
                self._status = RunStatus.ACCEPTED

    def update_status(self, status: RunStatus) -> None:
        with self._lock:
            if not self._status.done:
                self._status = status

    def update_feedback(self, feedback: Feedback) -> None:
        self._feedback = feedback
        if feedback.phase in ("playback_done", "playback_stopped"):
            self._playback = feedback.phase
            self._playback_over.set()
        if self._on_feedback is not None:
            self._on_feedback(self, feedback)

    def finish(self, result: RunResult) -> None:
        status = {Outcome.SUCCEEDED: RunStatus.SUCCEEDED, Outcome.CANCELED: RunStatus.CANCELED}
        with self._lock:
            if self._done.is_set():
                return
            self._result = result
            self._status = status.get(result.outcome, RunStatus.ABORTED)
            callbacks, self._callbacks = self._callbacks, []
            self._done.set()
        for callback in callbacks:
            callback(self)
