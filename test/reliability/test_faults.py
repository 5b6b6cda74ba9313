"""Reliability: faults injected into a running ``clew_planner``.

- the recording directory is missing (the node creates it), cannot be
  created (its parent is a regular file), or sits on a full disk (a tiny
  tmpfs; without mount rights, RLIMIT_FSIZE on the node process): the plan is
  served all the same, the answer or the log says why the recording failed,
  and the next plan works;
- SIGINT and SIGTERM during a run: the run is canceled, its recording
  finalised and readable by both readers (rosbags, and clew_ros' own
  Recording over the mcap stream reader), exit code 0;
- SIGKILL during a run: the recording reads up to its last written chunk with
  the MCAP stream reader, and ``recover_recording`` makes it whole.
"""

from __future__ import annotations

import contextlib
import json
import os
import resource
import signal
import subprocess
import time
import uuid
from collections.abc import Iterator
from pathlib import Path

import pytest

rclpy = pytest.importorskip("rclpy")
rosbags_rosbag2 = pytest.importorskip("rosbags.rosbag2")


from action_msgs.msg import GoalStatus  # noqa: E402
from helpers.node_harness import NodeProcess, Session, run_id_of, wait_until  # noqa: E402
from helpers.rel_node import set_parameters, status_is, wait_event  # noqa: E402
from mcap.reader import make_reader  # noqa: E402
from mcap.records import Message  # noqa: E402
from mcap.stream_reader import StreamReader  # noqa: E402
from std_srvs.srv import Trigger  # noqa: E402

from clew_ros.recording import Recording, recover_recording  # noqa: E402

pytestmark = pytest.mark.ros

ROOT = Path(__file__).resolve().parents[2]
FAST_WORLD = ROOT / "test" / "worlds" / "rel_fast.yaml"
UNREACHABLE = ROOT / "config" / "behind_wall.yaml"
FAST = {
    "trajectory.max_velocity": 20.0,
    "trajectory.max_acceleration": 400.0,
    "playback.rate": 50.0,
    "trajectory.grasp_dwell": 0.02,
}
#: A signal ends the node within this (s): cancel (~0.1 s), close the recording, shut rclpy down.
EXIT_BOUND_S = 5.0
SHUTDOWN_FIGURES: dict[str, float] = {}


# --------------------------------------------------------------------------- helpers


@contextlib.contextmanager
def tiny_tmpfs(path: Path, size_kib: int) -> Iterator[bool]:
    """Mount a tmpfs of ``size_kib`` KiB at ``path``; yields False (nothing mounted) without mount rights."""
    path.mkdir(parents=True, exist_ok=True)
    done = subprocess.run(
        ["mount", "-t", "tmpfs", "-o", f"size={size_kib}k", "tmpfs", str(path)],
        capture_output=True,
        text=True,
        check=False,
    )
    try:
        yield done.returncode == 0
    finally:
        if done.returncode == 0:
            subprocess.run(["umount", "-l", str(path)], check=False)


def fill(directory: Path, leave_bytes: int = 0) -> None:
    """Fill the filesystem of ``directory``, then free ``leave_bytes``."""
    filler = directory / "filler"
    fd = os.open(filler, os.O_WRONLY | os.O_CREAT | os.O_TRUNC)
    try:
        with contextlib.suppress(OSError):
            while True:
                os.write(fd, b"\0" * 1024)
    finally:
        os.close(fd)
    if leave_bytes:
        os.truncate(filler, max(0, filler.stat().st_size - leave_bytes))


def plan_and_wait(session: Session, timeout_s: float = 30.0) -> tuple[Trigger.Response, str]:
    response = session.plan(timeout_s=timeout_s)
    run_id = run_id_of(response.message)
    if response.success:
        session.wait_playback(run_id)
    return response, run_id


def read_both(run_dir: Path) -> tuple[Recording, dict[str, int]]:
    """Read a recording with clew_ros' Recording and with rosbags; returns both views."""
    recording = Recording(run_dir)
    with rosbags_rosbag2.Reader(run_dir) as reader:
        counts = {c.topic: c.msgcount for c in reader.connections}
        rosbags_total = sum(1 for _ in reader.messages())
    assert rosbags_total == len(recording.messages()) == sum(counts.values())
    return recording, counts


def events_in(recording: Recording) -> list[dict]:
    topic = next(t for t in recording.topics if t.endswith("/events"))
    return [json.loads(m.data) for m in recording.decoded(topic)]


# --------------------------------------------------------------------------- recording directory faults


