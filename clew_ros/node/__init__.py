"""The ROS 2 node ``clew_planner`` that serves the planner (see interface.md §3).

- ``main``: the ``clew_planner`` entry point (executor, signals, exit codes).
- ``multi``: the ``clew_planners`` entry point: several planners in namespaces, one process, one executor.
- ``namespaces``: ``NAMESPACE:=WORLD.yaml`` pairs, each planner's world and recording directory (no rclpy;
  ``clew_planners`` and ``launch/clew_planners.launch.py`` share it).
- ``planner_node``: the node: parameters, callbacks, the one-run-at-a-time policy.
- ``run``: one run's handle (its phase, cancel, outcome, recording) and the ``~/status`` table.
- ``worker``: one run's life in its thread: plan, check, publish the outcome, play back.
- ``publishing``: the node's publishers (the arm: URDF, TF, ``~/scene``); every message also goes to the
  run's recording.
- ``run_recording``: a run's recording as the node uses it (nothing when recording is off).

What needs message types but no node (messages, QoS, topics, parameters, frames, URDF) is in
:mod:`clew_ros.ros`; the timed plan and its player are in :mod:`clew_ros.motion`. Importing this package
imports nothing; the modules import rclpy as they need it.
"""

__all__: list[str] = []
