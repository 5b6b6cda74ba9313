"""CDR for recordings: rclpy's buffers tidied, and ``tf2_msgs/msg/TFMessage`` encoded by hand.

**Tidy.**
With rmw_fastrtps (Jazzy), ``serialize_message`` returns a buffer as long as
the *estimated* serialized size, which can exceed the message by a few bytes
per string, and its alignment padding is not zeroed. Strict readers
(``rosbags``) refuse such trailing bytes. :func:`tidy_cdr` walks the message
(its ``SLOT_TYPES``, XCDR1 plain CDR rules), cuts the buffer to the message's
real length and zeroes the padding, so equal messages record as equal bytes.

**TF without tf2_msgs.** The PyPI ROS wheels have no ``tf2_msgs``, yet a
recording must carry ``/tf`` and ``/tf_static`` (interface.md §4).
:func:`tf_message` encodes a list of transforms (anything with ``parent``,
``child``, ``translation`` and ``rotation``, as
:class:`clew_ros.node.frames.FrameTransform`) as the CDR of a
``TFMessage`` and returns a :class:`SerializedMessage` that
:meth:`clew_ros.recording.RunRecorder.write` records as it is; its schema
text comes from :mod:`clew_ros.recording.msgdefs`.
"""

from __future__ import annotations

import struct
from collections.abc import Iterable
from dataclasses import dataclass
from typing import Any, Protocol

__all__ = ["TF_MESSAGE_TYPE", "SerializedMessage", "TransformLike", "tf_message", "tidy_cdr"]

#: The type of ``/tf`` and ``/tf_static``.
TF_MESSAGE_TYPE = "tf2_msgs/msg/TFMessage"
#: CDR little-endian (XCDR1 plain CDR), the encapsulation rmw_fastrtps writes.
_ENCAPSULATION = b"\x00\x01\x00\x00"

_SIZES = {
    "boolean": 1,
    "octet": 1,
    "char": 1,
    "uint8": 1,
    "int8": 1,
    "int16": 2,
    "uint16": 2,
    "wchar": 2,
    "int32": 4,
    "uint32": 4,
    "float": 4,
    "int64": 8,
    "uint64": 8,
    "double": 8,
    "long double": 16,
}


class _Walker:
    """Follows the CDR layout of a message; offsets count from the end of the 4-byte encapsulation."""

    def __init__(self) -> None:
        from rosidl_parser import definition

        self.d = definition
        self.offset = 0
        self.padding: list[tuple[int, int]] = []

    def align(self, size: int) -> None:
        size = min(size, 8)
        gap = (-self.offset) % size
        if gap:
            self.padding.append((self.offset, gap))
            self.offset += gap

    def message(self, msg: Any) -> None:
        fields = list(msg.get_fields_and_field_types())
        types = type(msg).SLOT_TYPES
        if not fields:  # empty messages hold one uint8
            self.offset += 1
            return
        for name, slot_type in zip(fields, types, strict=True):  # both generated from the same .msg
            self.value(getattr(msg, name), slot_type)

    def value(self, value: Any, slot_type: Any) -> None:
        d = self.d
        if isinstance(slot_type, d.BasicType):
            size = _SIZES[slot_type.typename]
            self.align(size)
            self.offset += size
        elif isinstance(slot_type, d.AbstractString):
            self.align(4)
            self.offset += 4 + len(value.encode("utf-8")) + 1
        elif isinstance(slot_type, d.NamespacedType):
            self.message(value)
        elif isinstance(slot_type, d.AbstractNestedType):
            if isinstance(slot_type, d.AbstractSequence):
                self.align(4)
                self.offset += 4
            element = slot_type.value_type
            count = len(value)
            if isinstance(element, d.BasicType):
                if count:
                    size = _SIZES[element.typename]
                    self.align(size)
                    self.offset += size * count
            else:
                for item in value:
                    self.value(item, element)
        else:  # wide strings and anything unforeseen: give up, keep the buffer as it is
            raise NotImplementedError(type(slot_type).__name__)


def tidy_cdr(msg: Any, data: bytes) -> bytes:
    """``data`` (``serialize_message(msg)``) cut to the message's length, padding zeroed.

    Returns ``data`` unchanged when the layout cannot be followed or does not fit.
    """
    walker = _Walker()
    try:
        walker.message(msg)
    except (NotImplementedError, AttributeError, KeyError, TypeError, ValueError, ImportError):
        return data
    end = 4 + walker.offset
    if end > len(data):
        return data
    out = bytearray(data[:end]) + bytes((-end) % 4)  # DDS payloads end on a 4-byte boundary
    for start, gap in walker.padding:
        out[4 + start : 4 + start + gap] = bytes(gap)
    return bytes(out)


# --------------------------------------------------------------------------- messages encoded here


@dataclass(frozen=True)
class SerializedMessage:
    """A message already in CDR (with its 4-byte encapsulation header), of type ``type_name`` (``pkg/msg/Type``)."""

    type_name: str
    data: bytes


class TransformLike(Protocol):
    """One TF edge: the pose of frame ``child`` in frame ``parent``."""

    @property
    def parent(self) -> str: ...
    @property
    def child(self) -> str: ...
    @property
    def translation(self) -> tuple[float, float, float]: ...
    @property
    def rotation(self) -> tuple[float, float, float, float]: ...


class _Encoder:
    """Plain CDR, little endian; alignment counts from the end of the encapsulation header."""

    def __init__(self) -> None:
        self.buffer = bytearray(_ENCAPSULATION)

    def _align(self, size: int) -> None:
        self.buffer += bytes((-(len(self.buffer) - 4)) % size)

    def uint32(self, value: int) -> None:
        self._align(4)
        self.buffer += struct.pack("<I", value)

    def int32(self, value: int) -> None:
        self._align(4)
        self.buffer += struct.pack("<i", value)

    def string(self, value: str) -> None:
        data = value.encode("utf-8") + b"\x00"
        self.uint32(len(data))
        self.buffer += data

    def doubles(self, values: Iterable[float]) -> None:
        self._align(8)
        for value in values:
            self.buffer += struct.pack("<d", float(value))

    def finish(self) -> bytes:
        self.buffer += bytes((-len(self.buffer)) % 4)  # DDS payloads end on a 4-byte boundary
        return bytes(self.buffer)


def tf_message(transforms: Iterable[TransformLike], stamp_ns: int) -> SerializedMessage:
    """``tf2_msgs/msg/TFMessage`` holding ``transforms``, each stamped ``stamp_ns`` (ns since the epoch).

    The bytes are those rmw_fastrtps would send: a ``geometry_msgs/TransformStamped``
    sequence (header stamp and ``frame_id`` = ``parent``, ``child_frame_id``,
    translation, rotation ``x, y, z, w``).
    """
    edges = list(transforms)
    sec, nanosec = divmod(int(stamp_ns), 1_000_000_000)
    encoder = _Encoder()
    encoder.uint32(len(edges))
    for edge in edges:
        encoder.int32(sec)
        encoder.uint32(nanosec)
        encoder.string(edge.parent)
        encoder.string(edge.child)
        encoder.doubles(edge.translation)
        encoder.doubles(edge.rotation)
    return SerializedMessage(TF_MESSAGE_TYPE, encoder.finish())
