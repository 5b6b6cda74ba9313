"""The planar world of the contract's section 1 as the Ariadne's Clew Algorithm's space.

:class:`~clew_ros.planar.space.PlanarSpace` hands :mod:`clew_ros.core` a planar chain among polygons: its
kinematics, validity test, free intervals (compiled kernels, :mod:`clew_ros.planar.kernel`), SEARCH's
objectives, the approach cells that aim regrasps, the proof of infeasibility and the anytime improvement;
:func:`clew_ros.planar.space.plan` plans in a :class:`~clew_ros.planar.world.World`.
"""
