"""ROS 2 without a node: the messages, QoS, topics and parameters of interface.md §3, and the arm's frames.

- ``messages``: the one module that turns core values into ROS messages and back.
- ``events``: a run's ``~/events`` fields and terminal ``GoalStatus``.
- ``topics``: the node's topics, each with its message type and QoS.
- ``qos``: the QoS profiles, shared by the node and its clients.
- ``parameters``: the node's parameters: start values, descriptors and checks
  (:class:`~clew_ros.ros.parameters.NodeSettings`).
- ``urdf``: the arm's URDF (``~/robot_description``) generated from the world; no rclpy.
- ``frames``: the arm's and the object's TF frames (``/tf``, ``/tf_static``) at a joint state; no rclpy.
- ``spatial``: spatial worlds (interface.md section 1b) in ROS terms: the world of the parameters, the
  world's URDF as published, ``~/goal_pose`` as a stable placement, 3-D markers, every joint and link frame.

The node (:mod:`clew_ros.node`), its client (:mod:`clew_ros.client`) and the recordings made offline
(``clew_batch --record``) build their messages here, so they agree on every field. Importing this package
imports nothing; the modules import the message packages (and ``rclpy.qos``) as they need them.
"""

__all__: list[str] = []
