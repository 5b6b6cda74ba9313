"""Random waypoint paths for the tests of pruning and shortcuts."""

from __future__ import annotations

import numpy as np


def random_path(rng: np.random.Generator, joints: int) -> np.ndarray:
    """Manhattan-like moves, often undone, loops back to earlier waypoints (some off by less than 1e-12),
    repeats, and free moves."""
    points = [rng.uniform(-3.0, 3.0, joints)]
    for _ in range(int(rng.integers(1, 40))):
        point = points[-1].copy()
        draw = rng.random()
        if draw < 0.2 and len(points) > 2:
            point = points[int(rng.integers(0, len(points)))] + rng.choice([0.0, 5e-13, 3e-12])  # a loop, or nearly
        elif draw < 0.7:
            point[rng.integers(0, joints)] += rng.choice([-1.0, -0.5, 0.5, 1.0])
        elif draw < 0.9:
            point += rng.normal(0.0, 0.3, joints)
        points.append(point)  # else repeated
    return np.array(points)
