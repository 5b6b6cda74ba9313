"""Files that may be anything or must stay private: reading at most a given number of bytes, in pieces;
reading a regular file a user named (never a device, a pipe or a folder) up to a cap; making folders of
mode 0700."""

from __future__ import annotations

import errno
import os
import stat
from dataclasses import dataclass
from pathlib import Path
from typing import BinaryIO

__all__ = [
    "FILES",
    "FileRefusedError",
    "FileSettings",
    "private_folders",
    "read_at_most",
    "read_regular_file",
    "yaml_error_place",
]


@dataclass(frozen=True)
class FileSettings:
    """How files are read and private folders made."""

    #: Mode of the folders :func:`private_folders` makes: the owner's alone (recordings, batch results).
    private_folder_mode: int = 0o700
    #: Bytes read at a time (bytes): memory grows with the file, not with the limit.
    read_piece_bytes: int = 1 << 20


#: The settings this module works with.
FILES = FileSettings()


def read_at_most(stream: BinaryIO, limit: int) -> bytes:
    """The bytes of ``stream`` up to its end, or ``limit`` + 1 of them when it holds more (the caller refuses it).

    ``stream.read(limit + 1)`` would allocate ``limit`` bytes at once whatever the file holds; a device or a
    pipe given as a file never ends: both are read here in pieces of a megabyte.
    """
    pieces = []
    total = 0
    while total <= limit:
        piece = stream.read(min(FILES.read_piece_bytes, limit + 1 - total))
        if not piece:
            break
        pieces.append(piece)
        total += len(piece)
    return b"".join(pieces)


class FileRefusedError(ValueError):
    """A file :func:`read_regular_file` refuses; the message says why (never the file's name or contents)."""


def read_regular_file(path: Path, limit: int, cap: str) -> bytes:
    """The bytes of the regular file ``path``, refused (:class:`FileRefusedError`) when it cannot be opened, is not
    a regular file (a device such as ``/dev/zero``, a pipe, a folder) or holds more than ``limit`` bytes
    (``cap`` names the limit, ``Limits.<field>``). The file is opened without blocking (a pipe would wait for a
    writer) and checked after opening, so that what is read is what was checked."""
    try:
        descriptor = os.open(path, os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_CLOEXEC", 0))
    except OSError as error:
        raise FileRefusedError(error.strerror or type(error).__name__) from None
    try:
        status = os.fstat(descriptor)
        if not stat.S_ISREG(status.st_mode):
            raise FileRefusedError("not a regular file (a device, a pipe or a folder)")
        if status.st_size > limit:
            raise FileRefusedError(f"it holds {status.st_size} bytes, larger than {limit} bytes ({cap})")
        with os.fdopen(descriptor, "rb", closefd=False) as stream:
            data = read_at_most(stream, limit)
    except OSError as error:
        raise FileRefusedError(error.strerror or type(error).__name__) from None
    finally:
        os.close(descriptor)
    if len(data) > limit:  # grew since it was checked
        raise FileRefusedError(f"it holds more bytes, larger than {limit} bytes ({cap})")
    return data


def yaml_error_place(error: BaseException) -> str:
    """Where a YAML error lies (``line L, column C``) and its kind, without the snippet of the file PyYAML's
    message quotes: an error message never repeats what a file holds."""
    mark = getattr(error, "problem_mark", None) or getattr(error, "context_mark", None)
    place = f"line {mark.line + 1}, column {mark.column + 1}" if mark is not None else "in the text"
    return f"{type(error).__name__} at {place}"


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
            folder.mkdir(mode=FILES.private_folder_mode)
        except FileExistsError:
            continue  # made meanwhile: its mode is its maker's
        folder.chmod(FILES.private_folder_mode)
    if not path.is_dir():
        raise NotADirectoryError(errno.ENOTDIR, os.strerror(errno.ENOTDIR), str(path))
    return path
