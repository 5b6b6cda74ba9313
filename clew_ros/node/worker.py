"""The life of one accepted run, from its start to its last message.

:meth:`RunWorker.start` puts the run's start out (its recording opened,
status accepted, its world, the ``accepted`` event) in the caller's thread,
then :meth:`RunWorker.execute` runs in a thread of its own, outside the
executor: plan (landmarks as they come), check the plan, publish the outcome
(``~/trajectory``, feedback, status, event), play the plan back, close the
recording. It moves the :class:`~clew_ros.node.run.Run` along its phases; a
fault in it ends the run ``INTERNAL_ERROR`` and never the node.
"""

from __future__ import annotations

import threading
import time
from typing import TYPE_CHECKING

import numpy as np
from action_msgs.msg import GoalStatus

from clew_ros.core.clew import PlanResult, Progress
from clew_ros.core.settings import Outcome
from clew_ros.core.tree import LandmarkTree
from clew_ros.kinds import kind_of
from clew_ros.motion.playback import GripperEvent, Track, TrackState
from clew_ros.motion.player import play
from clew_ros.node.publishing import Publishing
from clew_ros.node.run import Phase, Run
from clew_ros.node.run_recording import Recordings
from clew_ros.ros import messages
from clew_ros.ros.events import accepted_fields, landmark_fields, outcome_event, outcome_fields
from clew_ros.ros.qos import GOAL_QOS

if TYPE_CHECKING:
    from rclpy.impl.rcutils_logger import RcutilsLogger
    from visualization_msgs.msg import MarkerArray

__all__ = ["RunWorker", "timed_plan"]


