"""Playing a timed plan back in real time: samples at a rate, gripper events as they are reached.

:func:`play` walks a :class:`~clew_ros.node.playback.Track` on the
monotonic clock and hands each sample and each grasp / ungrasp event to
callbacks (the node publishes ``~/joint_states``, ``~/object_pose`` and
``~/events``); it stops early when asked. No rclpy: tested without a ROS graph.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass

from clew_ros.node.playback import GripperEvent, Track, TrackState

__all__ = ["PlaybackEnd", "play"]


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
        Called with the :class:`~clew_ros.node.playback.TrackState` at each sample (joints, their
        velocities, gripper, object pose).
    on_event:
        Called with each grasp / ungrasp event once the playback reaches it,
        after the sample that reached it.
    """
    if wait_stop(0.0):
        return PlaybackEnd(stopped=True, at_s=None)
    events = track.events()
    next_event = 0
    period = 1.0 / rate_hz
    start = time.monotonic()
    tick = 0
    while True:
        t = time.monotonic() - start
        on_sample(track.state(t))
        while next_event < len(events) and events[next_event].time_s <= t:
            on_event(events[next_event])
            next_event += 1
        if t >= track.duration_s:
            return PlaybackEnd(stopped=False, at_s=track.duration_s)
        tick += 1
        wait = start + min(tick * period, track.duration_s) - time.monotonic()
        if wait_stop(max(0.0, wait)):
            return PlaybackEnd(stopped=True, at_s=t)
