"""Malformed plan files and recordings for the reader tests of ``test/security``.

Seeds are real: plan files from ``test/data/saved_plans`` and recordings
written by :class:`clew_ros.recording.RunRecorder` from the messages of
:mod:`helpers.rec_messages` for those plans (zstd, lz4 and uncompressed
chunks). :func:`plan_cases` and :func:`recording_cases` mutate them
deterministically (a seeded :class:`random.Random`): truncations, bit flips,
byte insertions and deletions, records and chunks whose declared lengths are
huge, deeply nested JSON, NaN and Infinity, wrong types, crafted schemas and
type names. Each case is ``(kind, bytes)``.
"""

from __future__ import annotations

import copy
import json
import random
import struct
from collections.abc import Iterator
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
SAVED_PLANS = ROOT / "test" / "data" / "saved_plans"
CONFIG = ROOT / "config"
#: (world file, saved plan) pairs used as seeds.
SEEDS = (("figure1", "figure1_seed0"), ("single_transfer", "single_transfer_seed1"))

_MAGIC = b"\x89MCAP0\r\n"
_OPCODE_CHUNK = 0x06
_OPCODE_SCHEMA = 0x03
_OPCODE_CHANNEL = 0x04
_OPCODE_MESSAGE = 0x05


def world_path(world: str) -> Path:
    return CONFIG / f"{world}.yaml"


def plan_bytes(name: str) -> bytes:
    return (SAVED_PLANS / f"{name}.json").read_bytes()


def write_recording(directory: Path, world: str, plan_name: str, *, compression: str = "zstd") -> Path:
    """A run of ``plan_name`` in ``world`` recorded as the node records it (small chunks: several of them);
    returns the ``.mcap`` file."""
    from clew_ros.planar.world import load_world
    from clew_ros.recording import RunRecorder
    from helpers import rec_messages
    from helpers.rec_landmark_events import with_landmark_events

    plan = json.loads(plan_bytes(plan_name))
    triples = rec_messages.sample_run(load_world(world_path(world)), world_path(world).read_text(), plan)
    triples = with_landmark_events(triples, plan["landmarks"])
    directory.mkdir(parents=True, exist_ok=True)
    recorder = RunRecorder(directory, "e" * 32, chunk_size=2048, compression=compression)
    for topic, msg, time_ns in triples:
        recorder.write(topic, msg, time_ns)
    folder = recorder.close()
    return next(folder.glob("*.mcap"))


# --------------------------------------------------------------------------- generic byte mutations


def truncations(data: bytes, rng: random.Random, count: int) -> Iterator[tuple[str, bytes]]:
    yield "truncated", b""
    for _ in range(count - 1):
        yield "truncated", data[: rng.randrange(1, len(data))]


def bit_flips(data: bytes, rng: random.Random, count: int) -> Iterator[tuple[str, bytes]]:
    for _ in range(count):
        mutated = bytearray(data)
        for _ in range(rng.randint(1, 8)):
            mutated[rng.randrange(len(mutated))] ^= 1 << rng.randrange(8)
        yield "bit flips", bytes(mutated)


def insertions(data: bytes, rng: random.Random, count: int) -> Iterator[tuple[str, bytes]]:
    for _ in range(count):
        at = rng.randrange(len(data))
        if rng.random() < 0.5:
            yield "bytes inserted", data[:at] + rng.randbytes(rng.randint(1, 64)) + data[at:]
        else:
            yield "bytes deleted", data[:at] + data[at + rng.randint(1, 64) :]


# --------------------------------------------------------------------------- plan files


