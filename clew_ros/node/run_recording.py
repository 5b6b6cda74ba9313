"""A run's recording as the node uses it: write, close, and what the answer says about it.

:class:`RunRecording` records nothing (a null object): :data:`NO_RECORDING`,
and the recordings of runs that are not recorded (``record.enabled`` false,
or the recording cannot be opened; :attr:`~RunRecording.text` says why).
:class:`BagRecording` writes through :class:`clew_ros.recording.RunRecorder`
(interface.md §4). :class:`Recordings` opens one per run.

Runs are recorded inside ``record.directory`` as resolved at start
(:attr:`~clew_ros.ros.parameters.NodeSettings.record_path`): the folders
:class:`Recordings` creates for it get mode 0700, and a run is not recorded
when that path has come to resolve elsewhere since (a symbolic link
changed). As each recorded run starts, the oldest complete runs beyond
``record.max_runs`` / ``record.max_bytes`` are deleted and logged
(:mod:`clew_ros.recording.retention`).

No method raises: a recording fault never stops a run, and the recorder
keeps what it could write. The first fault is logged and added to
:attr:`~RunRecording.text` (``... (recording failed: <why>)``), which the
``~/plan`` answer and the outcome event carry.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

from clew_ros.core.files import private_folders
from clew_ros.ros.parameters import NodeSettings

if TYPE_CHECKING:
    from rclpy.impl.rcutils_logger import RcutilsLogger
    from rclpy.qos import QoSProfile

    from clew_ros.recording import RunRecorder

__all__ = ["NO_RECORDING", "BagRecording", "Recordings", "RunRecording"]


class RunRecording:
    """A recording that records nothing; ``text`` says so (or is empty)."""

    def __init__(self, text: str = "", path: str | None = None) -> None:
        self._text = text
        self._path = path

    @property
    def path(self) -> str | None:
        """The run's rosbag2 directory (``None``: the run is not recorded)."""
        return self._path

    @property
    def text(self) -> str:
        """What the ``~/plan`` answer and the events say about the recording."""
        return self._text

    @property
    def is_open(self) -> bool:
        """Whether messages are still being recorded (closed after the run, or never opened)."""
        return False

    def write(self, topic: str, msg: object, time_ns: int, qos: QoSProfile | None = None) -> None:
        """Record ``msg`` as published on ``topic`` at ``time_ns`` (ns, the node's clock).

        ``qos`` is the profile the topic is offered with; the recording keeps it (interface.md §4).
        """

    def check(self) -> None:
        """Add a write error met so far to :attr:`text` (the recording stays open)."""

    def close(self) -> None:
        """Finish the recording (idempotent); add an error to :attr:`text`."""


#: The recording of no run (messages published outside a run, e.g. after a parameter change).
NO_RECORDING = RunRecording()


class BagRecording(RunRecording):
    """A run recorded by ``recorder`` into ``<record.directory>/<run id>/``.

    ``on_failure`` logs the first fault (once).
    """

    def __init__(self, recorder: RunRecorder, on_failure: Callable[[str], None]) -> None:
        super().__init__(f"recording {recorder.path}", str(recorder.path))
        self._recorder: RunRecorder | None = recorder
        self._on_failure = on_failure
        self._failure_lock = threading.Lock()
        self._failed = False

    @property
    def is_open(self) -> bool:
        return self._recorder is not None

    def write(self, topic: str, msg: object, time_ns: int, qos: QoSProfile | None = None) -> None:
        recorder = self._recorder
        if recorder is None:
            return
        try:
            recorder.write(topic, msg, time_ns, qos=qos)
        except Exception as error:  # noqa: BLE001 - a recording fault never stops the plan
            self._fail(f"write to {topic} failed: {error}")

    def check(self) -> None:
        recorder = self._recorder
        if recorder is not None and recorder.error:
            self._fail(recorder.error)

    def close(self) -> None:
        recorder, self._recorder = self._recorder, None
        if recorder is None:
            return
        try:
            recorder.close()
            error = recorder.error
        except Exception as close_error:  # noqa: BLE001 - reported, never raised into the run
            error = f"close failed: {close_error}"
        if error:
            self._fail(error)

    def _fail(self, reason: str) -> None:
        with self._failure_lock:
            if self._failed:
                return
            self._failed = True
            self._text += f" (recording failed: {reason})"
        self._on_failure(reason)


class Recordings:
    """Opens each run's recording as ``record.*`` says; one per node.

    The recorder (:mod:`clew_ros.recording`, which needs the ``mcap``
    packages) is imported at the first recorded run; if it cannot be, runs
    are not recorded and that is logged once.
    """

    def __init__(self, node_name: str, logger: RcutilsLogger) -> None:
        self._node_name = node_name
        self._logger = logger
        self._recorder_class: type[RunRecorder] | None = None
        self._unavailable: str | None = None  # why the recorder cannot be imported

    def open(self, settings: NodeSettings, run_hex: str) -> RunRecording:
        """The recording of run ``run_hex``: a :class:`BagRecording`, or one that says why there is none."""
        if not settings.record_enabled:
            return RunRecording("recording off (record.enabled is false)")
        recorder_class = self._recorder()
        if recorder_class is None:
            return RunRecording(f"not recorded: {self._unavailable}")
        directory = settings.record_path
        try:
            private_folders(directory)  # the recorder wants it to exist
        except OSError as error:
            text = f"not recorded: record.directory {directory} cannot be created ({error.strerror})"
            self._logger.error(f"run {run_hex}: {text}")
            return RunRecording(text)
        try:
            now = directory.resolve()
        except OSError as error:
            now = Path(f"? ({error.strerror})")
        if now != directory:
            text = (
                f"not recorded: record.directory {directory} now resolves to {now} (a symbolic link changed "
                "since the node started); recordings stay where the node was told at start"
            )
            self._logger.error(f"run {run_hex}: {text}")
            return RunRecording(text)
        try:
            recorder = recorder_class(directory, run_hex, node_name=self._node_name)
        except Exception as error:  # noqa: BLE001 - RecordingError and anything else: the run goes on unrecorded
            self._logger.error(f"run {run_hex}: cannot record to {directory / run_hex}: {error}")
            return RunRecording(f"not recorded: {error}")
        self._prune(settings, run_hex)

        def on_failure(reason: str) -> None:
            self._logger.error(f"run {run_hex}: recording failed: {reason}")

        return BagRecording(recorder, on_failure)

    def _prune(self, settings: NodeSettings, run_hex: str) -> None:
        """Delete the oldest complete runs beyond ``record.max_runs`` / ``record.max_bytes``; log each."""
        from clew_ros.recording.retention import RetentionPolicy, prune_runs

        policy = RetentionPolicy(settings.record_max_runs, settings.record_max_bytes)
        if policy.max_runs == 0 and policy.max_bytes == 0:
            return
        try:
            deleted = prune_runs(settings.record_path, policy, current=run_hex)
        except Exception as error:  # noqa: BLE001 - retention never stops a run
            self._logger.error(f"run {run_hex}: cannot apply the recording retention: {error!r}")
            return
        for run in deleted:
            self._logger.info(f"deleted the recording {run.path} ({run.size_bytes} bytes): {run.reason}")

    def _recorder(self) -> type[RunRecorder] | None:
        if self._recorder_class is None and self._unavailable is None:
            try:
                from clew_ros.recording import RunRecorder
            except ImportError as error:
                self._unavailable = f"the recorder is not available ({error})"
                self._logger.warning(f"runs are not recorded: {self._unavailable}")
            else:
                self._recorder_class = RunRecorder
        return self._recorder_class
