"""The validity test of ``interface.md`` section 1, over batches of configurations.

Two views of the same static geometry, prepared once per world (:func:`scene_of`):

* exact tests with shapely 2 ufuncs on arrays of geometries (:func:`is_valid`,
  :func:`explain_invalid`), used for validation, world checks
  (:func:`check_start_and_goal`) and the plan validator; touching counts as
  collision, exactly as the contract says;
* the same geometry packed into plain arrays for the compiled kernel
  (:func:`packed_world`, :mod:`clew_ros.planar.kernel`): free intervals, and a
  first pass of :func:`is_valid` that clears every configuration valid beyond
  doubt, so that only the doubtful ones (invalid, touching, or within rounding
  of a threshold) reach shapely.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from functools import lru_cache
from typing import Any

import numpy as np
import shapely

from clew_ros.core.errors import WorldError
from clew_ros.planar.geometry import polygon_edges
from clew_ros.planar.kernel import PackedWorld, clearly_valid
from clew_ros.planar.kinematics import joint_positions, transform_points
from clew_ros.planar.world import World

__all__ = [
    "Scene",
    "check_start_and_goal",
    "explain_invalid",
    "explain_placement",
    "is_placement_valid",
    "is_valid",
    "packed_carrying",
    "packed_world",
    "scene_of",
]


@dataclass(frozen=True, eq=False)
class Scene:
    """Static geometry of a world, prepared once."""

    obstacle_edges: np.ndarray  # (E, 2, 2)
    obstacle_union: shapely.Geometry  # prepared
    obstacle_polygons: np.ndarray  # (O,) shapely polygons
    object_edges: np.ndarray  # (V, 2, 2) object frame
    shrunk_parts: tuple[np.ndarray, ...]  # rings (Vs, 2) of the object shrunk by grasp_tolerance
    shrunk_edges: np.ndarray  # (Es, 2, 2) object frame
    link_radius: float
    adjacent_pairs: np.ndarray  # (P, 2) non-adjacent link pairs (a, b), b >= a + 2
    obstacle_boxes: np.ndarray  # (O, 2, 2) [low, high] corners of each obstacle

    def obstacle_geometry(self, index: np.ndarray) -> np.ndarray:
        """Prepared obstacle polygons by index; ``-1`` gives the union of all of them."""
        chosen: np.ndarray = np.where(index >= 0, self.obstacle_polygons[np.maximum(index, 0)], self.obstacle_union)  # type: ignore[call-overload]
        return chosen


@lru_cache(maxsize=64)
def scene_of(world: World) -> Scene:
    """The prepared static geometry of ``world`` (cached per world object)."""
    polygons = np.array([shapely.Polygon(o.vertices) for o in world.obstacles], dtype=object)
    shapely.prepare(polygons)
    union = shapely.union_all(polygons) if len(polygons) else shapely.GeometryCollection()
    shapely.prepare(union)
    edges = (
        np.concatenate([polygon_edges(o.vertices) for o in world.obstacles]) if world.obstacles else np.zeros((0, 2, 2))
    )
    shrunk = shapely.Polygon(world.object.polygon).buffer(-world.grasp_tolerance, join_style="mitre")
    parts = tuple(np.asarray(g.exterior.coords)[:-1] for g in getattr(shrunk, "geoms", [shrunk]) if not g.is_empty)
    shrunk_edges = np.concatenate([polygon_edges(p) for p in parts]) if parts else np.zeros((0, 2, 2))
    n = world.robot.dof
    pairs = np.array([(a, b) for a in range(n) for b in range(a + 2, n)], dtype=int).reshape(-1, 2)
    if not world.robot.self_collision:
        pairs = pairs[:0]
    boxes = np.array([[o.vertices.min(axis=0), o.vertices.max(axis=0)] for o in world.obstacles]).reshape(-1, 2, 2)
    return Scene(
        edges,
        union,
        polygons,
        polygon_edges(world.object.polygon),
        parts,
        shrunk_edges,
        world.robot.link_width / 2.0,
        pairs,
        boxes,
    )


def _contiguous(array: np.ndarray, shape: tuple[int, ...]) -> np.ndarray:
    return np.array(array, dtype=np.float64, order="C").reshape(shape)  # a writable copy: one kernel signature


@lru_cache(maxsize=64)
def packed_world(world: World) -> PackedWorld:
    """``world``'s geometry packed into arrays for the compiled kernel (once per world object)."""
    scene = scene_of(world)
    robot = world.robot
    n = robot.dof
    obstacle_starts = np.cumsum([0] + [len(o.vertices) for o in world.obstacles]).astype(np.int64)
    boxes = scene.obstacle_boxes.reshape(-1, 4)  # (O, 2, 2) [low, high] as xmin, ymin, xmax, ymax
    shrunk_starts = np.cumsum([0] + [len(part) for part in scene.shrunk_parts]).astype(np.int64)
    scale = max(
        [float(np.abs(world.bounds).max()), robot.reach + float(np.abs(robot.base).max())]
        + [float(np.abs(o.vertices).max()) for o in world.obstacles]
    )
    return PackedWorld(
        _contiguous(robot.base, (2,)),
        _contiguous(robot.link_lengths, (n,)),
        _contiguous(robot.joint_lower, (n,)),
        _contiguous(robot.joint_upper, (n,)),
        float(scene.link_radius),
        bool(robot.self_collision),
        _contiguous(world.bounds, (4,)),
        _contiguous(scene.obstacle_edges, (-1, 2, 2)),
        _contiguous(scene.object_edges, (-1, 2, 2)),
        _contiguous(scene.shrunk_edges, (-1, 2, 2)),
        obstacle_starts,
        _contiguous(boxes, (-1, 4)),
        shrunk_starts,
        1e-9 * (1.0 + scale),
    )


