"""The live view: a run shown in Foxglove while it runs, over a WebSocket on this machine, without ROS.

- ``view``: :class:`LiveView` (start / stop, ``publish_world``, ``publish_landmarks``, ``on_progress``,
  ``publish_outcome``, ``play``); its module docstring lists the channels and schemas served.
- ``messages``: core values as Foxglove's well-known messages (``SceneUpdate``, ``JointStates``).
- ``errors``: :class:`LiveViewError`, :class:`LiveViewUnavailableError` (foxglove-sdk is missing).

Needs ``foxglove-sdk``, the ``live`` extra (``pip install clew_ros[live]``);
importing this package does not import it, :meth:`LiveView.start` does.
``clew_plan --foxglove [PORT]`` uses it.
"""

from clew_ros.live.errors import INSTALL_HINT, LiveViewError, LiveViewUnavailableError
from clew_ros.live.view import DEFAULT_PORT, HOST, LiveView, is_available

__all__ = [
    "DEFAULT_PORT",
    "HOST",
    "INSTALL_HINT",
    "LiveView",
    "LiveViewError",
    "LiveViewUnavailableError",
    "is_available",
]
