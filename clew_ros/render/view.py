"""World-to-picture mapping, colours and the geometry every output draws."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from clew_ros.core.kinematics import joint_positions, transform_points
from clew_ros.core.world import World

__all__ = ["View", "COLORS", "LEGEND", "arm_points", "object_outline", "rest_poses"]

#: RGB colours shared by the PNG, GIF and SVG outputs.
COLORS = {
    "background": (255, 255, 255),
    "field": (248, 248, 244),
    "field_edge": (80, 80, 80),
    "obstacle": (106, 109, 120),
    "obstacle_edge": (55, 57, 64),
    "start": (45, 95, 200),
    "goal": (20, 150, 70),
    "grasp": (200, 40, 150),
    "tree_edge": (150, 100, 200),
    "tree_node": (115, 60, 175),
    "transit": (80, 130, 210),
    "transfer": (235, 125, 25),
    "arm": (45, 45, 52),
    "joint": (255, 255, 255),
    "open": (40, 170, 80),
    "closed": (215, 45, 45),
    "object_rest": (110, 150, 225),
    "object_held": (240, 155, 50),
    "text": (30, 30, 30),
    "muted": (110, 110, 110),
}

#: Legend entries: (label, colour key, style) with style one of box, dashed, dot, line.
LEGEND = [
    ("start", "start", "box"),
    ("goal", "goal", "dashed"),
    ("obstacle", "obstacle", "fill"),
    ("grasps", "grasp", "dot"),
    ("landmark tree", "tree_node", "dot"),
    ("transit", "transit", "line"),
    ("transfer", "transfer", "line"),
    ("gripper open", "open", "dot"),
    ("holding", "closed", "dot"),
]


@dataclass(frozen=True)
class View:
    """Maps world metres to picture pixels (y up in the world, down in the picture)."""

    xmin: float  # world x at the picture's left edge (m)
    ytop: float  # world y at the picture's top edge (m)
    scale: float  # pixels per metre
    margin: int
    width: int  # of the map area
    height: int  # of the map area

    @classmethod
    def fit(cls, world: World, size: int) -> "View":
        """The world's bounds (plus a little room) fitted into ``size`` pixels on the long side."""
        xmin, ymin, xmax, ymax = (float(v) for v in world.bounds)
        pad = 0.03 * max(xmax - xmin, ymax - ymin)
        xmin, ymin, xmax, ymax = xmin - pad, ymin - pad, xmax + pad, ymax + pad
        margin = max(4, size // 80)
        scale = (size - 2 * margin) / max(xmax - xmin, ymax - ymin)
        width = int(round(2 * margin + (xmax - xmin) * scale))
        height = int(round(2 * margin + (ymax - ymin) * scale))
        return cls(xmin, ymax, scale, margin, width, height)

    def px(self, points: np.ndarray) -> np.ndarray:
        """World points ``(..., 2)`` as pixel coordinates ``(..., 2)`` (floats)."""
        points = np.asarray(points, dtype=float)
        x = self.margin + (points[..., 0] - self.xmin) * self.scale
        y = self.margin + (self.ytop - points[..., 1]) * self.scale
        return np.stack([x, y], axis=-1)

    def length(self, metres: float) -> float:
        return metres * self.scale


def arm_points(world: World, q: np.ndarray) -> np.ndarray:
    """Base, joints and tip of the arm at ``q``: ``(n + 1, 2)``."""
    return joint_positions(world.robot, np.asarray(q, dtype=float)[None])[0]


def object_outline(world: World, pose: np.ndarray) -> np.ndarray:
    """The object's polygon at ``pose``: ``(V, 2)``."""
    return transform_points(np.asarray(pose, dtype=float), world.object.polygon)


def rest_poses(motion) -> list[np.ndarray]:
    """Where the object is put down along a motion (after each ungrasp)."""
    return [motion.object_poses[row] for row, kind, _grasp in motion.events if kind == "ungrasp"]
