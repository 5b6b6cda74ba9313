"""Proof that the object cannot get from its start to its goal: the free space eroded by the object's
inscribed disc separates them.

Let ``c`` be the centre and ``r`` the radius of the largest disc inside the object (object frame).
Wherever the object may be (inside the bounds, touching no obstacle), that disc is inside the bounds
and misses every obstacle, so ``c`` lies in the open set of points farther than ``r`` from every
obstacle and at least ``r`` inside the bounds. Any motion moves ``c`` continuously within that set,
hence within one of its connected components. When ``c`` at the start and ``c`` at the goal lie in
different components, no motion, by the arm or otherwise, takes the object to its goal. The
obstacles are grown by ``r`` with shapely's buffer, whose arcs are chords inside the true circles:
the computed free set contains the true one, so a separation found is a separation that holds.
"""

from __future__ import annotations

import numpy as np
import shapely

from clew_ros.core.kinematics import transform_points
from clew_ros.core.world import World

__all__ = ["separation"]


def separation(world: World) -> str | None:
    """Why the object cannot pass from ``world.object.initial`` to ``world.object.goal`` (a sentence), or
    ``None`` when this test proves nothing."""
    polygon = shapely.Polygon(world.object.polygon)
    circle = shapely.maximum_inscribed_circle(polygon, 1e-5)
    centre = np.asarray(circle.coords[0])
    radius = float(circle.length) * 0.999  # a disc surely inside: the search's tolerance works both ways
    xmin, ymin, xmax, ymax = world.bounds
    free = shapely.box(xmin + radius, ymin + radius, xmax - radius, ymax - radius)
    if world.obstacles:
        grown = shapely.union_all([shapely.Polygon(o.vertices) for o in world.obstacles]).buffer(radius, quad_segs=16)
        free = free.difference(grown)
    start, goal = (
        shapely.Point(transform_points(np.asarray(pose, float), centre[None])[0])
        for pose in (world.object.initial, world.object.goal)
    )
    parts = list(getattr(free, "geoms", [free]))
    where = [next((i for i, part in enumerate(parts) if part.contains(point)), None) for point in (start, goal)]
    if where[0] is None or where[1] is None or where[0] == where[1]:
        return None
    return (
        f"the object cannot pass from its start to its goal: the free space eroded by its inscribed disc "
        f"(radius {radius:.4f} m) puts them in different components"
    )
