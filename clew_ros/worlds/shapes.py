"""Movable objects of the generated worlds: bars, boxes, triangles, L shapes, random convex and non-convex
polygons, each with grasps on several of its edges.

An object is given in its own frame, centred on its centroid, vertices counter-clockwise on a 0.1 mm
grid (so that the parameter file holds short numbers), and grasps at points of its edges (midpoints,
and for bars also the quarter points of the long edges) computed from the rounded vertices: they lie
on the boundary within far less than the parser's 1e-6 m. Each grasp comes with the outward normal of
its edge, from which the witness chooses how the arm approaches it.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import shapely

__all__ = ["SHAPES", "ObjectShape", "make_shape"]

#: Grid (m) of the object's vertices in its own frame.
VERTEX_GRID_M = 1e-4
#: Shortest edge (m) and thinnest part (m, twice the inscribed radius) of a generated object.
MIN_EDGE_M = 0.03
MIN_THICKNESS_M = 0.05


@dataclass(frozen=True, eq=False)
class ObjectShape:
    """An object: ``vertices`` (V, 2) counter-clockwise, ``grasps`` (G, 2) on its edges with the edges'
    outward unit ``normals`` (G, 2), all in the object frame (m); ``kind`` names the family of shapes."""

    kind: str
    vertices: np.ndarray
    grasps: np.ndarray
    normals: np.ndarray

    @property
    def radius(self) -> float:
        """Largest distance (m) from the object's origin to a vertex."""
        return float(np.linalg.norm(self.vertices, axis=1).max())

    @property
    def inscribed_radius(self) -> float:
        """Radius (m) of the largest disc inside the object."""
        circle = shapely.maximum_inscribed_circle(shapely.Polygon(self.vertices), 1e-4)
        return float(circle.length)


def _on_grid(vertices: np.ndarray) -> np.ndarray:
    """``vertices`` centred on their polygon's centroid, counter-clockwise, rounded to :data:`VERTEX_GRID_M`."""
    polygon = shapely.Polygon(vertices)
    centroid = np.asarray(polygon.centroid.coords[0])
    if not polygon.exterior.is_ccw:
        vertices = vertices[::-1]
    rounded: np.ndarray = np.round((vertices - centroid) / VERTEX_GRID_M) * VERTEX_GRID_M
    return np.round(rounded, 4)


def _edge_points(vertices: np.ndarray, edges: list[int], fractions: list[float]) -> tuple[np.ndarray, np.ndarray]:
    """Points at ``fractions`` along each edge of ``edges`` (edge i runs from vertex i to i + 1), with
    the edges' outward normals (counter-clockwise polygon: the edge direction turned clockwise)."""
    points, normals = [], []
    count = len(vertices)
    for edge in edges:
        a, b = vertices[edge], vertices[(edge + 1) % count]
        direction = (b - a) / max(float(np.linalg.norm(b - a)), 1e-12)  # a null edge is refused by _acceptable
        for fraction in fractions:
            points.append(np.round(a + fraction * (b - a), 6))
            normals.append([direction[1], -direction[0]])
    return np.array(points), np.array(normals)


def _shape(
    kind: str, vertices: np.ndarray, edges: list[int] | None = None, fractions: list[float] | None = None
) -> ObjectShape:
    on_grid = _on_grid(np.asarray(vertices, dtype=float))
    grasps, normals = _edge_points(on_grid, list(range(len(on_grid))) if edges is None else edges, fractions or [0.5])
    return ObjectShape(kind, on_grid, grasps, normals)


def _bar(rng: np.random.Generator, size: float) -> ObjectShape:
    length = size
    width = float(rng.uniform(0.06, min(0.14, length / 3)))
    h, w = length / 2, width / 2
    vertices = np.array([[-h, -w], [h, -w], [h, w], [-h, w]])
    # the ends (edges 1, 3) at their middles, the long edges (0, 2) at their quarter points and middles
    shape = _shape("bar", vertices, [1, 3])
    long_grasps, long_normals = _edge_points(shape.vertices, [0, 2], [0.25, 0.5, 0.75])
    return ObjectShape(
        "bar",
        shape.vertices,
        np.concatenate([shape.grasps, long_grasps]),
        np.concatenate([shape.normals, long_normals]),
    )


