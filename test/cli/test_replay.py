"""clew_replay in a subprocess, a subscriber here: order, timing scaled by --rate, latched QoS, clean stop."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
import uuid
from pathlib import Path

import numpy as np
import pytest

rclpy = pytest.importorskip("rclpy")

from rclpy.executors import SingleThreadedExecutor  # noqa: E402
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy  # noqa: E402
from std_msgs.msg import String  # noqa: E402
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint  # noqa: E402

from clew_ros.recording import RunRecorder  # noqa: E402

T0_NS = 1_700_000_000_000_000_000
GAP_S = 0.6
RATE = 2.0
#: Pacing is behaviour (the recorded gaps scaled by --rate), read on the wall clock: a third of the
#: replayed gap (0.3 s) still tells rate 2 from 1.5 or 3, and is more than a loaded 2-core machine
#: delays a DDS delivery by luck.
TOLERANCE_S = 0.1
TIMEOUT_S = 30.0


@pytest.fixture(scope="module")
def timed_recording(tmp_path_factory) -> Path:
    """A latched trajectory, then five events GAP_S apart."""
    recorder = RunRecorder(tmp_path_factory.mktemp("replay"), "timed")
    trajectory = JointTrajectory(
        joint_names=["joint_1", "joint_2", "gripper"], points=[JointTrajectoryPoint(positions=[0.0, 0.5, 0.0])]
    )
    recorder.write("/clew_planner/trajectory", trajectory, T0_NS)
    for i in range(5):
        recorder.write("/clew_planner/events", String(data=f"event {i}"), T0_NS + int(i * GAP_S * 1e9))
    return recorder.close()


class Listener:
    """A node in this process that timestamps what it receives."""

    def __init__(self, prefix: str) -> None:
        self.context = rclpy.Context()
        rclpy.init(context=self.context)
        self.node = rclpy.create_node("replay_listener", context=self.context)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)
        self.events: list[tuple[float, str]] = []
        self.trajectories: list[JointTrajectory] = []
        self.node.create_subscription(
            String, f"{prefix}/clew_planner/events", lambda m: self.events.append((time.monotonic(), m.data)), 10
        )
        latched = QoSProfile(
            depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL, reliability=ReliabilityPolicy.RELIABLE
        )
        self.node.create_subscription(
            JointTrajectory, f"{prefix}/clew_planner/trajectory", self.trajectories.append, latched
        )

    def spin_until(self, done, timeout_s: float) -> bool:
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline:
            if done():
                return True
            self.executor.spin_once(timeout_sec=0.002)
        return done()

    def close(self) -> None:
        self.executor.shutdown()
        self.node.destroy_node()
        rclpy.shutdown(context=self.context)


def start_replay(recording: Path, log: Path, *args: str) -> tuple[subprocess.Popen, object]:
    out = log.open("wb")
    process = subprocess.Popen(
        [sys.executable, "-m", "clew_ros.cli.replay", str(recording), *args],
        stdout=out,
        stderr=subprocess.STDOUT,
        env=os.environ.copy(),
    )
    return process, out


@pytest.mark.ros
def test_replay_keeps_order_and_scaled_timing(timed_recording: Path, tmp_path: Path) -> None:
    prefix = f"/replay_{uuid.uuid4().hex[:8]}"
    listener = Listener(prefix)
    log = tmp_path / "replay.log"
    process, out = start_replay(
        timed_recording, log, "--rate", str(RATE), "--prefix", prefix, "--delay", "0", "--wait-for-subscribers", "20"
    )
    try:
        got_all = listener.spin_until(lambda: len(listener.events) == 5, TIMEOUT_S)
        publishers = listener.node.get_publishers_info_by_topic(f"{prefix}/clew_planner/trajectory")
        listener.spin_until(lambda: bool(listener.trajectories), 5.0)
        code = process.wait(timeout=15)
    finally:
        if process.poll() is None:
            process.kill()
        out.close()
        listener.close()
    output = log.read_text(errors="replace")
    assert got_all, f"received {listener.events}; replay output:\n{output}"
    assert [data for _t, data in listener.events] == [f"event {i}" for i in range(5)]
    gaps = np.diff([t for t, _data in listener.events])
    # The recorded gaps scaled by the rate: the median gap and the whole span (robust to one late
    # DDS delivery on a loaded machine, which bunches two arrivals without changing the schedule).
    assert abs(np.median(gaps) - GAP_S / RATE) < TOLERANCE_S, f"inter-arrival times {gaps.round(3)}"
    assert abs(gaps.sum() - len(gaps) * GAP_S / RATE) < 2 * TOLERANCE_S, f"inter-arrival times {gaps.round(3)}"
    assert code == 0, output
    assert listener.trajectories
    assert list(listener.trajectories[0].joint_names) == ["joint_1", "joint_2", "gripper"]
    assert publishers
    assert publishers[0].qos_profile.durability == DurabilityPolicy.TRANSIENT_LOCAL


@pytest.mark.ros
def test_replay_loops_until_sigterm(timed_recording: Path, tmp_path: Path) -> None:
    prefix = f"/replay_{uuid.uuid4().hex[:8]}"
    listener = Listener(prefix)
    log = tmp_path / "replay.log"
    process, out = start_replay(
        timed_recording,
        log,
        "--rate",
        "4",
        "--loop",
        "--prefix",
        prefix,
        "--delay",
        "0",
        "--wait-for-subscribers",
        "20",
    )
    try:
        looped = listener.spin_until(lambda: len(listener.events) >= 7, TIMEOUT_S)  # more than one pass
        process.send_signal(signal.SIGTERM)
        code = process.wait(timeout=10)
    finally:
        if process.poll() is None:
            process.kill()
        out.close()
        listener.close()
    output = log.read_text(errors="replace")
    assert looped, f"received {len(listener.events)} events; replay output:\n{output}"
    assert code == 0, output


def test_replay_refuses_a_missing_recording(tmp_path: Path, capsys) -> None:
    from clew_ros.cli.replay import main

    assert main([str(tmp_path / "nothing")]) == 2
    assert "does not exist" in capsys.readouterr().err
    assert main([str(tmp_path), "--rate", "0"]) == 2
