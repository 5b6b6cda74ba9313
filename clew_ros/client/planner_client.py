"""``PlannerClient``: send goals to a running ``clew_planner`` from your own rclpy node and follow them.

Only the planner's standard interface is used (interface.md section 3): a
goal is a ``~/goal_pose`` message whose header stamp identifies it; the
planner echoes that stamp (``goal_stamp_ns``) in the ``accepted`` event of
the run it starts, or in the ``aborted`` event that refuses it (``BUSY``, a
goal outside the world, ...). From then on ``~/status``, ``~/feedback`` and
``~/events`` are matched by run id, and a successful run's plan is rebuilt
from ``~/trajectory``. Nothing is parsed out of human-readable text.

Where each call may be made
---------------------------
- In a script, with a node that no executor spins: :meth:`RunHandle.wait`
  and :meth:`PlannerClient.wait_for_planner` spin the node themselves (with
  the client's own single-threaded executor) until they return.
- In a node spun by your executor: :meth:`PlannerClient.send_goal` with a goal (``None``, the planner's own
  goal, asks its ``get_parameters`` service and waits for the answer),
  :meth:`RunHandle.cancel`, :meth:`RunHandle.add_done_callback` and reading
  the handle never block and are safe in any callback. :meth:`RunHandle.wait`
  blocks, so call it from a thread of your own, or from a callback of a
  ``MultiThreadedExecutor`` (the client's subscriptions are in their own
  reentrant callback group); called from the thread of a
  ``SingleThreadedExecutor`` that spins the node it would never return, so it
  raises ``RuntimeError`` instead.
"""

from __future__ import annotations

import dataclasses
import json
import threading
import time
import weakref
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np
import yaml
from action_msgs.msg import GoalStatus, GoalStatusArray
from diagnostic_msgs.msg import DiagnosticStatus
from geometry_msgs.msg import PoseStamped
from rcl_interfaces.srv import GetParameters
from rclpy.callback_groups import ReentrantCallbackGroup
from rclpy.executors import MultiThreadedExecutor, SingleThreadedExecutor
from rclpy.node import Node
from std_msgs.msg import String
from std_srvs.srv import Trigger
from trajectory_msgs.msg import JointTrajectory

from clew_ros.client.run import (
    Feedback,
    PlannerNotFoundError,
    RunHandle,
    RunResult,
    RunStatus,
    RunTimeoutError,
)
from clew_ros.client.world_now import StartState, StateSender
from clew_ros.core.errors import ClewError
from clew_ros.core.settings import Outcome
from clew_ros.kinds import DEFAULT_KIND, WorldKind, kind_named, kind_of_parameters
from clew_ros.recording.trajectory import spatial_trajectory_plan
from clew_ros.ros import messages
from clew_ros.ros.qos import EVENTS_QOS, GOAL_QOS, LATCHED_QOS, STREAM_QOS

__all__ = ["PlannerClient", "spatial_trajectory_plan"]

_STATUS = {GoalStatus.STATUS_ACCEPTED: RunStatus.ACCEPTED, GoalStatus.STATUS_EXECUTING: RunStatus.EXECUTING}
_OUTCOME_EVENTS = ("succeeded", "aborted", "canceled")
#: The executors made to spin scripts' nodes (one per node, shared by its clients), each with a lock so that
#: one thread at a time spins it.
_SCRIPT_EXECUTORS: weakref.WeakKeyDictionary[SingleThreadedExecutor, threading.Lock] = weakref.WeakKeyDictionary()


