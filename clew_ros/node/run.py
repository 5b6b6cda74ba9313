"""One run of the node: its handle (:class:`Run`), its :class:`Phase` and the ``~/status`` table.

A :class:`Run` carries everything about one planning request, the way
rclpy's ``ServerGoalHandle`` carries one goal: its phase, whether a cancel or
a playback stop was asked for, its outcome and its recording. Its worker
moves it along; the node's policy and ``~/plan`` ask it. No rclpy here (only
message constants), so the phases are tested without a ROS graph.

Phases, in order (a run only moves forward; the transitions are the worker's)::

    ACCEPTED  -- begin_planning -->     PLANNING
    PLANNING  -- end_planning -->       PUBLISHING
    PUBLISHING -- outcome_published --> PLAYBACK (a plan), or FINISHED (none)
    PLAYBACK  -- finish -->             FINISHED

- ``ACCEPTED``: the run is the node's current run; its start goes out
  (status accepted, ``accepted`` event) and its worker starts.
- ``PLANNING``: status executing, the planner works; ``~/feedback`` says
  ``planning``.
- ``PUBLISHING``: the planner returned; the outcome is checked and published.
- ``PLAYBACK``: the outcome is out and was a plan: the plan plays back.
- ``FINISHED``: nothing more is published for the run; its recording is closed.

A run :attr:`~Run.is_busy` (refuses other requests, ``BUSY``) until its
outcome is out. :meth:`Run.request_cancel` stops the planner while the plan is
not known yet, and the playback after.
"""

from __future__ import annotations

import enum
import threading
import time
import uuid
from collections import OrderedDict
from functools import cached_property
from typing import TYPE_CHECKING, Literal

import numpy as np
from action_msgs.msg import GoalStatus

from clew_ros.core.settings import Outcome, Termination
from clew_ros.kinds import kind_of
from clew_ros.motion.playback import Track
from clew_ros.node.run_recording import NO_RECORDING, RunRecording
from clew_ros.ros.events import outcome_status
from clew_ros.ros.parameters import Configuration

if TYPE_CHECKING:
    from clew_ros.planar.world import World
    from clew_ros.spatial.world import SpatialWorld

__all__ = [
    "STATUS_HISTORY",
    "CancelKind",
    "Phase",
    "Run",
    "Source",
    "StatusTable",
]

#: How many runs ~/status keeps (the oldest are dropped).
STATUS_HISTORY = 100

#: What started a run (the ``source`` of its ``accepted`` event).
Source = Literal["plan", "goal_pose"]


def default_goal(world: object) -> np.ndarray:
    """What ``~/plan`` plans to, as the world's kind says: the object's goal (planar ``(x, y, theta)``,
    spatial 6 numbers), or a spatial motion-only query's ``world.robot.goal`` (joints) or
    ``world.robot.goal_pose`` (the tcp's pose)."""
    return kind_of(world).default_goal(world)


class Phase(enum.Enum):
    """Where a run is (module docstring); only :class:`Run` changes it."""

    ACCEPTED = "accepted"
    PLANNING = "planning"
    PUBLISHING = "publishing"
    PLAYBACK = "playback"
    FINISHED = "finished"


#: The phases in which a run refuses other requests (its outcome is not out yet).
BUSY_PHASES = frozenset({Phase.ACCEPTED, Phase.PLANNING, Phase.PUBLISHING})


class CancelKind(enum.Enum):
    """What :meth:`Run.request_cancel` stopped."""

    PLAN = "plan"  # the planner: the run ends CANCELED
    PLAYBACK = "playback"  # the playback (to come): the outcome stays


