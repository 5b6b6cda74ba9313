"""What the command-line tools print when they refuse an input: one line, whatever the input held."""

from __future__ import annotations

__all__ = ["one_line"]


def one_line(text: str, limit: int = 1000) -> str:
    """``text`` on one line: line breaks and other control characters (a name read from a file may hold
    them) shown escaped, cut to ``limit`` characters."""
    shown = "".join(c if c.isprintable() else ascii(c)[1:-1] for c in text)
    return shown if len(shown) <= limit else shown[: limit - 3] + "..."
