"""A conservative sphere model of a robot's collision geometry (like the sphere models of VAMP and cuRobo).

Every ``<collision>`` of every link is covered by spheres whose union contains it, so that what the
spheres call free is free for the URDF's geometry:

- a sphere: itself;
- a box: cut into near-cubic cells (edge at most ``primitive_cell_ratio`` x its thinnest side), each
  covered by the sphere through its corners;
- a cylinder: cut into slabs along its axis; a slab as thick as the radius is covered by the sphere
  through its rims, a flatter cylinder by square columns of cells that meet its disc;
- a mesh: voxelised at ``cell_m``. The cells that meet the surface (triangles split until no edge
  exceeds a cell; the cells each one's bounding box meets, at most two a side) and the cells enclosed by
  them (a flood fill from outside) hold the solid. Spheres are chosen greedily (a set cover): candidate
  centres on every other cell, each of radius (its depth below the surface + ``protrusion_m``), the
  candidate that covers the most uncovered cells first; a cell counts as covered only when all its
  corners are inside a sphere (a cell no candidate covers gets its own). Every point of the solid lies
  in a kept cell, so the cover is
  conservative by construction; ``protrusion_m`` trades tightness against the number of spheres.

Sphere centres are in the frame each link rides on (:class:`~clew_ros.spatial.robot.LinkModel.frame`).
:func:`over_approximation` measures how far the model reaches beyond the geometry.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import NDArray

from clew_ros.core.errors import WorldError
from clew_ros.core.parameters import LIMITS, Limits
from clew_ros.spatial.robot import Geometry, RobotModel

__all__ = [
    "SphereModel",
    "SphereSettings",
    "check_mesh_work",
    "cover",
    "inner_cover",
    "over_approximation",
    "sphere_model",
    "surface_points",
]

Array = NDArray[np.float64]
Matrix = NDArray[np.float64]


@dataclass(frozen=True)
class SphereSettings:
    """How finely the sphere model covers the collision geometry."""

    #: Voxel edge for meshes (m): the cover reaches at most about one cell beyond the surface from the
    #: voxelisation; smaller is tighter and slower to build (the work grows as the cube).
    cell_m: float = 0.01
    #: How far a mesh sphere may reach beyond the depth of its centre (m), on top of the cell's own reach:
    #: larger means fewer, bigger spheres (faster checks, a looser model).
    protrusion_m: float = 0.03
    #: Box and cylinder cells are cut no longer than this times the primitive's thinnest side (1: cubes)...
    primitive_cell_ratio: float = 1.0
    #: ... nor shorter than this (m): a thin plate is covered by a few spheres, not by hundreds.
    primitive_cell_m: float = 0.02
    #: A box or cylinder is never cut into more cells than this (coarser cells past it).
    max_primitive_cells: int = 64
    #: At most this many spheres of the inner model (spheres inside the geometry: touching them proves a
    #: collision) per mesh, the largest first.
    inner_per_mesh: int = 24


@dataclass(frozen=True, eq=False)
class SphereModel:
    """The spheres of a robot: ``centers`` (S, 3) in the frame of ``frames`` (S,), ``radii`` (S,) in m,
    ``links`` (S,) the index of the link (in :attr:`RobotModel.links`) each belongs to. Spheres of one link
    are contiguous: link i owns ``starts[i]:starts[i + 1]``."""

    centers: Array
    radii: Array
    frames: NDArray[np.int64]
    links: NDArray[np.int64]
    starts: NDArray[np.int64]
    #: The inner model: spheres inside the geometry (same conventions; a link may have none), or ``None``.
    inner: SphereModel | None = None

    @property
    def count(self) -> int:
        return len(self.radii)


# ----------------------------------------------------------------------------------------- primitives


def _grid_centers(sizes: Array, counts: NDArray[np.int64]) -> Array:
    axes = [(np.arange(k) + 0.5) / k * s - s / 2 for s, k in zip(sizes, counts, strict=True)]
    return np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)


def _cell_counts(sizes: Array, edge: float, limit: int) -> NDArray[np.int64]:
    counts = np.maximum(np.ceil(sizes / edge - 1e-9), 1).astype(np.int64)
    while int(np.prod(counts)) > limit:
        edge *= 1.25
        counts = np.maximum(np.ceil(sizes / edge - 1e-9), 1).astype(np.int64)
    return counts


def _cover_box(size: tuple[float, ...], settings: SphereSettings) -> tuple[Array, Array]:
    sizes = np.asarray(size, dtype=np.float64)
    edge = max(settings.primitive_cell_ratio * float(sizes.min()), settings.primitive_cell_m)
    counts = _cell_counts(sizes, edge, settings.max_primitive_cells)
    centers = _grid_centers(sizes, counts)
    return centers, np.full(len(centers), 0.5 * float(np.linalg.norm(sizes / counts)))


def _cover_cylinder(height: float, radius: float, settings: SphereSettings) -> tuple[Array, Array]:
    if height >= radius:  # slabs as thick as the radius, each in the sphere through its two rims
        k = math.ceil(height / (settings.primitive_cell_ratio * radius) - 1e-9)
        z = (np.arange(k) + 0.5) / k * height - height / 2
        centers = np.stack([np.zeros(k), np.zeros(k), z], axis=1)
        return centers, np.full(k, math.hypot(radius, height / (2 * k)))
    sizes = np.array([2 * radius, 2 * radius, height])
    edge = max(settings.primitive_cell_ratio * height, settings.primitive_cell_m)
    counts = _cell_counts(sizes, edge, settings.max_primitive_cells)
    centers = _grid_centers(sizes, counts)
    half = sizes / counts / 2
    # keep the columns whose square meets the disc (nearest point of the square within the radius)
    nearest = np.maximum(np.abs(centers[:, :2]) - half[:2], 0.0)
    keep = np.hypot(nearest[:, 0], nearest[:, 1]) <= radius
    return centers[keep], np.full(int(keep.sum()), float(np.linalg.norm(half)))


# ----------------------------------------------------------------------------------------- meshes


def _voxels(
    vertices: Array, faces: NDArray[np.int64], cell: float
) -> tuple[Array, NDArray[np.bool_], NDArray[np.bool_]]:
    """The grid's origin (m), its kept cells (those the surface meets and those it encloses) and the cells
    the surface meets."""
    import trimesh

    small_v, small_f = trimesh.remesh.subdivide_to_size(  # type: ignore[no-untyped-call]
        vertices, faces, max_edge=cell, max_iter=20
    )
    triangles = small_v[small_f]
    origin = vertices.min(axis=0) - 1.5 * cell
    shape = tuple(int(v) for v in np.ceil((vertices.max(axis=0) + 1.5 * cell - origin) / cell))
    surface = np.zeros(shape, dtype=bool)
    lo = np.floor((triangles.min(axis=1) - origin) / cell).astype(np.int64)
    hi = np.floor((triangles.max(axis=1) - origin) / cell).astype(np.int64)
    for dx in (0, 1):
        for dy in (0, 1):
            for dz in (0, 1):
                idx = np.minimum(lo + np.array([dx, dy, dz]), hi)
                surface[idx[:, 0], idx[:, 1], idx[:, 2]] = True
    outside = np.zeros(shape, dtype=bool)
    outside[0, 0, 0] = True
    while True:  # flood fill through the cells the surface does not touch (6-neighbours)
        grown = outside.copy()
        grown[1:] |= outside[:-1]
        grown[:-1] |= outside[1:]
        grown[:, 1:] |= outside[:, :-1]
        grown[:, :-1] |= outside[:, 1:]
        grown[:, :, 1:] |= outside[:, :, :-1]
        grown[:, :, :-1] |= outside[:, :, 1:]
        grown &= ~surface
        if np.array_equal(grown, outside):
            break
        outside = grown
    return origin, ~outside, surface


def _depths(points: Array, vertices: Array, faces: NDArray[np.int64], cell: float) -> Array:
    """Distance (m) from each point to the mesh surface, against surface samples half a cell apart."""
    import trimesh

    mesh = trimesh.Trimesh(vertices, faces, process=False)
    count = max(int(mesh.area / (cell / 2) ** 2), 100)
    samples = np.concatenate([vertices, np.asarray(trimesh.sample.sample_surface(mesh, count, seed=0)[0])])
    return _nearest(points, samples)


def _nearest(points: Array, samples: Array) -> Array:
    """Distance (m) from each point to the nearest of ``samples``."""
    out = np.empty(len(points))
    squared = (samples**2).sum(axis=1)
    for k in range(0, len(points), 256):  # |p - s|^2 = |p|^2 - 2 p.s + |s|^2, a chunk of points at a time
        chunk = points[k : k + 256]
        nearest = (squared[None, :] - 2.0 * chunk @ samples.T).min(axis=1) + (chunk**2).sum(axis=1)
        out[k : k + 256] = np.sqrt(np.maximum(nearest, 0.0))
    return out


def _erode(cells: NDArray[np.bool_]) -> NDArray[np.bool_]:
    """The cells whose 26 neighbours and themselves are all in ``cells`` (a 3x3x3 erosion, one axis at a time)."""
    out = cells.copy()
    for axis in range(3):
        moved = np.moveaxis(out, axis, 0)
        eroded = moved.copy()
        eroded[1:] &= moved[:-1]
        eroded[:-1] &= moved[1:]
        eroded[0] = eroded[-1] = False
        out = np.moveaxis(eroded, 0, axis)
    return out


def _inner_mesh(origin: Array, interior: NDArray[np.bool_], cell: float, limit: int) -> tuple[Array, Array]:
    """Spheres inside a mesh's solid: the cells no triangle meets that the surface encloses lie inside it, and
    so does the cube of such cells around one whose Chebyshev distance to the others is ``d`` (its inscribed
    sphere: radius ``(d - 0.5)`` cells). The largest first, each not inside one already kept, at most ``limit``."""
    depth = np.zeros(interior.shape, dtype=np.int64)
    level = interior
    while level.any():
        depth += level
        level = _erode(level)
    index = np.argwhere(depth > 0)
    if not len(index):
        return np.zeros((0, 3)), np.zeros(0)
    radius = (depth[tuple(index.T)] - 0.5) * cell
    centres = origin + (index + 0.5) * cell
    order = np.argsort(-radius, kind="stable")
    centres, radius = centres[order], radius[order]
    alive = np.ones(len(radius), dtype=bool)
    kept: list[int] = []
    while alive.any() and len(kept) < limit:
        best = int(np.argmax(alive))
        kept.append(best)
        alive &= np.linalg.norm(centres - centres[best], axis=1) + radius > radius[best] + 1e-12
    return np.asarray(centres[kept], dtype=np.float64), np.asarray(radius[kept], dtype=np.float64)


def _cover_mesh(
    vertices: Array, faces: NDArray[np.int64], settings: SphereSettings, where: str = "a mesh", limits: Limits = LIMITS
) -> tuple[Array, Array]:
    return _mesh_spheres(vertices, faces, settings, where, limits)[:2]


def _mesh_spheres(
    vertices: Array, faces: NDArray[np.int64], settings: SphereSettings, where: str = "a mesh", limits: Limits = LIMITS
) -> tuple[Array, Array, Array, Array]:
    """A mesh's outer cover (centres, radii) and inner spheres (centres, radii); its work capped by ``limits``."""
    cell = settings.cell_m
    check_mesh_work(vertices, faces, cell, where, limits)
    origin, kept, surface = _voxels(vertices, faces, cell)
    _check_cap(
        int(kept.sum()), limits.max_solid_cells, "max_solid_cells", f"{where}: its solid at {cell:g} m holds", "cells"
    )
    inner_c, inner_r = _inner_mesh(origin, kept & ~surface, cell, settings.inner_per_mesh)
    index = np.argwhere(kept)
    centers = origin + (index + 0.5) * cell
    half_diagonal = cell * math.sqrt(3) / 2
    # candidate centres: every other cell along each axis, each with radius (its depth + protrusion)
    candidate = np.flatnonzero(np.all(index % 2 == 0, axis=1))
    radius = _depths(centers[candidate], vertices, faces, cell) + settings.protrusion_m
    covers = np.empty((len(candidate), len(centers)), dtype=np.float32)
    for k in range(0, len(candidate), 256):
        gap = np.linalg.norm(centers[candidate[k : k + 256], None, :] - centers[None, :, :], axis=2)
        covers[k : k + 256] = gap + half_diagonal <= radius[k : k + 256, None]
    uncovered = np.ones(len(centers), dtype=np.float32)
    out_c, out_r = [], []
    while len(candidate):  # greedy set cover: the candidate that covers the most cells not yet covered
        gains = covers @ uncovered
        best = int(np.argmax(gains))
        if gains[best] <= 0.0:
            break
        out_c.append(centers[candidate[best]])
        out_r.append(radius[best])
        uncovered *= 1.0 - covers[best]
    rest = np.flatnonzero(uncovered)  # cells no candidate covers: each its own sphere
    out_c.extend(centers[rest])
    out_r.extend(np.full(len(rest), half_diagonal))
    return np.array(out_c), np.array(out_r), inner_c, inner_r


