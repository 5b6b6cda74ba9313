"""Errors raised by the recording package."""

from __future__ import annotations

__all__ = ["RecordingError"]


class RecordingError(Exception):
    """A recording cannot be created, written or read; the message names the path."""
