"""Reading recordings back, whole or cut short, without ROS.

:class:`Recording` reads a run directory (or one ``.mcap`` file) with the MCAP
stream reader, so a file whose writer was killed reads up to its last
complete chunk; messages decode with ``mcap_ros2`` from the schemas stored in
the file. A file is untrusted input: it is read within
:class:`RecordingLimits` (each chunk's declared size is checked before it is
decompressed, and it is decompressed no further), with mcap's CRC checks on;
whatever is wrong with it is a :class:`RecordingError` naming the file.
:func:`recover_recording` rewrites a file cut short whole (summary, index,
``metadata.yaml``) so that ``ros2 bag info/play`` and seeking readers accept
it.
"""

from __future__ import annotations

import contextlib
import io
import struct
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import yaml

from clew_ros.core.files import FileRefusedError, read_regular_file, yaml_error_place
from clew_ros.recording.errors import RecordingError
from clew_ros.recording.recorder import bag_metadata, default_offered_qos, write_bag_metadata

__all__ = ["RecordedMessage", "Recording", "RecordingLimits", "TopicInfo", "find_mcap", "recover_recording"]


@dataclass(frozen=True)
class TopicInfo:
    """One recorded topic: its type, message count and offered QoS (rosbag2 v9 dicts)."""

    name: str
    type_name: str
    message_count: int
    offered_qos_profiles: list[dict[str, Any]] = field(default_factory=list)
    type_description_hash: str = ""

    @property
    def transient_local(self) -> bool:
        return any(str(q.get("durability", "")).lower() == "transient_local" for q in self.offered_qos_profiles)


@dataclass(frozen=True)
class RecordedMessage:
    """One message as stored: CDR bytes and the log time (ns)."""

    topic: str
    type_name: str
    log_time_ns: int
    data: bytes


@dataclass(frozen=True)
class RecordingLimits:
    """What :class:`Recording` reads at most: beyond these a file is refused as corrupt or crafted.

    A run's recording is a few megabytes (the recorder writes 64 KiB chunks), so these leave a
    thousandfold margin while keeping a crafted file from taking the reader's memory.
    """

    #: Bytes of the ``.mcap`` file (it is read into memory whole).
    max_file_bytes: int = 1024 * 2**20
    #: Declared uncompressed bytes of one chunk, checked before it is decompressed (decompression bomb).
    max_chunk_bytes: int = 64 * 2**20
    #: Uncompressed bytes of all chunks together.
    max_total_bytes: int = 1024 * 2**20
    #: Bytes of the run directory's ``metadata.yaml`` (rosbag2 writes a few kilobytes).
    max_metadata_bytes: int = 16 * 2**20


def find_mcap(path: str | Path, *, limits: RecordingLimits | None = None) -> Path:
    """The MCAP file of a recording: ``path`` itself, or the one in a run directory (the one its
    ``metadata.yaml`` names, when that is a file of the directory)."""
    limit = (limits or RecordingLimits()).max_metadata_bytes
    path = Path(path)
    if path.is_file():
        if path.suffix != ".mcap":
            raise RecordingError(f"{path} is not an .mcap file or a recording directory")
        return path
    if not path.is_dir():
        why = "is not a regular file (a device, a pipe)" if path.exists() else "does not exist"
        raise RecordingError(f"recording {path} {why}")
    metadata = path / "metadata.yaml"
    if metadata.is_file():
        try:
            text = read_regular_file(metadata, limit, "RecordingLimits.max_metadata_bytes")
            info = yaml.safe_load(text.decode("utf-8"))["rosbag2_bagfile_information"]
            names: list[str] = [n for n in info.get("relative_file_paths", []) if str(n).endswith(".mcap")]
        except FileRefusedError as error:
            raise RecordingError(f"{metadata} is not rosbag2 metadata ({error})") from None
        except yaml.YAMLError as error:
            raise RecordingError(f"{metadata} is not rosbag2 metadata ({yaml_error_place(error)})") from None
        except (KeyError, TypeError, AttributeError, ValueError, RecursionError) as error:
            raise RecordingError(f"{metadata} is not rosbag2 metadata ({type(error).__name__})") from None
        # only a file of this folder: a name with a folder in it (``../``, absolute) is not followed
        plain = len(names) == 1 and isinstance(names[0], str) and Path(names[0]).name == names[0]
        if plain and (path / names[0]).is_file():
            return path / names[0]
    files = sorted(path.glob("*.mcap"))
    if len(files) != 1:
        raise RecordingError(f"{path} should hold exactly one .mcap file, found {len(files)}")
    return files[0]