class RunWorker:
    """Starts and runs the node's runs.

    Parameters
    ----------
    publishing:
        The node's publishers.
    recordings:
        Opens each run's recording.
    goal_topic:
        The full name of ``~/goal_pose``: a run's goal is recorded on it.
    logger:
        The node's logger.
    closing:
        Set when the node shuts down (a run canceled then says so).
    """

    def __init__(
        self,
        publishing: Publishing,
        recordings: Recordings,
        goal_topic: str,
        logger: RcutilsLogger,
        closing: threading.Event,
    ) -> None:
        self._out = publishing
        self._recordings = recordings
        self._goal_topic = goal_topic
        self._logger = logger
        self._closing = closing

    def start(self, run: Run, previous: Run | None) -> None:
        """Put ``run``'s start out once ``previous`` is over, then run it in a thread of its own."""
        try:
            if previous is not None:
                previous.wait_finished()  # a playback stops within one period
            self._announce(run)
        except Exception as error:  # noqa: BLE001 - the worker still runs, and ends the run
            self._logger.error(f"run {run.hex}: cannot announce its start: {error!r}")
        finally:
            run.mark_started()
        threading.Thread(target=self.execute, args=(run,), name=f"clew_run_{run.hex[:8]}", daemon=True).start()

    def _announce(self, run: Run) -> None:
        out, config = self._out, run.config
        run.recording = self._recordings.open(config.node, run.hex)
        out.set_status(run.id, run.accepted_ns, GoalStatus.STATUS_ACCEPTED, current=True)
        out.world(run.world, config.planner, run.recording, config.spatial)
        now = out.now_ns()
        goal = kind_of(run.world).goal_message(run.world, run.goal, now)
        if goal is not None:  # a pose (a joint goal is none)
            run.recording.write(self._goal_topic, goal, now, GOAL_QOS)
        out.publish_status(run.recording)
        request = {} if run.goal_stamp_ns is None else {"goal_stamp_ns": run.goal_stamp_ns}
        fields = accepted_fields(
            source=run.source,
            world=config.world.name,
            goal=run.goal,
            seed=config.planner.seed,
            recording=run.recording.text,
        )
        out.event(run.id, "accepted", run.recording, **fields, recording_path=run.recording.path, **request)
        self._logger.info(
            f"run {run.hex} accepted ({run.source}): goal {np.round(run.goal, 4).tolist()}, {run.recording.text}"
        )

    def execute(self, run: Run) -> None:
        """The run's thread: plan, publish the outcome, play back; close the recording."""
        try:
            self._plan_and_publish(run)
            if run.phase is Phase.PLAYBACK:
                self._play_back(run)
        except Exception as error:  # noqa: BLE001 - a bug here must not take the node down
            self._logger.error(f"run {run.hex}: internal error: {error!r}")
            if not run.is_outcome_out:  # else the outcome is out already: one outcome per run
                try:
                    run.conclude(
                        Outcome.INTERNAL_ERROR, f"internal error in the node: {error!r}", time.monotonic() - run.start_s
                    )
                    self._publish_outcome(run)
                except Exception as again:  # noqa: BLE001
                    self._logger.error(f"run {run.hex}: cannot publish its outcome: {again!r}")
        finally:
            run.recording.close()
            run.finish()

    # ------------------------------------------------------------------ planning

    def _plan_and_publish(self, run: Run) -> None:
        out, config = self._out, run.config
        run.begin_planning()
        out.set_status(run.id, run.accepted_ns, run.status)
        out.publish_status(run.recording)
        tree = _root_tree(run.world)
        out.publish("landmarks", _landmark_markers(run.world, tree, out.now_ns()), run.recording)
        announced = [1]  # landmarks already announced (the root)

        out.to_live("the landmark tree", lambda live: live.publish_landmarks(tree))

        def on_progress(progress: Progress) -> None:
            run.landmarks, run.best_distance = progress.landmarks, progress.best_distance
            out.to_live("progress", lambda live: live.publish_progress(progress))
            try:
                self._announce_landmarks(run, progress.tree, announced)
            except Exception as error:  # noqa: BLE001 - never let a publishing fault end the planning
                self._logger.error(f"run {run.hex}: cannot publish progress: {error!r}")

        world = run.world
        kind = kind_of(world)
        result = kind.plan(
            world,
            config.planner,
            goal=None if run.source == "plan" else run.goal,
            termination=run.termination(),
            progress=on_progress,
        )
        canceled = run.end_planning()
        run.landmarks = len(result.tree)
        self._announce_landmarks(run, result.tree, announced)
        out.to_live("the landmark tree", lambda live: live.publish_landmarks(result.tree))  # progress sent the rest
        outcome, message = result.outcome, result.message
        if canceled and outcome is not Outcome.CANCELED:
            outcome, message = Outcome.CANCELED, f"canceled (the run had ended {outcome.name} at the same moment)"
        if outcome is Outcome.CANCELED and self._closing.is_set():
            message += " (the node is shutting down)"
        track = None
        if outcome is Outcome.START_IN_COLLISION and (detail := kind.start_collision_detail(world)) is not None:
            message = f"{message}: {detail}"
        if outcome is Outcome.SUCCEEDED:
            outcome, message, track = timed_plan(run, result)
        run.conclude(outcome, message, float(result.stats.get("time_s", time.monotonic() - run.start_s)), track)
        self._publish_outcome(run)

    def _announce_landmarks(self, run: Run, tree: LandmarkTree, announced: list[int]) -> None:
        landmarks = list(tree)
        if len(landmarks) <= announced[0]:
            return
        for landmark in landmarks[announced[0] :]:
            self._out.event(run.id, "landmark", run.recording, **landmark_fields(landmark))
        announced[0] = len(landmarks)
        self._out.publish("landmarks", _landmark_markers(run.world, tree, self._out.now_ns()), run.recording)

    def _publish_outcome(self, run: Run) -> None:
        """Publish the concluded outcome; then the ``~/plan`` answer goes out."""
        out, outcome = self._out, run.outcome
        assert outcome is not None  # concluded
        if run.track is not None:
            out.publish("trajectory", messages.joint_trajectory(run.track, out.now_ns()), run.recording)
        out.outcome(run)
        fields = outcome_fields(
            outcome, run.message, landmarks=run.landmarks, time_s=run.elapsed_s, recording=run.recording.text
        )
        if run.track is not None:
            fields |= kind_of(run.world).plan_fields(run.world, run.track)
        out.event(run.id, outcome_event(outcome), run.recording, **fields)
        if run.track is None:
            run.recording.close()  # no playback follows: the recording is complete before the answer goes out
        else:
            run.recording.check()  # it closes after the playback; a write error met so far goes in the answer
        summary = f"run {run.hex}: {outcome.name}: {run.message.splitlines()[0] if run.message else ''}"
        # one call site per severity: rclpy refuses a call site whose severity changes between calls
        if outcome is Outcome.SUCCEEDED:
            self._logger.info(summary)
        else:
            self._logger.warning(summary)
        # from here a new request is served (a playback is stopped for it), never refused BUSY:
        # whoever saw the outcome may send the next goal at once
        run.outcome_published()

    # ------------------------------------------------------------------ playback

    def _play_back(self, run: Run) -> None:
        """``~/joint_states`` (positions and velocities), ``~/object_pose``, ``/tf``, ``~/scene`` and grasp events
        along the track, in time."""
        out, track = self._out, run.track
        assert track is not None  # PLAYBACK follows a plan
        kind = kind_of(run.world)

        def on_sample(state: TrackState) -> None:
            kind.publish_sample(
                out,
                run.world,
                state,
                setup=run.config.spatial,
                track=track,
                time_ns=out.now_ns(),
                recording=run.recording,
            )

        def on_event(event: GripperEvent) -> None:
            out.event(run.id, event.kind, run.recording, at_s=float(event.time_s), grasp=event.grasp)

        end = play(
            track, run.config.node.playback_rate_hz, wait_stop=run.wait_stop, on_sample=on_sample, on_event=on_event
        )
        out.feedback(run, end.phase)
        if end.at_s is None:  # a cancel or a new request came between the outcome and the first sample
            self._logger.info(f"run {run.hex}: playback stopped before it started")
        elif end.stopped:
            self._logger.info(f"run {run.hex}: playback stopped at {end.at_s:.2f} s of {track.duration_s:.2f} s")
        else:
            self._logger.info(f"run {run.hex}: playback done ({track.duration_s:.2f} s)")


def timed_plan(run: Run, result: PlanResult) -> tuple[Outcome, str, Track | None]:
    """A successful result as a validated, timed plan, or ``INTERNAL_ERROR`` if it fails validation.

    The plan is checked against the run's problem (its goal) by its kind's ``checked_plan``; one that fails is
    never published. Where the plan leaves the arm and the object is kept for ``state.advance``.
    """
    world = run.world
    kind = kind_of(world)
    planned = kind.checked_plan(world, result)
    if not planned.success:
        return Outcome.INTERNAL_ERROR, planned.message, None
    end = kind.end_state(planned)
    if end is not None:
        run.end_state = end
    return result.outcome, result.message, kind.track(world, planned, run.config.spatial, run.config.node)


def _root_tree(world: object) -> LandmarkTree:
    """The landmark tree's root (the start), as the planner's tree starts."""
    return kind_of(world).root_tree(world)


def _landmark_markers(world: object, tree: LandmarkTree, time_ns: int) -> MarkerArray:
    return kind_of(world).landmark_markers(world, tree, time_ns)
