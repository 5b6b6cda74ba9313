"""Playing a timed plan back: samples at a rate, gripper events as they are reached.

:func:`play` walks a :class:`~clew_ros.motion.playback.Track` on the
monotonic clock and hands each sample and each grasp / ungrasp event to
callbacks (the node publishes ``~/joint_states``, ``~/object_pose`` and
``~/events``); it stops early when asked. :func:`scheduled_samples` gives the
same samples at their scheduled times exactly, at once, with no clock and no
waiting (a recording made offline, ``clew_batch --record``). No rclpy: tested
without a ROS graph.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass

from clew_ros.motion.playback import GripperEvent, Track, TrackState

__all__ = ["PlaybackEnd", "play", "scheduled_samples"]


@dataclass(frozen=True)
class PlaybackEnd:
    """How a playback ended: done, or stopped at ``at_s`` (s of the track; ``None``: before it started)."""

    stopped: bool
    at_s: float | None

    @property
    def phase(self) -> str:
        """The ``phase`` of ``~/feedback``: ``playback_stopped`` or ``playback_done``."""
        return "playback_stopped" if self.stopped else "playback_done"


def play(
    track: Track,
    rate_hz: float,
    *,
    wait_stop: Callable[[float], bool],
    on_sample: Callable[[TrackState], None],
    on_event: Callable[[GripperEvent], None],
) -> PlaybackEnd:
    """Play ``track`` back in time; return how it ended.

    Parameters
    ----------
    rate_hz:
        Samples per second; the last sample is the track's last point.
    wait_stop:
        ``wait_stop(timeout_s)`` waits up to ``timeout_s`` and returns whether
        the playback is to stop (``threading.Event.wait``); asked once with
        ``0`` before the first sample.
    on_sample:
        Called with the :class:`~clew_ros.motion.playback.TrackState` at each sample (joints, their
        velocities, gripper, object pose).
    on_event:
        Called with each grasp / ungrasp event once the playback reaches it,
        after the sample that reached it.
    """
    if wait_stop(0.0):
        return PlaybackEnd(stopped=True, at_s=None)
    events = _Events(track)
    start = time.monotonic()
    tick = 0
    while True:
        t = time.monotonic() - start
        on_sample(track.state(t))
        for event in events.reached(t):
            on_event(event)
        if t >= track.duration_s:
            return PlaybackEnd(stopped=False, at_s=track.duration_s)
        tick += 1
        wait = start + _tick_s(track, rate_hz, tick) - time.monotonic()
        if wait_stop(max(0.0, wait)):
            return PlaybackEnd(stopped=True, at_s=t)


def scheduled_samples(track: Track, rate_hz: float) -> Iterator[tuple[float, TrackState, list[GripperEvent]]]:
    """What :func:`play` hands out, taken at the scheduled times exactly, without waiting.

    Yields ``(t_s, state, events)``: the time of the sample (s of the track;
    every ``1 / rate_hz``, the last one the track's end), the
    :class:`~clew_ros.motion.playback.TrackState` there, and the grasp /
    ungrasp events that sample reaches (each once, in order).
    """
    events = _Events(track)
    tick = 0
    while True:
        t = _tick_s(track, rate_hz, tick)
        yield t, track.state(t), events.reached(t)
        if t >= track.duration_s:
            return
        tick += 1


def _tick_s(track: Track, rate_hz: float, tick: int) -> float:
    """When sample ``tick`` is due (s of the track): every ``1 / rate_hz``, at most the track's end."""
    return min(tick / rate_hz, track.duration_s)


class _Events:
    """The track's grasp / ungrasp events, handed out once each as the playback reaches them."""

    def __init__(self, track: Track) -> None:
        self._events = track.events()
        self._next = 0

    def reached(self, t_s: float) -> list[GripperEvent]:
        """The events at or before ``t_s`` (s of the track) not handed out yet."""
        first = self._next
        while self._next < len(self._events) and self._events[self._next].time_s <= t_s:
            self._next += 1
        return self._events[first : self._next]
