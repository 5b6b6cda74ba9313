"""Reading recordings back, whole or cut short, without ROS.

:class:`Recording` reads a run directory (or one ``.mcap`` file) with the MCAP
stream reader, so a file whose writer was killed reads up to its last
complete chunk; messages decode with ``mcap_ros2`` from the schemas stored in
the file. :func:`recover_recording` rewrites such a file whole (summary,
index, ``metadata.yaml``) so that ``ros2 bag info/play`` and seeking readers
accept it.
"""

from __future__ import annotations

import struct
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, BinaryIO

import yaml

from clew_ros.recording.errors import RecordingError
from clew_ros.recording.recorder import bag_metadata, default_offered_qos, write_bag_metadata

__all__ = ["RecordedMessage", "Recording", "TopicInfo", "find_mcap", "recover_recording"]


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


def find_mcap(path: str | Path) -> Path:
    """The MCAP file of a recording: ``path`` itself, or the one in a run directory."""
    path = Path(path)
    if path.is_file():
        if path.suffix != ".mcap":
            raise RecordingError(f"{path} is not an .mcap file or a recording directory")
        return path
    if not path.is_dir():
        raise RecordingError(f"recording {path} does not exist")
    metadata = path / "metadata.yaml"
    if metadata.is_file():
        try:
            info = yaml.safe_load(metadata.read_text())["rosbag2_bagfile_information"]
            names: list[str] = [n for n in info.get("relative_file_paths", []) if str(n).endswith(".mcap")]
        except (OSError, yaml.YAMLError, KeyError, TypeError) as error:
            raise RecordingError(f"{metadata} is not rosbag2 metadata ({error})") from None
        if len(names) == 1 and (path / names[0]).is_file():
            return path / names[0]
    files = sorted(path.glob("*.mcap"))
    if len(files) != 1:
        raise RecordingError(f"{path} should hold exactly one .mcap file, found {len(files)}")
    return files[0]


def _yaml_or_none(text: str) -> Any:
    """``text`` parsed as YAML, or ``None`` if it is not YAML."""
    try:
        return yaml.safe_load(text)
    except yaml.YAMLError:
        return None


def _qos_list(text: str | None, topic: str) -> list[dict[str, Any]]:
    if text:
        value = _yaml_or_none(text)
        if isinstance(value, list) and all(isinstance(v, dict) for v in value):
            return value
    return [default_offered_qos(topic)]


class Recording:
    """A recording read into memory (recordings of one run are small).

    ``complete`` is False when the file stops before its footer (writer
    killed); everything up to the last complete chunk is still read.
    """

    def __init__(self, path: str | Path) -> None:
        self.path = Path(path)
        self.mcap_path = find_mcap(self.path)
        self.complete = False
        self.schemas: dict[int, Any] = {}
        self.channels: dict[int, Any] = {}
        self.bag_metadata: dict[str, Any] | None = None
        self._messages: list[RecordedMessage] = []
        try:
            stream = self.mcap_path.open("rb")
        except OSError as error:
            raise RecordingError(f"cannot read {self.mcap_path}: {error.strerror}") from None
        with stream:
            self._read(stream)
        self._messages.sort(key=lambda m: m.log_time_ns)  # stable: file order within equal times
        self._decoders: dict[int, Callable[[bytes], Any]] = {}

    def _read(self, stream: BinaryIO) -> None:
        """Every record of ``stream``, up to its end or, cut short, up to the last complete record."""
        from mcap.exceptions import InvalidMagic, McapError
        from mcap.records import Channel, Footer, Header, Message, Metadata, Schema
        from mcap.stream_reader import StreamReader

        started = False
        try:
            for record in StreamReader(stream).records:
                started = True
                if isinstance(record, Message):
                    self._add_message(record)
                elif isinstance(record, Schema):
                    self.schemas[record.id] = record
                elif isinstance(record, Channel):
                    self.channels[record.id] = record
                elif isinstance(record, Metadata) and record.name == "rosbag2":
                    self.bag_metadata = _yaml_or_none(record.metadata.get("serialized_metadata", ""))
                elif isinstance(record, Footer):
                    self.complete = True
                elif isinstance(record, Header) and record.profile not in ("ros2", ""):
                    raise RecordingError(f"{self.mcap_path} has MCAP profile {record.profile!r}, not 'ros2'")
        except InvalidMagic:
            if not started:
                raise RecordingError(f"{self.mcap_path} is not an MCAP file") from None
        except (McapError, struct.error, EOFError, ValueError):
            if not started:
                raise RecordingError(f"{self.mcap_path} is empty or cut before its header") from None
            # cut short: keep what was read up to the last complete record

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
        """The messages on ``topic`` decoded from the stored schema (``mcap_ros2``)."""
        from mcap_ros2.decoder import DecoderFactory

        channel = next((c for c in self.channels.values() if c.topic == topic), None)
        if channel is None:
            return []
        decoder = self._decoders.get(channel.id)
        if decoder is None:
            schema = self.schemas.get(channel.schema_id)
            decoder = DecoderFactory().decoder_for(channel.message_encoding, schema)
            if decoder is None:
                raise RecordingError(
                    f"{self.mcap_path}: cannot decode {topic} "
                    f"({channel.message_encoding!r} with schema {schema.name if schema else None})"
                )
            self._decoders[channel.id] = decoder
        return [decoder(m.data) for m in self._messages if m.topic == topic]

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
