"""Exact length of a CDR buffer from ``rclpy.serialization.serialize_message``.

With rmw_fastrtps (Jazzy), ``serialize_message`` returns a buffer as long as
the *estimated* serialized size, which can exceed the message by a few bytes
per string, and its alignment padding is not zeroed. Strict readers
(``rosbags``) refuse such trailing bytes. :func:`tidy_cdr` walks the message
(its ``SLOT_TYPES``, XCDR1 plain CDR rules), cuts the buffer to the message's
real length and zeroes the padding, so equal messages record as equal bytes.
"""

from __future__ import annotations

from typing import Any

__all__ = ["tidy_cdr"]

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
