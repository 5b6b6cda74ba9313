"""Small programs to copy: the planner used from your own nodes (``python -m clew_ros.examples.<name>``).

- :mod:`~clew_ros.examples.goal_sequence`: plan to a list of object goals, one after the other, and log
  each result;
- :mod:`~clew_ros.examples.trajectory_follower`: follow ``~/trajectory`` in time and publish the joint
  states, a stand-in for ``joint_trajectory_controller``.
"""
