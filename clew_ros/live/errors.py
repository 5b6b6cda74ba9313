"""Errors raised by the live view."""

from __future__ import annotations

__all__ = ["LiveViewError", "LiveViewUnavailableError"]

#: What to install for the live view (setup.py's ``live`` extra).
INSTALL_HINT = "pip install clew_ros[live]"


class LiveViewError(Exception):
    """The live view cannot do what was asked; the message says why."""


class LiveViewUnavailableError(LiveViewError):
    """``foxglove-sdk`` is not installed (the ``live`` extra)."""

    def __init__(self) -> None:
        super().__init__(f"the live view needs foxglove-sdk, which is not installed: {INSTALL_HINT}")
