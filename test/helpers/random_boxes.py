"""Random axis-aligned boxes around a planar arm's base, for the tests' random worlds."""

from __future__ import annotations

import numpy as np

__all__ = ["random_boxes"]


def random_boxes(rng: np.random.Generator, count: int, clear_radius: float) -> dict[str, list[float]]:
    """``count`` boxes ``box_i`` (half sizes 0.05-0.3 m, centres in [-2, 2]^2 but not within ``clear_radius``
    of the origin), as ``world.obstacles`` polygons (4 corners, counter-clockwise)."""
    boxes: dict[str, list[float]] = {}
    while len(boxes) < count:
        centre = rng.uniform(-2.0, 2.0, 2)
        if np.hypot(*centre) < clear_radius:
            continue
        half = rng.uniform(0.05, 0.3, 2)
        corners = [(-1, -1), (1, -1), (1, 1), (-1, 1)]
        boxes[f"box_{len(boxes)}"] = [float(v) for sx, sy in corners for v in centre + half * (sx, sy)]
    return boxes
