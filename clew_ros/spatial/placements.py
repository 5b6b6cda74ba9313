"""Supports, the movable object's shape and its stable placements (interface.md section 1b; the paper's
``C_stable``).

A support is an obstacle with a horizontal top face: a box one of whose axes is vertical, or an upright
cylinder. The object (a box or a cylinder) rests with one of its flat faces down — a box has 6 (named by
the outward normal in the object's frame: ``-z`` is its bottom, ``+x`` the face its x axis leaves by), a
cylinder its 2 caps (``-z``, ``+z``) — on a support's top face: the face's plane within
``placement_tolerance`` of the top's, its centre above the top face. A resting pose is
``Rz(yaw) @ rest(face)`` at ``(x, y, top + height(face))``.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from clew_ros.core.errors import WorldError, short_repr
from clew_ros.spatial.kernels.collide import clearance_of_sphere
from clew_ros.spatial.parameters import checked_value, world_value
from clew_ros.spatial.robot import Geometry
from clew_ros.spatial.scene import Obstacle, obstacle_arrays
from clew_ros.spatial.spheres import SphereSettings, cover
from clew_ros.spatial.tier import object_touches
from clew_ros.spatial.transforms import pose_matrix, rpy_matrix

__all__ = [
    "FACE_NORMALS",
    "FACE_RPY",
    "MovableObject",
    "Support",
    "check_placement",
    "face_down",
    "face_yaw",
    "object_extent",
    "object_from_parameters",
    "placement_pose",
    "project",
    "resting_on",
    "sample_placements",
    "supports_from_parameters",
]

Matrix = NDArray[np.float64]

#: Each face of a box, by its outward normal in the object's frame, and the rotation (roll, pitch, yaw) that
#: turns that normal to point down (-z); a cylinder has the first two only (its caps).
FACE_RPY: dict[str, tuple[float, float, float]] = {
    "-z": (0.0, 0.0, 0.0),
    "+z": (math.pi, 0.0, 0.0),
    "+x": (0.0, math.pi / 2, 0.0),
    "-x": (0.0, -math.pi / 2, 0.0),
    "+y": (-math.pi / 2, 0.0, 0.0),
    "-y": (math.pi / 2, 0.0, 0.0),
}
#: Each face's outward normal in the object's frame: (axis, sign).
FACE_NORMALS: dict[str, tuple[int, float]] = {
    "-z": (2, -1.0),
    "+z": (2, 1.0),
    "+x": (0, 1.0),
    "-x": (0, -1.0),
    "+y": (1, 1.0),
    "-y": (1, -1.0),
}


@dataclass(frozen=True)
class MovableObject:
    """The object: ``shape`` ``box`` (``size`` full extents [x, y, z], m) or ``cylinder`` ([height, radius]
    along its z)."""

    shape: str
    size: tuple[float, ...]

    @property
    def faces(self) -> tuple[str, ...]:
        return tuple(FACE_RPY) if self.shape == "box" else ("-z", "+z")

    def height(self, face: str) -> float:
        """How high the centre rests above the support's top (m) on ``face``."""
        axis, _ = FACE_NORMALS[face]
        return self.size[axis] / 2 if self.shape == "box" else self.size[0] / 2

    def geometry(self) -> Geometry:
        return Geometry("object", self.shape, self.size, np.eye(4))

    def face_points(self, face: str) -> NDArray[np.float64]:
        """A box face's 4 corners in the object's frame (a cylinder cap: its centre)."""
        axis, sign = FACE_NORMALS[face]
        if self.shape == "cylinder":
            return np.array([[0.0, 0.0, sign * self.size[0] / 2]])
        half = np.asarray(self.size) / 2
        others = [a for a in range(3) if a != axis]
        corners = np.zeros((4, 3))
        corners[:, axis] = sign * half[axis]
        for k, (u, v) in enumerate(((-1, -1), (1, -1), (1, 1), (-1, 1))):
            corners[k, others[0]] = u * half[others[0]]
            corners[k, others[1]] = v * half[others[1]]
        return corners


@dataclass(frozen=True, eq=False)
class Support:
    """A support's top face: height ``top`` (m), centre ``center`` (x, y), ``yaw`` of its local x axis;
    a rectangle of half extents ``half`` (x, y, m) or, for a cylinder, a disc of radius ``half[0]``."""

    name: str
    round: bool
    top: float
    center: tuple[float, float]
    yaw: float
    half: tuple[float, float]

    def local(self, xy: NDArray[np.float64]) -> NDArray[np.float64]:
        """Points ``(k, 2)`` of the plane in the top face's own frame."""
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        d = xy - np.asarray(self.center)
        return np.stack([c * d[:, 0] + s * d[:, 1], -s * d[:, 0] + c * d[:, 1]], axis=1)

    def contains(self, xy: NDArray[np.float64], inset: float = 0.0) -> NDArray[np.bool_]:
        """Whether each point (k, 2) lies on the top face, at least ``inset`` (m) from its edge."""
        p = self.local(xy)
        if self.round:
            return np.asarray(np.hypot(p[:, 0], p[:, 1]) <= self.half[0] - inset)
        return np.asarray(np.all(np.abs(p) <= np.asarray(self.half) - inset, axis=1))


