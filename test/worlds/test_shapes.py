"""The objects of generated worlds: simple polygons on a grid, grasps on their edges with outward normals."""

from __future__ import annotations

import numpy as np
import pytest
import shapely

from clew_ros.planar.world import WORLD_CHECKS
from clew_ros.worlds.shapes import MIN_EDGE_M, MIN_THICKNESS_M, SHAPES, make_shape


@pytest.mark.parametrize("kind", list(SHAPES))
@pytest.mark.parametrize("seed", range(5))
def test_a_shape_is_a_simple_polygon_with_grasps_on_its_edges(kind: str, seed: int) -> None:
    shape = make_shape(kind, np.random.default_rng(seed), 0.4)
    polygon = shapely.Polygon(shape.vertices)
    assert polygon.is_valid
    assert polygon.exterior.is_ccw
    assert np.allclose(shape.vertices, np.round(shape.vertices, 4))  # the 0.1 mm grid
    assert np.allclose(polygon.centroid.coords[0], 0.0, atol=1e-3)  # the frame is at the centroid
    edges = np.linalg.norm(np.roll(shape.vertices, -1, axis=0) - shape.vertices, axis=1)
    assert edges.min() >= MIN_EDGE_M
    assert 2 * shape.inscribed_radius >= MIN_THICKNESS_M
    assert shape.radius <= 0.3
    assert len(shape.grasps) >= 3
    distances = shapely.distance(polygon.exterior, shapely.points(shape.grasps))
    assert np.all(distances <= WORLD_CHECKS.grasp_on_boundary_tolerance_m / 10)
    assert np.allclose(np.linalg.norm(shape.normals, axis=1), 1.0)
    outside = shapely.points(shape.grasps + 1e-3 * shape.normals)
    inside = shapely.points(shape.grasps - 1e-3 * shape.normals)
    assert not np.any(shapely.contains(polygon, outside))
    assert np.all(shapely.contains(polygon, inside))


def test_shapes_are_what_their_names_say() -> None:
    rng = np.random.default_rng(3)
    assert len(make_shape("bar", rng, 0.5).vertices) == 4
    assert len(make_shape("bar", rng, 0.5).grasps) == 8  # both ends, three points on each long edge
    assert len(make_shape("box", rng, 0.5).grasps) == 4
    assert len(make_shape("triangle", rng, 0.5).vertices) == 3
    assert len(make_shape("L", rng, 0.5).vertices) == 6
    for kind, convex in (("convex", True), ("nonconvex", False), ("L", False)):
        polygon = shapely.Polygon(make_shape(kind, rng, 0.5).vertices)
        assert (polygon.area >= polygon.convex_hull.area - 1e-9) == convex, kind


def test_same_generator_same_shape() -> None:
    first = make_shape("nonconvex", np.random.default_rng(9), 0.5)
    second = make_shape("nonconvex", np.random.default_rng(9), 0.5)
    assert np.array_equal(first.vertices, second.vertices)
    assert np.array_equal(first.grasps, second.grasps)
