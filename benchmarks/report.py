"""What the comparison scripts (:mod:`benchmarks.variants`, :mod:`benchmarks.families_ab`) print and keep:
a header naming the command that made the table, and the table written as ``STEM.md`` with its runs as
``STEM.json``."""

from __future__ import annotations

import json
import os
import sys
import time
from pathlib import Path
from typing import Any

__all__ = ["command_line", "header", "write_report"]


def command_line(module: str, argv: list[str] | None) -> str:
    """``python -m MODULE ARGS``: the command as typed (``argv``, default the process's own arguments)."""
    return " ".join([f"python -m {module}", *(sys.argv[1:] if argv is None else argv)])


def header(command: str, started: float, load: float, what: str, *, prefix: str = "") -> str:
    """The line above a table: the command, when, how long (since ``started``, a ``time.monotonic()``
    reading), on how many cores and under what load, then ``what`` was planned."""
    return (
        f"`{command}` ({prefix}{time.strftime('%Y-%m-%d %H:%M')}, {(time.monotonic() - started) / 60:.1f} min on "
        f"{os.cpu_count()} cores, load average {load:.1f} at the start; {what}):"
    )


def write_report(out: Path, stem: str, text: str, data: dict[str, Any]) -> None:
    """``out/STEM.md`` (``text``) and ``out/STEM.json`` (``data``), then ``text`` on standard output."""
    out.mkdir(parents=True, exist_ok=True)
    (out / f"{stem}.md").write_text(text)
    (out / f"{stem}.json").write_text(json.dumps(data, indent=1) + "\n")
    print(text)
