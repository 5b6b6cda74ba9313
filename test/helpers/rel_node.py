"""Helpers of the reliability tests that talk to a running ``clew_planner``.

Built on :mod:`node_harness` (the node in a subprocess, a client here):

- :func:`parameter_msg` turns a plain Python value into an
  ``rcl_interfaces/Parameter`` (the ROS type is picked from the value, as
  ``ros2 param set`` does), so tests can send any value, bad ones included;
- :func:`set_parameters` calls ``~/set_parameters`` (or the atomic variant);
- :class:`ProcessStats` reads thread count, open files and RSS from ``/proc``;
- :func:`received_at` / :func:`status_is` time when a message arrived, so
  latencies are measured from receive times, not from polling loops;
- :func:`new_events` reads the JSON events that arrived after a mark.
"""

from __future__ import annotations

import json
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from action_msgs.msg import GoalStatusArray
from rcl_interfaces.msg import Parameter as ParameterMsg
from rcl_interfaces.msg import ParameterType, ParameterValue
from rcl_interfaces.srv import GetParameters, SetParameters, SetParametersAtomically

__all__ = [
    "ProcessStats",
    "get_parameters",
    "new_events",
    "parameter_msg",
    "received_at",
    "set_parameters",
    "settled_stats",
    "status_is",
    "wait_event",
]

INT64_MAX = 2**63 - 1


def parameter_value(value: Any) -> ParameterValue:
    """A ``ParameterValue`` for ``value`` (``None``: NOT_SET); lists take the type of their items."""
    if value is None:
        return ParameterValue(type=ParameterType.PARAMETER_NOT_SET)
    if isinstance(value, bool):
        return ParameterValue(type=ParameterType.PARAMETER_BOOL, bool_value=value)
    if isinstance(value, int):
        return ParameterValue(type=ParameterType.PARAMETER_INTEGER, integer_value=value)
    if isinstance(value, float):
        return ParameterValue(type=ParameterType.PARAMETER_DOUBLE, double_value=value)
    if isinstance(value, str):
        return ParameterValue(type=ParameterType.PARAMETER_STRING, string_value=value)
    if isinstance(value, (bytes, bytearray)):
        return ParameterValue(type=ParameterType.PARAMETER_BYTE_ARRAY, byte_array_value=[bytes([b]) for b in value])
    if isinstance(value, (list, tuple)):
        items = list(value)
        if items and all(isinstance(v, bool) for v in items):
            return ParameterValue(type=ParameterType.PARAMETER_BOOL_ARRAY, bool_array_value=items)
        if items and all(isinstance(v, int) and not isinstance(v, bool) for v in items):
            return ParameterValue(type=ParameterType.PARAMETER_INTEGER_ARRAY, integer_array_value=items)
        if items and all(isinstance(v, str) for v in items):
            return ParameterValue(type=ParameterType.PARAMETER_STRING_ARRAY, string_array_value=items)
        return ParameterValue(type=ParameterType.PARAMETER_DOUBLE_ARRAY, double_array_value=[float(v) for v in items])
    raise TypeError(f"no parameter type for {value!r}")


def parameter_msg(name: str, value: Any) -> ParameterMsg:
    return ParameterMsg(name=name, value=parameter_value(value))


def set_parameters(
    session: Any, values: dict[str, Any], *, atomically: bool = False, timeout_s: float = 10.0
) -> list[Any]:
    """Set ``values`` on the session's node; returns the ``SetParametersResult`` list (one for atomic)."""
    parameters = [parameter_msg(name, value) for name, value in values.items()]
    if atomically:
        request = SetParametersAtomically.Request(parameters=parameters)
        return [
            session.client.call(
                session.srv("set_parameters_atomically"), SetParametersAtomically, request, timeout_s=timeout_s
            ).result
        ]
    request = SetParameters.Request(parameters=parameters)
    return list(session.client.call(session.srv("set_parameters"), SetParameters, request, timeout_s=timeout_s).results)


def _plain(value: ParameterValue) -> Any:
    kind = value.type
    if kind == ParameterType.PARAMETER_BOOL:
        return value.bool_value
    if kind == ParameterType.PARAMETER_INTEGER:
        return value.integer_value
    if kind == ParameterType.PARAMETER_DOUBLE:
        return value.double_value
    if kind == ParameterType.PARAMETER_STRING:
        return value.string_value
    if kind == ParameterType.PARAMETER_DOUBLE_ARRAY:
        return list(value.double_array_value)
    if kind == ParameterType.PARAMETER_INTEGER_ARRAY:
        return list(value.integer_array_value)
    if kind == ParameterType.PARAMETER_STRING_ARRAY:
        return list(value.string_array_value)
    if kind == ParameterType.PARAMETER_BOOL_ARRAY:
        return list(value.bool_array_value)
    return None


