"""Compiled kernels of the spatial world (numba): they take the world packed into arrays
(:class:`clew_ros.spatial.checker.PackedScene`), never objects, and loop over whole batches.

- :mod:`~clew_ros.spatial.kernels.collide`: forward kinematics, sphere-vs-obstacle distances, batched
  validity, clearances and the conservative free interval of one joint.
- :mod:`~clew_ros.spatial.kernels.ik`: the tcp's pose error, Jacobian and damped least squares
  (Levenberg-Marquardt) over a batch of targets and seeds.
"""
