"""A plan in time: the timed plan the node publishes and plays back, and the player (no rclpy, no messages).

- ``timing``: the rest-to-rest quintic that times each straight piece within the joint limits.
- ``playback``: the timed plan (:class:`~clew_ros.motion.playback.Track`): trajectory points, grasp events,
  the state at any time.
- ``player``: plays a track back in real time, or gives its samples at their scheduled times at once.
- ``spatial``: a spatial plan timed (the planned URDF joints within their URDF and parameter limits) and
  every joint and link of the URDF at a state.

The node (``clew_ros.node``), its recordings made offline (``clew_batch --record``), the Foxglove live view
(``clew_ros.live``) and the example trajectory follower time a plan the same way through these modules.
"""

__all__: list[str] = []