@lru_cache(maxsize=64)
def packed_carrying(world: World) -> tuple[PackedWorld, PackedWorld]:
    """The validity test of a transfer in two parts that together are :func:`packed_world`'s but for one pair:
    everything except the held object against the links (all links, ``n`` joints), and the links but the
    last against the held object (``n - 1`` joints, nothing else). The pair left out, the last link
    against the object it holds, does not change during a transfer (both move with the end effector), so
    a margin asked of the two parts need not be asked of it."""
    packed = packed_world(world)
    no_parts = np.zeros(1, np.int64)
    empty = np.zeros((0, 2, 2))
    without_object = replace(packed, shrunk_edges=empty, shrunk_starts=no_parts)
    links_but_last = PackedWorld(
        packed.base,
        np.array(packed.lengths[:-1]),
        np.array(packed.lower[:-1]),
        np.array(packed.upper[:-1]),
        packed.link_radius,
        False,
        packed.bounds,
        empty,
        empty,
        packed.shrunk_edges,
        no_parts,
        np.zeros((0, 4)),
        packed.shrunk_starts,
        packed.rounding,
    )
    return without_object, links_but_last


@dataclass(frozen=True)
class BroadPhase:
    """The boxes' broad phase."""

    #: Largest boxes x obstacles comparison done per call (pairs); beyond it one box around all obstacles.
    max_box_pairs: int = 1 << 22


_BROAD_PHASE = BroadPhase()


def _box_rounding(coordinates: np.ndarray) -> float:
    """Extra padding that covers rounding for ``coordinates`` of this size: GEOS compares
    ``gap <= r`` where the boxes compare ``high + r >= low``, and the two can differ in the last bit."""
    return 1e-9 * (1.0 + float(np.abs(coordinates).max())) if np.size(coordinates) else 0.0


def _box_pairs(low: np.ndarray, high: np.ndarray, boxes: np.ndarray, pad: float) -> tuple[np.ndarray, ...]:
    """Broad phase: indices ``(*box index, obstacle)`` of the boxes ``[low, high]`` ``(..., 2)``, grown
    by ``pad``, that meet obstacle boxes ``boxes`` ``(O, 2, 2)`` (closed: touching meets). A pair
    left out cannot touch; obstacle ``-1`` stands for all of them (huge worlds: one box around all)."""
    if not len(boxes):
        return tuple(np.zeros(0, int) for _ in range(low.ndim))
    pad = pad + _box_rounding(boxes)
    low, high = low - pad, high + pad
    everything = low[..., 0].size * len(boxes) > _BROAD_PHASE.max_box_pairs
    if everything:
        boxes = np.array([[boxes[:, 0].min(axis=0), boxes[:, 1].max(axis=0)]])
    meet = low[..., 0, None] <= boxes[:, 1, 0]  # (..., O), one axis at a time: no size-2 reductions
    meet &= high[..., 0, None] >= boxes[:, 0, 0]
    meet &= low[..., 1, None] <= boxes[:, 1, 1]
    meet &= high[..., 1, None] >= boxes[:, 0, 1]
    found = np.nonzero(meet)
    return (*found[:-1], np.full_like(found[-1], -1)) if everything else found


