"""Four planners in one process (``clew_planners``), driven at once by four clients in this process.

The planners serve four worlds of ``config/`` in namespaces of their own:
three solvable ones and ``behind_wall``, whose planner keeps planning until
it is canceled. Each client is a node of its own (its own context), driven
from a thread of its own through :class:`clew_ros.client.PlannerClient`.
Round 1 sends the four goals together: the three solvable runs succeed
while the fourth still plans. Round 2 sends the three again and cancels
the fourth while they are under way: it ends ``CANCELED``, they succeed
again, with the same plans (same seed, same plan, whatever the others do).
Every stream (``~/status``, ``~/feedback``, ``~/events``) and every
recording of a planner holds its own runs only.
"""

from __future__ import annotations

import dataclasses
import json
import threading
import uuid
from collections.abc import Callable, Iterator
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest
import yaml

rclpy = pytest.importorskip("rclpy")

from action_msgs.msg import GoalStatusArray  # noqa: E402
from diagnostic_msgs.msg import DiagnosticStatus  # noqa: E402
from helpers.node_harness import (  # noqa: E402
    HAVE_RECORDER,
    LATCHED,
    Client,
    Inbox,
    PlannersProcess,
    kv,
    recorded_topics,
    wait_until,
)
from std_msgs.msg import String  # noqa: E402

from clew_ros.client import PlannerClient, RunHandle, RunResult, RunStatus  # noqa: E402
from clew_ros.core.settings import Outcome  # noqa: E402
from clew_ros.planar.plan import validate_plan  # noqa: E402
from clew_ros.planar.world import load_world  # noqa: E402

pytestmark = pytest.mark.ros

CONFIG = Path(__file__).resolve().parents[2] / "config"
#: namespace (under the test's own prefix) -> world file; "walled" never finds a plan.
WORLDS = {
    "figure1": "figure1.yaml",
    "arm3": "arm3_regrasp.yaml",
    "single": "single_transfer.yaml",
    "walled": "behind_wall.yaml",
}
SOLVABLE = ("figure1", "arm3", "single")
START_TIMEOUT_S = 90.0
RESULT_TIMEOUT_S = 120.0


@dataclasses.dataclass
class Graph:
    process: PlannersProcess
    prefix: str
    records: Path
    streams: Client
    status: dict[str, Inbox]
    feedback: dict[str, Inbox]
    events: dict[str, Inbox]

    def node_name(self, name: str) -> str:
        return f"{self.prefix}/{name}/clew_planner"


@pytest.fixture(scope="module")
def graph(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Graph]:
    tmp = tmp_path_factory.mktemp("many_planners")
    prefix = f"/t{uuid.uuid4().hex[:12]}"
    records = tmp / "records"
    # the command line's parameters win over the world files (behind_wall.yaml's limit is 5 s); a section
    # keyed with a node's full name reaches that node only
    walled_limit = tmp / "walled_limit.yaml"
    walled_limit.write_text(
        yaml.safe_dump({f"{prefix}/walled/clew_planner": {"ros__parameters": {"planner": {"time_limit": 90.0}}}})
    )
    process = PlannersProcess(
        tmp / "planners.log",
        {f"{prefix}/{name}": CONFIG / file for name, file in WORLDS.items()},
        [
            *("-p", f"record.directory:={records}"),
            *("-p", "planner.time_limit:=40.0"),
            # a quick playback, so that each run's recording is complete soon after its outcome
            *("-p", "trajectory.max_velocity:=30.0", "-p", "trajectory.max_acceleration:=300.0"),
            *("-p", "trajectory.grasp_dwell:=0.01"),
            *("--params-file", str(walled_limit)),
        ],
    )
    streams = Client("clew_many_planners_streams")
    names = {name: f"{prefix}/{name}/clew_planner" for name in WORLDS}
    graph = Graph(
        process,
        prefix,
        records,
        streams,
        status={name: streams.inbox(f"{node}/status", GoalStatusArray, LATCHED) for name, node in names.items()},
        feedback={name: streams.inbox(f"{node}/feedback", DiagnosticStatus) for name, node in names.items()},
        events={name: streams.inbox(f"{node}/events", String) for name, node in names.items()},
    )
    try:
        for name in WORLDS:
            try:
                graph.status[name].wait_for(timeout_s=START_TIMEOUT_S)  # latched: the planner is up and matched
            except AssertionError:
                pytest.fail(f"planner {name} did not come up; output:\n{process.output()}")
        yield graph
    finally:
        streams.close()
        code = process.stop()
        assert code == 0, f"clew_planners exit code {code}; output:\n{process.output()}"