def _plan_documents(document: dict) -> Iterator[tuple[str, object]]:
    """Plan documents whose structure is wrong (as Python values; NaN kept as floats)."""

    def changed(path: tuple, value: object) -> dict:
        copied = copy.deepcopy(document)
        target = copied
        for key in path[:-1]:
            target = target[key]
        target[path[-1]] = value
        return copied

    nan, inf = float("nan"), float("inf")
    for value in (nan, inf, -inf):
        yield "NaN or Infinity", changed(("segments", 0, "waypoints", 0, 0), value)
        yield "NaN or Infinity", changed(("final_object_pose", 1), value)
        yield "NaN or Infinity", changed(("landmarks", 0, "joints", 0), value)
    wrong = ("1.0", True, None, {}, [[1.0]], "x" * 10, 10**400, [])
    for value in wrong:
        yield "wrong types", changed(("segments", 0, "waypoints", 0, 0), value)
        yield "wrong types", changed(("segments", 0, "waypoints"), value)
        yield "wrong types", changed(("landmarks", 0, "object_pose"), value)
        yield "wrong types", changed(("joint_names",), value)
        if value is not None:  # null is a final pose (of a failed plan) and a grasp (of a transit)
            yield "wrong types", changed(("final_object_pose",), value)
            yield "wrong types", changed(("segments", 0, "grasp"), value)
        if not isinstance(value, str):
            yield "wrong types", changed(("message",), value)
    yield "wrong types", changed(("success",), "true")
    yield "wrong types", changed(("segments",), {"kind": "transit"})
    yield "wrong types", changed(("segments", 0, "waypoints"), [[0.0], [0.0, 1.0]])
    yield "unknown schema", changed(("format",), "clew-plan/2")
    yield "unknown schema", changed(("code",), "SOMETHING_ELSE")
    yield "unknown schema", changed(("segments", 0, "kind"), "teleport")
    yield "wrong types", [document]
    yield "wrong types", "clew-plan/1"


def plan_cases(seed: int = 0) -> Iterator[tuple[str, bytes]]:
    """Malformed plan files, from every saved plan of :data:`SEEDS`."""
    rng = random.Random(seed)
    for _world, name in SEEDS:
        data = plan_bytes(name)
        document = json.loads(data)
        for kind, value in _plan_documents(document):
            yield kind, json.dumps(value).encode()
        yield from truncations(data, rng, 25)
        yield from bit_flips(data, rng, 25)
        yield from insertions(data, rng, 20)
        for depth in (1_000, 100_000, 1_000_000):
            yield "nested JSON", b"[" * depth + b"]" * depth
            yield "nested JSON", data.replace(b'"stats": {', b'"stats": {"x": ' + b"[" * depth + b"]" * depth + b", ")
        yield "nested JSON", b'{"a":' * 100_000 + b"1" + b"}" * 100_000
        yield "NaN or Infinity", data.replace(b"0.0", b"NaN", 1)
        yield "NaN or Infinity", data.replace(b"0.0", b"-Infinity", 1)
        yield "NaN or Infinity", data.replace(b"0.0", b"1e999", 1)
        yield "binary", rng.randbytes(512)
        yield "binary", b"\xff\xfe" + data.decode().encode("utf-16-le")
        yield "binary", data[:100] + b"\xc3\x28" + data[100:]
        yield "wrong types", b"9" * 5000


# --------------------------------------------------------------------------- recordings


def records(data: bytes) -> Iterator[tuple[int, int, int]]:
    """``(offset, opcode, length)`` of each top-level record of a whole MCAP file (offset of its opcode)."""
    at = len(_MAGIC)
    while at + 9 <= len(data) - len(_MAGIC):
        opcode, length = struct.unpack_from("<BQ", data, at)
        yield at, opcode, length
        at += 9 + length


def _put(data: bytes, at: int, fmt: str, value: int) -> bytes:
    mutated = bytearray(data)
    struct.pack_into(fmt, mutated, at, value)
    return bytes(mutated)


def crafted_lengths(data: bytes) -> Iterator[tuple[str, bytes]]:
    """Records and chunks whose declared lengths are huge or past the end of the file."""
    huge = (2**31, 2**40, 2**63 - 1, 2**64 - 1, len(data) * 2)
    chunks = [(at, length) for at, opcode, length in records(data) if opcode == _OPCODE_CHUNK]
    for at, opcode, _length in list(records(data))[:6]:
        for value in huge:
            yield "huge record length", _put(data, at + 1, "<Q", value)
        del opcode
    for at, _length in chunks[:3]:
        body = at + 9
        for value in (2**26 + 1, 2**31, 2**40, 2**63 - 1, 2**64 - 1):
            yield "chunk over the size cap", _put(data, body + 16, "<Q", value)  # uncompressed_size
        yield "huge record length", _put(data, body + 28, "<I", 2**32 - 1)  # compression string length
        compression_length = struct.unpack_from("<I", data, body + 28)[0]
        for value in (2**40, 2**64 - 1):
            yield "huge record length", _put(data, body + 32 + compression_length, "<Q", value)  # data length
        yield "chunk size mismatch", _put(data, body + 16, "<Q", struct.unpack_from("<Q", data, body + 16)[0] - 1)
        yield "chunk size mismatch", _put(data, body + 16, "<Q", struct.unpack_from("<Q", data, body + 16)[0] + 7)


