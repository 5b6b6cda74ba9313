"""The exact side of the two-tier collision check: coal on the URDF's own collision geometry.

:class:`~clew_ros.spatial.checker.SpatialChecker` asks its sphere models first (outer spheres touching
nothing: free; inner spheres touching something: a collision). The contacts they leave open, in the thin
band between the two models (:mod:`clew_ros.spatial.kernels.band`), are decided here, one contact at a time,
on the geometry the contract names (interface.md section 1b, "Collision geometry"): every ``<collision>`` of
every link (boxes, cylinders and spheres as such, meshes as coal triangle BVHs), grown by
``world.robot.padding``; the obstacles, the object (box or cylinder) and the bounds (a half-space outside each face)
exactly. A gripper works millimetres from what it grasps: there the exact geometry answers.

The link poses are the planner's own kinematics (the band kernel's frames), so the two tiers test one pose.
``margin`` (m) asks for that much clearance on top (a free interval's sampled steps use it to prove the
configurations between two samples free, :meth:`SpatialChecker.free_intervals`).
"""

from __future__ import annotations

import importlib
import math
import weakref
from collections.abc import Sequence
from typing import Any, Protocol

import numpy as np
from numpy.typing import NDArray

from clew_ros.spatial.kernels.band import BOUNDS, OBSTACLE, PAIR, SUPPORT
from clew_ros.spatial.robot import Geometry, RobotModel
from clew_ros.spatial.scene import Obstacle


class MovableObject(Protocol):
    """What this module needs of :class:`clew_ros.spatial.placements.MovableObject` (which uses this module
    for an object resting among obstacles): its primitive."""

    @property
    def shape(self) -> str: ...

    @property
    def size(self) -> tuple[float, ...]: ...


__all__ = [
    "ExactTier",
    "coal_module",
    "coal_shape",
    "link_shapes",
    "object_touches",
    "outside_bounds",
    "robot_distance",
]

Matrix = NDArray[np.float64]

#: Each robot's link shapes, built once (meshes become BVHs: the costly part).
_LINK_SHAPES: weakref.WeakKeyDictionary[RobotModel, list[list[tuple[Any, Matrix]]]] = weakref.WeakKeyDictionary()


def coal_module() -> Any:
    """The coal module (a runtime dependency of spatial planning)."""
    try:
        return importlib.import_module("coal")
    except ImportError as error:  # pragma: no cover - installed with the package
        raise ImportError(
            f"spatial planning decides contacts on the exact geometry with coal ({error}): pip install coal"
        ) from None


def coal_shape(coal: Any, kind: str, size: Sequence[float], item: Geometry | None = None) -> Any:
    """A coal shape of a primitive (``shape_msgs/SolidPrimitive`` sizes) or of a mesh ``item``."""
    if kind == "box":
        return coal.Box(*size)
    if kind == "cylinder":
        return coal.Cylinder(size[1], size[0])
    if kind == "sphere":
        return coal.Sphere(size[0])
    assert item is not None
    mesh = coal.BVHModelOBBRSS()
    vertices, triangles = coal.StdVec_Vec3s(), coal.StdVec_Triangle()
    for v in item.vertices:
        vertices.append(np.asarray(v, dtype=np.float64))
    for f in item.faces:
        triangles.append(coal.Triangle(int(f[0]), int(f[1]), int(f[2])))
    mesh.beginModel(len(triangles), len(vertices))
    mesh.addSubModel(vertices, triangles)
    mesh.endModel()
    return mesh


def outside_bounds(coal: Any, bounds: Sequence[float]) -> list[Any]:
    """The six half-spaces outside ``bounds`` (``[xmin, ymin, zmin, xmax, ymax, zmax]``); coal's half-space
    ``(n, d)`` is the solid ``n . p <= d``."""
    out = []
    for axis in range(3):
        unit = np.zeros(3)
        unit[axis] = 1.0
        out.append(coal.Halfspace(unit, float(bounds[axis])))  # p[axis] <= min
        out.append(coal.Halfspace(-unit, -float(bounds[axis + 3])))  # p[axis] >= max
    return out


