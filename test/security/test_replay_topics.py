"""clew_replay publishes under /replay by default; the recorded (live) names only with --live-topics; the
recorded goal_pose never unless --include-goal."""

from __future__ import annotations

import os
import subprocess
import sys
import time
from pathlib import Path

import pytest

rclpy = pytest.importorskip("rclpy")

from geometry_msgs.msg import PoseStamped  # noqa: E402
from rclpy.executors import SingleThreadedExecutor  # noqa: E402
from std_msgs.msg import String  # noqa: E402

from clew_ros.cli.replay import main as clew_replay  # noqa: E402
from clew_ros.recording import RunRecorder  # noqa: E402

T0_NS = 1_700_000_000_000_000_000
EVENTS = "/clew_planner/events"
GOAL = "/clew_planner/goal_pose"


@pytest.fixture(scope="module")
def recording(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Five events and, between them, a goal the planner was sent."""
    recorder = RunRecorder(tmp_path_factory.mktemp("replay"), "a" * 32)
    for i in range(5):
        recorder.write(EVENTS, String(data=f"event {i}"), T0_NS + i * 20_000_000)
    goal = PoseStamped()
    goal.header.frame_id = "world"
    goal.pose.position.x = 0.5
    recorder.write(GOAL, goal, T0_NS + 10_000_000)
    return recorder.close()


def _dry_run(capsys: pytest.CaptureFixture[str], *argv: str) -> tuple[int, str, str]:
    code = clew_replay([*argv, "--dry-run"])
    captured = capsys.readouterr()
    return code, captured.out, captured.err


def test_default_is_under_replay_without_the_goal(recording: Path, capsys: pytest.CaptureFixture[str]) -> None:
    code, out, _ = _dry_run(capsys, str(recording))
    assert code == 0
    assert f"{EVENTS} -> /replay{EVENTS}" in out
    assert "goal_pose" not in out
    assert "would play 5 messages" in out


def test_live_topics_and_the_goal_only_when_asked(recording: Path, capsys: pytest.CaptureFixture[str]) -> None:
    code, out, _ = _dry_run(capsys, str(recording), "--live-topics")
    assert code == 0
    assert f"{EVENTS} -> {EVENTS}" in out
    assert "goal_pose" not in out
    code, out, _ = _dry_run(capsys, str(recording), "--include-goal")
    assert code == 0
    assert f"{GOAL} -> /replay{GOAL}" in out
    assert "would play 6 messages" in out
    code, out, _ = _dry_run(capsys, str(recording), "--prefix", "/mine")
    assert f"{EVENTS} -> /mine{EVENTS}" in out


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--live-topics", "--prefix", "/x"], "--live-topics and --prefix: give one of them"),
        (["--prefix", ""], "--prefix: expected a namespace such as /replay"),
        (["--prefix", "/"], "--prefix: expected a namespace such as /replay"),
        (["--topics", GOAL], "add --include-goal to play it"),
    ],
)
def test_refusals(recording: Path, capsys: pytest.CaptureFixture[str], argv: list[str], message: str) -> None:
    code, _, err = _dry_run(capsys, str(recording), *argv)
    assert code == 2
    assert len(err.splitlines()) == 1
    assert message in err


@pytest.mark.ros
def test_a_replay_reaches_replay_topics_and_not_the_live_ones(recording: Path, tmp_path: Path) -> None:
    context = rclpy.Context()
    rclpy.init(context=context)
    node = rclpy.create_node("replay_security_listener", context=context)
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(node)
    got: dict[str, list[object]] = {name: [] for name in (EVENTS, f"/replay{EVENTS}", GOAL, f"/replay{GOAL}")}
    for name in (EVENTS, f"/replay{EVENTS}"):
        node.create_subscription(String, name, got[name].append, 10)
    for name in (GOAL, f"/replay{GOAL}"):
        node.create_subscription(PoseStamped, name, got[name].append, 10)
    log = tmp_path / "replay.log"
    try:
        with log.open("wb") as out:
            process = subprocess.Popen(
                [sys.executable, "-m", "clew_ros.cli.replay", str(recording), "--delay", "0",
                 "--wait-for-subscribers", "20"],
                stdout=out, stderr=subprocess.STDOUT, env=os.environ.copy(),
            )  # fmt: skip
            deadline = time.monotonic() + 60
            while time.monotonic() < deadline and (len(got[f"/replay{EVENTS}"]) < 5 or process.poll() is None):
                executor.spin_once(timeout_sec=0.01)
            end = time.monotonic() + 0.5  # anything late on the live names would arrive now
            while time.monotonic() < end:
                executor.spin_once(timeout_sec=0.01)
            code = process.wait(timeout=30)
    finally:
        executor.shutdown()
        node.destroy_node()
        rclpy.shutdown(context=context)
    output = log.read_text(errors="replace")
    assert code == 0, output
    assert [m.data for m in got[f"/replay{EVENTS}"]] == [f"event {i}" for i in range(5)], output  # type: ignore[attr-defined]
    assert got[EVENTS] == []
    assert got[GOAL] == []
    assert got[f"/replay{GOAL}"] == []
