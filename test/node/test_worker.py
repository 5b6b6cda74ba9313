"""A run's worker, in process: a fault in it ends the run INTERNAL_ERROR, recorded, and the node serves on."""

from __future__ import annotations

import importlib.util
import threading
from pathlib import Path

import pytest

rclpy = pytest.importorskip("rclpy")

from action_msgs.msg import GoalStatus  # noqa: E402

from clew_ros.core.settings import Outcome  # noqa: E402
from clew_ros.kinds import planar as planar_kind  # noqa: E402  (the planner the planar kind runs)
from clew_ros.node.run import Phase  # noqa: E402
from clew_ros.planar.world import read_parameter_file  # noqa: E402
from clew_ros.ros.parameters import flatten  # noqa: E402

pytestmark = pytest.mark.ros

FAST_WORLD = Path(__file__).parents[1] / "worlds" / "rel_fast.yaml"
#: The node records only where mcap is installed.
HAVE_RECORDER = importlib.util.find_spec("mcap") is not None


@pytest.fixture
def node(tmp_path: Path):
    """A PlannerNode in this process (own context, no executor), recording to ``tmp_path / "recordings"``."""
    from rclpy.parameter import Parameter

    from clew_ros.node.planner_node import PlannerNode

    context = rclpy.Context()
    rclpy.init(context=context)
    values = flatten(read_parameter_file(FAST_WORLD))
    values.update(
        {
            "record.directory": str(tmp_path / "recordings"),
            "trajectory.max_velocity": 50.0,
            "trajectory.max_acceleration": 1000.0,
        }
    )
    node = PlannerNode(
        context=context,
        parameter_overrides=[Parameter(k, value=v) for k, v in values.items()],
        namespace=f"/worker{id(tmp_path) % 10**6}",
    )
    try:
        yield node
    finally:
        node.shutdown_runs()
        node.destroy_node()
        context.try_shutdown()


def test_a_planner_fault_ends_the_run_internal_error(node, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    def broken_plan(*args: object, **kwargs: object) -> None:
        raise RuntimeError("injected")

    monkeypatch.setattr(planar_kind, "plan", broken_plan)
    run, refusal = node.request_plan("plan")
    assert run is not None, refusal
    assert run.wait_outcome(10.0)
    assert run.outcome is Outcome.INTERNAL_ERROR
    assert run.message == "internal error in the node: RuntimeError('injected')"
    assert run.status == GoalStatus.STATUS_ABORTED
    assert run.wait_finished(5.0)
    assert run.phase is Phase.FINISHED
    assert node.current_run is run
    if HAVE_RECORDER:
        assert (tmp_path / "recordings" / run.hex / "metadata.yaml").is_file()

    monkeypatch.undo()  # the node serves on
    following, refusal = node.request_plan("plan")
    assert following is not None, refusal
    assert following.wait_outcome(20.0)
    assert following.outcome is Outcome.SUCCEEDED, following.message
    assert following.wait_finished(10.0)


def test_requests_while_a_run_plans_are_refused_busy(node, monkeypatch: pytest.MonkeyPatch) -> None:
    release = threading.Event()
    real_plan = planar_kind.plan

    def held_plan(*args: object, **kwargs: object):  # planning until released
        release.wait(10.0)
        return real_plan(*args, **kwargs)

    monkeypatch.setattr(planar_kind, "plan", held_plan)
    run, refusal = node.request_plan("plan")
    assert run is not None, refusal
    second, refusal = node.request_plan("goal_pose", run.goal)
    assert second is None
    assert f": BUSY: refused: run {run.hex} is still planning" in refusal
    release.set()
    assert run.wait_outcome(20.0)
    assert run.outcome is Outcome.SUCCEEDED, run.message