def _yaml_or_none(text: str) -> Any:
    """``text`` parsed as YAML, or ``None`` if it is not YAML (or nests deeper than the parser goes)."""
    try:
        return yaml.safe_load(text)
    except (yaml.YAMLError, RecursionError, ValueError):
        return None


def _schema_name(schema: Any) -> str:
    return "none" if schema is None else repr(schema.name[:80])


class _ChunkError(Exception):
    """A chunk cannot be read (bad compression, CRC or records): the file is read up to it."""


def _decompressed(compression: str, data: bytes, size: int) -> bytes:
    """``data`` decompressed, never more than ``size`` + 1 bytes; :class:`_ChunkError` unless it is ``size`` bytes."""
    if compression == "":
        out = data
    elif compression == "zstd":
        import zstandard

        try:
            with zstandard.ZstdDecompressor().stream_reader(data, read_across_frames=True) as stream:
                parts: list[bytes] = []
                total = 0
                while total <= size and (part := stream.read(size + 1 - total)):
                    parts.append(part)
                    total += len(part)
            out = b"".join(parts)
        except zstandard.ZstdError as error:
            raise _ChunkError(f"a chunk's zstd data is corrupt ({error})") from None
    elif compression == "lz4":
        import lz4.frame

        decompressor = lz4.frame.LZ4FrameDecompressor()
        try:
            out = decompressor.decompress(data, max_length=size + 1)
        except RuntimeError as error:  # what lz4 raises for corrupt frames
            raise _ChunkError(f"a chunk's lz4 data is corrupt ({error})") from None
    else:
        raise _ChunkError(f"a chunk has compression {compression!r:.40}, not zstd, lz4 or none")
    if len(out) != size:
        raise _ChunkError(f"a chunk holds {'more' if len(out) > size else 'fewer'} bytes than the {size} it declares")
    return out


def _qos_list(text: str | None, topic: str) -> list[dict[str, Any]]:
    if text:
        value = _yaml_or_none(text)
        if isinstance(value, list) and all(isinstance(v, dict) for v in value):
            return value
    return [default_offered_qos(topic)]


