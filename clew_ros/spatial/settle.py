"""Setting a carried object down: the stable placement under it and the configuration near a decoded end that
rests it there (docs/spatial.md, "Planning": every landmark's object rests on a support)."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from clew_ros.spatial.checker import SpatialChecker
from clew_ros.spatial.inverse import LEVEL_ROWS
from clew_ros.spatial.placements import Support, face_down, placement_pose, resting_on
from clew_ros.spatial.space_parts import SpaceParts
from clew_ros.spatial.transforms import inverse_matrix, matrices
from clew_ros.spatial.world import SpatialWorld

__all__ = ["footprint_inside", "rest_below", "rests", "settle"]

Array = NDArray[np.float64]


def footprint_inside(world: SpatialWorld, support: Support, face: str, pose: Array) -> bool:
    """Whether the object at ``pose`` (4x4), resting on ``face``, stands inside ``support``'s top."""
    assert world.object is not None
    thing = world.object.shape
    if thing.shape == "cylinder":
        return bool(support.contains(pose[None, :2, 3], inset=thing.size[1])[0])
    corners = thing.face_points(face) @ pose[:3, :3].T + pose[:3, 3]
    return bool(support.contains(corners[:, :2]).all())


def rests(world: SpatialWorld, object_pose: Array) -> bool:
    """Whether the object at ``object_pose`` (6 numbers) is at a stable placement."""
    thing = world.object
    assert thing is not None
    tolerance = world.tolerances["placement_tolerance"]
    return resting_on(thing.shape, matrices(object_pose)[0], world.supports, tolerance) is not None


def rest_below(parts: SpaceParts, object_pose: Array) -> Array | None:
    """The stable placement (4x4) under a carried object at ``object_pose`` (4x4): its face most nearly
    down, on the highest support under its centre at most :attr:`SpatialTuning.settle_drop_m` below
    that face, at the same x, y and yaw, its footprint inside the support's top; ``None`` if none."""
    world = parts.world
    thing = world.object
    assert thing is not None
    center = object_pose[:3, 3]
    face, yaw = face_down(thing.shape, object_pose[:3, :3])
    bottom = float(center[2]) - thing.shape.height(face)
    tuning = parts.tuning
    under = [
        s
        for s in world.supports
        if -tuning.settle_rise_m <= bottom - s.top <= tuning.settle_drop_m and s.contains(center[None, :2])[0]
    ]
    for support in sorted(under, key=lambda s: -s.top):
        placed = placement_pose(thing.shape, support, face, x=float(center[0]), y=float(center[1]), yaw=yaw)
        if footprint_inside(world, support, face, placed):
            return placed
    return None


def settle(
    parts: SpaceParts, checker: SpatialChecker, grasp_rel: Array, ends: Array
) -> tuple[Array, NDArray[np.bool_]]:
    """Configurations (B, n) near ``ends`` (B, n) that set the object held as ``grasp_rel`` down on a
    support (:func:`rest_below`), and whether each was found with a clear straight move to it."""
    rel = matrices(grasp_rel)[0]
    back = inverse_matrix(rel)
    held = parts.tcp(ends) @ rel
    out = ends.copy()
    ok = np.zeros(len(ends), dtype=bool)
    targets, rows = [], []
    for b, pose in enumerate(held):
        placed = rest_below(parts, pose)
        if placed is not None:
            targets.append(placed @ back)
            rows.append(b)
    if not rows:
        return out, ok
    found = parts.settle_ik.solve_many(
        targets, np.random.default_rng(0), seeds=[ends[b][None] for b in rows]
    )  # no random seeds: the generator is never drawn from
    reach = parts.tuning.settle_max_rad
    moves = [
        (b, solutions[0])
        for b, solutions in zip(rows, found, strict=True)
        if len(solutions) and np.max(np.abs(solutions[0] - ends[b])) <= reach
    ]
    if parts.tuning.level_settle:
        missed = [k for k, b in enumerate(rows) if b not in {m for m, _ in moves}]
        moves += _level_settle(parts, rel, ends, [rows[k] for k in missed], [targets[k] for k in missed])
        moves.sort(key=lambda move: move[0])
    if not moves:
        return out, ok
    index = np.array([b for b, _ in moves])
    goals = np.array([s for _, s in moves])
    clear = parts.clear(checker, ends[index], goals)
    out[index[clear]] = goals[clear]
    ok[index[clear]] = True
    return out, ok


def _level_settle(
    parts: SpaceParts, rel: Array, ends: Array, rows: list[int], targets: list[Array]
) -> list[tuple[int, Array]]:
    """Where the whole placement's pose is out of reach (an arm of 4-5 joints, joint limits): the object
    set down level at the support's height, its x, y and yaw left free (:meth:`InverseKinematics.solve_rows`
    seeded at the decoded end), kept where it then rests inside a support's top within
    :attr:`SpatialTuning.settle_max_rad` of that end. ``(row, configuration)`` pairs."""
    if not rows:
        return []
    object_targets = np.array([target @ rel for target in targets])
    reached, ok = parts.settle_ik.solve_rows(object_targets, ends[rows], LEVEL_ROWS, frame=rel)
    world = parts.world
    thing = world.object
    assert thing is not None
    tolerance = world.tolerances["placement_tolerance"]
    out = []
    for k in np.flatnonzero(ok):
        b = rows[int(k)]
        if np.max(np.abs(reached[k] - ends[b])) > parts.tuning.settle_max_rad:
            continue
        pose = parts.tcp(reached[k][None])[0] @ rel
        found = resting_on(thing.shape, pose, world.supports, tolerance)
        if found is not None and footprint_inside(world, found[0], found[1], pose):
            out.append((b, reached[k]))
    return out
