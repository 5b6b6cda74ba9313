"""Compiled kernels of the spatial world (numba): they take the world packed into named tuples of arrays
(:mod:`~clew_ros.spatial.kernels.packed`, built once by :class:`clew_ros.spatial.checker.SpatialChecker` and
:class:`clew_ros.spatial.inverse.InverseKinematics`), never objects, and loop over whole batches.

- :mod:`~clew_ros.spatial.kernels.packed`: the packed arguments (chain, sphere models, scene, held object;
  scratch).
- :mod:`~clew_ros.spatial.kernels.collide`: forward kinematics, sphere-vs-obstacle distances, the one validity
  test of a configuration (:func:`~clew_ros.spatial.kernels.collide.config_valid`) and its batch.
- :mod:`~clew_ros.spatial.kernels.intervals`: the conservative free interval of one joint.
- :mod:`~clew_ros.spatial.kernels.band`: the contacts the outer and inner sphere models leave to the exact
  geometry.
- :mod:`~clew_ros.spatial.kernels.ik`: the tcp's pose error, Jacobian and damped least squares
  (Levenberg-Marquardt) over a batch of targets and seeds, on the whole pose or some of its rows.
"""
