"""Test harness for ``clew_planner``: the node in a subprocess, a client here.

- :class:`NodeProcess` starts ``python -m clew_ros.node.main`` with a
  parameter file, ``-p`` overrides and a namespace of its own (so that no
  other node on the domain can answer in its place), and stops it by pid;
  :class:`PlannersProcess` starts ``clew_planners`` (several planners in one
  process) the same way.
- :class:`Client` is an rclpy node in its own context, spun by a background
  thread: services are called with a timeout and topics are collected into
  :class:`Inbox` es that tests wait on with conditions, never plain sleeps.
"""

from __future__ import annotations

import importlib.util
import json
import os
import re
import signal
import subprocess
import sys
import threading
import time
import uuid
from collections.abc import Callable
from pathlib import Path
from typing import Any

import rclpy
import yaml
from action_msgs.msg import GoalStatus, GoalStatusArray
from diagnostic_msgs.msg import DiagnosticStatus
from geometry_msgs.msg import PoseStamped
from rcl_interfaces.srv import GetParameters, SetParameters, SetParametersAtomically
from rclpy.executors import SingleThreadedExecutor
from rclpy.qos import QoSProfile
from sensor_msgs.msg import JointState
from std_msgs.msg import String
from std_srvs.srv import Trigger
from trajectory_msgs.msg import JointTrajectory
from visualization_msgs.msg import MarkerArray

from clew_ros.ros.qos import EVENTS_QOS, LATCHED_QOS

#: The node's own profiles (clew_ros.ros.qos): latched topics, and a deep reliable stream so that a test
#: reads every message.
LATCHED = LATCHED_QOS
STREAM = EVENTS_QOS

#: The services of a planner node that tests call, by name under the node, and their types.
NODE_SERVICES: dict[str, Any] = {
    "plan": Trigger,
    "cancel": Trigger,
    "set_parameters": SetParameters,
    "set_parameters_atomically": SetParametersAtomically,
    "get_parameters": GetParameters,
}
DISCOVERY_TIMEOUT_S = 20.0
PLAN_TIMEOUT_S = 30.0
RUN_ID = re.compile(r"run ([0-9a-f]{32})")
#: The node records runs (clew_ros.recording) only where the mcap package is installed (README: without
#: it the node plans but does not record); tests check recordings when it is.
HAVE_RECORDER = importlib.util.find_spec("mcap") is not None
EXIT_TIMEOUT_S = 10.0


class NodeProcess:
    """``clew_planner`` in a subprocess; output goes to ``log``."""

    def __init__(
        self,
        log: Path,
        params_file: Path | None = None,
        parameters: dict[str, Any] | None = None,
        namespace: str | None = None,
        env: dict[str, str] | None = None,
    ) -> None:
        self.namespace = namespace if namespace is not None else f"/t{uuid.uuid4().hex[:12]}"
        self.name = f"{self.namespace}/clew_planner" if self.namespace != "/" else "/clew_planner"
        command = [sys.executable, "-m", "clew_ros.node.main", "--ros-args", "-r", f"__ns:={self.namespace}"]
        if params_file is not None:
            if self.namespace != "/":
                params_file = _for_any_node(params_file, log.with_name(f"{log.stem}_params.yaml"))
            command += ["--params-file", str(params_file)]
        for key, value in (parameters or {}).items():
            command += ["-p", f"{key}:={_param_text(value)}"]
        self._start(command, log, env)

    def _start(self, command: list[str], log: Path, env: dict[str, str] | None) -> None:
        self.command = command
        self.log = log
        self._log_file = log.open("wb")
        self.proc = subprocess.Popen(
            command, stdout=self._log_file, stderr=subprocess.STDOUT, env={**os.environ, **(env or {})}
        )  # LOCALHOST discovery, ROS_DOMAIN_ID

    def output(self) -> str:
        if not self._log_file.closed:
            self._log_file.flush()
        return self.log.read_text(errors="replace")

    def stacks(self) -> str:
        """The node's log, after it printed where each of its threads is (if it is still running)."""
        if self.proc.poll() is None:
            before = len(self.output())
            self.proc.send_signal(signal.SIGUSR1)
            deadline = time.monotonic() + 2.0
            while "most recent call first" not in self.output()[before:] and time.monotonic() < deadline:
                time.sleep(0.05)
        return self.output()

    def stop(self, sig: int = signal.SIGINT, timeout_s: float = EXIT_TIMEOUT_S) -> int | None:
        """Send ``sig`` and wait; SIGKILL if it hangs. Returns the exit code (``None``: had to be killed)."""
        code: int | None
        if self.proc.poll() is None:
            self.proc.send_signal(sig)
            try:
                code = self.proc.wait(timeout=timeout_s)
            except subprocess.TimeoutExpired:
                self.stacks()  # into the log: where it hangs
                self.proc.kill()
                self.proc.wait()
                code = None
        else:
            code = self.proc.returncode
        if not self._log_file.closed:
            self._log_file.close()
        return code