def link_shapes(robot: RobotModel) -> list[list[tuple[Any, Matrix]]]:
    """Per link: its geometries as coal shapes, each with its 4x4 pose in the frame the link rides on."""
    shapes = _LINK_SHAPES.get(robot)
    if shapes is None:
        coal = coal_module()
        shapes = [
            [(coal_shape(coal, g.kind, g.size, g), link.offset @ g.origin) for g in link.geometries]
            for link in robot.links
        ]
        _LINK_SHAPES[robot] = shapes
    return shapes


def robot_distance(robot: RobotModel, q: Sequence[float], shape: Any, pose: Matrix) -> float:
    """The least distance (m) on the exact geometry between the robot at ``q`` (every link) and a coal shape."""
    coal = coal_module()
    frames = robot.frames(q)
    other = coal.Transform3s(np.ascontiguousarray(pose[:3, :3]), np.ascontiguousarray(pose[:3, 3]))
    request, result = coal.DistanceRequest(), coal.DistanceResult()
    best = math.inf
    for link, shapes in zip(robot.links, link_shapes(robot), strict=True):
        for item, local in shapes:
            placed = frames[link.frame] @ local
            result.clear()
            coal.distance(item, coal.Transform3s(placed[:3, :3], placed[:3, 3]), shape, other, request, result)
            best = min(best, float(result.min_distance))
    return best


def object_touches(thing: MovableObject, pose: Matrix, obstacles: Sequence[Obstacle]) -> list[str]:
    """The names of ``obstacles`` the object (its box or cylinder, exactly) at ``pose`` (4x4) touches."""
    coal = coal_module()
    mine = coal_shape(coal, thing.shape, thing.size)
    where = coal.Transform3s(np.ascontiguousarray(pose[:3, :3]), np.ascontiguousarray(pose[:3, 3]))
    request = coal.CollisionRequest()
    out = []
    for obstacle in obstacles:
        result = coal.CollisionResult()
        other = coal.Transform3s(
            np.ascontiguousarray(obstacle.pose[:3, :3]), np.ascontiguousarray(obstacle.pose[:3, 3])
        )
        if coal.collide(mine, where, coal_shape(coal, obstacle.shape, obstacle.size), other, request, result) > 0:
            out.append(obstacle.name)
    return out


