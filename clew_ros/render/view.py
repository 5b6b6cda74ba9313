"""World-to-pixel mapping (the geometry a picture shows is the scene's: :mod:`clew_ros.scene.items`)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from clew_ros.planar.world import World
from clew_ros.scene.items import arm_points, object_outline

__all__ = ["View", "arm_points", "object_outline"]


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
    def fit(cls, world: World, size: int) -> View:
        """The world's bounds (plus a little room) fitted into ``size`` pixels on the long side."""
        xmin, ymin, xmax, ymax = (float(v) for v in world.bounds)
        pad = 0.03 * max(xmax - xmin, ymax - ymin)
        xmin, ymin, xmax, ymax = xmin - pad, ymin - pad, xmax + pad, ymax + pad
        margin = max(4, size // 80)
        scale = (size - 2 * margin) / max(xmax - xmin, ymax - ymin)
        width = round(2 * margin + (xmax - xmin) * scale)
        height = round(2 * margin + (ymax - ymin) * scale)
        return cls(xmin, ymax, scale, margin, width, height)

    def px(self, points: np.ndarray) -> np.ndarray:
        """World points ``(..., 2)`` as pixel coordinates ``(..., 2)`` (floats)."""
        points = np.asarray(points, dtype=float)
        x = self.margin + (points[..., 0] - self.xmin) * self.scale
        y = self.margin + (self.ytop - points[..., 1]) * self.scale
        return np.stack([x, y], axis=-1)

    def length(self, metres: float) -> float:
        """``metres`` in pixels."""
        return metres * self.scale
