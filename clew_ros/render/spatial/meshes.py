"""Triangle meshes of what a 3-D picture shows: primitives (box, cylinder, sphere), the robot's links (their
collision geometry, large meshes simplified once per link and cached) and the robot at a configuration.

A mesh is ``(vertices (k, 3) float, faces (m, 3) int)``; :class:`RobotMesh` keeps every link's triangles in
the frame the link rides on (interface.md section 1b; :class:`~clew_ros.spatial.robot.RobotModel`), so a
configuration costs one matrix product per frame.
"""

from __future__ import annotations

import math
import weakref
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from clew_ros.spatial.robot import Geometry, RobotModel

__all__ = [
    "MeshSettings",
    "RobotMesh",
    "box_mesh",
    "cylinder_mesh",
    "geometry_mesh",
    "robot_mesh",
    "simplify",
    "sphere_mesh",
    "transform",
]

Array = NDArray[np.float64]
Faces = NDArray[np.int64]
Mesh = tuple[Array, Faces]


@dataclass(frozen=True)
class MeshSettings:
    """How finely primitives are tessellated and how far large meshes are simplified."""

    cylinder_sides: int = 24  # a cylinder's round side in 24 facets: round at 800 px, 48 triangles a cylinder
    sphere_subdivisions: int = 2  # an icosahedron split twice: 320 triangles, round at 800 px
    max_mesh_faces: int = 1500  # a link's mesh above this is simplified: 10 links x 1500 keeps a frame < 0.1 s


def box_mesh(size: Sequence[float]) -> Mesh:
    """A box of full extents ``size`` [x, y, z] (m) centred on its frame: 8 corners, 12 triangles."""
    hx, hy, hz = (float(v) / 2 for v in size)
    corners = np.array([[sx * hx, sy * hy, sz * hz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)])
    # corner index = 4 (x+) + 2 (y+) + (z+); each face two triangles, wound outward
    quads = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    faces = np.array([tri for a, b, c, d in quads for tri in ((a, b, c), (a, c, d))], dtype=np.int64)
    return corners, faces


def cylinder_mesh(height: float, radius: float, sides: int = 24) -> Mesh:
    """A cylinder along its frame's z, centred, ``height`` and ``radius`` in m: ``sides`` facets round."""
    angles = np.linspace(0.0, 2 * math.pi, sides, endpoint=False)
    ring = np.stack([radius * np.cos(angles), radius * np.sin(angles)], axis=1)
    h = height / 2
    vertices = np.vstack(
        [
            np.column_stack([ring, np.full(sides, -h)]),
            np.column_stack([ring, np.full(sides, h)]),
            [[0, 0, -h], [0, 0, h]],
        ]
    )
    k = np.arange(sides)
    nxt = (k + 1) % sides
    bottom, top = 2 * sides, 2 * sides + 1
    faces = np.vstack(
        [
            np.column_stack([k, nxt, sides + nxt]),
            np.column_stack([k, sides + nxt, sides + k]),
            np.column_stack([np.full(sides, bottom), nxt, k]),
            np.column_stack([np.full(sides, top), sides + k, sides + nxt]),
        ]
    ).astype(np.int64)
    return vertices, faces


def sphere_mesh(radius: float, subdivisions: int = 2) -> Mesh:
    """A sphere of ``radius`` (m) centred on its frame: an icosahedron split ``subdivisions`` times."""
    t = (1.0 + math.sqrt(5.0)) / 2.0
    vertices = np.array(
        [
            *([-1, t, 0], [1, t, 0], [-1, -t, 0], [1, -t, 0], [0, -1, t], [0, 1, t], [0, -1, -t], [0, 1, -t]),
            *([t, 0, -1], [t, 0, 1], [-t, 0, -1], [-t, 0, 1]),
        ],
        dtype=np.float64,
    )
    faces = np.array(
        [
            *([0, 11, 5], [0, 5, 1], [0, 1, 7], [0, 7, 10], [0, 10, 11], [1, 5, 9], [5, 11, 4], [11, 10, 2]),
            *([10, 7, 6], [7, 1, 8], [3, 9, 4], [3, 4, 2], [3, 2, 6], [3, 6, 8], [3, 8, 9], [4, 9, 5]),
            *([2, 4, 11], [6, 2, 10], [8, 6, 7], [9, 8, 1]),
        ],
        dtype=np.int64,
    )
    for _ in range(subdivisions):
        edges = np.sort(np.vstack([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]]), axis=1)
        unique, inverse = np.unique(edges, axis=0, return_inverse=True)
        middle = len(vertices) + inverse.reshape(3, -1).T  # (m, 3): the midpoints of edges 01, 12, 20
        vertices = np.vstack([vertices, (vertices[unique[:, 0]] + vertices[unique[:, 1]]) / 2])
        a, b, c = faces.T
        ab, bc, ca = middle.T
        faces = np.vstack([np.column_stack(f) for f in ((a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca))]).astype(
            np.int64
        )
    vertices = vertices / np.linalg.norm(vertices, axis=1, keepdims=True) * radius
    return vertices, faces