class Recording:
    """A recording read into memory (recordings of one run are small).

    ``complete`` is False when the file stops before its footer (writer
    killed) or a chunk fails its CRC or cannot be read (``problem`` says
    which); everything up to the last good chunk is still read. A file that
    is not an MCAP recording, or declares a record or chunk over
    :class:`RecordingLimits`, raises :class:`RecordingError` naming the file.
    """

    def __init__(self, path: str | Path, *, limits: RecordingLimits | None = None) -> None:
        self.path = Path(path)
        self.limits = limits or RecordingLimits()
        self.mcap_path = find_mcap(self.path, limits=self.limits)
        self.complete = False
        #: Why reading stopped before the footer (``None``: it did not, or the file just ends early).
        self.problem: str | None = None
        self.schemas: dict[int, Any] = {}
        self.channels: dict[int, Any] = {}
        self.bag_metadata: dict[str, Any] | None = None
        self._messages: list[RecordedMessage] = []
        self._decompressed = 0
        try:
            data = read_regular_file(self.mcap_path, self.limits.max_file_bytes, "RecordingLimits.max_file_bytes")
        except FileRefusedError as error:
            raise RecordingError(f"cannot read {self.mcap_path}: {error}; not read") from None
        self._read(data)
        self._messages.sort(key=lambda m: m.log_time_ns)  # stable: file order within equal times
        self._decoders: dict[int, Callable[[bytes], Any]] = {}

    def _read(self, data: bytes) -> None:
        """Every record of ``data``, up to its end or, cut short, up to the last complete record.

        mcap's :class:`~mcap.stream_reader.StreamReader` parses the records, checks every length against
        the file's size and every CRC; chunks are decompressed here, each checked against its declared size
        (and the limits) before and after.
        """
        from mcap.exceptions import InvalidMagic, McapError, RecordLengthLimitExceeded
        from mcap.records import Chunk
        from mcap.stream_reader import StreamReader

        started = False
        reader = StreamReader(io.BytesIO(data), emit_chunks=True, validate_crcs=True, record_size_limit=len(data))
        try:
            for record in reader.records:
                started = True
                if isinstance(record, Chunk):
                    for inner in self._chunk_records(record):
                        self._take(inner)
                else:
                    self._take(record)
        except InvalidMagic:
            if not started:
                raise RecordingError(f"{self.mcap_path} is not an MCAP file") from None
            self.problem = "its end is not an MCAP footer"
        except RecordLengthLimitExceeded:
            if not started:
                raise RecordingError(f"{self.mcap_path} is not an MCAP file (its header is corrupt)") from None
            # a record longer than the file: the file was cut inside it (writer killed)
        except (McapError, struct.error, EOFError, ValueError, OverflowError, _ChunkError) as error:
            if not started:
                raise RecordingError(f"{self.mcap_path} is empty or cut before its header") from None
            if not isinstance(error, McapError | struct.error | EOFError):
                self.problem = str(error)
            # cut short or corrupt further on: keep what was read up to the last complete record

    def _chunk_records(self, chunk: Any) -> list[Any]:
        """The records of ``chunk``, decompressed within :class:`RecordingLimits`; :class:`RecordingError`
        when it declares more than they allow, :class:`_ChunkError` when it is corrupt."""
        from mcap.records import Chunk
        from mcap.stream_reader import breakup_chunk

        size = chunk.uncompressed_size
        if size > self.limits.max_chunk_bytes:
            raise RecordingError(
                f"{self.mcap_path}: a chunk declares {size} bytes uncompressed, over the limit of "
                f"{self.limits.max_chunk_bytes} (a corrupt or crafted file); not read"
            )
        if self._decompressed + size > self.limits.max_total_bytes:
            raise RecordingError(
                f"{self.mcap_path}: its chunks hold more than {self.limits.max_total_bytes} bytes uncompressed; "
                "not read"
            )
        data = _decompressed(chunk.compression, chunk.data, size)
        self._decompressed += len(data)
        plain = Chunk(
            compression="",
            data=data,
            message_start_time=chunk.message_start_time,
            message_end_time=chunk.message_end_time,
            uncompressed_crc=chunk.uncompressed_crc,
            uncompressed_size=size,
        )
        try:
            records: list[Any] = breakup_chunk(plain, validate_crc=True)
        except (ValueError, struct.error) as error:  # mcap's CRCValidationError is a ValueError
            raise _ChunkError(f"a chunk is corrupt ({error})") from None
        return records

    def _take(self, record: Any) -> None:
        """Keep what a record of the file says."""
        from mcap.records import Channel, Footer, Header, Message, Metadata, Schema

        if isinstance(record, Message):
            self._add_message(record)
        elif isinstance(record, Schema):
            self.schemas[record.id] = record
        elif isinstance(record, Channel):
            self.channels[record.id] = record
        elif isinstance(record, Metadata) and record.name == "rosbag2":
            metadata = _yaml_or_none(record.metadata.get("serialized_metadata", ""))
            self.bag_metadata = metadata if isinstance(metadata, dict) else None
        elif isinstance(record, Footer):
            self.complete = True
        elif isinstance(record, Header) and record.profile not in ("ros2", ""):
            raise RecordingError(f"{self.mcap_path} has MCAP profile {record.profile!r:.80}, not 'ros2'")

    def _add_message(self, record: Any) -> None:
        """An MCAP message record, kept if its channel came before it."""
        channel = self.channels.get(record.channel_id)
        if channel is None:
            return
        schema = self.schemas.get(channel.schema_id)
        self._messages.append(
            RecordedMessage(channel.topic, schema.name if schema else "", record.log_time, bytes(record.data))
        )

    # ------------------------------------------------------------------ contents

    @property
    def topics(self) -> dict[str, TopicInfo]:
        """Every channel with at least one readable message, by topic name."""
        counts: dict[str, int] = {}
        for message in self._messages:
            counts[message.topic] = counts.get(message.topic, 0) + 1
        result = {}
        for channel in self.channels.values():
            if channel.topic in result:
                continue
            schema = self.schemas.get(channel.schema_id)
            result[channel.topic] = TopicInfo(
                channel.topic,
                schema.name if schema else "",
                counts.get(channel.topic, 0),
                _qos_list(channel.metadata.get("offered_qos_profiles"), channel.topic),
                channel.metadata.get("topic_type_hash", ""),
            )
        return result

    def messages(self, topics: Iterable[str] | None = None) -> list[RecordedMessage]:
        """Messages in log-time order, all or those on ``topics``."""
        if topics is None:
            return list(self._messages)
        wanted = set(topics)
        return [m for m in self._messages if m.topic in wanted]

    def decoded(self, topic: str) -> list[Any]:
        """The messages on ``topic`` decoded from the stored schema (``mcap_ros2``); :class:`RecordingError`
        names the file and topic when the schema or a message cannot be decoded."""
        from mcap_ros2.decoder import DecoderFactory

        channel = next((c for c in self.channels.values() if c.topic == topic), None)
        if channel is None:
            return []
        schema = self.schemas.get(channel.schema_id)
        decoder = self._decoders.get(channel.id)
        if decoder is None:
            try:
                with contextlib.redirect_stderr(io.StringIO()):  # mcap_ros2's parser prints what it refuses
                    decoder = DecoderFactory().decoder_for(channel.message_encoding, schema)
            except Exception as error:  # noqa: BLE001 - mcap_ros2 raises many types for a schema it cannot parse
                raise RecordingError(
                    f"{self.mcap_path}: cannot decode {topic}: its schema {_schema_name(schema)} does not parse "
                    f"({type(error).__name__})"
                ) from None
            if decoder is None:
                raise RecordingError(
                    f"{self.mcap_path}: cannot decode {topic} "
                    f"({channel.message_encoding!r:.40} with schema {_schema_name(schema)})"
                )
            self._decoders[channel.id] = decoder
        decoded = []
        for number, message in enumerate(m for m in self._messages if m.topic == topic):
            try:
                decoded.append(decoder(message.data))
            except Exception as error:  # noqa: BLE001 - a CDR reader fails in many ways on bytes that are not its type
                raise RecordingError(
                    f"{self.mcap_path}: message {number} on {topic} is not a {_schema_name(schema)} "
                    f"({type(error).__name__})"
                ) from None
        return decoded

    def last(self, topic: str) -> Any | None:
        """The last message on ``topic``, decoded, or ``None``."""
        messages = self.decoded(topic)
        return messages[-1] if messages else None


