"""Retention: the oldest runs of a recording directory deleted so that it keeps at most so many, or so many bytes.

Only folders that look like a run :class:`~clew_ros.recording.RunRecorder`
wrote are ever counted or deleted (:func:`is_run_folder`): named by a run id
(32 hex digits), a real directory (not a symbolic link) directly inside the
recording directory, holding a ``metadata.yaml`` (written when the run's
recording closed) and nothing but regular files. A run being recorded has
no ``metadata.yaml`` yet, and the current run is named to be kept, so it is
never deleted. No ROS needed.
"""

from __future__ import annotations

import os
import re
import shutil
import stat
from dataclasses import dataclass
from pathlib import Path

__all__ = ["DeletedRun", "RetentionPolicy", "is_run_folder", "prune_runs", "run_folders"]

#: A run folder's name: the run's UUID as 32 hex digits (interface.md §3).
RUN_ID_NAME = re.compile(r"[0-9a-f]{32}")


@dataclass(frozen=True)
class RetentionPolicy:
    """How much a recording directory keeps (``record.max_runs``, ``record.max_bytes``).

    ``max_runs``: most run folders, the current one included (0: no limit).
    ``max_bytes``: most bytes in the complete run folders, the current one not counted (0: no limit).
    """

    max_runs: int = 0
    max_bytes: int = 0


@dataclass(frozen=True)
class DeletedRun:
    """A run folder :func:`prune_runs` deleted, its size (bytes) and why."""

    path: Path
    size_bytes: int
    reason: str


@dataclass(frozen=True)
class _Run:
    path: Path
    closed_ns: int  # when its metadata.yaml was written (the run's recording closed)
    size_bytes: int


def is_run_folder(path: Path) -> bool:
    """Whether ``path`` is a complete run folder (see the module's docstring)."""
    return _inspect(path) is not None


def _inspect(path: Path) -> _Run | None:
    if not RUN_ID_NAME.fullmatch(path.name):
        return None
    try:
        if not stat.S_ISDIR(path.lstat().st_mode):
            return None  # a symbolic link or a file
        size = 0
        closed_ns = None
        with os.scandir(path) as entries:
            for entry in entries:
                info = entry.stat(follow_symlinks=False)
                if not stat.S_ISREG(info.st_mode):
                    return None  # a folder, a link, a device: not what a recorder writes
                size += info.st_size
                if entry.name == "metadata.yaml":
                    closed_ns = info.st_mtime_ns
    except OSError:
        return None
    return None if closed_ns is None else _Run(path, closed_ns, size)


def run_folders(directory: Path) -> list[Path]:
    """The complete run folders directly inside ``directory``, oldest first."""
    return [run.path for run in _runs(directory)]


def _runs(directory: Path) -> list[_Run]:
    try:
        with os.scandir(directory) as entries:
            candidates = [Path(entry.path) for entry in entries if RUN_ID_NAME.fullmatch(entry.name)]
    except OSError:
        return []
    runs = [run for run in map(_inspect, candidates) if run is not None]
    return sorted(runs, key=lambda run: (run.closed_ns, run.path.name))


def prune_runs(directory: Path, policy: RetentionPolicy, current: str | None = None) -> list[DeletedRun]:
    """Delete the oldest complete run folders of ``directory`` until ``policy`` holds; return what went.

    ``current`` names the run being recorded (never deleted, and counted in
    ``max_runs``). Oldest means the earliest closed (``metadata.yaml``'s
    time). A folder that cannot be deleted is left and the next one tried.
    """
    runs = [run for run in _runs(directory) if run.path.name != current]
    deleted: list[DeletedRun] = []
    keep_runs = policy.max_runs - (1 if current is not None else 0) if policy.max_runs > 0 else len(runs)
    total = sum(run.size_bytes for run in runs)
    for run in runs:
        over_count = len(runs) - len(deleted) > keep_runs
        over_bytes = policy.max_bytes > 0 and total > policy.max_bytes
        if not (over_count or over_bytes):
            break
        reason = (
            f"record.max_runs {policy.max_runs}"
            if over_count
            else f"record.max_bytes {policy.max_bytes} ({total} bytes in the complete runs)"
        )
        try:
            shutil.rmtree(run.path)
        except OSError:
            continue
        deleted.append(DeletedRun(run.path, run.size_bytes, reason))
        total -= run.size_bytes
    return deleted
