"""Spatial worlds (interface.md section 1b): a URDF arm in 3-D among primitive obstacles.

- :mod:`~clew_ros.spatial.robot`: the URDF's chain from ``base_link`` to ``tip_link`` folded into frames,
  with every link's collision geometry and the self-collision pairs an SRDF exempts.
- :mod:`~clew_ros.spatial.spheres`: the conservative sphere model of every link's collision geometry.
- :mod:`~clew_ros.spatial.scene`: obstacles (boxes, cylinders, spheres) from parameters and MoveIt planning
  scene YAML (`world.scene_file`), and bounds.
- :mod:`~clew_ros.spatial.placements`: supports, the movable object (box or cylinder) and its stable
  placements: the test, sampling, projection.
- :mod:`~clew_ros.spatial.checker`: the compiled, batched validity checker and free intervals of one joint
  (:mod:`~clew_ros.spatial.kernels`).
- :mod:`~clew_ros.spatial.inverse`: the tcp's inverse kinematics (damped least squares from many seeds,
  batched): every distinct solution within the joint limits, optionally only collision-free ones.
- :mod:`~clew_ros.spatial.random_robot`: random serial arms (4-8 revolute joints, capsule, box and cylinder
  links) as URDF text, seeded, so tests and benchmarks are never tuned to one arm.
- :mod:`~clew_ros.spatial.validate`: paths checked at 0.002 rad per joint under the checker (the object
  resting or held), each invalid piece named with its first invalid configuration and why.
- :mod:`~clew_ros.spatial.plan`: the spatial plan file (``world_kind: spatial``, 6-number poses), its
  replay and :func:`~clew_ros.spatial.plan.validate_plan` (transit and transfer segments, grasps, stable
  placements, the goal).
- :mod:`~clew_ros.spatial.exact`: a plan's collisions on the exact geometry (pinocchio + coal on the URDF's
  collision meshes, the obstacles and the object; the ``spatial-ref`` extra, imported when used).
- :mod:`~clew_ros.spatial.enclosure`: the proof that the goal placement is closed off by obstacles (a quick
  answer of the planner).
- :mod:`~clew_ros.spatial.world`: a whole spatial world from its parameters, checked, with its checker.
- :mod:`~clew_ros.spatial.transforms`: poses as 4x4 matrices (URDF ``rpy``, quaternions), one or a batch.
- :mod:`~clew_ros.spatial.space`: the world as the Ariadne's Clew Algorithm's space
  (:class:`~clew_ros.spatial.space.SpatialSpace`) and :func:`~clew_ros.spatial.space.plan`, the spatial
  planner's entry point; a facade over one module per concern: :mod:`~clew_ros.spatial.space_parts` (the
  checkers, kinematics and grasps every part shares), :mod:`~clew_ros.spatial.manhattan` (decoding),
  :mod:`~clew_ros.spatial.settle` (a carried object set down), :mod:`~clew_ros.spatial.distances`,
  :mod:`~clew_ros.spatial.search` (SEARCH's jobs), :mod:`~clew_ros.spatial.targets` (the configurations they
  aim at), :mod:`~clew_ros.spatial.ways` and :mod:`~clew_ros.spatial.straight` (straight moves),
  :mod:`~clew_ros.spatial.refusals` (quick answers), :mod:`~clew_ros.spatial.improvement`;
  :mod:`~clew_ros.spatial.motion_plan` (motion-only queries: the ACA's transit search),
  :mod:`~clew_ros.spatial.tuning`; the improvement's shortcuts and pruning are the generic ones of
  :mod:`clew_ros.core.improve`.

- :mod:`~clew_ros.spatial.offline`: a parameter tree to a checked spatial plan (what ``clew_plan``,
  ``clew_batch`` and the node share).

It runs without ROS (a test keeps it so).
"""

__all__ = ["WORLD_KIND"]

#: ``world.kind`` of a spatial world and a plan file's ``world_kind`` for it (the kind's name, written here once
#: for the modules that must not import the spatial planner to know it).
WORLD_KIND = "spatial"
