"""The ``clew_planner`` node: the planner core served over ROS 2 (interface.md §3).

This module holds the node's parameters, callbacks and policy: one run at a
time; a request while a run plans is refused (``BUSY``), never queued; a
request during a playback stops the playback. A run's state lives on its
handle (:mod:`~clew_ros.node.run`), its life in :mod:`~clew_ros.node.worker`
(playback: :mod:`~clew_ros.motion.player`); messages go out, and into the run's
recording (:mod:`~clew_ros.node.run_recording`), through
:mod:`~clew_ros.node.publishing`. A run plans in the world as it is now when the ``state.*`` inputs are on
(:mod:`~clew_ros.node.live_state`: one snapshot per run, taken as it is accepted).

Entry points for callbacks and in-process callers (tests):
:meth:`PlannerNode.request_plan` (a :class:`~clew_ros.node.run.Run` to wait
on: ``wait_outcome``, ``wait_finished``), :meth:`PlannerNode.cancel`,
:attr:`PlannerNode.current_run`, :meth:`PlannerNode.shutdown_runs`.

Threads: a ``MultiThreadedExecutor`` (``main``) runs the callbacks, each in
the group given, and explained, where it is created; a run plans and plays
back in a thread of its own. ``self._lock`` guards the policy's state (the
current run, the configuration, the shutdown flag); it is never held while
waiting.
"""

from __future__ import annotations

import threading
import time
from typing import Any

import numpy as np
from geometry_msgs.msg import PoseStamped
from rcl_interfaces.msg import SetParametersResult
from rclpy.callback_groups import MutuallyExclusiveCallbackGroup, ReentrantCallbackGroup
from rclpy.node import Node
from rclpy.parameter import Parameter
from std_srvs.srv import Trigger

from clew_ros.core.errors import ParameterError
from clew_ros.core.parameters import LIMITS
from clew_ros.core.settings import Outcome
from clew_ros.kinds import kind_of
from clew_ros.node.live_state import LiveState, StateRefusalError, describe_inputs
from clew_ros.node.live_view import start_live_view
from clew_ros.node.namespaces import namespaced_directory
from clew_ros.node.parameter_changes import declare_all, locked_or_over_caps, own_values, unknown_parameter
from clew_ros.node.publishing import Publishing
from clew_ros.node.run import CancelKind, Run, Source
from clew_ros.node.run_recording import NO_RECORDING, Recordings, RunRecording
from clew_ros.node.worker import RunWorker
from clew_ros.planar.kernel import warm_up
from clew_ros.ros import messages
from clew_ros.ros.node_parameters import LOCKED_PREFIXES, RUNTIME_CHANGES
from clew_ros.ros.parameters import (
    OWN_PREFIXES,
    Configuration,
    check_parameter_names,
    configuration_from_values,
    initial_values,
    plain_value,
    runtime_changes_allowed,
)
from clew_ros.ros.qos import GOAL_QOS

__all__ = ["NODE_NAME", "PlannerNode", "StartupError"]

NODE_NAME = "clew_planner"
#: Rate (Hz) of ~/status and ~/feedback while a plan runs.
STATUS_RATE_HZ = 5.0
#: How long ~/cancel waits for the run to stop before answering (s).
CANCEL_WAIT_S = 2.0
#: How long a refusal waits for the current run's start to be out, so that it is recorded in it (s).
START_WAIT_S = 10.0


class StartupError(RuntimeError):
    """The node cannot start (invalid parameters); already logged."""


