"""A run's recording as the node uses it: off, not possible, written, failing (no ROS graph)."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

pytest.importorskip("rclpy")
pytest.importorskip("mcap")

from std_msgs.msg import String

from clew_ros.node.run_recording import NO_RECORDING, BagRecording, Recordings, RunRecording
from clew_ros.recording import Recording
from clew_ros.ros.parameters import NodeSettings

RUN = "0123456789abcdef0123456789abcdef"


class Logger:
    """Keeps what the node would log."""

    def __init__(self) -> None:
        self.errors: list[str] = []
        self.warnings: list[str] = []

    def error(self, text: str) -> None:
        self.errors.append(text)

    def warning(self, text: str) -> None:
        self.warnings.append(text)


def settings(directory: Path, enabled: bool = True) -> NodeSettings:
    return NodeSettings(record_enabled=enabled, record_directory=str(directory))


def test_off_records_nothing_and_says_so(tmp_path: Path) -> None:
    recording = Recordings("clew_planner", Logger()).open(settings(tmp_path / "runs", enabled=False), RUN)
    assert recording.text == "recording off (record.enabled is false)"
    assert not recording.is_open
    recording.write("/clew_planner/events", String(data="x"), 1)
    recording.check()
    recording.close()
    assert not (tmp_path / "runs").exists()
    assert NO_RECORDING.text == ""
    assert not NO_RECORDING.is_open


def test_a_run_is_written_and_closed(tmp_path: Path) -> None:
    logger = Logger()
    recording = Recordings("clew_planner", logger).open(settings(tmp_path / "runs"), RUN)  # created if missing
    assert isinstance(recording, BagRecording)
    assert recording.is_open
    assert recording.text == f"recording {tmp_path / 'runs' / RUN}"
    for k in range(3):
        recording.write("/clew_planner/events", String(data=str(k)), 1_000_000_000 + k)
    recording.check()
    recording.close()
    recording.close()  # idempotent
    assert not recording.is_open
    assert recording.text == f"recording {tmp_path / 'runs' / RUN}"
    assert not logger.errors
    recording.write("/clew_planner/events", String(data="late"), 2_000_000_000)  # after close: dropped
    read = Recording(tmp_path / "runs" / RUN)
    assert read.complete
    assert [m.data for m in read.decoded("/clew_planner/events")] == ["0", "1", "2"]


def test_a_directory_that_cannot_be_made_leaves_the_run_unrecorded(tmp_path: Path) -> None:
    (tmp_path / "file").write_text("in the way")
    logger = Logger()
    recording = Recordings("clew_planner", logger).open(settings(tmp_path / "file" / "runs"), RUN)
    assert recording.text.startswith(f"not recorded: record.directory {tmp_path / 'file' / 'runs'} cannot be created")
    assert not recording.is_open
    assert logger.errors == [f"run {RUN}: {recording.text}"]


def test_an_existing_run_directory_is_not_overwritten(tmp_path: Path) -> None:
    (tmp_path / RUN).mkdir()
    logger = Logger()
    recording = Recordings("clew_planner", logger).open(settings(tmp_path), RUN)
    assert recording.text == f"not recorded: {tmp_path / RUN} exists already, not overwriting."
    assert logger.errors
    assert "cannot record to" in logger.errors[0]


def test_without_the_recorder_runs_are_not_recorded_and_that_is_logged_once(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setitem(sys.modules, "clew_ros.recording", None)  # any import of it raises ImportError
    logger = Logger()
    recordings = Recordings("clew_planner", logger)
    for run in (RUN, RUN[::-1]):
        recording = recordings.open(settings(tmp_path), run)
        assert recording.text.startswith("not recorded: the recorder is not available")
        assert not recording.is_open
    assert len(logger.warnings) == 1
    assert logger.warnings[0].startswith("runs are not recorded:")


class FailingRecorder:
    """A RunRecorder whose disk fills up: ``error`` is set, or ``write`` / ``close`` raise."""

    def __init__(self, raise_on: str = "") -> None:
        self.path = Path("/runs") / RUN
        self.error: str | None = None
        self.raise_on = raise_on

    def write(self, topic: str, msg: object, time_ns: int, *, qos: object = None) -> None:
        if self.raise_on == "write":
            raise OSError("disk full")
        self.error = "cannot write (writing a chunk): No space left on device"

    def close(self) -> Path:
        if self.raise_on == "close":
            raise OSError("gone")
        return self.path


@pytest.mark.parametrize(
    ("raise_on", "reason"),
    [
        ("", "cannot write (writing a chunk): No space left on device"),
        ("write", "write to /t failed: disk full"),
    ],
)
def test_the_first_fault_goes_into_the_text_once(raise_on: str, reason: str) -> None:
    failures: list[str] = []
    recording = BagRecording(FailingRecorder(raise_on), failures.append)  # type: ignore[arg-type]
    recording.write("/t", String(data="x"), 1)
    recording.write("/t", String(data="y"), 2)
    recording.check()
    recording.close()
    assert recording.text == f"recording /runs/{RUN} (recording failed: {reason})"
    assert failures == [reason]


def test_a_failing_close_is_reported_not_raised() -> None:
    failures: list[str] = []
    recording = BagRecording(FailingRecorder("close"), failures.append)  # type: ignore[arg-type]
    recording.close()
    assert failures == ["close failed: gone"]
    assert recording.text.endswith("(recording failed: close failed: gone)")
    assert isinstance(recording, RunRecording)
    assert not recording.is_open
