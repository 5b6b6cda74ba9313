"""clew_ros.client against real planners in other processes, driven through the client only.

Two planners run at once in their own namespaces: ``quick`` (plans in well
under a second) and ``walled`` (a wall hides its goal from the arm: it plans
until canceled or out of time). Every outcome the node can give is asked
for and told apart by code; so are "no planner", "busy" and "timed out".
(``START_IN_COLLISION`` cannot reach a running node: it refuses such a world
as a parameter; ``INTERNAL_ERROR`` is a planner bug, tested in-process in
test/node/test_worker.py.)
"""

from __future__ import annotations

import dataclasses
import subprocess
import sys
import threading
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest

rclpy = pytest.importorskip("rclpy")

from helpers.node_harness import HAVE_RECORDER, NodeProcess, wait_until  # noqa: E402
from rclpy.callback_groups import MutuallyExclusiveCallbackGroup  # noqa: E402
from rclpy.executors import MultiThreadedExecutor, SingleThreadedExecutor  # noqa: E402

from clew_ros.client import (  # noqa: E402
    PlannerClient,
    PlannerNotFoundError,
    RunHandle,
    RunResult,
    RunStatus,
    RunTimeoutError,
)
from clew_ros.core.settings import Outcome  # noqa: E402
from clew_ros.planar.plan import validate_plan  # noqa: E402
from clew_ros.planar.world import load_world  # noqa: E402

pytestmark = pytest.mark.ros

WORLDS = Path(__file__).parents[1] / "worlds"
QUICK_GOAL = (0.6, 1.1, 0.0)
RESULT_TIMEOUT_S = 60.0


@dataclasses.dataclass
class Planner:
    process: NodeProcess
    client: PlannerClient
    records: Path


@pytest.fixture(scope="module")
def node() -> Iterator[rclpy.node.Node]:
    context = rclpy.Context()
    rclpy.init(context=context)
    client_node = rclpy.create_node("clew_client_test", context=context)
    try:
        yield client_node
    finally:
        client_node.destroy_node()
        rclpy.try_shutdown(context=context)


def _start(tmp: Path, name: str, world: str, node, **parameters) -> Iterator[Planner]:
    records = tmp / f"{name}_recordings"
    process = NodeProcess(tmp / f"{name}.log", WORLDS / world, {"record.directory": str(records), **parameters})
    client = PlannerClient(node, process.name)
    try:
        client.wait_for_planner(timeout_s=60.0)
        yield Planner(process, client, records)
    finally:
        client.destroy()
        code = process.stop()
        assert code == 0, f"{name} exit code {code}; output:\n{process.output()}"


@pytest.fixture(scope="module")
def quick(tmp_path_factory, node) -> Iterator[Planner]:
    yield from _start(tmp_path_factory.mktemp("quick"), "quick", "node_quick.yaml", node)


@pytest.fixture(scope="module")
def walled(tmp_path_factory, node) -> Iterator[Planner]:
    yield from _start(
        tmp_path_factory.mktemp("walled"), "walled", "node_behind_wall.yaml", node, **{"planner.time_limit": 4.0}
    )


def test_a_goal_is_planned_and_the_result_is_typed(quick: Planner) -> None:
    seen: list[str] = []
    handle = quick.client.send_goal(QUICK_GOAL, on_feedback=lambda _h, feedback: seen.append(feedback.phase))
    assert handle.status is RunStatus.SENT
    assert handle.goal == QUICK_GOAL
    result = handle.wait(RESULT_TIMEOUT_S, playback=True)
    assert result.outcome is Outcome.SUCCEEDED
    assert result.succeeded
    assert handle.status is RunStatus.SUCCEEDED
    assert handle.run_id == result.run_id
    assert len(result.run_id) == 32
    world = load_world(WORLDS / "node_quick.yaml")
    goal_world = dataclasses.replace(world, object=dataclasses.replace(world.object, goal=np.array(QUICK_GOAL)))
    assert result.plan is not None
    assert validate_plan(goal_world, result.plan) == []
    assert result.trajectory is not None
    assert len(result.trajectory.points) >= 2
    assert result.landmarks >= 2
    assert result.time_s > 0
    assert "SUCCEEDED" in seen
    assert handle.playback == "playback_done"
    if HAVE_RECORDER:
        assert result.recording == str(quick.records / result.run_id)
        assert Path(result.recording).is_dir()
    # the planner's own goal (its world.object.goal parameter)
    default = quick.client.plan(timeout_s=RESULT_TIMEOUT_S)
    assert default.outcome is Outcome.SUCCEEDED
    assert default.run_id != result.run_id