def cover(geometry: Geometry, settings: SphereSettings) -> tuple[Array, Array]:
    """Spheres covering one geometry, centres in the geometry's own frame (before its ``origin``)."""
    if geometry.kind == "sphere":
        return np.zeros((1, 3)), np.array([geometry.size[0]])
    if geometry.kind == "box":
        return _cover_box(geometry.size, settings)
    if geometry.kind == "cylinder":
        return _cover_cylinder(geometry.size[0], geometry.size[1], settings)
    where = f"<link name={geometry.link!r}> mesh {geometry.source!r}"
    return _cover_mesh(geometry.vertices, geometry.faces, settings, where)


def inner_cover(geometry: Geometry, settings: SphereSettings) -> tuple[Array, Array]:
    """Spheres inside one geometry (touching one of them proves touching the geometry), centres in the
    geometry's own frame: a sphere itself; a box's cells' inscribed spheres; a cylinder's inscribed spheres
    along its axis (a flat one: its middle and a ring); a mesh's (see :func:`_inner_mesh`)."""
    if geometry.kind == "sphere":
        return np.zeros((1, 3)), np.array([geometry.size[0]])
    if geometry.kind == "box":
        sizes = np.asarray(geometry.size, dtype=np.float64)
        counts = _cell_counts(sizes, float(sizes.min()), settings.max_primitive_cells)
        return _grid_centers(sizes, counts), np.full(int(np.prod(counts)), float((sizes / counts).min()) / 2)
    if geometry.kind == "cylinder":
        height, radius = geometry.size
        if height >= 2 * radius:
            k = math.ceil(height / (2 * radius) - 1e-9)
            z = (np.arange(k) + 0.5) / k * height - height / 2
            return np.stack([np.zeros(k), np.zeros(k), z], axis=1), np.full(k, min(radius, height / (2 * k)))
        small = height / 2
        ring = radius - small
        m = min(max(int(2 * math.pi * ring / max(small, 1e-9)), 1), settings.max_primitive_cells - 1)
        angle = 2 * math.pi * np.arange(m) / m
        centres = np.concatenate(
            [np.zeros((1, 3)), np.stack([ring * np.cos(angle), ring * np.sin(angle), np.zeros(m)], 1)]
        )
        return centres, np.full(m + 1, small)
    return _mesh_spheres(geometry.vertices, geometry.faces, settings)[2:]