class Run:
    """One planning request and what became of it; thread safe.

    Parameters
    ----------
    source:
        ``"plan"`` (``~/plan``, to the configured goal) or ``"goal_pose"``.
    goal:
        The object goal ``(x, y, theta)`` (m, m, rad); ``None``: the configured one.
    config:
        The parameters the run plans with (taken when it is accepted).
    accepted_ns:
        When it was accepted (ns, the node's clock): the stamp of its status.
    goal_stamp_ns:
        The header stamp of the ``~/goal_pose`` message that asked for it (ns);
        echoed in its ``accepted`` event so that a client knows its run.
    """

    def __init__(
        self,
        source: Source,
        goal: np.ndarray | None,
        config: Configuration,
        accepted_ns: int,
        goal_stamp_ns: int | None = None,
    ) -> None:
        self.id = uuid.uuid4()
        self.goal_stamp_ns = goal_stamp_ns
        self.source: Source = source
        self.goal = np.array(default_goal(config.world) if goal is None else goal, dtype=float)
        self.config = config
        self.accepted_ns = accepted_ns
        self.start_s = time.monotonic()  # when accepted, on time.monotonic()
        #: Where its messages are recorded; the node opens it as the run starts.
        self.recording: RunRecording = NO_RECORDING
        # progress, written by the worker (read for ~/feedback)
        self.landmarks = 1
        self.best_distance = float("inf")  # m
        # the outcome, set once by conclude()
        self.outcome: Outcome | None = None
        self.message = ""
        self.elapsed_s = 0.0  # planning time, from the planner's stats
        self.track: Track | None = None  # the timed plan, after a success
        #: Where a successful spatial plan leaves the arm (its last waypoint) and the object (its final pose,
        #: ``None`` in a motion-only query): where ``state.advance`` starts the next run.
        self.end_state: tuple[np.ndarray, tuple[float, ...] | None] | None = None
        self._lock = threading.Lock()
        self._phase = Phase.ACCEPTED
        self._cancel = threading.Event()
        self._stop_playback = threading.Event()
        self._started = threading.Event()  # its start is out: the status table and recording hold it
        self._outcome_out = threading.Event()  # the outcome is published (the ~/plan answer goes out)
        self._finished = threading.Event()  # nothing more to publish; recording closed

    def __repr__(self) -> str:
        return f"Run({self.hex}, {self.source}, {self._phase.value}, {self.outcome})"

    # ------------------------------------------------------------------ what it is

    @property
    def hex(self) -> str:
        """The run id as in messages and recordings: 32 hex digits."""
        return self.id.hex

    @cached_property
    def world(self) -> World | SpatialWorld:
        """The problem this run solves: the configured world with the run's goal."""
        world = self.config.world
        if self.source == "plan":  # the configured goal (a spatial motion-only query: as it is)
            return world
        moved: World | SpatialWorld = kind_of(world).with_goal(world, self.goal)
        return moved

    @property
    def phase(self) -> Phase:
        return self._phase

    @property
    def is_busy(self) -> bool:
        """Whether other requests are refused (``BUSY``): the outcome is not out yet."""
        return self._phase in BUSY_PHASES

    @property
    def is_cancel_requested(self) -> bool:
        return self._cancel.is_set()

    @property
    def is_stop_requested(self) -> bool:
        """Whether the playback is to stop (or not to start)."""
        return self._stop_playback.is_set()

    @property
    def status(self) -> int:
        """The run's ``GoalStatus`` code for ``~/status``."""
        if self.outcome is not None:
            return outcome_status(self.outcome)
        status: int = GoalStatus.STATUS_ACCEPTED if self._phase is Phase.ACCEPTED else GoalStatus.STATUS_EXECUTING
        return status

    def termination(self) -> Termination:
        """The planner's stop condition: the run's time limit or its cancel."""
        return Termination(self.config.planner.time_limit, self._cancel)

    def result_text(self) -> str:
        """The ``~/plan`` answer: outcome, planner message, landmarks, time and recording."""
        outcome = self.outcome.name if self.outcome else "UNKNOWN"
        text = (
            f"run {self.hex}: {outcome}: {self.message}; landmarks {self.landmarks}; "
            f"time {self.elapsed_s:.2f} s; {self.recording.text}"
        )
        if self.outcome is Outcome.SUCCEEDED and self.recording.is_open and self.track is not None:
            text += f" (complete when the {self.track.duration_s:.1f} s playback ends)"
        return text

    # ------------------------------------------------------------------ the policy's requests

    def request_cancel(self) -> CancelKind | None:
        """Cancel the planning, or stop the playback once the plan is known; ``None`` when finished."""
        with self._lock:
            if self._phase in (Phase.ACCEPTED, Phase.PLANNING):
                self._cancel.set()
                return CancelKind.PLAN
            if self._phase in (Phase.PUBLISHING, Phase.PLAYBACK):
                self._stop_playback.set()
                return CancelKind.PLAYBACK
            return None

    def stop_playback(self) -> None:
        """Stop the playback, or keep it from starting (a new run takes over)."""
        self._stop_playback.set()

    def stop(self) -> None:
        """Cancel the planning and stop the playback, whatever the phase (the node shuts down)."""
        self._cancel.set()
        self._stop_playback.set()

    # ------------------------------------------------------------------ the worker's transitions

    def mark_started(self) -> None:
        """Its start is out (status accepted, recording open, ``accepted`` event)."""
        self._started.set()

    def begin_planning(self) -> None:
        """ACCEPTED -> PLANNING: the planner starts (status executing)."""
        with self._lock:
            self._advance(Phase.PLANNING)

    def end_planning(self) -> bool:
        """PLANNING -> PUBLISHING: the planner returned; whether a cancel was asked for by then."""
        with self._lock:
            self._advance(Phase.PUBLISHING)
            return self._cancel.is_set()

    def conclude(self, outcome: Outcome, message: str, elapsed_s: float, track: Track | None = None) -> None:
        """Set the outcome before it is published; ``track`` is the timed plan of a success.

        Once the outcome is out it is final: one outcome per run.
        """
        if self._outcome_out.is_set():
            raise RuntimeError(f"run {self.hex}: its outcome {self.outcome} is out already")
        self.outcome, self.message, self.elapsed_s = outcome, message, elapsed_s
        self.track = track if outcome is Outcome.SUCCEEDED else None

    @property
    def is_outcome_out(self) -> bool:
        return self._outcome_out.is_set()

    def outcome_published(self) -> None:
        """The outcome is out: -> PLAYBACK (a plan) or FINISHED; a new request is served from here on."""
        with self._lock:
            self._advance(Phase.PLAYBACK if self.track is not None else Phase.FINISHED)
        self._outcome_out.set()

    def finish(self) -> None:
        """-> FINISHED: the worker is done (playback over, recording closed)."""
        with self._lock:
            self._phase = Phase.FINISHED
        self._outcome_out.set()  # after a fault in the worker, too: nobody waits forever
        self._finished.set()

    def _advance(self, phase: Phase) -> None:
        order = list(Phase)
        if order.index(phase) < order.index(self._phase):
            raise RuntimeError(f"run {self.hex}: {self._phase.value} cannot go back to {phase.value}")
        self._phase = phase

    # ------------------------------------------------------------------ waiting

    def wait_started(self, timeout_s: float | None = None) -> bool:
        """Wait until its start is out; whether it is."""
        return self._started.wait(timeout_s)

    def wait_outcome(self, timeout_s: float | None = None) -> bool:
        """Wait until its outcome is published (or its worker ended); whether it is."""
        return self._outcome_out.wait(timeout_s)

    def wait_stop(self, timeout_s: float) -> bool:
        """Wait up to ``timeout_s`` for a playback stop; whether one was asked for."""
        return self._stop_playback.wait(timeout_s)

    def wait_finished(self, timeout_s: float | None = None) -> bool:
        """Wait until the run is over (playback ended, recording closed); whether it is."""
        return self._finished.wait(timeout_s)


