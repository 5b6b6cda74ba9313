"""clew_ros.batch.progress: the progress line; plain lines when stderr is not a terminal."""

from __future__ import annotations

import io

from clew_ros.batch.progress import ProgressBar, format_duration


def test_the_line_says_done_total_successes_rate_and_eta() -> None:
    bar = ProgressBar(200, done_before=50, stream=io.StringIO())
    start = bar.started
    bar.update(1, 40)  # the rate counts from the first job finished
    line = bar.line(11, 45, now=start + 100.0)
    assert "61/200 done" in line
    assert "45 ok" in line
    assert "jobs/s" in line
    assert "ETA" in line
    assert format_duration(3725.0) == "1:02:05"
    assert format_duration(float("nan")) == "--:--"


def test_without_a_terminal_plain_lines_and_the_last_state() -> None:
    stream = io.StringIO()
    bar = ProgressBar(4, stream=stream, interval_s=3600.0)
    for done in range(1, 5):
        bar.update(done, done)
    bar.close()
    lines = stream.getvalue().splitlines()
    assert "\r" not in stream.getvalue()
    assert lines == [lines[0], lines[-1]]  # the first update, then nothing until the close (throttled)
    assert "4/4 done, 4 ok" in lines[-1]
    assert "ETA 0:00:00" in lines[-1]


def test_disabled_shows_nothing() -> None:
    stream = io.StringIO()
    bar = ProgressBar(4, stream=stream, enabled=False)
    bar.update(1, 1)
    bar.close()
    assert stream.getvalue() == ""
