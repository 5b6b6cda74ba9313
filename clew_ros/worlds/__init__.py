"""Generated worlds (``clew_world``): families of worlds unlike figure1, solvable by construction.

Not an idea of the paper, so not part of :mod:`clew_ros.core` (which it uses). A family
(:data:`FAMILIES`) fixes what varies: the arm (2 to 10 joints, joint limits), the object's shape
(bar, box, triangle, L, random convex and non-convex polygons, grasps on several edges), the layout
of obstacles (shelves, pockets, walls with windows, clutter, blocks close to the goal) and the goal's
orientation tolerance. :func:`generate` builds the world of a family and seed: first a witness, a
random manipulation simulated from the start whose end is the goal, then the layout around it, then
the checks a user's world gets plus the witness validated at 0.002 rad; the ``unsolvable`` family
puts the goal where the object provably cannot go
(:func:`clew_ros.planar.passage.separation` proves it). :func:`write_world` writes the parameter file
and the witness plan next to it. Modules: :mod:`~clew_ros.worlds.arms`,
:mod:`~clew_ros.worlds.shapes`, :mod:`~clew_ros.worlds.witness`, :mod:`~clew_ros.worlds.sweep`,
:mod:`~clew_ros.worlds.layouts`, :mod:`~clew_ros.worlds.regrasp`,
:mod:`~clew_ros.worlds.families`, :mod:`~clew_ros.worlds.files`. Spatial worlds (a URDF arm in 3-D):
:mod:`~clew_ros.worlds.spatial` (``clew_world spatial_* --robot panda|ur5|random``) and
:mod:`~clew_ros.worlds.spatial_holds`.
"""

from clew_ros.planar.passage import separation
from clew_ros.worlds.errors import GenerationError, UnknownFamilyError
from clew_ros.worlds.families import FAMILIES, Family, GeneratedWorld, family_names, generate
from clew_ros.worlds.files import witness_path, world_text, write_world
from clew_ros.worlds.regrasp import regrasp_needed

__all__ = [
    "FAMILIES",
    "Family",
    "GeneratedWorld",
    "GenerationError",
    "UnknownFamilyError",
    "family_names",
    "generate",
    "regrasp_needed",
    "separation",
    "witness_path",
    "world_text",
    "write_world",
]
