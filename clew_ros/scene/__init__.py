"""One description of what to draw: the scene every view of a planar world shows.

The picture (:mod:`clew_ros.render`: PNG, GIF, SVG), the RViz markers
(:mod:`clew_ros.ros.messages`: ``~/world_markers``, ``~/landmarks``,
``~/scene``) and the Foxglove view (:mod:`clew_ros.live.messages`) take their
geometry and colours from here; each only chooses its own sizes and encodes.

- :mod:`~clew_ros.scene.palette`: the named RGBA colours (:data:`PALETTE`);
- :mod:`~clew_ros.scene.items`: the world (bounds, obstacles, the object at
  start and goal, grasp points), the arm at a configuration with its
  gripper and the object, the landmark tree (nodes, edges, outlines);
- :mod:`~clew_ros.scene.path`: a plan replayed and the tip's path by
  segment kind (transit, transfer).

Imports only :mod:`clew_ros.core`; no ROS, no drawing library.
"""

from clew_ros.scene.items import (
    HOLDING_THRESHOLD,
    ArmItems,
    LandmarkLike,
    ObstacleItem,
    TreeItems,
    WorldItems,
    arm_items,
    arm_points,
    gripper_key,
    object_key,
    object_outline,
    tree_items,
    world_items,
)
from clew_ros.scene.palette import ON_DARK, PALETTE, Colour, colour
from clew_ros.scene.path import Motion, TipPiece, plan_motion

__all__ = [
    "HOLDING_THRESHOLD",
    "ON_DARK",
    "PALETTE",
    "ArmItems",
    "Colour",
    "LandmarkLike",
    "Motion",
    "ObstacleItem",
    "TipPiece",
    "TreeItems",
    "WorldItems",
    "arm_items",
    "arm_points",
    "colour",
    "gripper_key",
    "object_key",
    "object_outline",
    "plan_motion",
    "tree_items",
    "world_items",
]
