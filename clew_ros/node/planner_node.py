"""The ``clew_planner`` node: the planner core served over ROS 2 (interface.md §3).

One run at a time. A run is accepted (``~/plan`` or ``~/goal_pose``),
planned in a worker thread, validated, published (``~/trajectory``) and
played back in time (``~/joint_states``, ``~/object_pose``, grasp events).
Its status ends (succeeded / aborted / canceled) when planning ends; the
playback that follows a success is not part of the planning: a new request
during playback stops the playback and starts the new run, while a request
during planning is refused (status aborted, code BUSY), never queued.

Threads and callback groups:

- the executor is a ``MultiThreadedExecutor``;
- ``~/plan`` is in a reentrant group: its callback blocks until the run's
  outcome is known, and a second call must still be answered (refused) at
  once, on another executor thread;
- ``~/cancel`` has a group of its own, so that it is never queued behind
  ``~/plan`` callbacks;
- ``~/goal_pose`` has a group of its own (it only starts a run);
- the status / feedback timer has a group of its own;
- parameter services stay in the node's default group;
- planning and playback run in one worker thread per run, outside the
  executor, so that no executor thread is busy while the planner works.

``self._lock`` guards the node's state (configuration, current run, status
table); ``self._start_lock`` serialises run starts (a start may wait for a
playback to stop). The worker never takes ``_start_lock``.
"""

from __future__ import annotations

import dataclasses
import threading
import time
import uuid
from collections import OrderedDict
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any

import numpy as np
from action_msgs.msg import GoalStatus, GoalStatusArray
from diagnostic_msgs.msg import DiagnosticStatus
from geometry_msgs.msg import PoseStamped
from rcl_interfaces.msg import SetParametersResult
from rclpy.callback_groups import MutuallyExclusiveCallbackGroup, ReentrantCallbackGroup
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import JointState
from std_msgs.msg import String
from std_srvs.srv import Trigger
from trajectory_msgs.msg import JointTrajectory
from visualization_msgs.msg import MarkerArray

from clew_ros.core.clew import Progress, plan
from clew_ros.core.errors import ParameterError
from clew_ros.core.kernel import warm_up
from clew_ros.core.plan import checked_plan
from clew_ros.core.settings import Outcome, Termination
from clew_ros.core.tree import LandmarkTree
from clew_ros.core.world import World
from clew_ros.node import messages
from clew_ros.node.parameters import (
    OWN_PREFIXES,
    Configuration,
    configuration_from_values,
    descriptor_for,
    initial_values,
    plain_value,
)
from clew_ros.node.playback import Track, track_from_plan

__all__ = ["NODE_NAME", "PlannerNode", "StartupError"]

NODE_NAME = "clew_planner"
#: Rate (Hz) of ~/status and ~/feedback while a plan runs.
STATUS_RATE_HZ = 5.0
#: How many runs ~/status keeps (the oldest are dropped).
STATUS_HISTORY = 100
#: How long ~/cancel waits for the run to stop before answering (s).
CANCEL_WAIT_S = 2.0

# Latched topics: a late subscriber gets the last message.
LATCHED_QOS = QoSProfile(depth=1, history=HistoryPolicy.KEEP_LAST, reliability=ReliabilityPolicy.RELIABLE,
                         durability=DurabilityPolicy.TRANSIENT_LOCAL)
STREAM_QOS = QoSProfile(depth=10, history=HistoryPolicy.KEEP_LAST, reliability=ReliabilityPolicy.RELIABLE,
                        durability=DurabilityPolicy.VOLATILE)
#: ~/goal_pose: a burst of goals is queued, not dropped; each is answered (a run, or a BUSY refusal).
GOAL_QOS = QoSProfile(depth=100, history=HistoryPolicy.KEEP_LAST, reliability=ReliabilityPolicy.RELIABLE,
                      durability=DurabilityPolicy.VOLATILE)
