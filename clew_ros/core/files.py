"""Reading a file that may be anything: at most a given number of bytes, in pieces."""

from __future__ import annotations

from typing import BinaryIO

__all__ = ["read_at_most"]

_PIECE = 1 << 20  # bytes read at a time: memory grows with the file, not with the limit


def read_at_most(stream: BinaryIO, limit: int) -> bytes:
    """The bytes of ``stream`` up to its end, or ``limit`` + 1 of them when it holds more (the caller refuses it).

    ``stream.read(limit + 1)`` would allocate ``limit`` bytes at once whatever the file holds; a device or a
    pipe given as a file never ends: both are read here in pieces of a megabyte.
    """
    pieces = []
    total = 0
    while total <= limit:
        piece = stream.read(min(_PIECE, limit + 1 - total))
        if not piece:
            break
        pieces.append(piece)
        total += len(piece)
    return b"".join(pieces)