class PlannersProcess(NodeProcess):
    """``clew_planners`` (``python -m clew_ros.node.multi``) in a subprocess: one planner per
    ``namespace -> world file`` of ``worlds``, with ``ros_args`` after ``--ros-args``."""

    def __init__(
        self, log: Path, worlds: dict[str, Path], ros_args: list[str], env: dict[str, str] | None = None
    ) -> None:
        self.names = {namespace: f"{namespace}/clew_planner" for namespace in worlds}
        pairs = [f"{namespace}:={path}" for namespace, path in worlds.items()]
        self._start([sys.executable, "-m", "clew_ros.node.multi", *pairs, "--ros-args", *ros_args], log, env)


def _for_any_node(params_file: Path, copy: Path) -> Path:
    """A copy of a ``clew_planner:`` parameter file keyed ``/**``: the key names the node with its
    namespace, so ``clew_planner`` matches only ``/clew_planner``."""
    document = yaml.safe_load(params_file.read_text())
    copy.write_text(yaml.safe_dump({"/**": next(iter(document.values()))}))
    return copy


def _param_text(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (list, tuple)):
        return "[" + ",".join(_param_text(v) for v in value) + "]"
    return str(value)


class Inbox:
    """Messages received on one topic, with their receive times (monotonic s)."""

    def __init__(self) -> None:
        self._items: list[tuple[float, Any]] = []
        self._condition = threading.Condition()

    def put(self, msg: Any) -> None:
        with self._condition:
            self._items.append((time.monotonic(), msg))
            self._condition.notify_all()

    @property
    def messages(self) -> list[Any]:
        with self._condition:
            return [m for _, m in self._items]

    def timed(self) -> list[tuple[float, Any]]:
        with self._condition:
            return list(self._items)

    def wait_for(self, predicate: Callable[[Any], bool] = lambda m: True, timeout_s: float = 10.0) -> Any:
        """The first message (old or new) matching ``predicate``; ``AssertionError`` after ``timeout_s``."""
        deadline = time.monotonic() + timeout_s
        with self._condition:
            while True:
                for _, msg in self._items:
                    if predicate(msg):
                        return msg
                remaining = deadline - time.monotonic()
                if remaining <= 0:
                    raise AssertionError(f"no matching message within {timeout_s} s ({len(self._items)} received)")
                self._condition.wait(remaining)