class Driver:
    """One client: a node in a context of its own, following one planner through ``PlannerClient``."""

    def __init__(self, planner: str) -> None:
        self.context = rclpy.Context()
        rclpy.init(context=self.context)
        self.node = rclpy.create_node(f"clew_driver_{uuid.uuid4().hex[:8]}", context=self.context)
        self.client = PlannerClient(self.node, planner)

    def close(self) -> None:
        self.client.destroy()
        self.node.destroy_node()
        rclpy.try_shutdown(context=self.context)


@pytest.fixture(scope="module")
def drivers(graph: Graph) -> Iterator[dict[str, Driver]]:
    made = {name: Driver(graph.node_name(name)) for name in WORLDS}
    try:
        with ThreadPoolExecutor(len(made)) as pool:
            list(pool.map(lambda d: d.client.wait_for_planner(timeout_s=START_TIMEOUT_S), made.values()))
        yield made
    finally:
        for driver in made.values():
            driver.close()


def _at_once(drivers: dict[str, Driver], names: tuple[str, ...], body: Callable[[str, Driver], RunResult]) -> dict:
    """``body(name, driver)`` for each name, each in a thread of its own, started together."""
    start = threading.Barrier(len(names))

    def drive(name: str) -> RunResult:
        start.wait(timeout=30.0)
        return body(name, drivers[name])

    with ThreadPoolExecutor(len(names)) as pool:
        futures = {name: pool.submit(drive, name) for name in names}
        return {name: future.result(timeout=2 * RESULT_TIMEOUT_S) for name, future in futures.items()}


def _check_success(name: str, result: RunResult) -> None:
    world = load_world(CONFIG / WORLDS[name])
    assert result.outcome is Outcome.SUCCEEDED, f"{name}: {result.outcome.name} {result.message}"
    assert result.plan is not None
    assert result.plan.world == world.name  # the namespace's own world, not another planner's
    assert validate_plan(world, result.plan) == [], name


def _segments(result: RunResult) -> list[tuple[str, int | None, list[list[float]]]]:
    assert result.plan is not None
    return [(s.kind, s.grasp, s.waypoints.tolist()) for s in result.plan.segments]


def _own_run_ids(stream: Inbox, run_id_of: Callable[[object], list[str]]) -> set[str]:
    return {run_id for msg in stream.messages for run_id in run_id_of(msg)}


def _status_ids(msg: GoalStatusArray) -> list[str]:
    return [bytes(entry.goal_info.goal_id.uuid).hex() for entry in msg.status_list]