def _support(obstacle: Obstacle) -> Support:
    rot, pos = obstacle.pose[:3, :3], obstacle.pose[:3, 3]
    upright = [a for a in range(3) if abs(rot[2, a]) > 1.0 - 1e-9]
    if obstacle.shape == "cylinder" and 2 in upright:
        return Support(
            obstacle.name, True, float(pos[2] + obstacle.size[0] / 2), (pos[0], pos[1]), 0.0, (obstacle.size[1],) * 2
        )
    if obstacle.shape == "box" and upright:
        axis = upright[0]
        others = [a for a in range(3) if a != axis]
        half = np.asarray(obstacle.size) / 2
        yaw = math.atan2(rot[1, others[0]], rot[0, others[0]])
        return Support(
            obstacle.name, False, float(pos[2] + half[axis]), (pos[0], pos[1]), yaw, (half[others[0]], half[others[1]])
        )
    raise WorldError(
        "world.supports",
        f"{obstacle.name!r} has no horizontal top face (expected a box with a vertical axis or an upright cylinder)",
    )


def supports_from_parameters(world: Mapping[str, Any], obstacles: Sequence[Obstacle]) -> tuple[Support, ...]:
    """The supports ``world.supports`` names, among ``obstacles``."""
    names = world_value(world, "world.supports") or []
    if isinstance(names, str) or not all(isinstance(n, str) for n in names):
        raise WorldError("world.supports", f"expected a list of obstacle names, got {short_repr(names)}")
    by_name = {o.name: o for o in obstacles}
    for name in names:
        if name not in by_name:
            raise WorldError("world.supports", f"{name!r} is not an obstacle; obstacles: {sorted(by_name)}")
    return tuple(_support(by_name[name]) for name in names)


def object_from_parameters(world: Mapping[str, Any]) -> MovableObject:
    """``world.object.shape`` (box or cylinder) and ``.size``."""
    tree = world.get("object")
    if not isinstance(tree, Mapping):
        raise WorldError("world.object", "expected shape and size")
    shape = checked_value(tree, "world.object.shape")
    if shape not in ("box", "cylinder"):
        raise WorldError("world.object.shape", f"expected box or cylinder, got {short_repr(shape)}")
    count = 3 if shape == "box" else 2
    given = world_value(tree, "world.object.size")
    try:
        size = tuple(float(v) for v in given)
    except (TypeError, ValueError):
        size = ()
    if len(size) != count or not all(math.isfinite(v) and v > 0.0 for v in size):
        what = "[x, y, z] full extents" if shape == "box" else "[height, radius]"
        raise WorldError("world.object.size", f"expected {count} positive numbers {what}, got {short_repr(given)}")
    return MovableObject(shape, size)


def placement_pose(thing: MovableObject, support: Support, face: str, *, x: float, y: float, yaw: float) -> Matrix:
    """The 4x4 pose of ``thing`` resting on ``face`` on ``support`` at ``(x, y)``, turned by ``yaw``."""
    out = np.eye(4)
    out[:3, :3] = rpy_matrix(0.0, 0.0, yaw) @ rpy_matrix(*FACE_RPY[face])
    out[:3, 3] = x, y, support.top + thing.height(face)
    return out


def resting_on(
    thing: MovableObject, pose: Matrix, supports: Sequence[Support], tolerance: float = 0.001
) -> tuple[Support, str] | None:
    """The support and face ``thing`` rests on at ``pose``, or ``None``: one of its flat faces down on a
    support's top face (the face's plane within ``tolerance`` (m) of the top's) and its centre above that
    top face."""
    rot, center = pose[:3, :3], pose[:3, 3]
    for face in thing.faces:
        axis, sign = FACE_NORMALS[face]
        normal = rot[:, axis] * sign  # the face's outward normal in world
        if normal[2] >= 0.0:
            continue
        points = thing.face_points(face) @ rot.T + center
        # the face's lowest and highest points (a cap's rim spreads by radius x the normal's tilt)
        spread = thing.size[1] * math.sqrt(max(0.0, 1.0 - float(normal[2]) ** 2)) if thing.shape == "cylinder" else 0.0
        low, high = float(points[:, 2].min()) - spread, float(points[:, 2].max()) + spread
        for support in supports:
            if (
                abs(low - support.top) <= tolerance
                and abs(high - support.top) <= tolerance
                and center[2] > support.top
                and support.contains(center[None, :2])[0]
            ):
                return support, face
    return None


def _footprint_inside(thing: MovableObject, support: Support, face: str, pose: Matrix) -> bool:
    if thing.shape == "cylinder":
        return bool(support.contains(pose[None, :2, 3], inset=thing.size[1])[0])
    corners = thing.face_points(face) @ pose[:3, :3].T + pose[:3, 3]
    return bool(support.contains(corners[:, :2]).all())