def _gather(robot: RobotModel, per_link: list[list[tuple[Array, Array]]]) -> SphereModel:
    """One :class:`SphereModel` of every link's spheres (local centres per geometry)."""
    centers, radii, frames, links = [np.zeros((0, 3))], [np.zeros(0)], [np.zeros(0)], [np.zeros(0)]
    for i, (link, covers) in enumerate(zip(robot.links, per_link, strict=True)):
        for geometry, (local_c, local_r) in zip(link.geometries, covers, strict=True):
            to_frame = link.offset @ geometry.origin
            centers.append(local_c @ to_frame[:3, :3].T + to_frame[:3, 3])
            radii.append(local_r)
            frames.append(np.full(len(local_r), link.frame))
            links.append(np.full(len(local_r), i))
    links_all = np.concatenate(links).astype(np.int64)
    return SphereModel(
        centers=np.concatenate(centers),
        radii=np.concatenate(radii),
        frames=np.concatenate(frames).astype(np.int64),
        links=links_all,
        starts=np.searchsorted(links_all, np.arange(len(robot.links) + 1)).astype(np.int64),
    )


def sphere_model(robot: RobotModel, settings: SphereSettings | None = None, limits: Limits = LIMITS) -> SphereModel:
    """The conservative sphere model of every link of ``robot``, with its inner model; a
    :class:`~clew_ros.core.errors.WorldError` (``world.robot.urdf``) when a mesh or the model passes one of
    ``limits``' caps (checked before the work that grows with it)."""
    settings = settings or SphereSettings()
    outer: list[list[tuple[Array, Array]]] = []
    inner: list[list[tuple[Array, Array]]] = []
    count = 0
    for link in robot.links:
        outer.append([])
        inner.append([])
        for geometry in link.geometries:
            if geometry.kind == "mesh":
                where = f"<link name={geometry.link!r}> mesh {geometry.source!r}"
                out_c, out_r, in_c, in_r = _mesh_spheres(geometry.vertices, geometry.faces, settings, where, limits)
            else:
                (out_c, out_r), (in_c, in_r) = cover(geometry, settings), inner_cover(geometry, settings)
            count += len(out_r) + len(in_r)
            _check_cap(
                count,
                limits.max_spheres,
                "max_spheres",
                f"<link name={link.name!r}>: the sphere model holds",
                "spheres",
            )
            outer[-1].append((out_c, out_r))
            inner[-1].append((in_c, in_r))
    return replace(_gather(robot, outer), inner=_gather(robot, inner))