class Client:
    """A client node in its own context, spun in a background thread."""

    def __init__(self, name: str = "clew_test_client") -> None:
        self.context = rclpy.Context()
        rclpy.init(context=self.context)
        self.node = rclpy.create_node(f"{name}_{uuid.uuid4().hex[:8]}", context=self.context)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)
        self._thread = threading.Thread(target=self._spin, daemon=True)
        self._thread.start()

    def _spin(self) -> None:
        while self.context.ok():
            try:
                self.executor.spin_once(timeout_sec=0.05)
            except Exception:  # shutting down
                if not self.context.ok():
                    return
                raise

    def inbox(self, topic: str, msg_type: Any, qos: QoSProfile = STREAM) -> Inbox:
        box = Inbox()
        self.node.create_subscription(msg_type, topic, box.put, qos)
        return box

    def call(
        self,
        service: str,
        srv_type: Any,
        request: Any = None,
        *,
        timeout_s: float = 20.0,
        wait_service_s: float = DISCOVERY_TIMEOUT_S,
    ) -> Any:
        """Call ``service`` and return its response; ``AssertionError`` on timeout."""
        future = self.call_async(service, srv_type, request, wait_service_s=wait_service_s)
        return wait_future(future, timeout_s, f"{service} did not answer")

    def call_async(
        self, service: str, srv_type: Any, request: Any = None, *, wait_service_s: float = DISCOVERY_TIMEOUT_S
    ) -> Any:
        client = self._client(service, srv_type)
        assert client.wait_for_service(timeout_sec=wait_service_s), f"{service} not found in {wait_service_s} s"
        self._wait_server_matched(service, wait_service_s)
        return client.call_async(srv_type.Request() if request is None else request)

    def _wait_server_matched(self, service: str, timeout_s: float) -> None:
        """Wait until the node serving ``service`` has matched this client's response readers.

        ``wait_for_service`` only says that this side has matched the server; the server may not have matched
        the client's response reader yet, and a response it sends then is lost (rmw_fastrtps waits 100 ms for
        the match, then rclpy warns "failed to send response (timeout)"): on a loaded machine a quick ~/plan
        was never answered. A participant announces its endpoints in order over reliable discovery, so once
        the node's latched ``~/status`` reaches a reader created after the service clients, the node has
        matched their response readers too. Done once a node, for the clients of all its services that tests
        call (:data:`NODE_SERVICES`, created first), so that a timed call later pays nothing for it.
        """
        matched: set[str] = self.__dict__.setdefault("_matched", set())
        if service in matched:
            return
        node = service.rsplit("/", 1)[0]
        for name, srv_type in NODE_SERVICES.items():
            self._client(f"{node}/{name}", srv_type)
        covered = {f"{node}/{name}" for name in NODE_SERVICES} | {service}
        box = Inbox()
        # kept until the client closes (destroying it while the spin thread waits on it would gain nothing)
        probes = self.__dict__.setdefault("_probes", [])
        probes.append(self.node.create_subscription(GoalStatusArray, f"{node}/status", box.put, LATCHED))
        try:
            box.wait_for(timeout_s=timeout_s)
        except AssertionError as error:
            raise AssertionError(f"{service}: the node's latched ~/status did not arrive: {error}") from None
        matched |= covered

    def _client(self, service: str, srv_type: Any) -> Any:
        clients = self.__dict__.setdefault("_clients", {})
        if service not in clients:
            clients[service] = self.node.create_client(srv_type, service)
        return clients[service]

    def publisher(
        self, topic: str, msg_type: Any, qos: QoSProfile = STREAM, *, timeout_s: float = DISCOVERY_TIMEOUT_S
    ) -> Any:
        """A publisher that is matched with at least one subscriber."""
        publisher = self.node.create_publisher(msg_type, topic, qos)
        deadline = time.monotonic() + timeout_s
        while publisher.get_subscription_count() == 0:
            assert time.monotonic() < deadline, f"nobody subscribes to {topic} after {timeout_s} s"
            time.sleep(0.02)
        return publisher

    def close(self) -> None:
        self.context.try_shutdown()
        self._thread.join(timeout=5.0)
        self.executor.shutdown(timeout_sec=1.0)
        self.node.destroy_node()


def wait_future(future: Any, timeout_s: float, what: str) -> Any:
    done = threading.Event()
    future.add_done_callback(lambda _f: done.set())
    assert done.wait(timeout_s), f"{what} within {timeout_s} s"
    return future.result()


def wait_until(predicate: Callable[[], bool], timeout_s: float, what: str) -> None:
    deadline = time.monotonic() + timeout_s
    while not predicate():
        assert time.monotonic() < deadline, f"{what}: not within {timeout_s} s"
        time.sleep(0.02)


