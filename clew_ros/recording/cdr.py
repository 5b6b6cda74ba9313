"""CDR of the recorded messages, by the libraries: rclpy's serializer and rosbags' type store.

**rclpy messages.** :meth:`~clew_ros.recording.RunRecorder.write` serialises
a message with ``rclpy.serialization.serialize_message`` (the rmw's C
serializer, on the caller's thread). With rmw_fastrtps (Jazzy) the alignment
padding of that buffer is not initialised: it carries stray bytes of memory,
so equal messages would record as different bytes, and its length is the
serializer's estimate, which can exceed the message (strict readers refuse the
extra bytes). :func:`canonical_cdr` (on the recorder's writer thread) decodes
and re-encodes the buffer with ``rosbags``
(:func:`~clew_ros.recording.msgdefs.typestore`): same values, zero padding,
exact length.

**TF without tf2_msgs.** The PyPI ROS wheels have no ``tf2_msgs``, yet a
recording must carry ``/tf`` and ``/tf_static`` (interface.md §4), and rosbags
knows Jazzy's ``tf2_msgs/msg/TFMessage``. :func:`tf_message` builds it with
rosbags from a list of transforms (anything with ``parent``, ``child``,
``translation`` and ``rotation``, as :class:`clew_ros.ros.frames.FrameTransform`)
and returns its CDR as a :class:`SerializedMessage`, which the recorder
records as it is and which the node publishes as it is where ``tf2_msgs`` is
installed (rclpy publishes serialized bytes): one message for both.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass
from typing import Protocol

from clew_ros.recording.msgdefs import typestore

__all__ = ["TF_MESSAGE_TYPE", "SerializedMessage", "TransformLike", "canonical_cdr", "tf_message"]

#: The type of ``/tf`` and ``/tf_static``.
TF_MESSAGE_TYPE = "tf2_msgs/msg/TFMessage"


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


def canonical_cdr(type_name: str, data: bytes) -> bytes:
    """``data`` (CDR of a ``type_name`` message, e.g. ``serialize_message``'s) decoded and re-encoded by rosbags.

    The decoding stops at the message's end: rmw_fastrtps may size the buffer
    by its estimate, a few bytes past the message (rosbags'
    ``Typestore.deserialize_cdr`` refuses those). Raises what rosbags raises for
    a type it does not know (``TypesysError``; see
    :func:`~clew_ros.recording.msgdefs.learn_types`) or bytes it cannot decode
    (``struct.error``, ``ValueError``).
    """
    store = typestore()
    definition = store.get_msgdef(type_name)
    little_endian = data[1:2] == b"\x01"
    deserialize = definition.deserialize_cdr_le if little_endian else definition.deserialize_cdr_be
    message, _end = deserialize(memoryview(data)[4:], 0, definition.cls, store)
    return bytes(store.serialize_cdr(message, type_name, little_endian=little_endian))


def tf_message(transforms: Iterable[TransformLike], stamp_ns: int) -> SerializedMessage:
    """``tf2_msgs/msg/TFMessage`` holding ``transforms``, each stamped ``stamp_ns`` (ns since the epoch), in CDR.

    Each edge is a ``geometry_msgs/TransformStamped``: header stamp and
    ``frame_id`` = ``parent``, ``child_frame_id`` = ``child``, translation,
    rotation ``x, y, z, w``.
    """
    store = typestore()
    types = store.types
    time = types["builtin_interfaces/msg/Time"]
    header = types["std_msgs/msg/Header"]
    stamped = types["geometry_msgs/msg/TransformStamped"]
    transform = types["geometry_msgs/msg/Transform"]
    vector = types["geometry_msgs/msg/Vector3"]
    quaternion = types["geometry_msgs/msg/Quaternion"]
    sec, nanosec = divmod(int(stamp_ns), 1_000_000_000)
    message = types[TF_MESSAGE_TYPE](
        transforms=[
            stamped(
                header=header(stamp=time(sec=sec, nanosec=nanosec), frame_id=edge.parent),
                child_frame_id=edge.child,
                transform=transform(
                    translation=vector(*map(float, edge.translation)),
                    rotation=quaternion(*map(float, edge.rotation)),
                ),
            )
            for edge in transforms
        ]
    )
    return SerializedMessage(TF_MESSAGE_TYPE, bytes(store.serialize_cdr(message, TF_MESSAGE_TYPE, little_endian=True)))
