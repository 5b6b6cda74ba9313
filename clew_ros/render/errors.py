"""Errors raised by the renderer."""

from __future__ import annotations

__all__ = ["RenderError"]


class RenderError(Exception):
    """The input cannot be rendered; the message says which input and why."""