def _inside_bounds(bounds: np.ndarray, points: np.ndarray, inset: float) -> np.ndarray:
    """Whether all points ``(N, P, 2)`` are inside the closed box shrunk by ``inset``."""
    low = bounds[:2] + inset
    high = bounds[2:] - inset
    inside: np.ndarray = np.all((points >= low) & (points <= high), axis=(1, 2))
    return inside


def _link_lines(points: np.ndarray) -> np.ndarray:
    n_conf, n_points = points.shape[:2]
    segments = np.stack([points[:, :-1], points[:, 1:]], axis=2)  # (N, n, 2, 2)
    lines: np.ndarray = np.asarray(shapely.linestrings(segments.reshape(-1, 2, 2)))
    return lines.reshape(n_conf, n_points - 1)


def _near(a: Any, b: Any, distance: float) -> np.ndarray:
    """Whether geometries ``a`` and ``b`` come within ``distance`` (touching counts), elementwise."""
    near: np.ndarray = np.asarray(shapely.dwithin(a, b, distance) if distance > 0 else shapely.intersects(a, b))
    return near


def is_placement_valid(world: World, object_poses: np.ndarray) -> np.ndarray:
    """Object inside bounds and outside every obstacle, per pose ``(N, 3)`` → ``(N,)``."""
    object_poses = np.atleast_2d(object_poses)
    vertices = transform_points(object_poses, world.object.polygon)
    ok = _inside_bounds(world.bounds, vertices, 0.0)
    if len(world.obstacles):
        scene = scene_of(world)
        conf, obstacle = _box_pairs(vertices.min(axis=1), vertices.max(axis=1), scene.obstacle_boxes, 0.0)
        keep = ok[conf]
        conf, obstacle = conf[keep], obstacle[keep]
        if len(conf):
            hit = shapely.intersects(shapely.polygons(vertices[conf]), scene.obstacle_geometry(obstacle))
            ok[conf[hit]] = False
    return ok


def is_valid(world: World, q: np.ndarray, object_poses: np.ndarray) -> np.ndarray:
    """Section 1's validity test for configurations ``q`` ``(N, n)`` with the object at ``(N, 3)``.

    Returns a boolean array ``(N,)``. The object pose is where the object is,
    carried or resting; the test is the same for transit and transfer.
    The compiled first pass (:func:`clew_ros.planar.kernel.clearly_valid`)
    clears the configurations valid beyond doubt; the others go to the exact
    test of :func:`exactly_valid`.
    """
    q = np.atleast_2d(np.asarray(q, dtype=float))
    object_poses = np.broadcast_to(np.asarray(object_poses, dtype=float), (len(q), 3))
    ok = clearly_valid(packed_world(world), q, object_poses)
    doubtful = np.flatnonzero(~ok)
    if len(doubtful):
        ok[doubtful] = exactly_valid(world, q[doubtful], object_poses[doubtful])
    return ok


def exactly_valid(world: World, q: np.ndarray, object_poses: np.ndarray) -> np.ndarray:
    """:func:`is_valid` with shapely alone: bounding boxes in numpy pick the (configuration, link)
    pairs that could touch something; only those go to shapely's exact test (GEOS)."""
    q = np.atleast_2d(np.asarray(q, dtype=float))
    object_poses = np.broadcast_to(np.asarray(object_poses, dtype=float), (len(q), 3))
    scene = scene_of(world)
    points = joint_positions(world.robot, q)
    r = scene.link_radius
    ok = _inside_bounds(world.bounds, points, r) & is_placement_valid(world, object_poses)
    low = np.minimum(points[:, :-1], points[:, 1:])  # (N, n, 2) each link's box
    high = np.maximum(points[:, :-1], points[:, 1:])
    if len(world.obstacles):
        conf, link, obstacle = _box_pairs(low, high, scene.obstacle_boxes, r)
        keep = ok[conf]
        conf, link, obstacle = conf[keep], link[keep], obstacle[keep]
        if len(conf):
            hit = _near(_lines(points, conf, link), scene.obstacle_geometry(obstacle), r)
            ok[conf[hit]] = False
    for part in scene.shrunk_parts:
        ring = transform_points(object_poses, part)  # (N, V, 2)
        ring_low, ring_high = ring.min(axis=1), ring.max(axis=1)
        meet = (low[..., 0] <= ring_high[:, None, 0]) & (high[..., 0] >= ring_low[:, None, 0])  # (N, n)
        meet &= (low[..., 1] <= ring_high[:, None, 1]) & (high[..., 1] >= ring_low[:, None, 1])
        conf, link = np.nonzero(ok[:, None] & meet)
        if len(conf):
            hit = shapely.intersects(_lines(points, conf, link), shapely.polygons(ring[conf]))
            ok[conf[hit]] = False
    for a, b in scene.adjacent_pairs:
        gap = np.maximum(low[:, a] - high[:, b], low[:, b] - high[:, a])  # (N, 2) box gap per axis
        meet = np.maximum(gap[:, 0], gap[:, 1]) <= 2 * r + _box_rounding(world.bounds)
        (conf,) = np.nonzero(ok & meet)
        if len(conf):
            hit = _near(_lines(points, conf, a), _lines(points, conf, b), 2 * r)
            ok[conf[hit]] = False
    ok_array: np.ndarray = ok
    return ok_array


