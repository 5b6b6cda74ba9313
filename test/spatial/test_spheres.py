"""clew_ros.spatial.spheres: the sphere model covers every collision geometry (sampled surface points)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from clew_ros.spatial.robot import Geometry, RobotModel
from clew_ros.spatial.spheres import SphereSettings, cover, over_approximation, sphere_model, surface_points

SETTINGS = SphereSettings()


def outside_by(points: np.ndarray, centers: np.ndarray, radii: np.ndarray) -> np.ndarray:
    """How far (m) each point lies outside the union of the spheres (<= 0: inside)."""
    return (np.linalg.norm(points[:, None, :] - centers[None, :, :], axis=2) - radii[None, :]).min(axis=1)


def primitive(kind: str, size: tuple[float, ...]) -> Geometry:
    return Geometry("link", kind, size, np.eye(4))


@pytest.mark.parametrize(
    "geometry",
    [
        primitive("sphere", (0.05,)),
        primitive("box", (0.1, 0.1, 0.1)),
        primitive("box", (0.3, 0.02, 0.15)),
        primitive("box", (0.0175, 0.007, 0.0235)),
        primitive("box", (2.0, 1.0, 0.01)),  # past max_primitive_cells: coarser cells
        primitive("cylinder", (0.283, 0.09)),
        primitive("cylinder", (0.03, 0.09)),
        primitive("cylinder", (0.5, 0.01)),
    ],
    ids=lambda g: f"{g.kind}{g.size}",
)
def test_primitives_are_covered(geometry: Geometry) -> None:
    centers, radii = cover(geometry, SETTINGS)
    points = surface_points(geometry, 4000, np.random.default_rng(1))
    assert outside_by(points, centers, radii).max() <= 1e-12
    over = over_approximation([(geometry, np.eye(4))], centers, radii, np.random.default_rng(2))
    assert over.max() < max(geometry.size)  # a cover, not a blanket over the whole scene


def test_an_open_mesh_still_has_its_surface_covered() -> None:
    trimesh = pytest.importorskip("trimesh")
    box = trimesh.creation.box(extents=[0.12, 0.08, 0.2])
    mesh = Geometry("link", "mesh", (), np.eye(4), np.asarray(box.vertices), np.asarray(box.faces)[2:])  # a side open
    centers, radii = cover(mesh, SETTINGS)
    points = surface_points(mesh, 4000, np.random.default_rng(3))
    assert outside_by(points, centers, radii).max() <= 1e-12


def test_a_closed_mesh_has_its_inside_covered_too() -> None:
    trimesh = pytest.importorskip("trimesh")
    ball = trimesh.creation.icosphere(subdivisions=2, radius=0.1)
    mesh = Geometry("link", "mesh", (), np.eye(4), np.asarray(ball.vertices), np.asarray(ball.faces))
    centers, radii = cover(mesh, SETTINGS)
    rng = np.random.default_rng(4)
    inside = rng.uniform(-0.1, 0.1, size=(4000, 3))
    inside = inside[np.linalg.norm(inside, axis=1) < 0.09]
    assert outside_by(inside, centers, radii).max() <= 1e-12


@pytest.mark.parametrize("name", ["panda", "panda_capsules", "ur5"])
def test_every_link_of_the_shipped_robots_is_covered(name: str, request: pytest.FixtureRequest) -> None:
    robot: RobotModel = request.getfixturevalue(name)
    model = request.getfixturevalue(f"{name}_spheres") if name != "panda_capsules" else sphere_model(robot, SETTINGS)
    rng = np.random.default_rng(5)
    worst, over = 0.0, []
    for i, link in enumerate(robot.links):
        mine = slice(model.starts[i], model.starts[i + 1])
        assert np.all(model.links[mine] == i)
        assert np.all(model.frames[mine] == link.frame)
        placed = [(geometry, link.offset @ geometry.origin) for geometry in link.geometries]
        for geometry, pose in placed:
            points = surface_points(geometry, 1500, rng) @ pose[:3, :3].T + pose[:3, 3]
            worst = max(worst, float(outside_by(points, model.centers[mine], model.radii[mine]).max()))
        over.append(over_approximation(placed, model.centers[mine], model.radii[mine], rng))
    assert worst <= 1e-9
    distances = np.concatenate(over)
    # mesh cells reach past the surface by up to a cell diagonal, spheres by the protrusion on top
    assert distances.max() <= math.sqrt(3) * SETTINGS.cell_m + SETTINGS.protrusion_m + 0.04
    print(
        f"{name}: {model.count} spheres, over-approximation mean {distances.mean() * 1e3:.1f} mm, "
        f"max {distances.max() * 1e3:.1f} mm"
    )
