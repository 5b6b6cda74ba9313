"""Errors raised by the planner core, and :func:`short_repr` for the values their messages quote."""

from __future__ import annotations

from typing import Any

__all__ = ["ClewError", "ParameterError", "PlanFileError", "WorldError", "short_repr"]


class ClewError(Exception):
    """Base of every error the core raises."""


class ParameterError(ClewError, ValueError):
    """A parameter is invalid.

    ``parameter`` is the full parameter name at fault (``world.robot.initial``),
    ``expected`` says what was expected; ``str(error)`` holds both.
    """

    def __init__(self, parameter: str, expected: str) -> None:
        self.parameter = parameter
        self.expected = expected
        super().__init__(f"{parameter}: {expected}")


class WorldError(ParameterError):
    """A ``world.*`` parameter is invalid (or the world it describes is)."""


class PlanFileError(ClewError, ValueError):
    """A plan file cannot be read (wrong format, missing keys)."""


def short_repr(value: Any, limit: int = 80) -> str:
    """``repr(value)`` cut to ``limit`` characters, for error messages (a 400-digit integer is not a message)."""
    try:
        text = repr(value)
    except ValueError:  # an integer of more digits than Python converts to text
        return f"an integer of about {value.bit_length() * 0.30103:.0f} digits"
    return text if len(text) <= limit else text[: limit - 3] + "..."
