"""The batch's progress on stderr: done / total, successes, rate, ETA.

On a terminal one line redrawn in place (at most five times a second); else
(a log file, a pipe) a plain line every ``interval_s`` seconds, so that logs
stay readable. The last state is always written when the bar closes.
"""

from __future__ import annotations

import math
import sys
import time
from typing import TextIO

__all__ = ["ProgressBar", "format_duration"]

_BAR_WIDTH = 24
_TTY_INTERVAL_S = 0.2


def format_duration(seconds: float) -> str:
    """``H:MM:SS`` (``--:--`` when unknown)."""
    if not math.isfinite(seconds):
        return "--:--"
    whole = round(seconds)
    return f"{whole // 3600}:{whole // 60 % 60:02d}:{whole % 60:02d}"


class ProgressBar:
    """Progress of a batch of ``total`` jobs, ``done_before`` of them done by an earlier run.

    :meth:`update` with this run's counts; :meth:`close` at the end.
    """

    def __init__(
        self,
        total: int,
        done_before: int = 0,
        *,
        stream: TextIO | None = None,
        enabled: bool = True,
        interval_s: float = 10.0,
    ) -> None:
        self.total = total
        self.done_before = done_before
        self.stream = stream or sys.stderr
        self.enabled = enabled
        self.tty = self.stream.isatty()
        self.interval_s = _TTY_INTERVAL_S if self.tty else interval_s
        self.started = time.monotonic()
        self._last_shown = -float("inf")
        self._line = ""
        self._done = 0
        self._successes = 0
        self._first: tuple[float, int] | None = None  # (time, jobs done) at the first job finished

    def line(self, done: int, successes: int, now: float | None = None) -> str:
        """The progress line after ``done`` jobs of this run, ``successes`` plans found in all.

        The rate counts from the first job finished, so that starting the workers does not skew the ETA.
        """
        now = time.monotonic() if now is None else now
        finished = self.done_before + done
        if self._first is not None and done > self._first[1] and now > self._first[0]:
            rate = (done - self._first[1]) / (now - self._first[0])
        else:
            rate = done / (now - self.started) if done and now > self.started else math.nan
        remaining = self.total - finished
        eta = 0.0 if remaining == 0 else remaining / rate if rate > 0 else math.nan
        filled = round(_BAR_WIDTH * finished / self.total) if self.total else _BAR_WIDTH
        bar = "#" * filled + "-" * (_BAR_WIDTH - filled)
        rate_text = f"{rate:.2f} jobs/s" if math.isfinite(rate) else "-- jobs/s"
        return (
            f"clew_batch: [{bar}] {finished}/{self.total} done, {successes} ok, {rate_text}, ETA {format_duration(eta)}"
        )

    def update(self, done: int, successes: int) -> None:
        """Show ``done`` jobs of this run and ``successes`` plans found in all (throttled)."""
        now = time.monotonic()
        if self._first is None and done:
            self._first = (now, done)
        self._done, self._successes = done, successes
        if not self.enabled or now - self._last_shown < self.interval_s:
            return
        self._last_shown = now
        self._show(self.line(done, successes, now))

    def _show(self, line: str) -> None:
        if self.tty:
            padding = " " * max(0, len(self._line) - len(line))
            self.stream.write("\r" + line + padding)
        else:
            self.stream.write(line + "\n")
        self._line = line
        self.stream.flush()

    def close(self) -> None:
        """Write the last state (and end the line on a terminal)."""
        if not self.enabled:
            return
        self._show(self.line(self._done, self._successes))
        if self.tty:
            self.stream.write("\n")
            self.stream.flush()