@pytest.mark.parametrize(
    ("goal", "outcome"),
    [
        ((5.0, 0.0, 0.0), Outcome.INVALID_WORLD),  # outside world.bounds: refused before planning
        ((1.95, 0.0, 0.0), Outcome.GOAL_IN_COLLISION),  # the object would stick out of the bounds
        ((1.85, 1.0, 0.0), Outcome.GOAL_OUT_OF_REACH),
    ],
)
def test_hopeless_goals_end_with_their_own_code(quick: Planner, goal, outcome) -> None:
    result = quick.client.send_goal(goal).wait(RESULT_TIMEOUT_S)
    assert result.outcome is outcome
    assert not result.succeeded
    assert result.plan is None
    assert result.message


@pytest.fixture(scope="module")
def coarse(tmp_path_factory, node) -> Iterator[Planner]:
    """The walled world at the coarsest resolution: EXPLORE's first landmark is already too close."""
    yield from _start(
        tmp_path_factory.mktemp("coarse"), "coarse", "node_behind_wall.yaml", node, **{"planner.resolution": 10.0}
    )


def test_no_path_at_resolution_is_its_own_code(coarse: Planner) -> None:
    result = coarse.client.send_goal().wait(RESULT_TIMEOUT_S)
    assert result.outcome is Outcome.NO_PATH_AT_RESOLUTION
    assert result.plan is None


def test_busy_cancel_time_limit_and_timeout_on_a_planner_that_keeps_planning(walled: Planner) -> None:
    client = walled.client
    first = client.send_goal()
    assert client.wait_until(lambda: first.status is RunStatus.EXECUTING, 30.0)
    with pytest.raises(RunTimeoutError):
        first.wait(timeout_s=0.2)
    busy = client.send_goal().wait(RESULT_TIMEOUT_S)
    assert busy.outcome is Outcome.BUSY
    assert busy.run_id != first.run_id
    assert first.cancel()
    canceled = first.wait(RESULT_TIMEOUT_S)
    assert canceled.outcome is Outcome.CANCELED
    assert first.status is RunStatus.CANCELED
    assert not first.cancel()  # over: nothing to cancel
    limited = client.send_goal().wait(RESULT_TIMEOUT_S)
    assert limited.outcome is Outcome.TIME_LIMIT
    assert limited.plan is None


def test_two_planners_are_followed_at_once(quick: Planner, walled: Planner) -> None:
    long = walled.client.send_goal()
    short = quick.client.send_goal(QUICK_GOAL)
    assert short.wait(RESULT_TIMEOUT_S).outcome is Outcome.SUCCEEDED
    assert not long.done()  # the walled planner is still at work (its limit is 4 s)
    assert long.wait(RESULT_TIMEOUT_S).outcome is Outcome.TIME_LIMIT
    assert short.run_id != long.run_id


def test_no_planner_is_told_apart(node) -> None:
    client = PlannerClient(node, "/nobody/clew_planner")
    try:
        assert not client.planner_ready()
        with pytest.raises(PlannerNotFoundError):
            client.wait_for_planner(timeout_s=0.5)
        with pytest.raises(PlannerNotFoundError):
            client.send_goal(QUICK_GOAL)
    finally:
        client.destroy()