# ----------------------------------------------------------------------------------------- caps


def _check_cap(count: int, limit: int, cap: str, what: str, unit: str) -> None:
    if count > limit:
        raise WorldError("world.robot.urdf", f"{what} {count} {unit}, more than Limits.{cap} ({limit})")


def check_mesh_work(
    vertices: Array, faces: NDArray[np.int64], cell: float, where: str, limits: Limits = LIMITS
) -> None:
    """Refuse a mesh whose voxelising at ``cell`` (m) would pass ``Limits.max_mesh_cells`` (the grid, from the
    mesh's extent) or ``Limits.max_split_triangles`` (its triangles split until no edge exceeds a cell: each
    triangle whose longest edge is ``e`` becomes ``4 ** ceil(log2(e / cell))``), before any of that work."""
    extent = vertices.max(axis=0) - vertices.min(axis=0) + 3.0 * cell
    cells = float(np.prod(np.ceil(extent / cell)))
    _check_cap(
        int(min(cells, 2**62)),
        limits.max_mesh_cells,
        "max_mesh_cells",
        f"{where}: its voxel grid at {cell:g} m holds",
        "cells",
    )
    corners = vertices[faces]
    longest = np.linalg.norm(corners - np.roll(corners, 1, axis=1), axis=2).max(axis=1)
    halvings = np.ceil(np.log2(np.maximum(longest / cell, 1.0)))
    pieces = float(np.sum(np.power(4.0, np.minimum(halvings, 30.0))))
    _check_cap(
        int(min(pieces, 2**62)),
        limits.max_split_triangles,
        "max_split_triangles",
        f"{where}: split to {cell:g} m it holds",
        "triangles",
    )


