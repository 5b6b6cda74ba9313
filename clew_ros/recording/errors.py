"""Errors raised by the recording package."""

from __future__ import annotations

__all__ = ["RecordingError", "TrajectoryError"]


class RecordingError(Exception):
    """A recording cannot be created, written or read; the message names the path."""


class TrajectoryError(RecordingError, ValueError):
    """A recorded trajectory does not describe a plan (names, point widths, non-finite positions); the message
    names where it came from."""