@pytest.fixture(scope="module")
def quick(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Session]:
    tmp = tmp_path_factory.mktemp("faults")
    session = Session(
        NodeProcess(
            tmp / "node.log",
            FAST_WORLD,
            # the development switch: the tests move record.directory at run time (else fixed: test/security)
            {
                "record.directory": str(tmp / "missing" / "deeper" / "runs"),
                "parameters.allow_runtime_changes": True,
                **FAST,
            },
        )
    )
    session.tmp = tmp
    try:
        yield session
    finally:
        code = session.close()
        assert code == 0, f"node exit code {code}; output:\n{session.node.output()}"


def test_missing_record_directory_is_created(quick: Session) -> None:
    runs = quick.tmp / "missing" / "deeper" / "runs"
    assert not runs.exists()
    response, run_id = plan_and_wait(quick)
    assert response.success, response.message
    assert f"recording {runs / run_id}" in response.message, response.message
    wait_until((runs / run_id / "metadata.yaml").is_file, 5.0, "the closed recording")
    recording, _counts = read_both(runs / run_id)
    assert recording.complete
    assert events_in(recording)[-1]["event"] in ("succeeded", "grasp", "ungrasp")


def test_record_directory_that_cannot_be_created(quick: Session) -> None:
    blocker = quick.tmp / "blocker"
    blocker.write_text("a regular file, not a directory")
    assert set_parameters(quick, {"record.directory": str(blocker / "sub")})[0].successful
    response, run_id = plan_and_wait(quick)
    assert response.success, response.message
    assert "not recorded" in response.message, response.message
    assert "record.directory" in response.message, response.message
    assert "Not a directory" in response.message or "File exists" in response.message, response.message
    # once the directory is fixed, runs are recorded again
    assert set_parameters(quick, {"record.directory": str(quick.tmp / "ok")})[0].successful
    response, run_id = plan_and_wait(quick)
    assert response.success, response.message
    assert f"recording {quick.tmp / 'ok' / run_id}" in response.message, response.message
    wait_until((quick.tmp / "ok" / run_id / "metadata.yaml").is_file, 5.0, "recording once fixed")


def test_disk_full(quick: Session, tmp_path: Path) -> None:
    """A tmpfs filled up: the run is not recorded (no room for the file), then half recorded; plans go on."""
    mount = tmp_path / "full"
    with tiny_tmpfs(mount, 64) as mounted:
        if not mounted:
            pytest.skip("no mount rights here; test_disk_full_by_rlimit covers this")
        fill(mount)
        assert set_parameters(quick, {"record.directory": str(mount / "runs")})[0].successful
        response, run_id = plan_and_wait(quick)
        assert response.success, response.message
        assert "not recorded" in response.message, response.message
        assert "No space left" in response.message, response.message
        assert str(mount) in response.message  # the answer says where
        assert not any((mount / "runs").iterdir()), "a failed start leaves nothing behind"

        # some room: the recording starts, then its writes fail; the node says so and goes on
        (mount / "filler").unlink()
        (mount / "runs").mkdir(exist_ok=True)
        fill(mount, leave_bytes=8 * 1024)
        response, run_id = plan_and_wait(quick)
        assert response.success, response.message
        wait_until(
            lambda: f"run {run_id}: recording failed" in quick.node.output(),
            10.0,
            "the node reports the failed recording",
        )
        assert "No space left" in quick.node.output()
        # what was written reads up to the last complete chunk
        partial = Recording(mount / "runs" / run_id)
        assert not partial.complete
        assert set_parameters(quick, {"record.directory": str(quick.tmp / "ok")})[0].successful
    response, run_id = plan_and_wait(quick)
    assert response.success, response.message
    assert "recording failed" not in response.message, response.message