class PlannerNode(Node):
    """Serves :func:`clew_ros.core.clew.plan` as ``~/plan``, ``~/goal_pose`` and ``~/cancel``.

    ``record_subdirectory`` (``clew_planners``: the node's namespace) makes the
    node record into ``<record.directory>/<record_subdirectory>``; its
    ``record.directory`` parameter is declared so.
    """

    def __init__(self, node_name: str = NODE_NAME, *, record_subdirectory: str | None = None, **kwargs: Any) -> None:
        # Every --params-file / -p value is declared as the node is created (world.obstacles.<name>
        # with any name); _declare_parameters checks them and gives each its descriptor.
        # Undeclared parameters stay allowed, but only parameters.allow_runtime_changes lets
        # ros2 param set add one under LOCKED_PREFIXES (an obstacle).
        super().__init__(
            node_name, allow_undeclared_parameters=True, automatically_declare_parameters_from_overrides=True, **kwargs
        )
        self._lock = threading.Lock()  # the policy: _run, _config and _closing change under it
        self._closing = threading.Event()  # shutting down: no new run
        self._run: Run | None = None  # the current run: the last accepted
        self._pending_world_change = False  # set by on_set, republished by post_set
        self._refusals = ("", 0)  # the current run's id and the refusals recorded in its recording
        self._config = self._declare_parameters(record_subdirectory)
        warm_up_s = warm_up()  # the planning kernel, before any plan (main() did it; another program may not)
        if warm_up_s > 1.0:
            self.get_logger().info(f"planning kernel compiled in {warm_up_s:.1f} s (cached for the next start)")
        self._out = Publishing(self, self._closing, link_faces=self._config.node.marker_link_faces)
        self._out.live = start_live_view(self, self._config)

        # ~/plan blocks until its run's outcome is out, and a second call must still be
        # answered (refused) at once, on another executor thread: a reentrant group.
        self.create_service(Trigger, "~/plan", self._on_plan, callback_group=ReentrantCallbackGroup())
        # ~/cancel in a group of its own: never queued behind ~/plan or ~/goal_pose callbacks.
        self.create_service(Trigger, "~/cancel", self._on_cancel, callback_group=MutuallyExclusiveCallbackGroup())
        # ~/goal_pose in a group of its own with the state inputs (created first): one at a time, in order.
        inputs = MutuallyExclusiveCallbackGroup()
        self._state = LiveState(self, self._config, self._out, inputs, lambda: self.current_run)
        goal_sub = self.create_subscription(
            PoseStamped, "~/goal_pose", self._on_goal_pose, GOAL_QOS, callback_group=inputs
        )
        # the status / feedback timer in a group of its own; parameter services stay in the default group.
        self.create_timer(1.0 / STATUS_RATE_HZ, self._on_timer, callback_group=MutuallyExclusiveCallbackGroup())
        self._worker = RunWorker(
            self._out,
            Recordings(self.get_name(), self.get_logger()),
            goal_sub.topic_name,
            self.get_logger(),
            self._closing,
        )

        # Parameter changes: checked as a whole (on_set), then republished (post_set).
        self.add_on_set_parameters_callback(self._on_set_parameters)
        self.add_post_set_parameters_callback(self._on_parameters_set)

        self._publish_world()
        self._out.publish_status(NO_RECORDING)
        world = self._config.world
        self.get_logger().info(
            f"serving world '{world.name}' ({world.robot.dof} joints, {len(world.obstacles)} obstacles); "
            f"recording {'to ' + str(self._config.node.record_path) if self._config.node.record_enabled else 'off'}"
            f"{describe_inputs(self._config.node)}"
        )
        if self._config.node.allow_runtime_changes:
            self.get_logger().warning(
                f"{RUNTIME_CHANGES} is true: any peer on the ROS domain may change the "
                f"{', '.join(p + '*' for p in LOCKED_PREFIXES)} parameters (the world, the trajectory limits, "
                "the recordings); for development only"
            )

    # ----------------------------------------------------------------- runs: the public entry points

    @property
    def current_run(self) -> Run | None:
        """The last accepted run (planning, playing back or finished), if any."""
        with self._lock:
            return self._run

    def request_plan(
        self, source: Source = "plan", goal: np.ndarray | None = None, goal_stamp_ns: int | None = None
    ) -> tuple[Run | None, str]:
        """Start a run to ``goal`` (``(x, y, theta)``, a spatial world's ``(x, y, z, roll, pitch, yaw)``;
        ``None``: ``world.object.goal``, or a spatial motion-only query's ``world.robot.goal``), or refuse it.

        ``goal_stamp_ns``, the stamp of the ``~/goal_pose`` that asks, is echoed
        in the run's ``accepted`` event or in the refusal's ``aborted`` event.

        Returns ``(run, "")`` once the run's start is out (status accepted,
        ``accepted`` event) and its worker runs, or ``(None, why)`` when a run
        is still planning (``BUSY``: it gets a UUID of its own, status
        aborted and an ``aborted`` event) or the node shuts down. A playback
        in progress is stopped for the new run.
        """
        concluding = self.current_run
        if concluding is not None and concluding.outcome is not None:
            # its outcome is being published: whoever saw it may send the next goal at once, never refused BUSY
            concluding.wait_outcome(START_WAIT_S)
        code = Outcome.BUSY
        with self._lock:  # the policy: one run at a time; never queued; planned in the state of the moment
            previous = self._run
            if self._closing.is_set():
                refusal = "the node is shutting down"
            elif previous is not None and previous.is_busy:
                refusal = (
                    f"refused: run {previous.hex} is still planning "
                    f"(started {time.monotonic() - previous.start_s:.1f} s ago); "
                    "requests are not queued; cancel it with ~/cancel or wait"
                )
            else:
                try:
                    config, refusal = self._state.snapshot(self._config, previous), None
                except StateRefusalError as error:
                    code, refusal = error.code, f"refused: {error.message}"
                else:
                    run = self._run = Run(source, goal, config, self._out.now_ns(), goal_stamp_ns)
                    if previous is not None:
                        previous.stop_playback()
        if refusal is not None:
            return None, self._refuse(code, refusal, source, goal_stamp_ns)
        self._worker.start(run, previous)
        return run, ""

    def cancel(self) -> tuple[bool, str]:
        """Cancel the current run's planning, or stop its playback; ``(success, message)`` of ``~/cancel``.

        Answers once the run has stopped (at most :data:`CANCEL_WAIT_S`).
        """
        with self._lock:
            run = self._run
            kind = run.request_cancel() if run is not None else None
        if run is None or kind is None:
            return False, "nothing to cancel: no run is planning or playing back"
        asked = time.monotonic()
        stopped = run.wait_outcome(CANCEL_WAIT_S) if kind is CancelKind.PLAN else run.wait_finished(CANCEL_WAIT_S)
        took = f"in {1000 * (time.monotonic() - asked):.0f} ms"
        if kind is CancelKind.PLAN:
            message = (
                f"canceled run {run.hex} {took}: {run.result_text()}"
                if stopped
                else f"cancel requested; run {run.hex} is stopping"
            )
        else:
            outcome = run.outcome.name if run.outcome else "unknown"
            message = (
                f"stopped the playback of run {run.hex} {took} (its outcome stays {outcome})"
                if stopped
                else f"stopping the playback of run {run.hex} (its outcome stays {outcome})"
            )
        self.get_logger().info(message.splitlines()[0])
        return True, message

    def shutdown_runs(self, timeout_s: float = 10.0) -> None:
        """Refuse new runs; cancel the running plan, stop the playback, close the recording; wait for the worker.
        Then stop the live view, if any."""
        with self._lock:
            self._closing.set()
            run = self._run
        try:
            self._stop_runs(run, timeout_s)
        finally:
            live, self._out.live = self._out.live, None
            if live is not None:
                live.stop()

    def _stop_runs(self, run: Run | None, timeout_s: float) -> None:
        if run is None:
            return
        run.stop()
        if not run.wait_finished(timeout_s):
            self.get_logger().error(f"run {run.hex}: the worker did not stop within {timeout_s} s")

    def _refuse(self, code: Outcome, message: str, source: Source, goal_stamp_ns: int | None = None) -> str:
        """Publish a refused request (a UUID of its own, status aborted, an aborted event); its text."""
        text = self._out.refusal(code, message, source, self._refusal_recording(), goal_stamp_ns)
        self.get_logger().warning(text)
        return text

    def _refusal_recording(self) -> RunRecording:
        """Where a refusal is recorded: the current run's recording, after that run's start, for the first
        ``Limits.max_recorded_refusals`` refusals while it is current; past them, nowhere (published only)."""
        current = self.current_run
        if current is None or not current.wait_started(START_WAIT_S):
            return NO_RECORDING
        with self._lock:
            if self._refusals[0] != current.hex:
                self._refusals = (current.hex, 0)
            count = self._refusals[1] + 1
            self._refusals = (current.hex, count)
        if count == LIMITS.max_recorded_refusals + 1:
            self.get_logger().warning(
                f"run {current.hex}: {LIMITS.max_recorded_refusals} refused requests recorded "
                "(Limits.max_recorded_refusals); further ones are published, not recorded"
            )
        return current.recording if count <= LIMITS.max_recorded_refusals else NO_RECORDING

    # ----------------------------------------------------------------- callbacks

    def _on_plan(self, request: Trigger.Request, response: Trigger.Response) -> Trigger.Response:
        del request  # Trigger requests are empty
        run, refusal = self.request_plan("plan")
        if run is None:
            response.success, response.message = False, refusal
            return response
        while not run.wait_outcome(0.5) and not self._closing.is_set():
            pass
        response.success = run.outcome is Outcome.SUCCEEDED
        response.message = run.result_text()
        return response

    def _on_cancel(self, request: Trigger.Request, response: Trigger.Response) -> Trigger.Response:
        del request
        response.success, response.message = self.cancel()
        return response

    def _on_goal_pose(self, msg: PoseStamped) -> None:
        with self._lock:
            world = self._config.world
        stamp_ns = msg.header.stamp.sec * 10**9 + msg.header.stamp.nanosec
        try:
            goal = kind_of(world).goal_from_pose_stamped(msg, world)
        except messages.GoalPoseError as error:
            self._refuse(Outcome.INVALID_WORLD, f"refused: {error}", "goal_pose", stamp_ns)
            return
        self.request_plan("goal_pose", goal, stamp_ns)

    def _on_timer(self) -> None:
        run = self.current_run
        if run is not None:
            self._out.planning_progress(run)

    def _publish_world(self) -> None:
        """``~/world_yaml`` and ``~/world_markers`` of the parameters (a run publishes its own problem)."""
        with self._lock:
            config = self._config
        self._out.world(config.world, config.planner, NO_RECORDING, config.spatial)

    # ----------------------------------------------------------------- parameters

    def _declare_parameters(self, record_subdirectory: str | None) -> Configuration:
        """Declare every parameter with its descriptor; raise :class:`StartupError` if any is invalid.

        The overrides (``--params-file`` / ``-p``) are declared already, typed by
        their value; they get their descriptor here (``dynamic_typing``: a later
        ``30`` for ``30.0`` is checked by :mod:`~clew_ros.ros.parameters`, not
        refused by rclpy). The others are declared with their start values.
        ``parameters.allow_runtime_changes`` is read first: it decides which
        descriptors are read-only (rclpy then refuses any change of those,
        naming the parameter).
        """
        overrides = self._own_values()
        try:
            allow = runtime_changes_allowed(overrides)
            values = initial_values(overrides)
            check_parameter_names(set(values) | set(self.get_parameters_by_prefix("")))
            if record_subdirectory is not None:
                values["record.directory"] = namespaced_directory(str(values["record.directory"]), record_subdirectory)
            config = configuration_from_values(values)
        except ParameterError as error:
            self.get_logger().error(f"invalid parameter {error}; not starting")
            raise StartupError(str(error)) from None
        declare_all(self, values, overrides, allow_runtime_changes=allow, lock_planner=config.node.lock_planner)
        return config

    def _own_values(self) -> dict[str, Any]:
        """Current values of the node's own parameters, by full name."""
        return own_values(self)

    def _on_set_parameters(self, parameters: list[Parameter]) -> SetParametersResult:
        try:
            return self._check_parameters(parameters)
        except Exception as error:  # noqa: BLE001 - a checking bug must refuse the change, not end the node
            names = ", ".join(p.name for p in parameters)
            self.get_logger().error(f"internal error while checking {names}: {error!r}")
            return SetParametersResult(
                successful=False,
                reason=f"{names}: internal error while checking the "
                f"change ({type(error).__name__}: {error}); nothing was changed",
            )

    def _check_parameters(self, parameters: list[Parameter]) -> SetParametersResult:
        refusal = locked_or_over_caps(parameters, self._config.node, set(self.get_parameters_by_prefix("")))
        refusal = refusal or unknown_parameter(parameters, self.has_parameter)
        if refusal is not None:
            return SetParametersResult(successful=False, reason=refusal)
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
            if world_change and run is not None and run.is_busy:
                reason = (
                    f"{own[0].name}: the world cannot change while run {run.hex} is planning; "
                    "cancel it (~/cancel) or wait for its outcome"
                )
                return SetParametersResult(successful=False, reason=reason)
            try:
                config = configuration_from_values(values, listed_obstacles_only=True, previous=self._config)
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
            self._publish_world()
