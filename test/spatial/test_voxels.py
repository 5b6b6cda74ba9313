"""Point clouds as occupied cubes (``clew_ros.spatial.voxels``, interface.md section 3c): each cube holds a kept
point, every kept point lies in a cube, the dropped points (non-finite, out of bounds, on the arm's spheres
grown by ``grow_m``, inside a solid grown by ``grow_m``) are those a plain per-point reference drops, and the
dense grid and the sorted keys give the same cubes."""

from __future__ import annotations

import math

import numpy as np
import pytest

from clew_ros.spatial import voxels
from clew_ros.spatial.scene import make_obstacle
from clew_ros.spatial.transforms import pose_matrix
from clew_ros.spatial.voxels import occupied_cubes

VOXEL = 0.02
GROW = 0.01
SPHERES = np.array([[0.0, 0.0, 0.5], [0.1, 0.0, 0.6]])
RADII = np.array([0.05, 0.04])
SOLIDS = [
    make_obstacle("box", "box", [0.2, 0.1, 0.05], pose_matrix([0.4, 0.3, 0.2, 0.3, 0.0, 0.7]), "t"),
    make_obstacle("can", "cylinder", [0.2, 0.05], pose_matrix([-0.3, 0.2, 0.3, 0.0, 0.4, 0.0]), "t"),
    make_obstacle("ball", "sphere", [0.06], pose_matrix([0.0, -0.4, 0.4, 0.0, 0.0, 0.0]), "t"),
]
BOUNDS = np.array([-0.6, -0.6, 0.0, 0.6, 0.6, 1.0])


def _reference_dropped(points: np.ndarray) -> np.ndarray:
    """Per point, plainly: whether it is dropped."""
    out = []
    for p in points:
        if not np.all(np.isfinite(p)) or np.any(p < BOUNDS[:3]) or np.any(p > BOUNDS[3:]):
            out.append(True)
            continue
        if any(np.linalg.norm(p - c) <= r + GROW for c, r in zip(SPHERES, RADII, strict=True)):
            out.append(True)
            continue
        inside = False
        for solid in SOLIDS:
            local = solid.pose[:3, :3].T @ (p - solid.pose[:3, 3])
            if solid.shape == "box":
                inside |= bool(np.all(np.abs(local) <= np.asarray(solid.size) / 2 + GROW))
            elif solid.shape == "cylinder":
                inside |= (
                    math.hypot(local[0], local[1]) <= solid.size[1] + GROW and abs(local[2]) <= solid.size[0] / 2 + GROW
                )
            else:
                inside |= float(np.linalg.norm(local)) <= solid.size[0] + GROW
        out.append(inside)
    return np.array(out)


def _cloud(rng: np.random.Generator) -> np.ndarray:
    near = [rng.normal(c, 0.05, size=(300, 3)) for c in (SPHERES[0], SOLIDS[0].pose[:3, 3], SOLIDS[1].pose[:3, 3])]
    spread = rng.uniform(-0.7, 1.0, size=(3000, 3))
    points = np.concatenate([*near, rng.normal(SOLIDS[2].pose[:3, 3], 0.05, size=(300, 3)), spread])
    points[:5] = np.nan
    return points.astype(np.float32)


def test_the_cubes_hold_exactly_the_points_a_per_point_reference_keeps() -> None:
    points = _cloud(np.random.default_rng(3))
    cubes = occupied_cubes(
        points, voxel_m=VOXEL, grow_m=GROW, sphere_centers=SPHERES, sphere_radii=RADII, solids=SOLIDS, bounds=BOUNDS
    )
    as64 = points.astype(np.float64)
    dropped = _reference_dropped(as64)
    assert 0 < dropped.sum() < len(points), "some points dropped, some kept"
    kept_cells = {tuple(c) for c in np.floor(as64[~dropped] / VOXEL).astype(int).tolist()}
    cube_cells = [tuple(c) for c in np.floor(cubes / VOXEL).astype(int).tolist()]
    assert len(cube_cells) == len(set(cube_cells)), "each cube once"
    assert set(cube_cells) == kept_cells
    assert np.allclose(cubes / VOXEL - np.floor(cubes / VOXEL), 0.5), "centres of grid cells"
    assert cube_cells == sorted(cube_cells), "in cell order"


def test_the_sorted_keys_give_the_same_cubes_as_the_dense_grid(monkeypatch: pytest.MonkeyPatch) -> None:
    points = _cloud(np.random.default_rng(4))
    options = {"voxel_m": VOXEL, "grow_m": GROW, "sphere_centers": SPHERES, "sphere_radii": RADII, "solids": SOLIDS}
    dense = occupied_cubes(points, **options)  # type: ignore[arg-type]
    monkeypatch.setattr(voxels, "VOXELS", voxels.VoxelSettings(grid_cells=10))
    assert np.array_equal(occupied_cubes(points, **options), dense)  # type: ignore[arg-type]


def test_no_points_left_is_no_cubes() -> None:
    on_arm = SPHERES + np.array([0.0, 0.0, 0.01])
    cubes = occupied_cubes(on_arm, voxel_m=VOXEL, grow_m=GROW, sphere_centers=SPHERES, sphere_radii=RADII)
    assert cubes.shape == (0, 3)
    assert occupied_cubes(
        np.zeros((0, 3)), voxel_m=VOXEL, grow_m=0.0, sphere_centers=SPHERES, sphere_radii=RADII
    ).shape == (0, 3)