def get_parameters(session: Any, names: list[str], timeout_s: float = 10.0) -> dict[str, Any]:
    response = session.client.call(
        session.srv("get_parameters"), GetParameters, GetParameters.Request(names=names), timeout_s=timeout_s
    )
    return {name: _plain(value) for name, value in zip(names, response.values, strict=True)}


@dataclass(frozen=True)
class ProcessStats:
    """One sample of a process: threads (``/proc/<pid>/task``), open fds, resident memory (KiB)."""

    threads: int
    fds: int
    rss_kib: int

    @classmethod
    def of(cls, pid: int) -> ProcessStats:
        rss = 0
        proc = Path(f"/proc/{pid}")
        with (proc / "status").open() as status:
            for line in status:
                if line.startswith("VmRSS:"):
                    rss = int(line.split()[1])
        return cls(len(list((proc / "task").iterdir())), len(list((proc / "fd").iterdir())), rss)


def settled_stats(pid: int, baseline: ProcessStats, timeout_s: float = 10.0) -> ProcessStats:
    """Sample until threads and fds are back at ``baseline`` (worker threads end after a run) or time out."""
    deadline = time.monotonic() + timeout_s
    while True:
        now = ProcessStats.of(pid)
        if (now.threads <= baseline.threads and now.fds <= baseline.fds) or time.monotonic() > deadline:
            return now
        time.sleep(0.05)


def received_at(inbox: Any, predicate: Callable[[Any], bool], timeout_s: float) -> float:
    """Monotonic receive time of the first message in ``inbox`` matching ``predicate`` (waits for it)."""
    msg = inbox.wait_for(predicate, timeout_s)
    for stamp, item in inbox.timed():
        if item is msg:
            return stamp
    raise AssertionError("message vanished from the inbox")


def status_is(run_id: str, status: int) -> Callable[[GoalStatusArray], bool]:
    """Predicate: a ``~/status`` message listing ``run_id`` with ``status``."""

    def predicate(msg: GoalStatusArray) -> bool:
        return any(bytes(e.goal_info.goal_id.uuid).hex() == run_id and e.status == status for e in msg.status_list)

    return predicate


def new_events(session: Any, mark: int) -> list[dict]:
    """The ``~/events`` (decoded) received after the first ``mark`` messages."""
    return [json.loads(m.data) for m in session.events.messages[mark:]]


def wait_event(
    session: Any, mark: int, predicate: Callable[[dict], bool], timeout_s: float = 10.0
) -> tuple[dict, float]:
    """The first event after ``mark`` matching ``predicate`` and its receive time."""

    def matches(msg: Any) -> bool:
        return predicate(json.loads(msg.data))

    deadline = time.monotonic() + timeout_s
    while True:
        timed = session.events.timed()[mark:]
        for stamp, msg in timed:
            if matches(msg):
                return json.loads(msg.data), stamp
        assert time.monotonic() < deadline, (
            f"no matching event within {timeout_s} s; got {[json.loads(m.data).get('event') for _, m in timed]}"
        )
        time.sleep(0.01)  # poll; the receive time comes from the inbox, not from this loop


def goal_publisher(session: Any, qos: Any = None, timeout_s: float = 20.0) -> Any:
    """A ``~/goal_pose`` publisher whose messages the node is known to receive (cached on the session).

    A fresh publisher may see its subscriber before the subscriber sees it; a message sent in that
    window is lost. So the first messages are probes (a goal in frame ``rel_probe``, refused at once)
    sent until the node answers one.
    """
    from geometry_msgs.msg import PoseStamped

    cache = session.__dict__.setdefault("_rel_goal_publishers", {})
    key = None if qos is None else qos.depth
    if key in cache:
        return cache[key]
    publisher = (
        session.client.publisher(f"{session.node.name}/goal_pose", PoseStamped)
        if qos is None
        else session.client.publisher(f"{session.node.name}/goal_pose", PoseStamped, qos)
    )
    probe = PoseStamped()
    probe.header.frame_id = "rel_probe"
    probe.pose.orientation.w = 1.0
    deadline = time.monotonic() + timeout_s
    while True:
        mark = len(session.events.messages)
        publisher.publish(probe)
        try:
            wait_event(session, mark, lambda e: "rel_probe" in str(e.get("message", "")), 1.0)
            break
        except AssertionError:
            assert time.monotonic() < deadline, "the node never answered a goal pose"
    cache[key] = publisher
    return publisher
