"""The ROS 2 node ``clew_planner`` that serves the planner (see interface.md §3)."""