class Session:
    """One node and one client with inboxes on every topic of the node."""

    def __init__(self, node: NodeProcess) -> None:
        self.node = node
        self.client = Client()
        name = node.name
        self.status = self.client.inbox(f"{name}/status", GoalStatusArray, LATCHED)
        self.feedback = self.client.inbox(f"{name}/feedback", DiagnosticStatus)
        self.events = self.client.inbox(f"{name}/events", String)
        self.joint_states = self.client.inbox(f"{name}/joint_states", JointState)
        self.object_pose = self.client.inbox(f"{name}/object_pose", PoseStamped)
        self.trajectory = self.client.inbox(f"{name}/trajectory", JointTrajectory, LATCHED)
        self.world_markers = self.client.inbox(f"{name}/world_markers", MarkerArray, LATCHED)

    def srv(self, name: str) -> str:
        return f"{self.node.name}/{name}"

    def plan(self, timeout_s: float = PLAN_TIMEOUT_S) -> Trigger.Response:
        """Call ``~/plan``; a call it does not answer fails with the node's log, its threads' stacks last."""
        try:
            return self.client.call(self.srv("plan"), Trigger, timeout_s=timeout_s)
        except AssertionError as error:
            raise AssertionError(f"{error}\n--- the node's log ---\n{self.node.stacks()}") from None

    def events_of(self, run_id: str) -> list[dict]:
        return [e for e in (json.loads(m.data) for m in self.events.messages) if e["run_id"] == run_id]

    def status_of(self, run_id: str) -> int | None:
        """The run's status in the latest ~/status (None: not listed)."""
        for msg in reversed(self.status.messages):
            for entry in msg.status_list:
                if bytes(entry.goal_info.goal_id.uuid).hex() == run_id:
                    return entry.status
            return None
        return None

    def wait_status(self, run_id: str, status: int, timeout_s: float = 10.0) -> None:
        wait_until(
            lambda: self.status_of(run_id) == status,
            timeout_s,
            f"run {run_id} status {status} (now {self.status_of(run_id)})",
        )

    def wait_playback(self, run_id: str, timeout_s: float = 15.0) -> None:
        self.feedback.wait_for(
            lambda m: kv(m).get("run_id") == run_id and kv(m).get("phase") == "playback_done", timeout_s
        )

    def wait_idle(self, timeout_s: float = PLAN_TIMEOUT_S) -> None:
        """Wait until every run has an outcome and every playback has ended."""
        terminal = {GoalStatus.STATUS_SUCCEEDED, GoalStatus.STATUS_ABORTED, GoalStatus.STATUS_CANCELED}
        for event in [json.loads(m.data) for m in self.events.messages]:
            if event["event"] != "accepted":
                continue
            run_id = event["run_id"]
            wait_until(lambda run_id=run_id: self.status_of(run_id) in terminal, timeout_s, f"run {run_id} outcome")
            if self.status_of(run_id) == GoalStatus.STATUS_SUCCEEDED:
                self.feedback.wait_for(
                    lambda m, run_id=run_id: (
                        kv(m).get("run_id") == run_id and kv(m).get("phase", "").startswith("playback_")
                    ),
                    timeout_s,
                )

    def close(self) -> int | None:
        self.client.close()
        return self.node.stop()


def kv(msg: DiagnosticStatus) -> dict[str, str]:
    return {kv.key: kv.value for kv in msg.values}


def run_id_of(message: str) -> str:
    match = RUN_ID.search(message)
    assert match, f"no run id in {message!r}"
    return match.group(1)


def recorded_topics(directory: Path) -> set[str]:
    from mcap.reader import make_reader

    wait_until(lambda: len(list(directory.glob("*.mcap"))) == 1, 10.0, "one .mcap file")
    with next(directory.glob("*.mcap")).open("rb") as stream:
        summary = make_reader(stream).get_summary()
    return {channel.topic for channel in summary.channels.values()}