def simplify(vertices: Array, faces: Faces, max_faces: int) -> Mesh:
    """A mesh of at most ``max_faces`` triangles (when it has more): vertex clustering on a grid that is
    coarsened until few enough triangles survive (each cell's vertices merged at their mean; triangles
    that lose a corner dropped). Good enough for a flat-shaded picture, not for collision checking."""
    if len(faces) <= max_faces:
        return vertices, faces
    extent = float(np.ptp(vertices, axis=0).max()) or 1.0
    cells = 128
    out = vertices, faces
    while cells >= 2:
        keys = np.floor((vertices - vertices.min(axis=0)) / (extent / cells)).astype(np.int64)
        _, label = np.unique(keys, axis=0, return_inverse=True)
        label = label.reshape(-1)
        count = np.bincount(label).astype(np.float64)
        merged = np.stack([np.bincount(label, weights=vertices[:, i]) / count for i in range(3)], axis=1)
        remapped = label[faces]
        keep = (
            (remapped[:, 0] != remapped[:, 1]) & (remapped[:, 1] != remapped[:, 2]) & (remapped[:, 0] != remapped[:, 2])
        )
        kept = np.unique(np.sort(remapped[keep], axis=1), axis=0, return_index=True)[1]
        out = merged, remapped[keep][np.sort(kept)]
        if len(out[1]) <= max_faces:
            break
        cells //= 2
    return out


def transform(matrix: Array, vertices: Array) -> Array:
    """Vertices (k, 3) moved by a 4x4 ``matrix``."""
    out: Array = vertices @ matrix[:3, :3].T + matrix[:3, 3]
    return out


def geometry_mesh(geometry: Geometry, settings: MeshSettings) -> Mesh:
    """A link's (or the object's) collision geometry as triangles in its own frame (``origin`` applied)."""
    if geometry.kind == "box":
        vertices, faces = box_mesh(geometry.size)
    elif geometry.kind == "cylinder":
        vertices, faces = cylinder_mesh(geometry.size[0], geometry.size[1], settings.cylinder_sides)
    elif geometry.kind == "sphere":
        vertices, faces = sphere_mesh(geometry.size[0], settings.sphere_subdivisions)
    else:
        vertices, faces = simplify(np.asarray(geometry.vertices), np.asarray(geometry.faces), settings.max_mesh_faces)
    return transform(geometry.origin, vertices), faces


@dataclass(frozen=True, eq=False)
class RobotMesh:
    """Every link's triangles, grouped by the frame each rides on: ``vertices`` (k, 3) in that frame,
    ``frame`` (k,) the frame of each vertex, ``faces`` (m, 3) and ``link`` (m,) the index of each
    triangle's link in ``robot.links``."""

    vertices: Array
    frame: NDArray[np.int64]
    faces: Faces
    link: NDArray[np.int64]

    def at(self, frames: Array) -> Array:
        """The vertices in ``world`` for the robot's frames (n + 1, 4, 4) at one configuration."""
        rotation = frames[self.frame, :3, :3]
        out: Array = np.einsum("kij,kj->ki", rotation, self.vertices) + frames[self.frame, :3, 3]
        return out


_CACHE: weakref.WeakKeyDictionary[RobotModel, dict[MeshSettings, RobotMesh]] = weakref.WeakKeyDictionary()


def robot_mesh(robot: RobotModel, settings: MeshSettings | None = None) -> RobotMesh:
    """The robot's triangles (built once per robot and settings, then cached while the robot lives)."""
    settings = settings or MeshSettings()
    cached = _CACHE.setdefault(robot, {})
    if settings in cached:
        return cached[settings]
    vertices, frames, faces, links = [], [], [], []
    base = 0
    for index, link in enumerate(robot.links):
        for geometry in link.geometries:
            v, f = geometry_mesh(geometry, settings)
            vertices.append(transform(link.offset, v))
            frames.append(np.full(len(v), link.frame, dtype=np.int64))
            faces.append(f + base)
            links.append(np.full(len(f), index, dtype=np.int64))
            base += len(v)
    mesh = RobotMesh(
        np.vstack(vertices) if vertices else np.zeros((0, 3)),
        np.concatenate(frames) if frames else np.zeros(0, dtype=np.int64),
        np.vstack(faces).astype(np.int64) if faces else np.zeros((0, 3), dtype=np.int64),
        np.concatenate(links) if links else np.zeros(0, dtype=np.int64),
    )
    cached[settings] = mesh
    return mesh