def _box(rng: np.random.Generator, size: float) -> ObjectShape:
    a, b = size * rng.uniform(0.45, 0.8, 2) / 2
    return _shape("box", np.array([[-a, -b], [a, -b], [a, b], [-a, b]]))


def _triangle(rng: np.random.Generator, size: float) -> ObjectShape:
    for _ in range(100):
        angles = np.sort(rng.uniform(0.0, 2 * np.pi, 3))
        gaps = np.diff(np.r_[angles, angles[0] + 2 * np.pi])
        if gaps.min() > 1.2:
            radii = size / 2 * rng.uniform(0.8, 1.0, 3)
            return _shape("triangle", np.stack([radii * np.cos(angles), radii * np.sin(angles)], axis=1))
    return _shape("triangle", size / 2 * np.array([[1.0, 0.0], [-0.5, 0.866], [-0.5, -0.866]]))


def _l_shape(rng: np.random.Generator, size: float) -> ObjectShape:
    width, height = size * rng.uniform(0.55, 1.0, 2)
    thickness = float(rng.uniform(0.3, 0.45)) * min(width, height)
    vertices = np.array(
        [[0, 0], [width, 0], [width, thickness], [thickness, thickness], [thickness, height], [0, height]]
    )
    return _shape("L", vertices)


def _convex(rng: np.random.Generator, size: float) -> ObjectShape:
    count = int(rng.integers(5, 9))
    angles = np.sort(rng.uniform(0.0, 2 * np.pi, count))
    a, b = size / 2, size / 2 * float(rng.uniform(0.55, 1.0))
    hull = shapely.MultiPoint(np.stack([a * np.cos(angles), b * np.sin(angles)], axis=1)).convex_hull
    if not isinstance(hull, shapely.Polygon):  # all points on a line: not a polygon, draw again
        return _box(rng, size)
    return _shape("convex", shapely.get_coordinates(hull)[:-1])


def _non_convex(rng: np.random.Generator, size: float) -> ObjectShape:
    count = 2 * int(rng.integers(3, 5))
    angles = np.arange(count) * 2 * np.pi / count + rng.uniform(-0.15, 0.15, count)
    # an inner vertex well inside the chord between its two outer neighbours: a notch, never convex
    inner = np.cos(2 * np.pi / count) * rng.uniform(0.55, 0.8, count)
    radii = size / 2 * np.where(np.arange(count) % 2 == 0, rng.uniform(0.85, 1.0, count), inner)
    return _shape("nonconvex", np.stack([radii * np.cos(angles), radii * np.sin(angles)], axis=1))


#: The shape kinds and how each is made from a generator and a size (m, about the largest dimension).
SHAPES: dict[str, Callable[[np.random.Generator, float], ObjectShape]] = {
    "bar": _bar,
    "box": _box,
    "triangle": _triangle,
    "L": _l_shape,
    "convex": _convex,
    "nonconvex": _non_convex,
}


def _acceptable(shape: ObjectShape) -> bool:
    polygon = shapely.Polygon(shape.vertices)
    edges = np.linalg.norm(np.roll(shape.vertices, -1, axis=0) - shape.vertices, axis=1)
    return bool(polygon.is_valid and edges.min() >= MIN_EDGE_M and 2 * shape.inscribed_radius >= MIN_THICKNESS_M)


def make_shape(kind: str, rng: np.random.Generator, size: float) -> ObjectShape:
    """An object of ``kind`` (a key of :data:`SHAPES`) about ``size`` m across, drawn from ``rng``.

    Draws again (at most 100 times) until the polygon is simple, its edges at least
    :data:`MIN_EDGE_M` long and its inscribed disc at least :data:`MIN_THICKNESS_M` across.
    """
    for _ in range(100):
        shape = SHAPES[kind](rng, size)
        if _acceptable(shape):
            return shape
    raise ValueError(f"no acceptable {kind} of size {size:.3f} m in 100 draws")
