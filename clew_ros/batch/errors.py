"""Errors of :mod:`clew_ros.batch`: one base type, and what the command line maps to its exit codes."""

from __future__ import annotations

__all__ = ["BatchError", "BatchInputError", "ExecutorError", "ExecutorUnavailableError"]


class BatchError(Exception):
    """Base of every error :mod:`clew_ros.batch` raises."""


class BatchInputError(BatchError, ValueError):
    """The batch's input is invalid: ``argument`` names what is at fault (an option, a world file, a
    parameter of one), ``expected`` says what was expected; ``str(error)`` holds both."""

    def __init__(self, argument: str, expected: str) -> None:
        self.argument = argument
        self.expected = expected
        super().__init__(f"{argument}: {expected}")


class ExecutorUnavailableError(BatchError):
    """The executor asked for cannot be used here (Ray not installed, no cluster at the address)."""


class ExecutorError(BatchError):
    """The executor failed as a whole (its workers die as they start); no job can run."""
