"""Files that may be anything or must stay private: reading at most a given number of bytes, in pieces;
making folders of mode 0700."""

from __future__ import annotations

import errno
import os
from pathlib import Path
from typing import BinaryIO

__all__ = ["PRIVATE_FOLDER_MODE", "private_folders", "read_at_most"]

#: Mode of the folders :func:`private_folders` makes: the owner's alone (recordings, batch results).
PRIVATE_FOLDER_MODE = 0o700

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


def private_folders(path: Path) -> Path:
    """``path`` and its missing parents created, each with mode 0700 (set explicitly: the umask may take bits
    off); an existing folder keeps its mode (the operator's), and so does one made meanwhile by another process.
    Raises :class:`NotADirectoryError` when ``path`` ends up something other than a folder."""
    missing = []
    folder = path
    while not folder.exists():
        missing.append(folder)
        if folder.parent == folder:
            break
        folder = folder.parent
    for folder in reversed(missing):
        try:
            folder.mkdir(mode=PRIVATE_FOLDER_MODE)
        except FileExistsError:
            continue  # made meanwhile: its mode is its maker's
        folder.chmod(PRIVATE_FOLDER_MODE)
    if not path.is_dir():
        raise NotADirectoryError(errno.ENOTDIR, os.strerror(errno.ENOTDIR), str(path))
    return path
