"""A Foxglove WebSocket client for tests: subscribes to every channel and decodes what it receives.

Written from the protocol as Foxglove documents it (the ``foxglove.sdk.v1``
subprotocol): the server sends ``serverInfo`` and ``advertise`` as JSON text;
the client sends ``subscribe``; each message then arrives as a binary frame
``0x01, subscription id (u32 LE), log time (u64 LE ns), payload``. Payloads
are decoded from the schema the server advertised, as the Foxglove app does:
protobuf from the base64 ``FileDescriptorSet`` (with ``google.protobuf``),
JSON as JSON. Needs ``websockets`` and ``protobuf`` (the ``live`` extra).
"""

from __future__ import annotations

import base64
import json
import struct
import time
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from typing import Any

from google.protobuf import descriptor_pb2, descriptor_pool, json_format, message_factory
from websockets.sync.client import ClientConnection, connect

SUBPROTOCOL = "foxglove.sdk.v1"
MESSAGE_DATA = 0x01


@dataclass
class Received:
    """One decoded message: its topic, schema name, log time (ns) and content (a dict)."""

    topic: str
    schema: str
    log_time_ns: int
    data: dict[str, Any]


@dataclass
class FoxgloveClient:
    """A connection that has subscribed to every advertised channel; :meth:`receive` decodes messages."""

    ws: ClientConnection
    server_info: dict[str, Any]
    channels: dict[int, dict[str, Any]]  # channel id -> its advertisement
    decoders: dict[int, Any] = field(default_factory=dict)  # subscription id -> payload -> dict
    topics: dict[int, tuple[str, str]] = field(default_factory=dict)  # subscription id -> (topic, schema name)

    @classmethod
    @contextmanager
    def connect(cls, port: int, *, channels: int, timeout_s: float = 10.0) -> Iterator[FoxgloveClient]:
        """``with FoxgloveClient.connect(port, channels=n) as client:`` connects to ``ws://127.0.0.1:<port>``,
        waits for ``n`` advertised channels and subscribes to all; the connection closes at the end.

        No keepalive pings: a client in the planner's process may not answer in time while it plans.
        """
        uri = f"ws://127.0.0.1:{port}"
        with connect(uri, subprotocols=[SUBPROTOCOL], open_timeout=timeout_s, ping_interval=None) as ws:
            assert ws.subprotocol == SUBPROTOCOL
            server_info = json.loads(ws.recv(timeout=timeout_s))
            assert server_info["op"] == "serverInfo"
            advertised: dict[int, dict[str, Any]] = {}
            deadline = time.monotonic() + timeout_s
            while len(advertised) < channels:
                message = json.loads(ws.recv(timeout=max(0.1, deadline - time.monotonic())))
                if message["op"] == "advertise":
                    advertised.update({c["id"]: c for c in message["channels"]})
            client = cls(ws, server_info, advertised)
            subscriptions = []
            for subscription_id, (channel_id, channel) in enumerate(sorted(advertised.items()), start=1):
                client.decoders[subscription_id] = _decoder(channel)
                client.topics[subscription_id] = (channel["topic"], channel["schemaName"])
                subscriptions.append({"id": subscription_id, "channelId": channel_id})
            ws.send(json.dumps({"op": "subscribe", "subscriptions": subscriptions}))
            yield client

    def receive(self, timeout_s: float = 10.0) -> Received:
        """The next message of a subscribed channel, decoded (JSON status and other text ops are skipped)."""
        deadline = time.monotonic() + timeout_s
        while True:
            frame = self.ws.recv(timeout=max(0.01, deadline - time.monotonic()))
            if isinstance(frame, str) or frame[0] != MESSAGE_DATA:
                continue
            subscription_id, log_time = struct.unpack_from("<IQ", frame, 1)
            topic, schema = self.topics[subscription_id]
            return Received(topic, schema, log_time, self.decoders[subscription_id](frame[13:]))

    def receive_until(self, done: Any, timeout_s: float = 30.0) -> list[Received]:
        """Messages until ``done(message)`` is true for one (included); raises ``TimeoutError`` after ``timeout_s``."""
        deadline = time.monotonic() + timeout_s
        out = []
        while True:
            left = deadline - time.monotonic()
            if left <= 0:
                raise TimeoutError(f"no message ended the wait in {timeout_s} s; got {len(out)}")
            message = self.receive(left)
            out.append(message)
            if done(message):
                return out


def _decoder(channel: dict[str, Any]) -> Any:
    """payload -> dict for an advertised channel, from the schema it advertises."""
    if channel["encoding"] == "json":
        assert channel["schemaEncoding"] == "jsonschema"
        json.loads(channel["schema"])  # the schema itself is JSON
        return json.loads
    assert channel["encoding"] == "protobuf", channel["encoding"]
    assert channel["schemaEncoding"] == "protobuf"
    return protobuf_decoder(channel["schemaName"], base64.b64decode(channel["schema"]))


def protobuf_decoder(schema_name: str, descriptor_set: bytes) -> Any:
    """payload -> dict for protobuf message ``schema_name`` of a serialised ``FileDescriptorSet``
    (fields at their defaults included, names as in the .proto)."""
    files = descriptor_pb2.FileDescriptorSet.FromString(descriptor_set).file
    pool = descriptor_pool.DescriptorPool()
    pending = list(files)
    while pending:  # dependencies first, whatever the set's order
        added = [f for f in pending if all(_has_file(pool, d) for d in f.dependency)]
        assert added, f"unresolvable imports in {[f.name for f in pending]}"
        for proto in added:
            pool.Add(proto)
            pending.remove(proto)
    message_class = message_factory.GetMessageClass(pool.FindMessageTypeByName(schema_name))

    def decode(payload: bytes) -> dict[str, Any]:
        message = message_class.FromString(payload)
        return json_format.MessageToDict(
            message, preserving_proto_field_name=True, always_print_fields_with_no_presence=True
        )

    return decode


def _has_file(pool: Any, name: str) -> bool:
    try:
        pool.FindFileByName(name)
    except KeyError:
        return False
    return True
