"""A point cloud as occupied cubes (interface.md section 3c, ``~/points``), over whole arrays.

:func:`occupied_cubes` drops the points that are not obstacles (non-finite, outside the bounds, on the arm:
within ``grow_m`` of its sphere cover, or inside the object or a known obstacle grown by ``grow_m``), then
marks the cube of edge ``voxel_m`` each remaining point falls in. The arm test and the marking are compiled
loops over the points (numba); a point outside the arm's bounding box costs six comparisons, and the cubes
are found on a dense occupancy grid over the points' extent (a sort of the keys when that grid would be
too large), so 300,000 points take a few milliseconds (docs/benchmarks.md).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numba
import numpy as np
from numpy.typing import NDArray

from clew_ros.spatial.scene import Obstacle

__all__ = ["VOXELS", "VoxelSettings", "occupied_cubes"]

Array = NDArray[np.float64]


@dataclass(frozen=True)
class VoxelSettings:
    """How a point cloud is voxelised."""

    #: The most cells (bytes) of the dense occupancy grid; a cloud spread wider is voxelised by sorting its keys.
    grid_cells: int = 64_000_000


#: The settings :func:`occupied_cubes` works with.
VOXELS = VoxelSettings()

_jit = numba.njit(cache=True, nogil=True, error_model="numpy")


_BOX, _CYLINDER, _SPHERE = 0, 1, 2


@_jit
def _in_solid(x: float, y: float, z: float, rot: Any, pos: Any, kind: int, dims: Any, grow: float) -> Any:  # noqa: PLR0917
    """Whether a point lies in a solid (its rotation, position, kind, SolidPrimitive dims) grown by ``grow``."""
    dx, dy, dz = x - pos[0], y - pos[1], z - pos[2]
    lx = rot[0, 0] * dx + rot[1, 0] * dy + rot[2, 0] * dz
    ly = rot[0, 1] * dx + rot[1, 1] * dy + rot[2, 1] * dz
    lz = rot[0, 2] * dx + rot[1, 2] * dy + rot[2, 2] * dz
    if kind == _BOX:
        return abs(lx) <= dims[0] / 2 + grow and abs(ly) <= dims[1] / 2 + grow and abs(lz) <= dims[2] / 2 + grow
    if kind == _CYLINDER:
        return lx * lx + ly * ly <= (dims[1] + grow) ** 2 and abs(lz) <= dims[0] / 2 + grow
    return lx * lx + ly * ly + lz * lz <= (dims[0] + grow) ** 2


@_jit
def _on_arm(x: float, y: float, z: float, low: Any, high: Any, spheres: Any, reach2: Any) -> bool:  # noqa: PLR0917
    """Whether a point lies within ``sqrt(reach2[s])`` of a sphere ``s`` (none outside ``low``..``high``)."""
    if not (low[0] <= x <= high[0] and low[1] <= y <= high[1] and low[2] <= z <= high[2]):
        return False
    for s in range(spheres.shape[0]):
        dx, dy, dz = x - spheres[s, 0], y - spheres[s, 1], z - spheres[s, 2]
        if dx * dx + dy * dy + dz * dz <= reach2[s]:
            return True
    return False


@_jit
def _in_solids(x: float, y: float, z: float, solids: Any, grow: float) -> bool:
    """Whether a point lies in one of ``solids`` (rotations, positions, kinds, dims, squared reaches)."""
    rot, pos, kind, dims, reach2 = solids
    for k in range(kind.shape[0]):
        dx, dy, dz = x - pos[k, 0], y - pos[k, 1], z - pos[k, 2]
        if dx * dx + dy * dy + dz * dz <= reach2[k] and _in_solid(x, y, z, rot[k], pos[k], kind[k], dims[k], grow):
            return True
    return False


@_jit
def _keep(  # noqa: PLR0917  # pragma: no cover
    xyz: Any, bounds: Any, low: Any, high: Any, spheres: Any, reach2: Any, solids: Any, grow: float,
    voxel: float, cells: Any, keep: Any, extent: Any,
) -> int:  # fmt: skip
    """For each point: whether it is kept (finite, inside ``bounds``, off the arm's spheres, outside every
    solid) into ``keep`` and its cell into ``cells``; the kept cells' lowest and highest into ``extent`` (2, 3);
    the count kept (compiled)."""
    count = 0
    for i in range(xyz.shape[0]):
        x, y, z = xyz[i, 0], xyz[i, 1], xyz[i, 2]
        if not (np.isfinite(x) and np.isfinite(y) and np.isfinite(z)):
            continue
        if x < bounds[0] or y < bounds[1] or z < bounds[2] or x > bounds[3] or y > bounds[4] or z > bounds[5]:
            continue
        if _on_arm(x, y, z, low, high, spheres, reach2) or _in_solids(x, y, z, solids, grow):
            continue
        keep[i] = True
        cells[i, 0], cells[i, 1], cells[i, 2] = math.floor(x / voxel), math.floor(y / voxel), math.floor(z / voxel)
        for a in range(3):
            extent[0, a] = cells[i, a] if count == 0 else min(extent[0, a], cells[i, a])
            extent[1, a] = cells[i, a] if count == 0 else max(extent[1, a], cells[i, a])
        count += 1
    return count


@_jit
def _mark(cells: Any, keep: Any, low: Any, span: Any, grid: Any) -> int:  # pragma: no cover
    """Set the grid cell of each kept point; how many cells are set (compiled)."""
    count = 0
    for i in range(cells.shape[0]):
        if keep[i]:
            a, b, c = cells[i, 0] - low[0], cells[i, 1] - low[1], cells[i, 2] - low[2]
            k = (a * span[1] + b) * span[2] + c
            if grid[k] == 0:
                grid[k] = 1
                count += 1
    return count


@_jit
def _centres(grid: Any, low: Any, span: Any, voxel: float, out: Any) -> None:  # pragma: no cover
    """The centre of each set cell, in cell order (compiled)."""
    n = 0
    for k in range(grid.shape[0]):
        if grid[k]:
            c = k % span[2]
            b = (k // span[2]) % span[1]
            a = k // (span[2] * span[1])
            out[n, 0] = (low[0] + a + 0.5) * voxel
            out[n, 1] = (low[1] + b + 0.5) * voxel
            out[n, 2] = (low[2] + c + 0.5) * voxel
            n += 1


def _bounding_radius(shape: str, size: Sequence[float]) -> float:
    if shape == "box":
        return float(np.linalg.norm(np.asarray(size) / 2))
    if shape == "cylinder":
        return math.hypot(size[0] / 2, size[1])
    return float(size[0])


def _solid_arrays(solids: Sequence[Obstacle], grow: float) -> tuple[Array, Array, NDArray[np.int64], Array, Array]:
    kinds = {"box": _BOX, "cylinder": _CYLINDER, "sphere": _SPHERE}
    rot = np.array([s.pose[:3, :3] for s in solids], dtype=np.float64).reshape(-1, 3, 3)
    pos = np.array([s.pose[:3, 3] for s in solids], dtype=np.float64).reshape(-1, 3)
    kind = np.array([kinds[s.shape] for s in solids], dtype=np.int64)
    dims = np.array([[*s.size, 0.0, 0.0][:3] for s in solids], dtype=np.float64).reshape(-1, 3)
    reach = np.array([_bounding_radius(s.shape, s.size) + grow for s in solids], dtype=np.float64)
    return rot, pos, kind, dims, reach * reach


def occupied_cubes(
    points: NDArray[np.floating[Any]],
    *,
    voxel_m: float,
    grow_m: float,
    sphere_centers: Array,
    sphere_radii: Array,
    solids: Sequence[Obstacle] = (),
    bounds: Array | None = None,
) -> Array:
    """The centres (k, 3) of the cubes of edge ``voxel_m`` (a grid aligned on the origin of ``world``) that
    hold at least one point of ``points`` (N, 3) once these are dropped: non-finite points, points outside
    ``bounds`` (when given), points within ``grow_m`` of the arm's spheres (``sphere_centers`` (S, 3) in
    ``world``, ``sphere_radii``) and points inside a solid of ``solids`` (the object, known obstacles)
    grown by ``grow_m``. In the order of their cells (x, then y, then z), so a cloud gives the same cubes in
    the same order every time."""
    xyz = np.ascontiguousarray(np.asarray(points).reshape(-1, 3))
    spheres = np.ascontiguousarray(np.asarray(sphere_centers, dtype=np.float64).reshape(-1, 3))
    radii = np.asarray(sphere_radii, dtype=np.float64) + grow_m
    if len(radii):
        low = np.min(spheres - radii[:, None], axis=0)
        high = np.max(spheres + radii[:, None], axis=0)
    else:
        low, high = np.full(3, np.inf), np.full(3, -np.inf)
    box = np.concatenate([np.full(3, -np.inf), np.full(3, np.inf)]) if bounds is None else np.asarray(bounds, float)
    cells = np.zeros((len(xyz), 3), dtype=np.int64)
    keep = np.zeros(len(xyz), dtype=np.bool_)
    extent = np.zeros((2, 3), dtype=np.int64)
    count = _keep(
        xyz, box, low, high, spheres, radii * radii, _solid_arrays(solids, grow_m), float(grow_m), float(voxel_m),
        cells, keep, extent,
    )  # fmt: skip
    if count == 0:
        return np.zeros((0, 3))
    low_cell = extent[0]
    span = extent[1] - low_cell + 1
    if int(np.prod(span)) <= VOXELS.grid_cells:
        grid = np.zeros(int(np.prod(span)), dtype=np.uint8)
        out: Array = np.empty((_mark(cells, keep, low_cell, span, grid), 3))
        _centres(grid, low_cell, span, float(voxel_m), out)
        return out
    rel = cells[keep] - low_cell
    index = np.unique((rel[:, 0] * span[1] + rel[:, 1]) * span[2] + rel[:, 2])
    occupied = np.stack(np.unravel_index(index, tuple(int(v) for v in span)), axis=1) + low_cell
    return np.asarray((occupied + 0.5) * voxel_m, dtype=np.float64)