def test_four_planners_plan_at_once_and_a_cancel_stops_only_its_own(graph: Graph, drivers: dict[str, Driver]) -> None:
    handles: dict[str, list[RunHandle]] = {name: [] for name in WORLDS}

    # round 1: four goals together; the solvable three succeed while the walled planner still plans
    def first_round(name: str, driver: Driver) -> RunResult:
        handle = driver.client.send_goal()  # the planner's own goal: its world.object.goal parameter
        handles[name].append(handle)
        if name == "walled":
            assert driver.client.wait_until(lambda: handle.status is RunStatus.EXECUTING, RESULT_TIMEOUT_S)
            return RunResult(handle.run_id or "", Outcome.INTERNAL_ERROR, "still planning")
        return handle.wait(RESULT_TIMEOUT_S, playback=True)

    first = _at_once(drivers, tuple(WORLDS), first_round)
    for name in SOLVABLE:
        _check_success(name, first[name])
    walled = handles["walled"][0]
    assert not walled.done(), "the behind-wall world's planner stopped while the others planned"
    assert walled.status is RunStatus.EXECUTING

    # round 2: the three again, and the walled planner's run canceled once they are accepted
    accepted = threading.Barrier(len(SOLVABLE) + 1)

    def second_round(name: str, driver: Driver) -> RunResult:
        if name == "walled":
            accepted.wait(timeout=RESULT_TIMEOUT_S)
            assert walled.cancel()
            return walled.wait(RESULT_TIMEOUT_S)
        handle = driver.client.send_goal()
        handles[name].append(handle)
        assert driver.client.wait_until(lambda: handle.run_id is not None, RESULT_TIMEOUT_S)
        accepted.wait(timeout=RESULT_TIMEOUT_S)
        return handle.wait(RESULT_TIMEOUT_S, playback=True)

    second = _at_once(drivers, tuple(WORLDS), second_round)
    assert second["walled"].outcome is Outcome.CANCELED, second["walled"].message
    assert second["walled"].run_id == walled.run_id
    for name in SOLVABLE:
        _check_success(name, second[name])
        assert second[name].run_id != first[name].run_id
        # same seed, same plan: neither the other planners nor the cancel changed it
        assert _segments(second[name]) == _segments(first[name]), name

    run_ids = {name: {h.run_id for h in hs if h.run_id is not None} for name, hs in handles.items()}
    assert all(len(ids) == len(handles[name]) for name, ids in run_ids.items())
    every = set().union(*run_ids.values())
    assert len(every) == sum(len(ids) for ids in run_ids.values())  # no run id is shared

    # each planner's streams carry its own runs, and all of them
    for name, own in run_ids.items():
        for run_id in own:  # the outcome of each run is on its planner's ~/events and ~/feedback
            graph.events[name].wait_for(lambda m, r=run_id: json.loads(m.data).get("run_id") == r, RESULT_TIMEOUT_S)
            graph.feedback[name].wait_for(lambda m, r=run_id: kv(m).get("run_id") == r, RESULT_TIMEOUT_S)
        statuses = _own_run_ids(graph.status[name], _status_ids)
        feedback = _own_run_ids(graph.feedback[name], lambda m: [kv(m)["run_id"]])
        events = _own_run_ids(graph.events[name], lambda m: [json.loads(m.data)["run_id"]])
        assert own <= statuses
        for stream, seen in (("~/status", statuses), ("~/feedback", feedback), ("~/events", events)):
            strangers = seen & (every - own)
            assert not strangers, f"{name}'s {stream} carries runs of other planners: {strangers}"
            assert seen <= own, f"{name}'s {stream} carries runs it did not start: {seen - own}"

    # each planner records into <record.directory>/<its namespace>/<run id>/, with its own topics only
    if HAVE_RECORDER:
        results = [(name, result) for name, result in [*first.items(), *second.items()] if name != "walled"]
        results.append(("walled", second["walled"]))
        for name, result in results:
            directory = graph.records / graph.prefix.strip("/") / name / result.run_id
            assert result.recording == str(directory)
            # metadata.yaml is written when the recording closes, right after the playback's last feedback
            wait_until(lambda d=directory: (d / "metadata.yaml").is_file(), 10.0, f"{name}: recording closed")
            topics = recorded_topics(directory)
            own_topics = {t for t in topics if t.startswith(graph.node_name(name) + "/")}
            assert own_topics, f"{name}: nothing of its own recorded"
            assert topics - own_topics <= {"/tf", "/tf_static"}, f"{name} recorded {sorted(topics - own_topics)}"
