"""clew_ros: manipulation planning with the Ariadne's Clew Algorithm for ROS 2.

A planar arm carries a movable object to a goal placement among polygonal
obstacles, re-grasping when needed. The planner core (``clew_ros.core``)
never imports rclpy; the ROS 2 node (``clew_ros.node``) serves it as the
``clew_planner`` node, and the command-line tools (``clew_ros.cli``) plan,
replay and render offline.
"""

__version__ = "0.1.0"
