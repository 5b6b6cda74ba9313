"""What the driver writes under the output folder: private (folders 0700, files 0600), and only under names
it has checked.

Plans, recordings and the index can say more about a deployment than the worlds (paths, timings); they are
the operator's, not every local user's. Names that come back from workers (the files of a recording, which a
Ray cluster node sends) are checked to be plain file names before anything is written with them: a worker
cannot write outside the job's folder.
"""

from __future__ import annotations

import os
from collections.abc import Iterable
from pathlib import Path

from clew_ros.batch.errors import BatchError
from clew_ros.core.files import FILES

__all__ = [
    "FILE_MODE",
    "FOLDER_MODE",
    "UnsafeNameError",
    "check_file_name",
    "check_file_names",
    "write_private",
]

FOLDER_MODE = FILES.private_folder_mode
FILE_MODE = 0o600


class UnsafeNameError(BatchError, ValueError):
    """A name from a worker is not a plain file name (a path, ``..``, a NUL, empty); nothing was written."""


def check_file_name(name: object) -> str:
    """``name`` when it is a plain file name: text, not empty, not ``.`` or ``..``, no ``/``, ``\\`` or NUL
    (so not absolute either); else :class:`UnsafeNameError`."""
    if (
        not isinstance(name, str)
        or name in ("", ".", "..")
        or any(c in name for c in "/\\\x00")
        or len(name.encode("utf-8", "surrogatepass")) > 255
    ):
        raise UnsafeNameError(f"{name!r:.120} is not a plain file name")
    return name


def check_file_names(names: Iterable[object]) -> None:
    """:func:`check_file_name` of each of ``names``."""
    for name in names:
        check_file_name(name)


def write_private(path: Path, data: bytes, *, sync: bool = True) -> None:
    """``data`` into a new file ``path`` (replaced if there) of mode 0600, synced when ``sync``."""
    descriptor = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC | os.O_NOFOLLOW, FILE_MODE)
    try:
        os.fchmod(descriptor, FILE_MODE)  # an older file of the same name keeps its mode through O_TRUNC
        view = memoryview(data)
        while view:
            view = view[os.write(descriptor, view) :]
        if sync:
            os.fsync(descriptor)
    finally:
        os.close(descriptor)
