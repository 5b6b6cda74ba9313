"""The ROS 2 node ``clew_planner`` that serves the planner (see interface.md §3).

- ``main``: the ``clew_planner`` entry point (executor, signals, exit codes).
- ``planner_node``: the node: services, topics, runs, the worker thread.
- ``parameters``: parameter names, defaults, descriptors and checks.
- ``messages``: the one module that turns core values into ROS messages and back.
- ``playback``: the timed plan (trajectory times, grasp events, samples); no rclpy.
- ``call_plan``: a small client that calls ``~/plan`` (for pip installs without ``ros2``).

Importing this package imports nothing; the modules import rclpy as they need it.
"""

__all__: list[str] = []
