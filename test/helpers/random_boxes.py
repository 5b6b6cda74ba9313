"""Random axis-aligned boxes around a planar arm's base, for the tests' random worlds."""

from __future__ import annotations

import numpy as np

from clew_ros.planar.world import World, world_from_parameters

__all__ = ["random_box_world", "random_boxes"]


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


def random_box_world(seed: int, joints: int, width: float) -> tuple[World, np.random.Generator]:
    """A world of six :func:`random_boxes` around an arm of ``joints`` joints (limits +-3 rad, links of
    ``width``, 1.9 m of reach at most) and a small bar resting near its base; also the generator, to go on
    drawing from."""
    rng = np.random.default_rng(seed)
    boxes = random_boxes(rng, 6, clear_radius=0.6)
    polygon = [0.0, 0.0, 0.2, 0.0, 0.2, 0.08, 0.0, 0.08]
    parameters = {
        "world": {
            "name": f"random_{seed}",
            "bounds": [-2.5, -2.5, 2.5, 2.5],
            "robot": {
                "base": [0.0, 0.0],
                "link_lengths": (rng.uniform(0.3, 1.0, joints) * 1.8 / joints + 0.1).tolist(),
                "link_width": width,
                "joint_lower": [-3.0] * joints,
                "joint_upper": [3.0] * joints,
                "initial": [0.0] * joints,
            },
            "obstacle_names": list(boxes),
            "obstacles": boxes,
            "object": {"polygon": polygon, "initial": [0.0, 0.35, 0.0], "goal": [0.0, 0.35, 0.0], "grasps": [0, 0]},
        }
    }
    return world_from_parameters(parameters), rng
