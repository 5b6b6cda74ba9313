"""The batch index ``index.jsonl``: one JSON object per finished job, one complete line each.

Lines are only ever appended, each by a single ``write`` of the whole line
followed by ``flush`` and ``fsync``, so a killed driver leaves every line it
wrote whole. A line cut short all the same (a crash of the machine) is the
last one: :meth:`Index.open` cuts it off, and lines that are not JSON objects
are skipped. A job planned again (its world file or settings changed) gets
a new line; the last line of a job is its record.

The columns (:data:`COLUMNS`): ``job`` (``<world folder>/seed_<seed>``),
``world`` (``world.name``), ``world_path``, ``seed``, ``code`` (the outcome:
``SUCCEEDED``, ``TIME_LIMIT``, ..., ``INTERNAL_ERROR``), ``success``,
``message``, ``plan_time_s`` (the planner's time), ``wall_time_s`` (the
job's time in its worker), ``landmarks``, ``transfers`` and
``joint_travel_rad`` (of a plan found, else null), ``plan`` (the plan file,
relative to the output folder), ``recording`` (the run's recording folder,
relative to the output folder, with ``--record``; else null), ``attempts``, ``error`` (why the job failed:
an exception, a dead worker, a time-out; else null), ``fingerprint`` (what
decided the plan, :attr:`clew_ros.batch.jobs.Job.fingerprint`) and
``finished`` (UTC, ISO 8601).
"""

from __future__ import annotations

import json
import os
from collections.abc import Iterator, Mapping
from pathlib import Path
from types import TracebackType
from typing import Any

from clew_ros.batch.errors import BatchInputError
from clew_ros.batch.files import FILE_MODE
from clew_ros.core.files import private_folders

__all__ = ["COLUMNS", "INDEX_NAME", "Index"]

INDEX_NAME = "index.jsonl"
COLUMNS = (
    "job",
    "world",
    "world_path",
    "seed",
    "code",
    "success",
    "message",
    "plan_time_s",
    "wall_time_s",
    "landmarks",
    "transfers",
    "joint_travel_rad",
    "plan",
    "recording",
    "attempts",
    "error",
    "fingerprint",
    "finished",
)


class Index:
    """The index of the batch in ``folder``: its records so far (:attr:`records`, the last per job) and
    :meth:`append` for the next one. Open with :meth:`open`; close (or use as a context manager)."""

    def __init__(self, path: Path, records: dict[str, dict[str, Any]], *, repaired_bytes: int, skipped_lines: int):
        self.path = path
        self.records = records
        #: Bytes of a cut-short last line removed when the index was opened.
        self.repaired_bytes = repaired_bytes
        #: Complete lines that were not JSON objects with a ``job`` (ignored).
        self.skipped_lines = skipped_lines
        self._fd: int | None = os.open(path, os.O_WRONLY | os.O_APPEND | os.O_CREAT | os.O_NOFOLLOW, FILE_MODE)
        os.fchmod(self._fd, FILE_MODE)  # an index an older version wrote world-readable becomes private

    @classmethod
    def open(cls, folder: str | Path) -> Index:
        """The index in ``folder`` (created with the folder if missing), its torn last line cut off."""
        folder = private_folders(Path(folder))
        path = folder / INDEX_NAME
        try:
            data = path.read_bytes() if path.exists() else b""
        except OSError as error:
            raise BatchInputError("--out", f"cannot read the index {path} ({error.strerror})") from None
        complete = data[: data.rfind(b"\n") + 1]
        if len(complete) < len(data):
            with path.open("r+b") as stream:
                stream.truncate(len(complete))
                os.fsync(stream.fileno())
        records: dict[str, dict[str, Any]] = {}
        skipped = 0
        for record in _parsed_lines(complete):
            if record is None:
                skipped += 1
            else:
                records[record["job"]] = record
        return cls(path, records, repaired_bytes=len(data) - len(complete), skipped_lines=skipped)

    def append(self, record: Mapping[str, Any]) -> None:
        """Add ``record`` (a job's columns) as one complete line, on disk when this returns."""
        if self._fd is None:
            raise ValueError(f"{self.path}: the index is closed")
        line = (json.dumps(dict(record), separators=(", ", ": ")) + "\n").encode()
        written = os.write(self._fd, line)
        while written < len(line):  # a regular file takes it whole; this is for the odd short write
            written += os.write(self._fd, line[written:])
        os.fsync(self._fd)
        self.records[str(record["job"])] = dict(record)

    def close(self) -> None:
        """Close the file (idempotent)."""
        if self._fd is not None:
            os.close(self._fd)
            self._fd = None

    def __enter__(self) -> Index:
        return self

    def __exit__(
        self, kind: type[BaseException] | None, value: BaseException | None, traceback: TracebackType | None
    ) -> None:
        self.close()


def _parsed_lines(data: bytes) -> Iterator[dict[str, Any] | None]:
    """Each line of ``data`` as a record, or ``None`` for a line that is not one."""
    for line in data.splitlines():
        if not line.strip():
            continue
        try:
            record = json.loads(line, parse_constant=_no_constant)
        except (ValueError, RecursionError):  # not JSON, not UTF-8, NaN, nested deeper than the parser goes
            yield None
            continue
        yield record if isinstance(record, dict) and isinstance(record.get("job"), str) else None


def _no_constant(name: str) -> Any:
    raise ValueError(f"{name} is not a value an index line holds")