EVENTS_QOS = QoSProfile(depth=100, history=HistoryPolicy.KEEP_LAST, reliability=ReliabilityPolicy.RELIABLE,
                        durability=DurabilityPolicy.VOLATILE)


class StartupError(RuntimeError):
    """The node cannot start (invalid parameters); already logged."""


@dataclass
class Run:
    """One planning request and what became of it."""

    id: uuid.UUID
    source: str  # "plan" or "goal_pose"
    goal: np.ndarray
    config: Configuration
    accepted_ns: int
    cancel: threading.Event = field(default_factory=threading.Event)
    stop_playback: threading.Event = field(default_factory=threading.Event)
    done: threading.Event = field(default_factory=threading.Event)  # outcome known, terminal status out
    finished: threading.Event = field(default_factory=threading.Event)  # playback over, recording closed
    phase: str = "planning"  # planning -> publishing -> playback -> finished
    outcome: Outcome | None = None
    outcome_sent: bool = False  # the outcome event is out (never send a second one)
    message: str = ""
    landmarks: int = 1
    best_distance: float = float("inf")
    started: float = field(default_factory=time.monotonic)
    recorder: Any = None
    recording: str = ""  # what the response says about the recording
    playback_s: float = 0.0
    elapsed: float = 0.0  # s of planning, from the planner's stats
    track: Track | None = None  # the timed plan, after a success
    thread: threading.Thread | None = None

    @property
    def hex(self) -> str:
        return self.id.hex

    @cached_property
    def world(self) -> World:
        """The problem this run solves: the configured world with the run's goal."""
        world = self.config.world
        return dataclasses.replace(world, object=dataclasses.replace(world.object, goal=self.goal))

    @property
    def planning(self) -> bool:
        return self.phase in ("planning", "publishing")