class PlannerClient:
    """Follow runs of the planner ``planner`` (its node name with namespace) from ``node``.

    Example (a script)::

        rclpy.init()
        node = rclpy.create_node("my_client")
        client = PlannerClient(node)
        client.wait_for_planner(timeout_s=10.0)
        result = client.send_goal((0.6, 1.1, 0.0)).wait(timeout_s=60.0)
        if result.succeeded:
            print(len(result.plan.segments), "segments;", result.plan.grasp_count, "grasps")
        else:
            print(result.outcome.name, result.message)   # BUSY, TIME_LIMIT, GOAL_IN_COLLISION, ...
    """

    def __init__(self, node: Node, planner: str = "/clew_planner", *, joint_states_topic: str | None = None) -> None:
        self._node = node
        self.planner = planner.rstrip("/") or "/clew_planner"
        # the start states a goal may carry go to the planner's joint_states (relative: its namespace's)
        namespace = self.planner.rsplit("/", 1)[0]
        self._world_now = StateSender(node, self.planner, joint_states_topic or f"{namespace}/joint_states")
        self._group = ReentrantCallbackGroup()
        self._changed = threading.Condition()
        self._lock = threading.Lock()
        self._pending: dict[int, RunHandle] = {}  # goal stamp (ns) -> handle not answered yet
        self._runs: dict[str, RunHandle] = {}  # run id -> handle
        self._trajectories: list[JointTrajectory] = []  # the last few received, newest last
        self._world_text: str | None = None
        self._status_seen = False
        self._callback_threads: dict[int, set[int]] = {}  # id(executor) -> threads that ran our callbacks
        self._last_stamp_ns = 0
        name = self.planner
        group = self._group
        self._goal_pub = node.create_publisher(PoseStamped, f"{name}/goal_pose", GOAL_QOS, callback_group=group)
        # the service clients before the latched ~/status's subscription: a participant announces its endpoints
        # in order, so once ~/status arrives (planner_ready) the planner has matched their response readers too,
        # and its first answer is not lost (Fast DDS drops a response to a reader it has not matched yet)
        self._cancel = node.create_client(Trigger, f"{name}/cancel", callback_group=group)
        self._parameters = node.create_client(GetParameters, f"{name}/get_parameters", callback_group=group)
        self._subscriptions = [
            node.create_subscription(String, f"{name}/events", self._on_event, EVENTS_QOS, callback_group=group),
            node.create_subscription(
                GoalStatusArray, f"{name}/status", self._on_status, LATCHED_QOS, callback_group=group
            ),
            node.create_subscription(
                DiagnosticStatus, f"{name}/feedback", self._on_feedback, STREAM_QOS, callback_group=group
            ),
            node.create_subscription(
                JointTrajectory, f"{name}/trajectory", self._on_trajectory, LATCHED_QOS, callback_group=group
            ),
            node.create_subscription(
                String, f"{name}/world_yaml", self._on_world_yaml, LATCHED_QOS, callback_group=group
            ),
        ]

    # -- the planner ---------------------------------------------------------------------------------

    def planner_ready(self) -> bool:
        """Whether the planner is there: it listens on ``~/goal_pose``, and its ``~/events`` and
        latched ``~/status`` reach this node (never blocks)."""
        return (
            self._goal_pub.get_subscription_count() > 0
            and self._subscriptions[0].get_publisher_count() > 0
            and self._status_seen
        )

    def wait_for_planner(self, timeout_s: float | None = 10.0) -> None:
        """Wait until :meth:`planner_ready`; raises :class:`PlannerNotFoundError` after ``timeout_s``."""
        if not self._wait_until(self.planner_ready, timeout_s):
            raise PlannerNotFoundError(
                f"no planner at {self.planner} within {timeout_s} s (is clew_planner running, "
                "with the same ROS_DOMAIN_ID?)"
            )

    def default_goal(self, timeout_s: float | None = 10.0) -> tuple[float, ...]:
        """The planner's ``world.object.goal`` parameter (through its standard ``get_parameters`` service):
        ``(x, y, yaw)``, or a spatial world's ``(x, y, z, roll, pitch, yaw)``; a spatial motion-only query's
        ``world.robot.goal_pose`` (the tcp's goal pose). A motion-only query to joint values
        (``world.robot.goal``) has no goal pose: :class:`PlannerNotFoundError` says to call ``~/plan``."""
        if not self._parameters.wait_for_service(timeout_sec=timeout_s):
            raise PlannerNotFoundError(f"{self.planner}/get_parameters did not answer within {timeout_s} s")
        names = ["world.object.goal", "world.robot.goal_pose", "world.robot.goal"]
        future = self._parameters.call_async(GetParameters.Request(names=names))
        if not self._wait_until(future.done, timeout_s):
            raise RunTimeoutError(f"{self.planner}/get_parameters did not answer within {timeout_s} s")
        values = future.result().values
        found = [[float(v) for v in (value.double_array_value or value.integer_array_value)] for value in values]
        for goal in found[:2]:
            if len(goal) in (3, 6):
                return tuple(goal)
        if len(found) > 2 and found[2]:
            raise PlannerNotFoundError(
                f"{self.planner} plans a motion-only query to joint values (world.robot.goal), which a "
                "~/goal_pose cannot carry: call its ~/plan service (python -m clew_ros.client.call_plan does)"
            )
        raise PlannerNotFoundError(
            f"{self.planner} has no world.object.goal parameter of three or six numbers (nor world.robot.goal_pose)"
        )

    # -- goals ---------------------------------------------------------------------------------------

    def send_goal(
        self,
        goal: Sequence[float] | PoseStamped | None = None,
        *,
        on_feedback: Callable[[RunHandle, Feedback], None] | None = None,
        start: StartState | None = None,
        object_pose: Sequence[float] | PoseStamped | None = None,
    ) -> RunHandle:
        """Send a goal; returns its handle at once.

        ``goal``: the object's goal placement ``(x, y, yaw)`` in frame ``world``,
        for a spatial planner ``(x, y, z, roll, pitch, yaw)`` (URDF's ``rpy``; it
        must be a stable placement, else the run is refused saying why), or a
        ``PoseStamped`` in that frame (any orientation); on a spatial motion-only query (no object) the tcp's
        goal pose, reached by the planner's own inverse kinematics; ``None``: the planner's own
        ``world.object.goal`` or ``world.robot.goal_pose`` (asked with :meth:`default_goal`, which waits for
        the parameter service). ``on_feedback(handle, feedback)`` is called on
        each ``~/feedback`` of the run. Raises :class:`PlannerNotFoundError`
        when :meth:`planner_ready` is false (call :meth:`wait_for_planner` first).

        ``start`` (a ``JointState``, or joint name -> position) and ``object_pose`` (``x, y, z, roll, pitch,
        yaw`` or a ``PoseStamped``) are the world as it is now (interface.md section 3c): published on the
        planner's ``joint_states`` (the constructor's ``joint_states_topic``) and ``~/object`` before the
        goal, each waiting (at most 5 s) until the planner has acknowledged it, so that the run plans from
        them; the planner must have ``state.joint_states`` / ``state.object_pose`` on (else
        :class:`PlannerNotFoundError` says so).
        """
        if not self.planner_ready():
            raise PlannerNotFoundError(f"no planner at {self.planner} yet: call wait_for_planner() first")
        if goal is None:
            goal = self.default_goal()
        with self._lock:  # wall-clock ns (a sim clock may be at 0 in every client): unique goal stamps
            stamp_ns = max(time.time_ns(), self._last_stamp_ns + 1)
            self._last_stamp_ns = stamp_ns
        if start is not None:
            self._world_now.send_start(start, stamp_ns)
        if object_pose is not None:
            self._world_now.send_object(object_pose, stamp_ns)
        target: tuple[float, ...]
        if isinstance(goal, PoseStamped):
            msg = goal
            msg.header.stamp.sec, msg.header.stamp.nanosec = divmod(stamp_ns, 10**9)
            target = (self._kind() or kind_named(DEFAULT_KIND)).pose_goal(msg)
        else:
            target = tuple(float(v) for v in goal)
            if len(target) == 6:
                from clew_ros.ros.spatial import pose_stamped

                msg = pose_stamped(target, stamp_ns)
            elif len(target) == 3:
                msg = messages.goal_pose_stamped(np.array(target), stamp_ns)
            else:
                raise ValueError(f"goal: expected (x, y, yaw) or (x, y, z, roll, pitch, yaw), got {goal!r}")
        handle = RunHandle(self, target, stamp_ns, on_feedback)
        with self._lock:
            self._pending[stamp_ns] = handle
        self._goal_pub.publish(msg)
        return handle

    def plan(
        self,
        goal: Sequence[float] | PoseStamped | None = None,
        *,
        timeout_s: float | None = None,
        start: StartState | None = None,
        object_pose: Sequence[float] | PoseStamped | None = None,
    ) -> RunResult:
        """:meth:`send_goal` then :meth:`RunHandle.wait` (scripts)."""
        return self.send_goal(goal, start=start, object_pose=object_pose).wait(timeout_s)

    def destroy(self) -> None:
        """Remove the client's publisher, subscriptions and service clients from the node; runs still followed
        end with ``INTERNAL_ERROR`` ("the client was destroyed"), so no ``wait()`` is left hanging."""
        with self._lock:
            left = [*self._pending.values(), *self._runs.values()]
            self._pending.clear()
            self._runs.clear()
        for handle in left:
            if not handle.done():
                handle.finish(RunResult(handle.run_id or "", Outcome.INTERNAL_ERROR, "the client was destroyed"))
        self._notify()
        node = self._node
        node.destroy_publisher(self._goal_pub)
        for subscription in self._subscriptions:
            node.destroy_subscription(subscription)
        node.destroy_client(self._cancel)
        node.destroy_client(self._parameters)
        self._world_now.destroy()

    # -- waiting -------------------------------------------------------------------------------------

    def wait_until(self, predicate: Callable[[], bool], timeout_s: float | None) -> bool:
        """Wait until ``predicate()`` is true (e.g. ``lambda: handle.status is RunStatus.EXECUTING``), at most
        ``timeout_s``; ``False`` when the time is up. Spins a script's node as :meth:`RunHandle.wait` does."""
        return self._wait_until(predicate, timeout_s)

    def _wait_until(self, predicate: Callable[[], bool], timeout_s: float | None) -> bool:
        deadline = None if timeout_s is None else time.monotonic() + timeout_s

        def left() -> float:
            return 0.1 if deadline is None else min(0.1, deadline - time.monotonic())

        node = self._node
        executor = node.executor
        spun_elsewhere = executor is not None and executor not in _SCRIPT_EXECUTORS and node in executor.get_nodes()
        if not spun_elsewhere:
            # a script's node that nobody spins (rclpy.spin_once leaves node.executor set after it returns):
            # spin it here, with one executor per node for all its clients
            if executor is None or executor not in _SCRIPT_EXECUTORS:
                executor = SingleThreadedExecutor(context=node.context)
                _SCRIPT_EXECUTORS[executor] = threading.Lock()
                executor.add_node(node)
            spinning = _SCRIPT_EXECUTORS[executor]  # type: ignore[index]  # one of ours: a SingleThreadedExecutor
            while not predicate():
                if left() <= 0:
                    return False
                with spinning:
                    executor.spin_once(timeout_sec=max(0.0, left()))
            return True
        callback_threads = self._callback_threads.get(id(executor), set())
        if threading.get_ident() in callback_threads and not isinstance(executor, MultiThreadedExecutor):
            raise RuntimeError(
                "waiting here would block the executor that must deliver the answer: in a node "
                "spun by a SingleThreadedExecutor use RunHandle.add_done_callback, or wait "
                "from another thread"
            )
        with self._changed:
            while not predicate():
                if left() <= 0:
                    return False
                self._changed.wait(timeout=left())
        return True

    def _notify(self) -> None:
        executor = self._node.executor
        if executor is not None:
            self._callback_threads.setdefault(id(executor), set()).add(threading.get_ident())
        with self._changed:
            self._changed.notify_all()

    # -- what the planner says -------------------------------------------------------------------------

    def _on_event(self, msg: String) -> None:
        try:
            event = json.loads(msg.data)
        except ValueError:
            return
        if not isinstance(event, dict):
            return
        kind, run_id = event.get("event"), event.get("run_id")
        if not isinstance(run_id, str):
            return
        stamp = event.get("goal_stamp_ns")
        with self._lock:
            handle = self._pending.pop(stamp, None) if isinstance(stamp, int) else None
            if handle is not None:
                self._runs[run_id] = handle
            else:
                handle = self._runs.get(run_id)
        if handle is not None:
            if kind == "accepted":
                handle.mark_accepted(run_id)
                handle.recording = (event.get("recording_path"), str(event.get("recording", "")))
                if handle.cancel_requested:  # asked before the planner answered: its run is this one now
                    self._cancel.call_async(Trigger.Request())
            elif kind in _OUTCOME_EVENTS:
                if handle.run_id is None:
                    handle.mark_accepted(run_id)  # refused: the refusal has its own run id
                self._finish(handle, event)
        self._notify()

    def _finish(self, handle: RunHandle, event: dict[str, Any]) -> None:
        code = event.get("code")
        outcome = Outcome[code] if isinstance(code, str) and code in Outcome.__members__ else Outcome.INTERNAL_ERROR
        path, note = handle.recording
        result = RunResult(
            run_id=str(event.get("run_id")),
            outcome=outcome,
            message=str(event.get("message", "")),
            landmarks=int(event.get("landmarks") or 0),
            time_s=float(event.get("time_s") or 0.0),
            recording=path,
            recording_note=note,
        )
        if outcome is Outcome.SUCCEEDED:
            handle.outcome_fields = event
            handle.outcome_event = result  # completed when its trajectory is here
            self._complete_success(handle)
        else:
            handle.finish(result)

    def _complete_success(self, handle: RunHandle) -> None:
        """Finish a success once its trajectory and a world are here (called again as either arrives)."""
        result = handle.outcome_event
        if result is None or handle.done():
            return
        trajectory = self._trajectory_of(handle)
        if trajectory is None:
            return
        kind, parameters = self._kind(), self._world_parameters()
        if kind is None or parameters is None:
            return
        try:
            plan = kind.plan_from_trajectory(parameters, trajectory, handle.outcome_fields, result.message)
            if plan is None:
                return
        except (
            ValueError,
            IndexError,
            KeyError,
            TypeError,
        ) as error:  # the world changed under the run (another joint count)
            handle.finish(
                dataclasses.replace(
                    result, outcome=Outcome.INTERNAL_ERROR, message=f"the client cannot rebuild the plan: {error}"
                )
            )
            return
        handle.finish(dataclasses.replace(result, plan=plan, trajectory=trajectory))

    def _trajectory_of(self, handle: RunHandle) -> JointTrajectory | None:
        """The run's ``~/trajectory``: the oldest one stamped at or after the run's acceptance (both stamps are
        the planner's clock; the trajectory is stamped when its playback starts, after the outcome)."""
        accepted = handle.accepted_stamp_ns
        if accepted is None:
            return None
        with self._lock:
            later = [t for t in self._trajectories if t.header.stamp.sec * 10**9 + t.header.stamp.nanosec >= accepted]
        return later[0] if later else None

    def _world_parameters(self) -> dict[str, Any] | None:
        """The planner's parameters as its ``~/world_yaml`` says (``None``: not seen yet)."""
        if self._world_text is None:
            return None
        try:
            parameters = next(iter(yaml.safe_load(self._world_text).values()))["ros__parameters"]
        except (yaml.YAMLError, AttributeError, KeyError, StopIteration, TypeError):
            return None
        return parameters if isinstance(parameters, dict) else None

    def _kind(self) -> WorldKind | None:
        """The kind of the planner's world, as its ``~/world_yaml`` says (``None``: not seen yet, or unknown)."""
        parameters = self._world_parameters()
        if parameters is None:
            return None
        try:
            return kind_of_parameters(parameters)
        except ClewError:
            return None

    def _on_status(self, msg: GoalStatusArray) -> None:
        self._status_seen = True
        with self._lock:
            runs = dict(self._runs)
        for entry in msg.status_list:
            handle = runs.get(bytes(entry.goal_info.goal_id.uuid).hex())
            if handle is None:
                continue
            if handle.accepted_stamp_ns is None:
                handle.accepted_stamp_ns = entry.goal_info.stamp.sec * 10**9 + entry.goal_info.stamp.nanosec
                self._complete_success(handle)
            if entry.status in _STATUS:
                handle.update_status(_STATUS[entry.status])
        self._notify()

    def _on_feedback(self, msg: DiagnosticStatus) -> None:
        values = {kv.key: kv.value for kv in msg.values}
        with self._lock:
            handle = self._runs.get(values.get("run_id", ""))
        if handle is not None:
            try:
                feedback = Feedback(
                    values.get("phase", msg.message),
                    int(values.get("landmarks", "0")),
                    float(values.get("best_distance", "inf")),
                    float(values.get("elapsed", "0")),
                )
            except ValueError:
                return
            if feedback.phase == "planning":
                handle.update_status(RunStatus.EXECUTING)
            handle.update_feedback(feedback)
        self._notify()

    def _on_trajectory(self, msg: JointTrajectory) -> None:
        with self._lock:
            self._trajectories = [*self._trajectories[-7:], msg]
            waiting = [h for h in self._runs.values() if h.outcome_event is not None and not h.done()]
        for handle in waiting:
            self._complete_success(handle)
        self._notify()

    def _on_world_yaml(self, msg: String) -> None:
        self._world_text = msg.data
        with self._lock:
            waiting = [h for h in self._runs.values() if h.outcome_event is not None and not h.done()]
        for handle in waiting:
            self._complete_success(handle)
        self._notify()

    def cancel(self, handle: RunHandle) -> None:
        """Ask the planner to cancel ``handle``'s run (``~/cancel`` cancels its current run, which is this one
        while it is not done); :meth:`RunHandle.cancel` calls it."""
        if handle.run_id is None:  # not answered yet: cancel it once its run is known to be this one
            handle.cancel_requested = True
            return
        self._cancel.call_async(Trigger.Request())
