"""Errors raised by the planner core."""

from __future__ import annotations

__all__ = ["ClewError", "ParameterError", "PlanFileError", "WorldError"]


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
