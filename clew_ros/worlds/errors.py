"""Errors raised by the world generator."""

from __future__ import annotations

from clew_ros.core.errors import ClewError

__all__ = ["GenerationError", "UnknownFamilyError"]


class GenerationError(ClewError, RuntimeError):
    """No world could be built within the bounded number of attempts; the message says which and why."""


class UnknownFamilyError(ClewError, ValueError):
    """The family named is not one of :data:`clew_ros.worlds.families.FAMILIES`; the message lists them."""

    def __init__(self, name: str, known: list[str]) -> None:
        self.name = name
        self.known = known
        super().__init__(f"unknown family {name!r}: expected one of {', '.join(known)}")