def sample_placements(
    thing: MovableObject,
    support: Support,
    face: str,
    obstacles: Sequence[Obstacle],
    *,
    count: int,
    rng: np.random.Generator,
    tries: int = 20,
    settings: SphereSettings | None = None,
) -> NDArray[np.float64]:
    """Up to ``count`` poses (k, 4, 4) of ``thing`` resting on ``face`` on ``support`` with its footprint
    inside the top face and touching no obstacle but the support (its conservative sphere cover first, its
    exact box or cylinder where the spheres touch), drawn uniformly in position and yaw; at most ``tries`` x
    ``count`` draws."""
    centers, radii = cover(thing.geometry(), settings or SphereSettings())
    others = [o for o in obstacles if o.name != support.name]
    packed = obstacle_arrays(others)
    out: list[Matrix] = []
    for _ in range(tries * count):
        if len(out) == count:
            break
        u, v = rng.uniform(-1.0, 1.0, size=2)
        if support.round:
            angle, reach = rng.uniform(0.0, 2 * math.pi), support.half[0] * math.sqrt(rng.uniform())
            local = np.array([reach * math.cos(angle), reach * math.sin(angle)])
        else:
            local = np.array([u * support.half[0], v * support.half[1]])
        c, s = math.cos(support.yaw), math.sin(support.yaw)
        x, y = support.center[0] + c * local[0] - s * local[1], support.center[1] + s * local[0] + c * local[1]
        pose = placement_pose(thing, support, face, x=x, y=y, yaw=rng.uniform(-math.pi, math.pi))
        if not _footprint_inside(thing, support, face, pose):
            continue
        placed = centers @ pose[:3, :3].T + pose[:3, 3]
        if any(
            clearance_of_sphere(
                p, r, packed["obs_kind"][o], packed["obs_r"][o], packed["obs_t"][o], packed["obs_dims"][o]
            )
            <= 0.0
            for o in range(len(others))
            for p, r in zip(placed, radii, strict=True)
        ) and object_touches(thing, pose, others):
            continue  # the spheres touch an obstacle, and so does the exact box or cylinder
        out.append(pose)
    return np.array(out).reshape(-1, 4, 4)


def object_extent(thing: MovableObject, pose: Matrix) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The object's exact axis-aligned extent (lowest and highest x, y, z) at ``pose`` (4x4): a box's corners, a
    cylinder's cap rims."""
    if thing.shape == "box":
        half = np.asarray(thing.size) / 2
        local = np.array(np.meshgrid(*[[-h, h] for h in half], indexing="ij")).reshape(3, -1).T
        points = local @ pose[:3, :3].T + pose[:3, 3]
        return points.min(axis=0), points.max(axis=0)
    axis = pose[:3, 2]
    rim = thing.size[1] * np.sqrt(np.maximum(0.0, 1.0 - axis**2))  # a cap's reach along each world axis
    caps = pose[:3, 3] + np.outer([-1.0, 1.0], axis * thing.size[0] / 2)
    return caps.min(axis=0) - rim, caps.max(axis=0) + rim


def face_down(thing: MovableObject, rot: Matrix) -> tuple[str, float]:
    """The face of ``thing`` whose outward normal points most nearly down with the object turned by ``rot``
    (3x3), and the yaw (rad) about world z that turning leaves once that face is turned exactly down."""
    face = min(thing.faces, key=lambda f: float(rot[2, FACE_NORMALS[f][0]] * FACE_NORMALS[f][1]))
    return face, face_yaw(rot, face)


def face_yaw(rot: Matrix, face: str) -> float:
    """The yaw (rad) about world z of an object turned by ``rot`` (3x3) once ``face`` is turned exactly down."""
    turned = rot @ rpy_matrix(*FACE_RPY[face]).T  # Rz(yaw) when the face is exactly down
    return math.atan2(float(turned[1, 0]), float(turned[0, 0]))


def project(thing: MovableObject, pose: Matrix, supports: Sequence[Support]) -> Matrix | None:
    """The stable placement nearest ``pose``: the face whose normal points most nearly down, rested on the
    support under the centre whose top is nearest that face's height (its yaw and x, y kept); ``None`` when no
    support lies under the centre."""
    center = pose[:3, 3]
    face, yaw = face_down(thing, pose[:3, :3])
    under = [s for s in supports if s.contains(center[None, :2])[0]]
    if not under:
        return None
    bottom = float(center[2]) - thing.height(face)
    support = min(under, key=lambda s: abs(s.top - bottom))
    return placement_pose(thing, support, face, x=float(center[0]), y=float(center[1]), yaw=yaw)


def check_placement(
    thing: MovableObject, pose: Sequence[float], supports: Sequence[Support], tolerance: float, parameter: str
) -> tuple[Support, str]:
    """The support and face of a given placement (``world.object.initial`` / ``.goal``), or a
    :class:`WorldError` naming ``parameter`` and why it is not a stable placement."""
    matrix = pose_matrix(pose)
    found = resting_on(thing, matrix, supports, tolerance)
    if found is None:
        names = ", ".join(s.name for s in supports) or "none (world.supports is empty)"
        raise WorldError(
            parameter,
            f"{short_repr(list(pose))} is not a stable placement: no flat face of the {thing.shape} lies within "
            f"{tolerance} m of a support's top face with its centre above it (supports: {names})",
        )
    return found