def _in_own_node(quick: Planner, executor_type, body) -> None:
    """Run ``body(node, client, done)`` in a node of its own, spun by ``executor_type`` in a thread."""
    context = rclpy.Context()
    rclpy.init(context=context)
    node = rclpy.create_node("clew_client_in_a_node", context=context)
    executor = executor_type(context=context)
    executor.add_node(node)
    thread = threading.Thread(target=executor.spin, daemon=True)
    thread.start()
    client = PlannerClient(node, quick.process.name)
    try:
        wait_until(client.planner_ready, 60.0, "the planner seen from the node")
        body(node, client)
    finally:
        client.destroy()
        executor.shutdown()
        thread.join(timeout=10.0)
        node.destroy_node()
        rclpy.try_shutdown(context=context)


def test_inside_a_node_with_a_single_threaded_executor(quick: Planner) -> None:
    """Callbacks only: send from a timer, hear the result in a done callback; wait() refuses to deadlock."""
    results: list[RunResult] = []
    refused: list[str] = []

    def body(node, client) -> None:
        def on_done(handle: RunHandle) -> None:
            try:
                handle.wait(timeout_s=1.0)
            except RuntimeError as error:  # waiting in the executor's own thread would never end
                refused.append(str(error))
            results.append(handle.result)

        def on_timer() -> None:
            timer.cancel()
            client.send_goal(QUICK_GOAL).add_done_callback(on_done)

        timer = node.create_timer(0.05, on_timer)
        wait_until(lambda: results, RESULT_TIMEOUT_S, "the result in the done callback")

    _in_own_node(quick, SingleThreadedExecutor, body)
    assert results[0].outcome is Outcome.SUCCEEDED
    assert refused
    assert "SingleThreadedExecutor" in refused[0]


def test_inside_a_node_with_a_multi_threaded_executor(quick: Planner) -> None:
    """A callback may wait for the result: the client's subscriptions run on the executor's other threads."""
    results: list[RunResult] = []

    def body(node, client) -> None:
        def on_timer() -> None:
            timer.cancel()
            results.append(client.send_goal(QUICK_GOAL).wait(RESULT_TIMEOUT_S))

        timer = node.create_timer(0.05, on_timer, callback_group=MutuallyExclusiveCallbackGroup())
        wait_until(lambda: results, RESULT_TIMEOUT_S, "the result waited for in a callback")

    _in_own_node(quick, MultiThreadedExecutor, body)
    assert results[0].outcome is Outcome.SUCCEEDED
    assert results[0].plan is not None


def test_the_examples_run_against_a_real_planner(quick: Planner) -> None:
    follower = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "clew_ros.examples.trajectory_follower",
            "--planner",
            quick.process.name,
            "--count",
            "1",
            "--rate",
            "100",
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
    )
    printed: list[str] = []
    reader = threading.Thread(target=lambda: printed.extend(follower.stdout), daemon=True)
    reader.start()
    try:
        wait_until(lambda: any(line.startswith("following ") for line in printed), 60.0, "the follower ready")
        sequence = subprocess.run(
            [
                sys.executable,
                "-m",
                "clew_ros.examples.goal_sequence",
                "--planner",
                quick.process.name,
                "0.6,1.1,0.0",
                "5.0,0.0,0.0",
            ],
            capture_output=True,
            text=True,
            timeout=120,
        )
        lines = [line for line in sequence.stdout.splitlines() if line.startswith("goal ")]
        assert len(lines) == 2, sequence.stdout + sequence.stderr
        assert lines[0].startswith("goal 1/2 (0.6, 1.1, 0.0): SUCCEEDED, ")
        assert "grasps" in lines[0]
        assert lines[1].startswith("goal 2/2 (5.0, 0.0, 0.0): INVALID_WORLD")
        assert sequence.returncode == 1  # not every goal was planned
        assert follower.wait(timeout=60) == 0
        reader.join(timeout=10)
    finally:
        if follower.poll() is None:
            follower.kill()
            follower.wait()
    followed = [line for line in printed if line.startswith("followed ")]
    assert len(followed) == 1, printed
    assert "points over" in followed[0], printed