# ----------------------------------------------------------------------------------------- measuring


def surface_points(geometry: Geometry, count: int, rng: np.random.Generator) -> Array:
    """About ``count`` points on the geometry's surface (its corners and edges included), in its frame."""
    if geometry.kind == "mesh":
        import trimesh

        mesh = trimesh.Trimesh(geometry.vertices, geometry.faces, process=False)
        sampled = np.asarray(trimesh.sample.sample_surface(mesh, count, seed=rng)[0])
        return np.concatenate([geometry.vertices, sampled])
    if geometry.kind == "sphere":
        d = rng.normal(size=(count, 3))
        return np.asarray(geometry.size[0] * d / np.linalg.norm(d, axis=1, keepdims=True), dtype=np.float64)
    if geometry.kind == "box":
        half = np.asarray(geometry.size) / 2
        p = rng.uniform(-half, half, size=(count, 3))
        face = rng.integers(0, 3, size=count)
        p[np.arange(count), face] = np.where(rng.random(count) < 0.5, -1.0, 1.0) * half[face]
        corners = np.array(np.meshgrid(*[[-h, h] for h in half], indexing="ij")).reshape(3, -1).T
        return np.concatenate([corners, p])
    height, radius = geometry.size
    angle = rng.uniform(0, 2 * math.pi, size=count)
    rho = np.where(rng.random(count) < 0.5, radius, radius * np.sqrt(rng.random(count)))
    z = np.where(
        rho >= radius, rng.uniform(-height / 2, height / 2, size=count), np.sign(rng.random(count) - 0.5) * height / 2
    )
    rims = np.stack([radius * np.cos(angle), radius * np.sin(angle), np.sign(angle - math.pi) * height / 2], axis=1)
    return np.concatenate([np.stack([rho * np.cos(angle), rho * np.sin(angle), z], axis=1), rims])