def _mcap(schema_name: str, schema_encoding: str, schema_text: bytes, encoding: str, messages: list[bytes]) -> bytes:
    """A small MCAP written with mcap's own writer, on the node's event topic."""
    import io

    from mcap.writer import Writer

    stream = io.BytesIO()
    writer = Writer(stream)
    writer.start(profile="ros2", library="security test")
    schema = writer.register_schema(schema_name, schema_encoding, schema_text)
    channel = writer.register_channel("/clew_planner/events", encoding, schema)
    for number, message in enumerate(messages):
        writer.add_message(channel, log_time=number, data=message, publish_time=number)
    writer.finish()
    return stream.getvalue()


def crafted_recordings() -> Iterator[tuple[str, bytes]]:
    """MCAPs written to be wrong: type names that name other Python modules, schemas that do not parse,
    messages that are not their type, a bomb of a chunk, another profile."""
    import zstandard
    from mcap.records import Chunk

    string = b"string data\n"
    good = b"\x00\x01\x00\x00" + struct.pack("<I", 3) + b"hi\x00\x00"
    for name in ("antigravity/msg/String", "os/msg/Path", "std_msgs/String", "../../etc/msg/X", "std_msgs/msg/x;y"):
        yield "crafted type name", _mcap(name, "ros2msg", string, "cdr", [good])
    yield "crafted schema", _mcap("std_msgs/msg/String", "ros2msg", b"strin data\n", "cdr", [good])
    yield "crafted schema", _mcap("std_msgs/msg/String", "ros2msg", b"Foo[" * 1000 + b" x\n", "cdr", [good])
    yield "crafted schema", _mcap("std_msgs/msg/String", "ros2msg", b"\xff\xfe\n", "cdr", [good])
    yield "crafted schema", _mcap("std_msgs/msg/String", "protobuf", string, "cdr", [good])
    yield "crafted schema", _mcap("std_msgs/msg/String", "ros2msg", string, "json", [good])
    yield "crafted schema", _mcap("std_msgs/msg/String", "ros2msg", b"MyType a\n", "cdr", [good])
    for message in (b"", b"\x00", good[:6], b"\x00\x01\x00\x00" + struct.pack("<I", 2**31) + b"x", b"\x01" * 64):
        yield "message not its type", _mcap("std_msgs/msg/String", "ros2msg", string, "cdr", [message])
    yield "message not its type", _mcap("std_msgs/msg/String", "ros2msg", string, "cdr", [b"\x00\x01\x00\x00\xff\xfe"])

    # a chunk whose zstd frame decompresses to far more than the cap (its frame header says so too)
    zeros = zstandard.ZstdCompressor().compress(b"\x00" * (80 * 2**20))
    for declared in (80 * 2**20, 1000):  # over the cap; under it, but the data holds 80 MiB
        chunk = Chunk(
            compression="zstd",
            data=zeros,
            message_start_time=0,
            message_end_time=0,
            uncompressed_crc=0,
            uncompressed_size=declared,
        )
        yield "decompression bomb", _chunk_file(chunk)
    yield "crafted profile", _mcap("std_msgs/msg/String", "ros2msg", string, "cdr", [good]).replace(b"ros2", b"ros1", 1)


def _chunk_file(chunk) -> bytes:
    """A file holding the MCAP magic, a header, ``chunk`` and nothing more (as if cut after it)."""
    from mcap.data_stream import RecordBuilder
    from mcap.records import Header

    builder = RecordBuilder()
    Header(profile="ros2", library="security test").write(builder)
    chunk.write(builder)
    return _MAGIC + builder.end()


def recording_cases(mcaps: list[bytes], seed: int = 0) -> Iterator[tuple[str, bytes]]:
    """Malformed recordings: the real ``mcaps`` mutated, then the crafted ones."""
    rng = random.Random(seed)
    for data in mcaps:
        yield from truncations(data, rng, 30)
        yield from bit_flips(data, rng, 40)
        yield from insertions(data, rng, 20)
        yield from crafted_lengths(data)
        yield "binary", rng.randbytes(rng.randint(1, 4096))
        yield "binary", _MAGIC + rng.randbytes(2048)
        yield "binary", _MAGIC
    yield from crafted_recordings()