class StatusTable:
    """The runs of ``~/status``: ``run id -> (accepted stamp (ns), GoalStatus code)``.

    Keeps the last ``history`` runs. Not locked: the node's publishing
    serialises updates and snapshots (:class:`~clew_ros.node.publishing.Publishing`).
    """

    def __init__(self, history: int = STATUS_HISTORY) -> None:
        self._history = history
        self._entries: OrderedDict[uuid.UUID, tuple[int, int]] = OrderedDict()
        self._current: uuid.UUID | None = None

    def set(self, run_id: uuid.UUID, stamp_ns: int, status: int, *, current: bool = False) -> None:
        """Enter or update a run; ``current``: it is the node's current run (listed first from now on)."""
        self._entries[run_id] = (stamp_ns, status)  # an update keeps the run's place
        if current:
            self._current = run_id
        while len(self._entries) > self._history:
            self._entries.popitem(last=False)

    def entries(self) -> list[tuple[uuid.UUID, int, int]]:
        """``(run id, stamp (ns), status)`` of each run kept: the current run first (``status_list[0]`` is the
        run a status display should show), then the others, newest first (a refused request is not current)."""
        ordered = [(run_id, stamp, status) for run_id, (stamp, status) in reversed(self._entries.items())]
        return sorted(ordered, key=lambda entry: entry[0] != self._current)  # stable: the rest keep their order

    def __len__(self) -> int:
        return len(self._entries)