def test_disk_full_by_rlimit(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """The same fault without a mount: the node's files may not grow past 8 KiB (RLIMIT_FSIZE).

    Python ignores SIGXFSZ, so a write past the limit fails with EFBIG ("File too large") instead of
    killing the process. The limit is set on the running node (prlimit) before any run starts. Runs
    only where tmpfs cannot be mounted (else test_disk_full covers the fault), or with
    CLEW_REL_RLIMIT=1 in the environment.
    """
    if os.environ.get("CLEW_REL_RLIMIT") != "1":
        with tiny_tmpfs(tmp_path / "probe", 4) as mounted:
            if mounted:
                pytest.skip("tmpfs can be mounted here (test_disk_full); CLEW_REL_RLIMIT=1 runs this too")
    monkeypatch.setenv("ROS_LOG_DIR", str(tmp_path / "ros_log"))  # rcl's own log file: small, out of the way
    node = NodeProcess(tmp_path / "node.log", FAST_WORLD, {"record.directory": str(tmp_path / "runs"), **FAST})
    limit = 8 * 1024
    resource.prlimit(node.proc.pid, resource.RLIMIT_FSIZE, (limit, limit))
    session = Session(node)
    try:
        response, run_id = plan_and_wait(session)
        assert response.success, response.message
        wait_until(lambda: f"run {run_id}: recording failed" in node.output(), 10.0, "the failed recording")
        assert "File too large" in node.output()
        response, _ = plan_and_wait(session)
        assert response.success, response.message
    finally:
        code = session.close()
    assert code == 0, node.output()


# --------------------------------------------------------------------------- signals


def start_long_run(tmp_path: Path) -> Session:
    """A node that will plan the unreachable world (it explores until stopped)."""
    tmp_path.mkdir(parents=True, exist_ok=True)
    session = Session(
        NodeProcess(
            tmp_path / "node.log", UNREACHABLE, {"record.directory": str(tmp_path / "runs"), "planner.time_limit": 60.0}
        )
    )
    session.runs = tmp_path / "runs"
    return session


def planning(session: Session) -> tuple[str, Path]:
    """Call ~/plan without waiting; return (run id, run directory) once the run is executing."""
    session.client.call_async(session.srv("plan"), Trigger)
    accepted, _ = wait_event(session, 0, lambda e: e["event"] == "accepted", 20.0)
    run_id = accepted["run_id"]
    session.status.wait_for(status_is(run_id, GoalStatus.STATUS_EXECUTING), 10.0)
    return run_id, session.runs / run_id


def test_signals_during_a_run(tmp_path: Path) -> None:
    """SIGINT, SIGTERM and SIGKILL, each to a node of its own (started side by side) while it plans."""
    sessions = {sig: start_long_run(tmp_path / sig.name) for sig in (signal.SIGINT, signal.SIGTERM, signal.SIGKILL)}
    try:
        runs = {sig: planning(session) for sig, session in sessions.items()}
        for sig in (signal.SIGINT, signal.SIGTERM):
            session = sessions[sig]
            sent = time.monotonic()
            code = session.node.stop(sig, timeout_s=EXIT_BOUND_S)
            SHUTDOWN_FIGURES[sig.name] = time.monotonic() - sent
            print(f"\n{sig.name} during a run: exit {code} after {1000 * SHUTDOWN_FIGURES[sig.name]:.0f} ms")
            assert code == 0, session.node.output()
            check_finalised(*runs[sig])
        run_id, run_dir = runs[signal.SIGKILL]
        mcap_path = run_dir / f"{run_id}_0.mcap"
        # the recorder flushes a chunk at least every 0.5 s: wait for one past the header
        wait_until(lambda: mcap_path.stat().st_size > 2048, 10.0, "a flushed chunk")
        assert sessions[signal.SIGKILL].node.stop(signal.SIGKILL, timeout_s=5.0) == -signal.SIGKILL
        check_recoverable(run_id, run_dir)
    finally:
        for session in sessions.values():
            session.close()


def check_finalised(run_id: str, run_dir: Path) -> None:
    """After SIGINT / SIGTERM: metadata written, both readers agree, the run ended CANCELED."""
    assert (run_dir / "metadata.yaml").is_file()
    recording, counts = read_both(run_dir)
    assert recording.complete
    outcome = [e for e in events_in(recording) if e["event"] in ("succeeded", "aborted", "canceled")]
    assert [e["code"] for e in outcome] == ["CANCELED"]
    assert "shutting down" in outcome[0]["message"]
    assert outcome[0]["run_id"] == run_id
    assert any(t.endswith("/landmarks") for t in counts)
    assert any(t.endswith("/world_yaml") for t in counts)


def check_recoverable(run_id: str, run_dir: Path) -> None:
    """After SIGKILL: no metadata; the stream reader reads up to the cut; recover_recording makes it whole."""
    mcap_path = run_dir / f"{run_id}_0.mcap"
    assert not (run_dir / "metadata.yaml").exists()
    messages = 0
    with mcap_path.open("rb") as stream, contextlib.suppress(Exception):  # the cut: an incomplete record
        for record in StreamReader(stream).records:
            messages += isinstance(record, Message)
    recording = Recording(run_dir)
    assert not recording.complete
    assert len(recording.messages()) == messages > 0
    events = events_in(recording)
    assert events[0]["event"] == "accepted"
    assert events[0]["run_id"] == run_id

    recover_recording(run_dir)  # python -c "from clew_ros.recording import recover_recording as r; r('<dir>')"
    assert (run_dir / f"{run_id}_0.mcap.truncated").is_file()
    assert (run_dir / "metadata.yaml").is_file()
    recovered, counts = read_both(run_dir)
    assert recovered.complete
    assert sum(counts.values()) == messages
    with mcap_path.open("rb") as stream:
        summary = make_reader(stream).get_summary()
    assert summary is not None
    assert sum(summary.statistics.channel_message_counts.values()) == messages
    assert uuid.UUID(hex=run_id)