def _lines(points: np.ndarray, conf: np.ndarray, link: np.ndarray | int) -> np.ndarray:
    """LineStrings of links ``link`` of configurations ``conf`` (joint positions ``points`` ``(N, n + 1, 2)``)."""
    return np.asarray(shapely.linestrings(np.stack([points[conf, link], points[conf, link + 1]], axis=1)))


def explain_placement(world: World, object_pose: np.ndarray) -> str | None:
    """Why the object cannot rest at ``object_pose``, or ``None`` when it can."""
    scene = scene_of(world)
    vertices = transform_points(np.asarray(object_pose, float)[None], world.object.polygon)
    if not _inside_bounds(world.bounds, vertices, 0.0)[0]:
        return "the object leaves world.bounds"
    polygon = shapely.Polygon(vertices[0])
    for obstacle, geometry in zip(world.obstacles, scene.obstacle_polygons, strict=True):
        if polygon.intersects(geometry):
            return f"the object hits obstacle '{obstacle.name}'"
    return None


def explain_invalid(world: World, q: np.ndarray, object_pose: np.ndarray) -> str | None:
    """Why configuration ``q`` with the object at ``object_pose`` is invalid, or ``None``."""
    scene = scene_of(world)
    q = np.asarray(q, dtype=float)
    object_pose = np.asarray(object_pose, dtype=float)
    points = joint_positions(world.robot, q[None])
    r = scene.link_radius
    lines = _link_lines(points)[0]
    low, high = world.bounds[:2] + r, world.bounds[2:] - r
    for i, line in enumerate(lines):
        ends = points[0, i : i + 2]
        if np.any(ends < low) or np.any(ends > high):
            return f"link {i + 1} leaves world.bounds"
        for obstacle, geometry in zip(world.obstacles, scene.obstacle_polygons, strict=True):
            if _near(line, geometry, r):
                return f"link {i + 1} hits obstacle '{obstacle.name}'"
    reason = explain_placement(world, object_pose)
    if reason:
        return reason
    for part in scene.shrunk_parts:
        shrunk = shapely.Polygon(transform_points(object_pose[None], part)[0])
        for i, line in enumerate(lines):
            if line.intersects(shrunk):
                return f"link {i + 1} goes into the object (deeper than world.grasp_tolerance)"
    for a, b in scene.adjacent_pairs:
        if _near(lines[a], lines[b], 2 * r):
            return f"link {a + 1} hits link {b + 1} (self-collision)"
    return None


def check_start_and_goal(world: World) -> World:
    """``world`` when its start and goal are valid, else :class:`~clew_ros.core.errors.WorldError`.

    Checks, in this order, that the object may rest at ``world.object.initial``
    and at ``world.object.goal``, and that ``world.robot.initial`` with the
    object at its start is a valid configuration (section 1); the error names
    the parameter at fault and says what collides. Returns ``world`` so that
    it chains: ``check_start_and_goal(world_from_parameters(tree))``.
    """
    reason = explain_placement(world, world.object.initial)
    if reason:
        raise WorldError("world.object.initial", f"expected a collision-free placement, but {reason}")
    reason = explain_placement(world, world.object.goal)
    if reason:
        raise WorldError("world.object.goal", f"expected a collision-free placement, but {reason}")
    reason = explain_invalid(world, world.robot.initial, world.object.initial)
    if reason:
        raise WorldError("world.robot.initial", f"expected a valid start configuration, but {reason}")
    return world