def _distance_to(geometry: Geometry, points: Array, rng: np.random.Generator) -> Array:
    """Distance (m) from points outside the geometry (in its frame) to it; 0 inside."""
    if geometry.kind == "sphere":
        return np.asarray(np.maximum(np.linalg.norm(points, axis=1) - geometry.size[0], 0.0), dtype=np.float64)
    if geometry.kind == "box":
        outside = np.maximum(np.abs(points) - np.asarray(geometry.size) / 2, 0.0)
        return np.asarray(np.linalg.norm(outside, axis=1), dtype=np.float64)
    if geometry.kind == "cylinder":
        height, radius = geometry.size
        radial = np.maximum(np.hypot(points[:, 0], points[:, 1]) - radius, 0.0)
        return np.hypot(radial, np.maximum(np.abs(points[:, 2]) - height / 2, 0.0))
    return _nearest(points, surface_points(geometry, 20_000, rng))


def over_approximation(
    geometries: Sequence[tuple[Geometry, Matrix]], centers: Array, radii: Array, rng: np.random.Generator
) -> Array:
    """How far the boundary of a cover lies from the geometry it covers (m), at points sampled on that
    boundary: their mean and max are the model's over-approximation. ``geometries`` are the covered
    geometries with their 4x4 poses in the frame of the spheres ``centers`` / ``radii``."""
    golden = math.pi * (3.0 - math.sqrt(5.0))
    k = np.arange(100)
    z = 1 - 2 * (k + 0.5) / 100
    ring = np.sqrt(1 - z * z)
    unit = np.stack([ring * np.cos(golden * k), ring * np.sin(golden * k), z], axis=1)
    points = (centers[:, None, :] + radii[:, None, None] * unit[None, :, :]).reshape(-1, 3)
    keep = np.ones(len(points), dtype=bool)
    for center, radius in zip(centers, radii, strict=True):  # inside no other sphere
        keep &= np.linalg.norm(points - center, axis=1) >= radius - 1e-12
    boundary = points[keep]
    out = np.full(len(boundary), np.inf)
    for geometry, pose in geometries:
        local = (boundary - pose[:3, 3]) @ pose[:3, :3]
        out = np.minimum(out, _distance_to(geometry, local, rng))
    return out