class PlannerNode(Node):
    """Serves :func:`clew_ros.core.clew.plan` as ``~/plan``, ``~/goal_pose`` and ``~/cancel``."""

    def __init__(self, node_name: str = NODE_NAME, **kwargs: Any) -> None:
        # Every --params-file / -p value is declared as the node is created, so that
        # world.obstacles.<name> with any name is among the node's parameters;
        # _declare_parameters then checks them and gives each its descriptor.
        # Undeclared parameters stay allowed: ros2 param set may add an obstacle.
        super().__init__(node_name, allow_undeclared_parameters=True,
                         automatically_declare_parameters_from_overrides=True, **kwargs)
        self._lock = threading.Lock()
        self._start_lock = threading.Lock()
        # ~/status and ~/feedback are built and published under this lock, so
        # that the latched ~/status never ends on an older snapshot.
        self._status_lock = threading.RLock()
        self._run: Run | None = None
        self._statuses: OrderedDict[uuid.UUID, list[int]] = OrderedDict()
        self._shutting_down = False
        self._recorder_api: tuple[Any, str] | None = None
        self._pending_world_change = False  # set by on_set, republished by post_set
        self._config = self._declare_parameters()
        # the planning kernel is compiled (or loaded from numba's cache) before any plan: main() did
        # it before creating the node; a node built in another program does it here
        warm_up_s = warm_up()
        if warm_up_s > 1.0:
            self.get_logger().info(f"planning kernel compiled in {warm_up_s:.1f} s (cached for the next start)")

        self._pubs = {
            "status": self.create_publisher(GoalStatusArray, "~/status", LATCHED_QOS),
            "feedback": self.create_publisher(DiagnosticStatus, "~/feedback", STREAM_QOS),
            "trajectory": self.create_publisher(JointTrajectory, "~/trajectory", LATCHED_QOS),
            "joint_states": self.create_publisher(JointState, "~/joint_states", STREAM_QOS),
            "object_pose": self.create_publisher(PoseStamped, "~/object_pose", STREAM_QOS),
            "events": self.create_publisher(String, "~/events", EVENTS_QOS),
            "landmarks": self.create_publisher(MarkerArray, "~/landmarks", LATCHED_QOS),
            "world_markers": self.create_publisher(MarkerArray, "~/world_markers", LATCHED_QOS),
            "world_yaml": self.create_publisher(String, "~/world_yaml", LATCHED_QOS),
        }
        # ~/plan blocks until its run ends and must not keep a second call
        # (or ~/cancel) waiting: reentrant group, and ~/cancel in a group of its own.
        self._plan_group = ReentrantCallbackGroup()
        self._cancel_group = MutuallyExclusiveCallbackGroup()
        self._goal_group = MutuallyExclusiveCallbackGroup()
        self._timer_group = MutuallyExclusiveCallbackGroup()
        self.create_service(Trigger, "~/plan", self._on_plan, callback_group=self._plan_group)
        self.create_service(Trigger, "~/cancel", self._on_cancel, callback_group=self._cancel_group)
        self._goal_sub = self.create_subscription(PoseStamped, "~/goal_pose", self._on_goal_pose, GOAL_QOS,
                                                  callback_group=self._goal_group)
        self.create_timer(1.0 / STATUS_RATE_HZ, self._on_timer, callback_group=self._timer_group)

        # Parameter changes: checked as a whole (on_set), then republished (post_set).
        self.add_on_set_parameters_callback(self._on_set_parameters)
        self.add_post_set_parameters_callback(self._on_parameters_set)

        self._publish_world(None)
        self._publish_status(None)
        world = self._config.world
        self.get_logger().info(
            f"serving world '{world.name}' ({world.robot.dof} joints, {len(world.obstacles)} obstacles); "
            f"recording {'to ' + str(self._config.node.record_path) if self._config.node.record_enabled else 'off'}")

    # ----------------------------------------------------------------- parameters

    def _declare_parameters(self) -> Configuration:
        """Declare every parameter with its descriptor; raise :class:`StartupError` if any is invalid.

        The overrides (``--params-file`` / ``-p``) are already declared, with the
        type of their value (``automatically_declare_parameters_from_overrides``);
        they get their descriptor here (``dynamic_typing``, so that a later
        ``30`` for ``30.0`` is checked by :mod:`~clew_ros.node.parameters`, not
        refused by rclpy). The other parameters are declared with their
        start values.
        """
        overrides = self._own_values()
        try:
            values = initial_values(overrides)
            config = configuration_from_values(values)
        except ParameterError as error:
            self.get_logger().error(f"invalid parameter {error}; not starting")
            raise StartupError(str(error)) from None
        for name, value in values.items():
            if name in overrides:
                self.set_descriptor(name, descriptor_for(name))
            else:
                value = None if value == [] else value  # an empty list has no parameter type
                self.declare_parameter(name, value, descriptor_for(name), ignore_override=True)
        return config

    def _own_values(self) -> dict[str, Any]:
        """Current values of the node's own parameters, by full name."""
        values = {}
        for prefix in OWN_PREFIXES:
            group = prefix.rstrip(".")
            for name, parameter in self.get_parameters_by_prefix(group).items():
                values[f"{group}.{name}"] = plain_value(parameter.value)
        return values

    def _on_set_parameters(self, parameters: list[Parameter]) -> SetParametersResult:
        try:
            return self._check_parameters(parameters)
        except Exception as error:  # noqa: BLE001 - a checking bug must refuse the change, not end the node
            names = ", ".join(p.name for p in parameters)
            self.get_logger().error(f"internal error while checking {names}: {error!r}")
            return SetParametersResult(successful=False, reason=f"{names}: internal error while checking the "
                                       f"change ({type(error).__name__}: {error}); nothing was changed")

    def _check_parameters(self, parameters: list[Parameter]) -> SetParametersResult:
        for p in parameters:
            if not p.name.startswith(OWN_PREFIXES) and not self.has_parameter(p.name):
                return SetParametersResult(successful=False, reason=(
                    f"{p.name}: unknown parameter; clew_planner takes "
                    + ", ".join(prefix + "*" for prefix in OWN_PREFIXES)))
        own = [p for p in parameters if p.name.startswith(OWN_PREFIXES)]
        if not own:
            return SetParametersResult(successful=True)
        values = self._own_values()
        for p in own:
            if p.type_ == Parameter.Type.NOT_SET:
                values.pop(p.name, None)
            else:
                values[p.name] = plain_value(p.value)
        world_change = any(p.name.startswith("world.") for p in own)
        with self._lock:
            run = self._run
            if world_change and run is not None and run.planning:
                reason = (f"{own[0].name}: the world cannot change while run {run.hex} is planning; "
                          "cancel it (~/cancel) or wait for its outcome")
                return SetParametersResult(successful=False, reason=reason)
            try:
                config = configuration_from_values(values, listed_obstacles_only=True)
            except ParameterError as error:
                return SetParametersResult(successful=False, reason=str(error))
            self._pending_world_change = world_change or any(p.name.startswith("planner.") for p in own)
            self._config = config
        return SetParametersResult(successful=True)

    def _on_parameters_set(self, parameters: list[Parameter]) -> None:
        if self._pending_world_change:
            self._pending_world_change = False
            names = ", ".join(p.name for p in parameters)
            self.get_logger().info(f"parameters changed ({names}); republishing ~/world_markers and ~/world_yaml")
            self._publish_world(None)

    # ----------------------------------------------------------------- publishing

    def _now_ns(self) -> int:
        return self.get_clock().now().nanoseconds

    def _emit(self, run: Run | None, name: str, msg: Any) -> None:
        """Publish ``msg`` on ``~/<name>`` and write it to the run's recording, if any."""
        publisher = self._pubs[name]
        self._record(run, publisher.topic_name, msg)
        try:
            publisher.publish(msg)
        except Exception as error:  # noqa: BLE001 - the context is gone while shutting down
            if not self._shutting_down:
                self.get_logger().error(f"cannot publish on {publisher.topic_name}: {error}")

    def _record(self, run: Run | None, topic: str, msg: Any) -> None:
        if run is None or run.recorder is None:
            return
        try:
            run.recorder.write(topic, msg, self._now_ns())
        except Exception as error:  # noqa: BLE001 - a recording fault never stops the plan
            self._recording_failed(run, f"write to {topic} failed: {error}")

    def _recording_failed(self, run: Run, reason: str) -> None:
        if "failed" not in run.recording:
            run.recording += f" (recording failed: {reason})"
            self.get_logger().error(f"run {run.hex}: recording failed: {reason}")

    def _recording_run(self) -> Run | None:
        with self._lock:
            return self._run

    def _publish_world(self, run: Run | None) -> None:
        """``~/world_yaml`` and ``~/world_markers``: the run's problem (its goal), else the parameters'."""
        if run is not None:
            world, planner = run.world, run.config.planner
        else:
            with self._lock:
                world, planner = self._config.world, self._config.planner
        self._emit(run, "world_yaml", messages.world_yaml_message(world, planner, self.get_name()))
        self._emit(run, "world_markers", messages.world_markers(world, self._now_ns()))

    def _set_status(self, run_id: uuid.UUID, accepted_ns: int, status: int) -> None:
        with self._lock:
            self._statuses[run_id] = [accepted_ns, status]
            self._statuses.move_to_end(run_id)
            while len(self._statuses) > STATUS_HISTORY:
                self._statuses.popitem(last=False)

    def _publish_status(self, run: Run | None) -> None:
        with self._status_lock:
            with self._lock:
                entries = [(run_id, stamp, status) for run_id, (stamp, status) in self._statuses.items()]
            self._emit(run, "status", messages.goal_status_array(entries, self._now_ns()))

    def _event(self, run: Run | None, run_id: uuid.UUID, event: str, at_s: float | None = None,
               **fields: Any) -> None:
        """One ``~/events`` message; ``time`` is ``at_s`` if given (grasp events), else wall-clock seconds."""
        self._emit(run, "events", messages.event_message(run_id, event, time.time() if at_s is None else at_s,
                                                         **fields))

    def _publish_feedback(self, run: Run, phase: str) -> None:
        self._emit(run, "feedback", messages.feedback_status(
            run.id, landmarks=run.landmarks, best_distance=run.best_distance,
            elapsed_s=time.monotonic() - run.started, phase=phase))

    def _on_timer(self) -> None:
        with self._status_lock:
            run = self._recording_run()
            if run is not None and run.phase == "planning":
                self._publish_feedback(run, "planning")
                self._publish_status(run)

    # ----------------------------------------------------------------- requests

    def _on_plan(self, request: Trigger.Request, response: Trigger.Response) -> Trigger.Response:
        del request  # Trigger requests are empty
        run, refusal = self._start_run("plan", None)
        if run is None:
            response.success, response.message = False, refusal
            return response
        while not run.done.wait(timeout=0.5):
            if self._shutting_down:
                break
        response.success = run.outcome is Outcome.SUCCEEDED
        response.message = self._result_text(run)
        return response

    def _on_goal_pose(self, msg: PoseStamped) -> None:
        with self._lock:
            world = self._config.world
        try:
            goal = messages.goal_from_pose_stamped(msg, world)
        except messages.GoalPoseError as error:
            self._refuse(Outcome.INVALID_WORLD, f"refused: {error}", "goal_pose")
            return
        self._start_run("goal_pose", goal)

    def _on_cancel(self, request: Trigger.Request, response: Trigger.Response) -> Trigger.Response:
        del request
        with self._lock:
            run = self._run
            kind = None
            if run is not None and run.phase == "planning":
                run.cancel.set()
                kind = "plan"
            elif run is not None and run.phase in ("publishing", "playback"):
                run.stop_playback.set()
                kind = "playback"
        if kind is None:
            response.success = False
            response.message = "nothing to cancel: no run is planning or playing back"
            return response
        if kind == "plan":
            asked = time.monotonic()
            stopped = run.done.wait(timeout=CANCEL_WAIT_S)
            response.success = True
            response.message = (f"canceled run {run.hex} in {1000 * (time.monotonic() - asked):.0f} ms: "
                                f"{self._result_text(run)}" if stopped
                                else f"cancel requested; run {run.hex} is stopping")
        else:
            asked = time.monotonic()
            stopped = run.finished.wait(timeout=CANCEL_WAIT_S)
            outcome = run.outcome.name if run.outcome else "unknown"
            response.success = True
            response.message = (f"stopped the playback of run {run.hex} in {1000 * (time.monotonic() - asked):.0f} ms "
                                 f"(its outcome stays {outcome})" if stopped
                                 else f"stopping the playback of run {run.hex} (its outcome stays {outcome})")
        self.get_logger().info(response.message.splitlines()[0])
        return response

    def _refuse(self, code: Outcome, message: str, source: str) -> tuple[None, str]:
        """A request that does not become a run: its own UUID, status aborted, an aborted event."""
        run_id = uuid.uuid4()
        now = self._now_ns()
        self._set_status(run_id, now, GoalStatus.STATUS_ABORTED)
        recording = self._recording_run()
        self._publish_status(recording)
        self._event(recording, run_id, "aborted", code=code.name, code_value=code.value, message=message,
                    source=source)
        text = f"run {run_id.hex}: {code.name}: {message}"
        self.get_logger().warning(text)
        return None, text

    def _start_run(self, source: str, goal: np.ndarray | None) -> tuple[Run | None, str]:
        """Accept a run and start its worker, or refuse it; returns ``(run, "")`` or ``(None, reason)``."""
        with self._start_lock:
            with self._lock:
                current = self._run
                if self._shutting_down:
                    refusal = "the node is shutting down"
                elif current is not None and current.planning:
                    refusal = (f"refused: run {current.hex} is still planning "
                               f"(started {time.monotonic() - current.started:.1f} s ago); "
                               "requests are not queued; cancel it with ~/cancel or wait")
                else:
                    refusal = None
                    if current is not None:
                        current.stop_playback.set()
                config = self._config
            if refusal is not None:
                return self._refuse(Outcome.BUSY, refusal, source)
            if current is not None and current.thread is not None:
                current.thread.join()  # a playback stops within one period
            run = Run(id=uuid.uuid4(), source=source,
                      goal=np.array(config.world.object.goal if goal is None else goal, dtype=float),
                      config=config, accepted_ns=self._now_ns())
            with self._lock:
                self._run = run
            self._open_recording(run)
            self._set_status(run.id, run.accepted_ns, GoalStatus.STATUS_ACCEPTED)
            self._publish_world(run)
            self._record(run, self._goal_sub.topic_name, messages.goal_pose_stamped(run.goal, self._now_ns()))
            self._publish_status(run)
            self._event(run, run.id, "accepted", source=source, world=config.world.name,
                        goal=run.goal.tolist(), seed=config.planner.seed, recording=run.recording)
            self.get_logger().info(f"run {run.hex} accepted ({source}): goal {np.round(run.goal, 4).tolist()}, "
                                   f"{run.recording}")
            run.thread = threading.Thread(target=self._work, args=(run,), name=f"clew_run_{run.hex[:8]}",
                                          daemon=True)
            run.thread.start()
            return run, ""

    # ----------------------------------------------------------------- recording

    def _open_recording(self, run: Run) -> None:
        settings = run.config.node
        if not settings.record_enabled:
            run.recording = "recording off (record.enabled is false)"
            return
        recorder_class, problem = self._recorder()
        if recorder_class is None:
            run.recording = f"not recorded: {problem}"
            return
        path = settings.record_path / run.hex
        try:
            settings.record_path.mkdir(parents=True, exist_ok=True)  # the recorder wants it to exist
        except OSError as error:
            run.recording = f"not recorded: record.directory {settings.record_path} cannot be created ({error.strerror})"
            self.get_logger().error(f"run {run.hex}: {run.recording}")
            return
        try:
            run.recorder = recorder_class(settings.record_path, run.hex, node_name=self.get_name())
        except Exception as error:  # noqa: BLE001 - RecordingError and anything else: the run goes on unrecorded
            run.recording = f"not recorded: {error}"
            self.get_logger().error(f"run {run.hex}: cannot record to {path}: {error}")
            return
        run.recording = f"recording {path}"

    def _recorder(self) -> tuple[Any, str]:
        """``(RunRecorder, "")``, or ``(None, why not)`` while ``clew_ros.recording`` does not exist."""
        if self._recorder_api is None:
            try:
                from clew_ros.recording import RunRecorder
            except ImportError as error:
                self._recorder_api = (None, f"the recorder is not available ({error})")
                self.get_logger().warning(f"runs are not recorded: {self._recorder_api[1]}")
            else:
                self._recorder_api = (RunRecorder, "")
        return self._recorder_api

    def _close_recording(self, run: Run) -> None:
        recorder, run.recorder = run.recorder, None
        if recorder is None:
            return
        try:
            recorder.close()
            error = getattr(recorder, "error", None)
        except Exception as close_error:  # noqa: BLE001 - reported, never raised into the run
            error = f"close failed: {close_error}"
        if error:
            self._recording_failed(run, str(error))

    # ----------------------------------------------------------------- the worker

    def _work(self, run: Run) -> None:
        try:
            self._plan_and_publish(run)
            if run.outcome is Outcome.SUCCEEDED and run.track is not None:
                self._play_back(run)
        except Exception as error:  # noqa: BLE001 - a bug here must not take the node down
            self.get_logger().error(f"run {run.hex}: internal error: {error!r}")
            if not run.outcome_sent:  # else the outcome is out already: one outcome per run
                try:
                    self._finish(run, Outcome.INTERNAL_ERROR, f"internal error in the node: {error!r}")
                except Exception as again:  # noqa: BLE001
                    self.get_logger().error(f"run {run.hex}: cannot publish its outcome: {again!r}")
        finally:
            run.done.set()
            self._close_recording(run)
            with self._lock:
                run.phase = "finished"
            run.finished.set()

    def _plan_and_publish(self, run: Run) -> None:
        run.track = None
        config = run.config
        self._set_status(run.id, run.accepted_ns, GoalStatus.STATUS_EXECUTING)
        self._publish_status(run)
        self._emit(run, "landmarks", messages.landmark_markers(_root_tree(config), self._now_ns()))
        seen = [1]  # landmarks already announced (the root)

        def on_progress(progress: Progress) -> None:
            run.landmarks, run.best_distance = progress.landmarks, progress.best_distance
            try:
                self._announce_landmarks(run, progress.tree, seen)
            except Exception as error:  # noqa: BLE001 - never let a publishing fault end the planning
                self.get_logger().error(f"run {run.hex}: cannot publish progress: {error!r}")

        result = plan(config.world, config.planner, goal=None if run.source == "plan" else run.goal,
                      termination=Termination(config.planner.time_limit, run.cancel), progress=on_progress)
        with self._lock:
            canceled = run.cancel.is_set()
            run.phase = "publishing"
        run.landmarks = len(result.tree)
        self._announce_landmarks(run, result.tree, seen)
        outcome, message = result.outcome, result.message
        if canceled and outcome is not Outcome.CANCELED:
            outcome, message = Outcome.CANCELED, f"canceled (the run had ended {outcome.name} at the same moment)"
        if outcome is Outcome.CANCELED and self._shutting_down:
            message += " (the node is shutting down)"
        stats = dict(result.stats)
        if outcome is Outcome.SUCCEEDED:
            world = run.world  # validated against the run's goal
            planned = checked_plan(world, result)
            if not planned.success:  # it failed validation: not published
                outcome, message = Outcome.INTERNAL_ERROR, planned.message
            else:
                run.track = track_from_plan(world, planned, joint_speed_rad_s=config.node.joint_speed_rad_s,
                                            grasp_dwell_s=config.node.grasp_dwell_s)
        self._finish(run, outcome, message, stats)

    def _announce_landmarks(self, run: Run, tree, seen: list[int]) -> None:
        landmarks = list(tree)
        if len(landmarks) <= seen[0]:
            return
        for landmark in landmarks[seen[0]:]:
            self._event(run, run.id, "landmark", id=landmark.id, parent=landmark.parent, grasp=landmark.grasp,
                        object_pose=landmark.object_pose, joints=landmark.joints)
        seen[0] = len(landmarks)
        self._emit(run, "landmarks", messages.landmark_markers(tree, self._now_ns()))

    def _finish(self, run: Run, outcome: Outcome, message: str, stats: dict | None = None) -> None:
        """Publish the run's outcome; set ``done`` (the ~/plan answer goes out)."""
        stats = stats or {}
        run.outcome, run.message = outcome, message
        run.elapsed = float(stats.get("time_s", time.monotonic() - run.started))
        status = {Outcome.SUCCEEDED: GoalStatus.STATUS_SUCCEEDED,
                  Outcome.CANCELED: GoalStatus.STATUS_CANCELED}.get(outcome, GoalStatus.STATUS_ABORTED)
        event = {Outcome.SUCCEEDED: "succeeded", Outcome.CANCELED: "canceled"}.get(outcome, "aborted")
        if outcome is Outcome.SUCCEEDED:
            run.playback_s = run.track.duration_s
            self._emit(run, "trajectory", messages.joint_trajectory(run.track, self._now_ns()))
        with self._status_lock:
            self._publish_feedback(run, outcome.name)
            self._set_status(run.id, run.accepted_ns, status)
            self._publish_status(run)
        self._event(run, run.id, event, code=outcome.name, code_value=outcome.value, message=message,
                    landmarks=run.landmarks, time_s=run.elapsed, recording=run.recording)
        if outcome is not Outcome.SUCCEEDED:
            # no playback follows: the recording is complete before the answer goes out
            self._close_recording(run)
        with self._lock:
            # from here a new request is served (a playback is stopped for it), never refused BUSY:
            # whoever saw the outcome may send the next goal at once
            run.phase = "playback" if outcome is Outcome.SUCCEEDED and run.track is not None else "finished"
        run.outcome_sent = True
        if outcome is Outcome.SUCCEEDED and run.recorder is not None:
            # the recording closes after the playback; fold a write error met so far into the answer
            error = getattr(run.recorder, "error", None)
            if error:
                self._recording_failed(run, str(error))
        summary = f"run {run.hex}: {outcome.name}: {message.splitlines()[0] if message else ''}"
        # one call site per severity: rclpy refuses a call site whose severity changes between calls
        if outcome is Outcome.SUCCEEDED:
            self.get_logger().info(summary)
        else:
            self.get_logger().warning(summary)
        run.done.set()

    def _result_text(self, run: Run) -> str:
        outcome = run.outcome.name if run.outcome else "UNKNOWN"
        text = (f"run {run.hex}: {outcome}: {run.message}; landmarks {run.landmarks}; "
                f"time {run.elapsed:.2f} s; {run.recording}")
        if run.outcome is Outcome.SUCCEEDED and run.recorder is not None:
            text += f" (complete when the {run.playback_s:.1f} s playback ends)"
        return text

    def _play_back(self, run: Run) -> None:
        """Publish ``~/joint_states``, ``~/object_pose`` and grasp events along ``run.track``, in time."""
        with self._lock:
            stopped_before_start = run.stop_playback.is_set()
            run.phase = "playback"
        if stopped_before_start:  # a cancel or a new request came between the outcome and the first sample
            self._publish_feedback(run, "playback_stopped")
            self.get_logger().info(f"run {run.hex}: playback stopped before it started")
            return
        track: Track = run.track
        events = track.events()
        next_event = 0
        period = 1.0 / run.config.node.playback_rate_hz
        start = time.monotonic()
        tick = 0
        while True:
            t = time.monotonic() - start
            joints, gripper, pose = track.sample(t)
            now = self._now_ns()
            self._emit(run, "joint_states", messages.joint_state(track.joint_names, joints, gripper, now))
            self._emit(run, "object_pose", messages.object_pose_stamped(pose, now))
            while next_event < len(events) and events[next_event].time_s <= t:
                e = events[next_event]
                self._event(run, run.id, e.kind, at_s=float(e.time_s), grasp=e.grasp)
                next_event += 1
            if t >= track.duration_s:
                self._publish_feedback(run, "playback_done")
                self.get_logger().info(f"run {run.hex}: playback done ({track.duration_s:.2f} s)")
                return
            tick += 1
            wait = start + min(tick * period, track.duration_s) - time.monotonic()
            if run.stop_playback.wait(timeout=max(0.0, wait)):
                self._publish_feedback(run, "playback_stopped")
                self.get_logger().info(f"run {run.hex}: playback stopped at {t:.2f} s of {track.duration_s:.2f} s")
                return

    # ----------------------------------------------------------------- shutdown

    def shutdown_runs(self, timeout_s: float = 10.0) -> None:
        """Cancel the running plan, stop playback, close the recording; wait for the worker."""
        with self._lock:
            self._shutting_down = True
            run = self._run
        if run is None:
            return
        run.cancel.set()
        run.stop_playback.set()
        if run.thread is not None:
            run.thread.join(timeout=timeout_s)
            if run.thread.is_alive():
                self.get_logger().error(f"run {run.hex}: the worker did not stop within {timeout_s} s")


def _root_tree(config: Configuration) -> LandmarkTree:
    """The tree a run starts with: the root landmark only."""
    return LandmarkTree(config.world.robot.initial, config.world.object.initial)