class ExactTier:
    """Exact contact tests of one checker's scene: the robot's links, ``obstacles`` (the resting object among
    them), ``bounds``, and the ``held`` object (its shape and its 4x4 pose in frame ``robot.tcp_frame``)."""

    def __init__(
        self,
        robot: RobotModel,
        obstacles: Sequence[Obstacle],
        bounds: Sequence[float] | None,
        held: tuple[MovableObject, Matrix] | None = None,
    ) -> None:
        self.coal = coal = coal_module()
        self.robot = robot
        self.pieces: list[list[tuple[Any, Matrix]]] = list(link_shapes(robot))
        self.frames = [link.frame for link in robot.links]
        self.padding = [robot.padding] * len(robot.links)
        if held is not None:
            shape, placed = held
            self.pieces.append([(coal_shape(coal, shape.shape, shape.size), placed)])
            self.frames.append(robot.tcp_frame)
            self.padding.append(0.0)
        #: every piece's geometries, flat: shape, frame, pose in that frame; piece p owns ``first[p]:first[p + 1]``
        self.shapes = [shape for piece in self.pieces for shape, _ in piece]
        self.first = np.cumsum([0, *(len(piece) for piece in self.pieces)])
        self._frame_of = np.repeat(self.frames, [len(piece) for piece in self.pieces]).astype(np.int64)
        local = np.array([pose for piece in self.pieces for _, pose in piece]).reshape(-1, 4, 4)
        self._local_r, self._local_t = local[:, :3, :3], local[:, :3, 3]
        self.obstacles = [(coal_shape(coal, o.shape, o.size), self._transform(o.pose)) for o in obstacles]
        #: the outside of ``bounds``: a half-space beyond each face (anything wholly past a face meets it too)
        self.slabs = (
            [] if bounds is None else [(shape, self._transform(np.eye(4))) for shape in outside_bounds(coal, bounds)]
        )
        self._request = coal.CollisionRequest()
        self._result = coal.CollisionResult()
        #: contacts decided so far (a count of work that does not depend on the machine)
        self.checks = 0

    def _transform(self, pose: Matrix) -> Any:
        return self.coal.Transform3s(np.ascontiguousarray(pose[:3, :3]), np.ascontiguousarray(pose[:3, 3]))

    def placements(self, frames_r: Matrix, frames_t: Matrix) -> tuple[Matrix, Matrix]:
        """Every geometry's rotation (k, G, 3, 3) and position (k, G, 3) in ``world`` for each of ``k`` rows of
        frames (``frames_r`` (k, n+1, 3, 3), ``frames_t`` (k, n+1, 3)), in one batched product."""
        on = frames_r[:, self._frame_of]
        rot = np.einsum("kgij,gjl->kgil", on, self._local_r)
        pos = np.einsum("kgij,gj->kgi", on, self._local_t) + frames_t[:, self._frame_of]
        return rot, pos

    def _placed(self, piece: int, rot: Matrix, pos: Matrix) -> list[tuple[Any, Any]]:
        """Piece ``piece``'s shapes with their transforms in ``world`` (one row of :meth:`placements`)."""
        transform = self.coal.Transform3s
        return [(self.shapes[g], transform(rot[g], pos[g])) for g in range(self.first[piece], self.first[piece + 1])]

    def _hits(self, mine: list[tuple[Any, Any]], other: Any, where: Any, margin: float) -> bool:
        request, result = self._request, self._result
        request.security_margin = margin
        for shape, transform in mine:
            result.clear()
            if self.coal.collide(shape, transform, other, where, request, result) > 0:
                return True
        return False

    def contact(
        self,
        row: NDArray[np.int64],
        placement: tuple[Matrix, Matrix],
        margin: NDArray[np.float64] | None = None,
        placed: dict[int, list[tuple[Any, Any]]] | None = None,
        *,
        moved_only: bool = False,
    ) -> bool:
        """Whether the band contact ``row`` (``(kind, a, b)``, :mod:`clew_ros.spatial.kernels.band`) touches on
        the exact geometry at ``placement`` (one row of :meth:`placements`), with ``margin`` (m, per piece; the
        margins of one joint's move: a pair of pieces it both moves, or neither, keeps none) of clearance asked
        on top of the padding. ``moved_only``: the configuration is one joint's move from a free one (the pieces
        with a margin are those it moves), so a contact whose pieces keep their relative pose is free as there.
        on top of the padding; ``placed``: the pieces already placed there (filled in as they are placed)."""
        placed = {} if placed is None else placed
        grow = np.zeros(len(self.pieces)) if margin is None else margin
        kind, a, b = int(row[0]), int(row[1]), int(row[2])
        if moved_only and (grow[a] > 0) == (kind == PAIR and grow[b] > 0):
            return False  # as at the configuration the move starts from, which is free
        self.checks += 1
        if a not in placed:
            placed[a] = self._placed(a, *placement)
        mine = placed[a]
        if kind in (OBSTACLE, SUPPORT):
            shape, where = self.obstacles[b]
            return self._hits(mine, shape, where, self.padding[a] + grow[a])
        if kind == BOUNDS:
            return any(self._hits(mine, shape, where, self.padding[a] + grow[a]) for shape, where in self.slabs)
        assert kind == PAIR
        if b not in placed:
            placed[b] = self._placed(b, *placement)
        # one joint moves: the pieces it moves turn together, so a pair keeps the margin of a piece moved alone
        grown = self.padding[a] + self.padding[b] + (grow[a] + grow[b] if (grow[a] > 0) != (grow[b] > 0) else 0.0)
        return any(self._hits(mine, shape, where, grown) for shape, where in placed[b])

    def free(
        self,
        contacts: NDArray[np.int64],
        placement: tuple[Matrix, Matrix],
        margin: NDArray[np.float64] | None = None,
        *,
        moved_only: bool = False,
    ) -> bool:
        """Whether none of ``contacts`` (rows ``(kind, a, b)``) touches on the exact geometry at ``placement``
        (see :meth:`contact`)."""
        placed: dict[int, list[tuple[Any, Any]]] = {}
        return not any(self.contact(row, placement, margin, placed, moved_only=moved_only) for row in contacts)
