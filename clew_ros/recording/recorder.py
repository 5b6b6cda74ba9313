"""``RunRecorder``: one planning run written as a rosbag2 directory with one MCAP file.

The node calls :meth:`RunRecorder.write` from its planning and publishing
paths; the call serialises the message (CDR, ``rclpy.serialization``) and
hands it to a writer thread, so it never waits for the disk. The writer
thread puts the bytes in canonical form with rosbags
(:func:`~clew_ros.recording.cdr.canonical_cdr`: zero padding, exact length),
so the caller pays for the C serializer only. The writer
thread writes a chunked MCAP incrementally and flushes the file after every
chunk and at least every ``flush_period_s``, so a process that is killed
leaves a file that the MCAP stream reader reads up to its last chunk
(:func:`clew_ros.recording.reader.recover_recording` rewrites it whole).
:meth:`RunRecorder.close` writes the MCAP summary and ``metadata.yaml``
(rosbag2 version 9, as ROS 2 Jazzy writes it).

A run's folder is made with mode 0700 and its files with mode 0600 (set
explicitly, whatever the umask), only directly inside the recording
directory: the run id must be a plain name, and the folder must resolve to
``<resolved directory>/<run id>`` (no symbolic link on the way); files are
opened without following a symbolic link.
"""

from __future__ import annotations

import atexit
import contextlib
import itertools
import os
import queue
import threading
import time
from pathlib import Path
from typing import Any

import yaml

import clew_ros
from clew_ros.recording.cdr import SerializedMessage, canonical_cdr
from clew_ros.recording.errors import RecordingError
from clew_ros.recording.msgdefs import (
    learn_types,
    message_definition,
    message_type_name,
    type_description_hash,
    typestore,
)

__all__ = [
    "ROSBAG2_VERSION",
    "TRANSIENT_LOCAL_TOPICS",
    "RunRecorder",
    "bag_metadata",
    "default_offered_qos",
    "write_bag_metadata",
]

#: rosbag2 metadata version written by ROS 2 Jazzy.
ROSBAG2_VERSION = 9
#: Topics (last name component) that the node offers with transient-local durability (depth 1).
TRANSIENT_LOCAL_TOPICS = frozenset(
    {"status", "trajectory", "landmarks", "world_markers", "world_yaml", "robot_description", "tf_static"}
)
#: Volatile topics (last name component) that the node offers with depth 100 (the others: 10).
_DEEP_TOPICS = frozenset({"events", "goal_pose", "tf"})

#: Modes of what a recorder makes: only the node's user reads a recording (it holds the world and the goals).
FOLDER_MODE = 0o700
FILE_MODE = 0o600

_STOP = object()
_FLUSH = object()
_QUEUE_LIMIT_BYTES = 256 * 2**20


def default_offered_qos(topic: str) -> dict[str, Any]:
    """The QoS profile (rosbag2 v9 form) the node offers on ``topic``.

    Used for a message written without its QoS (and by readers for a topic
    recorded without one). Reliable; transient-local with depth 1 for the
    latched topics of :data:`TRANSIENT_LOCAL_TOPICS`, volatile with depth 100
    for ``events``, ``goal_pose`` and ``/tf``, 10 otherwise (as
    :mod:`clew_ros.ros.qos`). Zero durations mean "default" (no deadline,
    lifespan or lease).
    """
    last = topic.rstrip("/").rsplit("/", 1)[-1]
    if last in TRANSIENT_LOCAL_TOPICS:
        return _qos_dict("keep_last", 1, "reliable", "transient_local")
    return _qos_dict("keep_last", 100 if last in _DEEP_TOPICS else 10, "reliable", "volatile")


def _qos_dict(
    history: str, depth: int, reliability: str, durability: str, liveliness: str = "automatic"
) -> dict[str, Any]:
    zero = {"sec": 0, "nsec": 0}
    return {
        "history": history,
        "depth": int(depth),
        "reliability": reliability,
        "durability": durability,
        "deadline": dict(zero),
        "lifespan": dict(zero),
        "liveliness": liveliness,
        "liveliness_lease_duration": dict(zero),
        "avoid_ros_namespace_conventions": False,
    }


