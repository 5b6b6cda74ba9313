"""Playing a timed plan back in real time: samples, gripper events, stop (no ROS graph)."""

from __future__ import annotations

import threading
import time

import numpy as np
import pytest

from clew_ros.motion import player
from clew_ros.motion.playback import GripperEvent, TrackState
from clew_ros.motion.player import play, scheduled_samples


class Line:
    """A track of ``duration_s`` whose one joint equals the time, with a grasp and an ungrasp."""

    def __init__(self, duration_s: float) -> None:
        self.duration_s = duration_s
        self._events = [GripperEvent("grasp", 2, 0.3 * duration_s, 1), GripperEvent("ungrasp", 2, 0.6 * duration_s, 2)]

    def events(self) -> list[GripperEvent]:
        return list(self._events)

    def state(self, t_s: float) -> TrackState:
        t = min(max(t_s, 0.0), self.duration_s)
        gripper = float(0.3 * self.duration_s <= t < 0.6 * self.duration_s)
        return TrackState(np.array([t]), np.array([1.0]), gripper, np.zeros(3))


def recorded(duration_s: float, rate_hz: float, stop: threading.Event):
    samples, events = [], []
    end = play(
        Line(duration_s),
        rate_hz,
        wait_stop=stop.wait,
        on_sample=lambda state: samples.append((time.monotonic(), float(state.joints[0]), state.gripper)),
        on_event=lambda e: events.append((len(samples), e)),
    )
    return end, samples, events


def test_plays_in_time_to_the_last_point() -> None:
    start = time.monotonic()
    end, samples, events = recorded(0.5, 20.0, threading.Event())
    took = time.monotonic() - start
    assert not end.stopped
    assert end.phase == "playback_done"
    assert end.at_s == 0.5
    assert took >= 0.5  # paced in real time: never ahead of the track (load can only make it later)
    assert samples[-1][1] == 0.5  # the last sample is the last point
    assert 9 <= len(samples) <= 13  # 20 Hz over 0.5 s, the first at 0 and the last at the end
    times = [q for _, q, _ in samples]
    assert times == sorted(times)
    # each event once, in order, right after the first sample at or past its time
    assert [e.kind for _, e in events] == ["grasp", "ungrasp"]
    for count, event in events:
        assert samples[count - 1][1] >= event.time_s
        assert count < 2 or samples[count - 2][1] < event.time_s


def test_a_stop_ends_it_within_a_period() -> None:
    stop = threading.Event()
    stopped_at: list[float] = []

    def request_stop() -> None:
        stopped_at.append(time.monotonic())
        stop.set()

    threading.Timer(0.2, request_stop).start()
    end, samples, events = recorded(10.0, 20.0, stop)
    assert end.stopped
    assert end.phase == "playback_stopped"
    assert end.at_s is not None
    assert end.at_s == samples[-1][1]  # it ends at the last sample sent
    # within a period: at most the sample being sent when the stop came follows it (whatever the load)
    assert sum(1 for sent, _, _ in samples if sent > stopped_at[0]) <= 1
    # liveness: it ended at the stop, long before the track's 10 s (a loaded machine may start it late)
    assert end.at_s < 5.0
    assert all(event.time_s <= end.at_s for _, event in events)  # nothing past where it stopped


def test_a_stop_before_the_start_sends_nothing() -> None:
    stop = threading.Event()
    stop.set()
    end, samples, events = recorded(1.0, 20.0, stop)
    assert end.stopped
    assert end.at_s is None
    assert end.phase == "playback_stopped"
    assert not samples
    assert not events


class _NoClock:
    """Stands in for the player's ``time`` module: any use of the clock fails the test."""

    def __getattr__(self, name: str) -> object:
        raise AssertionError(f"the schedule used time.{name}: it must not wait for the clock")


def test_scheduled_samples_are_plays_ticks_at_once(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(player, "time", _NoClock())  # not paced: it never reads the clock, let alone waits
    schedule = list(scheduled_samples(Line(5.0), 20.0))  # 5 s of track
    times = [t for t, _, _ in schedule]
    assert times[0] == 0.0
    assert times[-1] == 5.0  # the last sample is the last point
    assert len(times) == 101  # every 1 / 20 s
    assert np.all(np.diff(times) > 0)
    assert [float(state.joints[0]) for _, state, _ in schedule] == times
    # each event once, in order, with the first sample at or past its time
    reached = [(t, event) for t, _, events in schedule for event in events]
    assert [event.kind for _, event in reached] == ["grasp", "ungrasp"]
    for t, event in reached:
        assert t >= event.time_s
        assert t - 1.0 / 20.0 < event.time_s