def recover_recording(path: str | Path) -> Path:
    """Make a recording cut short (writer killed) whole again; return its directory.

    Reads everything up to the last complete chunk, writes it to a new MCAP
    (with summary and index) in place of the old file, which is kept as
    ``<name>.mcap.truncated``, and writes ``metadata.yaml``. A complete
    recording with ``metadata.yaml`` is left as it is.
    """
    from mcap.writer import Writer

    recording = Recording(path)
    directory = recording.mcap_path.parent
    if recording.complete and (directory / "metadata.yaml").is_file():
        return directory
    target = recording.mcap_path
    temporary = target.with_name(target.name + ".recovering")
    topics = recording.topics
    try:
        with temporary.open("wb") as stream:
            writer = Writer(stream)
            writer.start(profile="ros2", library="clew_ros recover_recording")
            schema_ids = {
                sid: writer.register_schema(s.name, s.encoding, s.data) for sid, s in recording.schemas.items()
            }
            channel_ids = {}
            for channel in recording.channels.values():
                if channel.topic not in channel_ids:
                    channel_ids[channel.topic] = writer.register_channel(
                        channel.topic,
                        channel.message_encoding,
                        schema_ids.get(channel.schema_id, 0),
                        dict(channel.metadata),
                    )
            for sequence, message in enumerate(recording.messages()):
                writer.add_message(
                    channel_ids[message.topic],
                    log_time=message.log_time_ns,
                    data=message.data,
                    publish_time=message.log_time_ns,
                    sequence=sequence,
                )
            writer.finish()  # type: ignore[no-untyped-call]  # (mcap leaves finish() unannotated)
        if not recording.complete:
            target.replace(target.with_name(target.name + ".truncated"))
        temporary.replace(target)
    except OSError as error:
        raise RecordingError(f"cannot rewrite {target}: {error.strerror}") from None
    messages = recording.messages()
    start = messages[0].log_time_ns if messages else 0
    end = messages[-1].log_time_ns if messages else 0
    custom = {"recovered": "true" if not recording.complete else "false"}
    if recording.bag_metadata and isinstance(recording.bag_metadata.get("custom_data"), dict):
        custom = {**recording.bag_metadata["custom_data"], **custom}
    information = bag_metadata(
        target.name,
        [
            {
                "name": t.name,
                "type": t.type_name,
                "offered_qos_profiles": t.offered_qos_profiles,
                "type_description_hash": t.type_description_hash,
                "message_count": t.message_count,
            }
            for t in topics.values()
        ],
        start,
        end - start,
        custom_data=custom,
    )
    write_bag_metadata(directory, information)
    return directory