def _qos_from_profile(profile: Any) -> dict[str, Any]:
    """An rclpy ``QoSProfile`` in rosbag2 v9 form."""

    def name(policy: Any) -> str:
        return str(getattr(policy, "name", policy)).lower()

    def duration(value: Any) -> dict[str, int]:
        nanoseconds = int(getattr(value, "nanoseconds", 0) or 0)
        return {"sec": nanoseconds // 10**9, "nsec": nanoseconds % 10**9}

    qos = _qos_dict(
        name(profile.history),
        profile.depth,
        name(profile.reliability),
        name(profile.durability),
        name(profile.liveliness),
    )
    qos["deadline"] = duration(profile.deadline)
    qos["lifespan"] = duration(profile.lifespan)
    qos["liveliness_lease_duration"] = duration(profile.liveliness_lease_duration)
    qos["avoid_ros_namespace_conventions"] = bool(profile.avoid_ros_namespace_conventions)
    return qos


def _dump(value: Any) -> str:
    return yaml.safe_dump(value, sort_keys=False, default_flow_style=False)


class _Topic:
    """What the writer knows about one recorded topic."""

    def __init__(self, name: str, type_name: str, qos: dict[str, Any]) -> None:
        self.name = name
        self.type_name = type_name
        self.qos = qos
        self.type_hash = type_description_hash(type_name)
        self.channel_id: int | None = None
        self.canonical = False  # rosbags encodes the type as its schema says: rclpy's bytes go through canonical_cdr
        self.written = 0  # on disk (in a flushed chunk)
        self.pending = 0  # in the chunk being built


def bag_metadata(
    file_name: str,
    topics: list[dict[str, Any]],
    starting_time_ns: int,
    duration_ns: int,
    *,
    custom_data: dict[str, str] | None = None,
    ros_distro: str | None = None,
) -> dict[str, Any]:
    """The ``rosbag2_bagfile_information`` mapping of a one-file MCAP bag.

    ``topics`` holds dicts with ``name``, ``type``, ``offered_qos_profiles``
    (rosbag2 v9 dicts), ``type_description_hash`` and ``message_count``.
    """
    count = sum(int(t["message_count"]) for t in topics)
    return {
        "version": ROSBAG2_VERSION,
        "storage_identifier": "mcap",
        "duration": {"nanoseconds": int(duration_ns)},
        "starting_time": {"nanoseconds_since_epoch": int(starting_time_ns)},
        "message_count": count,
        "topics_with_message_count": [
            {
                "topic_metadata": {
                    "name": t["name"],
                    "type": t["type"],
                    "serialization_format": "cdr",
                    "offered_qos_profiles": t["offered_qos_profiles"],
                    "type_description_hash": t.get("type_description_hash", ""),
                },
                "message_count": int(t["message_count"]),
            }
            for t in topics
        ],
        "compression_format": "",
        "compression_mode": "",
        "relative_file_paths": [file_name],
        "files": [
            {
                "path": file_name,
                "starting_time": {"nanoseconds_since_epoch": int(starting_time_ns)},
                "duration": {"nanoseconds": int(duration_ns)},
                "message_count": count,
            }
        ],
        "custom_data": dict(custom_data) if custom_data else None,
        "ros_distro": ros_distro or os.environ.get("ROS_DISTRO") or "jazzy",
    }


def write_bag_metadata(directory: Path, information: dict[str, Any]) -> Path:
    """Write ``metadata.yaml`` atomically (temporary file of mode 0600, then rename); return its path."""
    path = Path(directory) / "metadata.yaml"
    temporary = path.with_name("metadata.yaml.tmp")
    with contextlib.suppress(FileNotFoundError):
        temporary.unlink()  # left by a writer killed between write and rename: never written through
    with _create_private(temporary, "w") as stream:
        stream.write(_dump({"rosbag2_bagfile_information": information}))
    temporary.replace(path)
    return path


def _create_private(path: Path, mode: str) -> Any:
    """A new file of mode 0600 opened for writing (``mode`` ``"w"`` or ``"wb"``); never through a symbolic link,
    never over an existing file (:class:`FileExistsError`)."""
    fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_NOFOLLOW", 0), FILE_MODE)
    try:
        os.fchmod(fd, FILE_MODE)  # the umask may have taken bits off; never adds any
        return os.fdopen(fd, mode)
    except BaseException:
        os.close(fd)
        raise


class RunRecorder:
    """Records one run as ``<directory>/<run_id>/`` (``metadata.yaml`` + ``<run_id>_0.mcap``).

    Parameters
    ----------
    directory:
        Existing, writable directory that holds the runs (``record.directory``).
    run_id:
        Name of the run's directory (the run UUID as 32 hex digits).
    node_name:
        Name of the recording node, kept in ``custom_data``.
    chunk_size:
        MCAP chunk size (bytes): a killed process loses at most the chunk in
        progress. Keyword-only, like the other settings.
    flush_period_s:
        Longest time (s) a written message waits in an unfinished chunk.
    compression:
        ``"zstd"`` (rosbag2's MCAP default), ``"lz4"`` or ``"none"``.

    Raises
    ------
    RecordingError
        ``directory`` is missing or not writable, the run directory exists
        already (a recorder never overwrites), or ``mcap`` or ``rosbags`` is
        not installed.

    :meth:`write` never raises and never waits for the disk; the first error
    met while writing is kept in :attr:`error` and later messages are dropped.
    :meth:`close` is idempotent and thread safe; it also runs at interpreter
    exit if nobody called it.
    """

    def __init__(
        self,
        directory: str | os.PathLike,
        run_id: str,
        node_name: str = "clew_planner",
        *,
        chunk_size: int = 64 * 1024,
        flush_period_s: float = 0.5,
        compression: str = "zstd",
    ) -> None:
        from rclpy.serialization import serialize_message  # here: reading recordings needs no rclpy

        try:
            from mcap.writer import CompressionType, Writer
            from rosbags.typesys import Stores  # noqa: F401 - what canonical_cdr and tf_message encode with
        except ImportError as error:  # before anything is created on disk
            package = (error.name or "mcap").partition(".")[0]
            raise RecordingError(f"the {package} package is not installed ({error})") from None
        self._serialize = serialize_message
        self.run_id = run_id
        self.node_name = node_name
        self.path = self._make_directory(Path(directory), run_id)
        self.mcap_path = self.path / f"{run_id}_0.mcap"
        try:
            self._file = _create_private(self.mcap_path, "wb")
        except OSError as error:
            with contextlib.suppress(OSError):
                self.path.rmdir()  # created just above: leave nothing behind
            raise RecordingError(f"cannot create {self.mcap_path}: {error.strerror}") from None

        compressions = {"zstd": CompressionType.ZSTD, "lz4": CompressionType.LZ4, "none": CompressionType.NONE}
        if compression not in compressions:
            self._abandon()
            raise RecordingError(
                f"compression {compression!r} is not a valid option, must be one of {', '.join(compressions)}"
            )
        self._writer = Writer(self._file, chunk_size=chunk_size, compression=compressions[compression])
        self._flush_period_s = float(flush_period_s)
        self._topics: dict[str, _Topic] = {}
        self._schemas: dict[str, tuple[int, bool]] = {}  # type -> schema id, whether canonical_cdr applies
        self._start_ns: int | None = None
        self._end_ns: int | None = None
        self._error: str | None = None
        self._failed = False  # the writer thread stopped writing after an error
        self._dropped = 0
        self._dropped_lock = threading.Lock()
        self._queued_bytes = 0
        self._sequence = itertools.count()
        self._lock = threading.Lock()  # orders write() puts before close()'s stop
        self._closed = False
        self._close_lock = threading.Lock()
        self._queue: queue.SimpleQueue = queue.SimpleQueue()
        try:
            self._writer.start(profile="ros2", library=f"clew_ros {clew_ros.__version__} RunRecorder")
            self._file.flush()
        except OSError as error:
            self._abandon()
            raise RecordingError(f"cannot write {self.mcap_path}: {error.strerror}") from None
        self._thread = threading.Thread(target=self._run, name=f"recorder-{run_id[:8]}", daemon=True)
        self._thread.start()
        atexit.register(self._close_at_exit)

    @staticmethod
    def _make_directory(directory: Path, run_id: str) -> Path:
        """Create ``directory/run_id`` with mode 0700 (never over an existing one, never outside ``directory``);
        :class:`RecordingError` says why not."""
        if not run_id or "/" in run_id or "\\" in run_id or "\0" in run_id or run_id in (".", ".."):
            raise RecordingError(f"run id {run_id!r} cannot name a directory")
        if not directory.is_dir():
            raise RecordingError(f"recording directory {directory} does not exist or is not a directory")
        if not os.access(directory, os.W_OK | os.X_OK):
            raise RecordingError(f"recording directory {directory} is not writable")
        path = directory / run_id
        try:
            path.mkdir(mode=FOLDER_MODE)
        except FileExistsError:
            raise RecordingError(f"{path} exists already, not overwriting.") from None
        except OSError as error:
            raise RecordingError(f"cannot create the recording directory {path}: {error.strerror}") from None
        try:
            fd = os.open(path, os.O_RDONLY | os.O_DIRECTORY | getattr(os, "O_NOFOLLOW", 0))
            try:
                os.fchmod(fd, FOLDER_MODE)  # the umask may have taken bits off
            finally:
                os.close(fd)
            inside = path.resolve() == directory.resolve() / run_id
        except OSError as error:
            inside, reason = False, error.strerror
        else:
            reason = f"it resolves to {path.resolve()}, not inside {directory.resolve()}"
        if not inside:
            with contextlib.suppress(OSError):
                path.rmdir()
            raise RecordingError(f"cannot record into {path}: {reason}")
        return path

    def _abandon(self) -> None:
        """Undo a start that failed (disk full, ...): close the file, remove what was created."""
        with contextlib.suppress(OSError):
            self._file.close()  # may fail to flush the header: the fd is closed all the same
        with contextlib.suppress(OSError):
            self.mcap_path.unlink()
            self.path.rmdir()

    # ------------------------------------------------------------------ public API

    @property
    def error(self) -> str | None:
        """The first error met while recording (disk full, ...), or ``None``."""
        return self._error

    @property
    def closed(self) -> bool:
        return self._closed

    @property
    def dropped(self) -> int:
        """Messages not recorded (after an error, after close, or unserialisable)."""
        return self._dropped

    def write(self, topic: str, msg: Any, time_ns: int, *, qos: Any = None) -> None:
        """Record ``msg`` on ``topic`` at ``time_ns``; never raises, never blocks on the disk.

        Parameters
        ----------
        topic:
            Full topic name, e.g. ``/clew_planner/status``.
        msg:
            An rclpy message instance (its type names the schema), or a
            :class:`~clew_ros.recording.cdr.SerializedMessage` (CDR already,
            e.g. :func:`~clew_ros.recording.cdr.tf_message`), recorded as it is.
        time_ns:
            Receive/log time (ns since the epoch), e.g. ``node.get_clock().now().nanoseconds``.
        qos:
            The rclpy ``QoSProfile`` offered on the topic; only the first
            message of a topic uses it (default: :func:`default_offered_qos`).
        """
        if self._closed or self._failed:
            self._drop()
            return
        try:
            if isinstance(msg, SerializedMessage):
                data, type_name, canonical = msg.data, msg.type_name, True
            else:
                data, type_name, canonical = self._serialize(msg), message_type_name(msg), False
            offered = _qos_from_profile(qos) if qos is not None else None
            time_ns = int(time_ns)
            if not 0 <= time_ns < 2**64:
                raise ValueError(f"time_ns {time_ns} is not a time in ns since the epoch")
        except Exception as error:  # noqa: BLE001 - write() must not raise into the planner
            self._set_error(f"{self.mcap_path}: cannot record a message on {topic}: {error!r}")
            self._drop()
            return
        with self._lock:
            if self._closed:  # close() ran in another thread since the check above
                self._drop()  # type: ignore[unreachable]
                return
            if self._queued_bytes + len(data) > _QUEUE_LIMIT_BYTES:
                self._set_error(f"{self.mcap_path}: the writer is {self._queued_bytes} bytes behind; messages dropped")
                self._drop()
                return
            self._queued_bytes += len(data)
            self._queue.put((topic, type_name, data, canonical, time_ns, offered))

    def close(self) -> Path:
        """Finish the recording: flush, write the MCAP summary and ``metadata.yaml``.

        Returns the run directory. Idempotent and thread safe: later and
        concurrent calls wait for the first one and return the same path.
        Never raises for disk errors (they are kept in :attr:`error`).
        """
        with self._close_lock:
            if not self._closed:
                with self._lock:
                    self._closed = True
                    self._queue.put(_STOP)
                self._thread.join()
                with contextlib.suppress(Exception):  # the interpreter is shutting down
                    atexit.unregister(self._close_at_exit)
        return self.path

    def __enter__(self) -> RunRecorder:
        return self

    def __exit__(self, *exc_info: Any) -> None:
        self.close()

    def __repr__(self) -> str:
        state = "closed" if self._closed else "open"
        return f"RunRecorder({str(self.path)!r}, {state}, error={self._error!r})"

    # ------------------------------------------------------------------ writer thread

    def _close_at_exit(self) -> None:
        self.close()

    def _drop(self) -> None:
        with self._dropped_lock:
            self._dropped += 1

    def _set_error(self, message: str) -> None:
        if self._error is None:
            self._error = message

    def _fail(self, error: BaseException, doing: str) -> None:
        reason = getattr(error, "strerror", None) or repr(error)
        self._set_error(f"cannot write {self.mcap_path} ({doing}): {reason}")
        self._failed = True
        with contextlib.suppress(OSError):
            self._file.close()

    def _run(self) -> None:
        with contextlib.suppress(Exception):  # made on this thread, not the caller's; a fault shows at the first type
            typestore()
        last_flush = time.monotonic()
        while True:
            pending = any(t.pending for t in self._topics.values())
            timeout = max(0.0, self._flush_period_s - (time.monotonic() - last_flush)) if pending else None
            try:
                item = self._queue.get(timeout=timeout)
            except queue.Empty:
                item = _FLUSH
            if item is _STOP:
                break
            if item is _FLUSH:
                if not self._failed:
                    self._flush_chunk()
                last_flush = time.monotonic()
                continue
            topic, type_name, data, canonical, time_ns, offered = item
            with self._lock:
                self._queued_bytes -= len(data)
            if self._failed:
                self._drop()
                continue
            if self._add(topic, type_name, data, canonical=canonical, time_ns=time_ns, offered=offered):
                last_flush = time.monotonic()
            elif time.monotonic() - last_flush >= self._flush_period_s:
                self._flush_chunk()
                last_flush = time.monotonic()
        self._finish()

    def _channel(self, topic: str, type_name: str, offered: dict[str, Any] | None) -> _Topic:
        entry = self._topics.get(topic)
        if entry is not None:
            if entry.type_name != type_name:
                raise TypeError(f"topic {topic} was recorded as {entry.type_name}, got {type_name}")
            return entry
        entry = _Topic(topic, type_name, offered or default_offered_qos(topic))
        schema = self._schemas.get(type_name)
        if schema is None:
            try:
                definition, encoding = message_definition(type_name), "ros2msg"
            except RecordingError as error:
                self._set_error(f"{self.mcap_path}: {error}; {topic} recorded without a schema")
                definition, encoding = "", ""
            schema_id = self._writer.register_schema(type_name, encoding, definition.encode())
            schema = self._schemas[type_name] = (schema_id, learn_types(type_name, definition))
        schema_id, entry.canonical = schema
        entry.channel_id = self._writer.register_channel(
            topic,
            "cdr",
            schema_id,
            {"offered_qos_profiles": _dump([entry.qos]).strip(), "topic_type_hash": entry.type_hash},
        )
        self._topics[topic] = entry
        return entry

    def _add(
        self, topic: str, type_name: str, data: bytes, *, canonical: bool, time_ns: int, offered: dict | None
    ) -> bool:
        """Write one message (``data`` in canonical form already or not); return True when a chunk went to disk."""
        try:
            before = self._file.tell()
            try:
                entry = self._channel(topic, type_name, offered)
            except TypeError as error:
                self._set_error(f"{self.mcap_path}: {error}")
                self._drop()
                return False
            assert entry.channel_id is not None  # registered by _channel
            if not canonical and entry.canonical:
                with contextlib.suppress(Exception):  # rosbags refuses it: rclpy's bytes are valid CDR all the same
                    data = canonical_cdr(type_name, data)
            self._writer.add_message(
                entry.channel_id,
                log_time=time_ns,
                data=data,
                publish_time=time_ns,
                sequence=next(self._sequence) & 0xFFFFFFFF,
            )
            entry.pending += 1
            self._start_ns = time_ns if self._start_ns is None else min(self._start_ns, time_ns)
            self._end_ns = time_ns if self._end_ns is None else max(self._end_ns, time_ns)
            if self._file.tell() != before:  # the writer finished a chunk: make it durable
                self._file.flush()
                self._commit()
                return True
        except Exception as error:  # noqa: BLE001 - disk full, file too large, ...
            self._fail(error, "writing a chunk")
        return False

    def _flush_chunk(self) -> None:
        flush = getattr(self._writer, "flush", None)  # mcap >= 1.2.2: finish the chunk in progress
        if flush is None or not any(t.pending for t in self._topics.values()):
            return
        try:
            flush()
            self._file.flush()
            self._commit()
        except Exception as error:  # noqa: BLE001
            self._fail(error, "flushing a chunk")

    def _commit(self) -> None:
        for entry in self._topics.values():
            entry.written += entry.pending
            entry.pending = 0

    def _information(self) -> dict[str, Any]:
        topics = [
            {
                "name": t.name,
                "type": t.type_name,
                "offered_qos_profiles": [t.qos],
                "type_description_hash": t.type_hash,
                "message_count": t.written,
            }
            for t in self._topics.values()
        ]
        start = self._start_ns or 0
        custom = {"run_id": self.run_id, "node": self.node_name, "writer": f"clew_ros {clew_ros.__version__}"}
        if self._error:
            custom["error"] = self._error
        return bag_metadata(self.mcap_path.name, topics, start, (self._end_ns or start) - start, custom_data=custom)

    def _finish(self) -> None:
        if not self._failed:
            saved = {name: (t.written, t.pending) for name, t in self._topics.items()}
            self._commit()  # finish() writes the chunk in progress
            try:
                self._writer.add_metadata("rosbag2", {"serialized_metadata": _dump(self._information())})
                self._writer.finish()
                self._file.flush()
                os.fsync(self._file.fileno())
                self._file.close()
            except Exception as error:  # noqa: BLE001
                for name, (written, pending) in saved.items():
                    self._topics[name].written, self._topics[name].pending = written, pending
                self._fail(error, "writing the summary")
        try:
            write_bag_metadata(self.path, self._information())
        except OSError as error:
            self._set_error(f"cannot write {self.path / 'metadata.yaml'}: {error.strerror}")
