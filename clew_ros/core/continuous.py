"""A straight joint-space move checked continuously: valid at any checking resolution.

Along ``q(t) = a + t (b - a)`` a point of the arm or of the carried object
moves at most ``V = sum_j |b_j - a_j| R_j`` over the whole move, where
``R_j`` is the length of links ``j..n-1`` plus, in a transfer, the object's
largest distance from the tip (the velocity of a point is ``sum_j dq_j x
(p - p_j)``). Every distance the validity test compares (link to obstacle,
link to link, link to the shrunk object, object to obstacle, to the bounds)
changes by at most that motion: for two moving bodies, measure in the frame
of the nearer one to the base, where only the joints between them move the
other; the last link and the object it carries do not move relative to each
other (so that pair, at a fixed distance during a transfer, is checked
once, at the start, and left out of the margins below:
:func:`clew_ros.core.collision.packed_carrying`). So when the compiled first
pass of the validity test (:func:`clew_ros.core.kernel.clearly_valid`)
clears the midpoint of a piece ``[t0, t1]`` with every distance past its
threshold by more than ``V (t1 - t0) / 2``, the whole piece is valid, at
any checking resolution.

A long move is first rejected when one of every :data:`COARSE_STRIDE`-th
midpoint of its first level is not valid at all (most blocked moves end
there, at a fraction of the cost). Pieces that fail are halved (the margin
halves with them) down to ``min_margin``; a piece still not cleared rejects
the move, and so does a midpoint that is not valid at all (at once). A move
accepted is therefore valid all along, with at least ``min_margin`` to spare
at every point checked (the improvement and SEARCH's joins ask for half
``planner.clearance``).

The check is conservative: ``False`` may also mean "not proven". A caller that counts its work passes a
:class:`CheckBudget` (configurations checked, and a stop test asked between levels).
"""

from __future__ import annotations

import dataclasses
import itertools
import math
from typing import Protocol

import numpy as np

from clew_ros.core.collision import is_valid, packed_carrying, packed_world
from clew_ros.core.kernel import PackedWorld, clearly_valid
from clew_ros.core.kinematics import compose, tip_poses, transform_points
from clew_ros.core.world import World

__all__ = [
    "CHECK_STEP_RAD",
    "COARSE_STRIDE",
    "MAX_MARGIN_M",
    "MIN_MARGIN_FACTOR",
    "CheckBudget",
    "interpolate",
    "path_valid",
    "straight_move_clear",
]

#: The validator's step (rad per joint, interface.md section 2).
CHECK_STEP_RAD = 0.002

#: Moves the planner checks this way (the improvement's, SEARCH's joins) keep at least this fraction of
#: ``planner.clearance`` from everything (m / m).
MIN_MARGIN_FACTOR = 0.5
#: Largest margin (m) the first level of a straight-move check asks for.
MAX_MARGIN_M = 0.05
#: A long straight move is first rejected by every this-many-th midpoint of its first level, if one is invalid.
COARSE_STRIDE = 4


class CheckBudget(Protocol):
    """What a check reports its work to, and asks whether to stop."""

    def spend_checks(self, configurations: int, calls: int = 1) -> None: ...

    def stop(self) -> bool: ...


def _reach_radii(world: World, grasp_rel: np.ndarray | None) -> np.ndarray:
    """``R_j``: how far from joint ``j`` any point moved by it can be (links ``j..n-1`` and the carried object)."""
    lengths = np.asarray(world.robot.link_lengths, dtype=float)
    radii = np.cumsum(lengths[::-1])[::-1]
    if grasp_rel is not None:
        radii = radii + float(np.max(np.linalg.norm(transform_points(grasp_rel, world.object.polygon), axis=-1)))
    return radii


def straight_move_clear(
    world: World,
    a: np.ndarray,
    b: np.ndarray,
    *,
    object_pose: np.ndarray | None = None,
    grasp_rel: np.ndarray | None = None,
    min_margin: float,
    budget: CheckBudget | None = None,
) -> bool:
    """Whether every configuration of the straight joint-space move ``a`` -> ``b`` is valid with at
    least ``min_margin`` (m) to spare, the object resting at ``object_pose`` (transit) or carried as
    ``grasp_rel`` (transfer). Conservative: ``False`` may also mean "not proven" (module docstring)."""
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    if grasp_rel is None and object_pose is None:
        raise ValueError("give object_pose (transit) or grasp_rel (transfer)")
    resting = np.zeros(3) if object_pose is None else np.asarray(object_pose, dtype=float)
    motion = float(np.abs(b - a) @ _reach_radii(world, grasp_rel)) * (1.0 + 1e-9) + 1e-12  # V (m)
    parts = _margin_parts(world, a, b, grasp_rel, min_margin=min_margin, budget=budget)
    if parts is None:
        return False
    # level k: 2**k pieces, each cleared by its midpoint with margin motion / 2**(k + 1)
    level = max(0, math.ceil(math.log2(max(motion / (2.0 * MAX_MARGIN_M), 1.0))))
    pending = np.arange(2**level, dtype=float)  # piece indices at this level
    if len(pending) >= 2 * COARSE_STRIDE:  # a long move: every COARSE_STRIDE-th midpoint first, valid at all?
        t = (pending[COARSE_STRIDE // 2 :: COARSE_STRIDE] + 0.5) / 2.0**level
        q = a + t[:, None] * (b - a)
        poses = (
            np.broadcast_to(resting, (len(q), 3))
            if grasp_rel is None
            else compose(tip_poses(world.robot, q), grasp_rel)
        )
        if not _all_valid(world, q, np.asarray(poses), budget):
            return False  # most blocked moves end here, for a fraction of the first level's checks
    while len(pending):
        if budget is not None and budget.stop():
            return False
        pieces = 2.0**level
        margin = motion / (2.0 * pieces)
        margin = max(margin, min_margin)  # the last level: a piece this short needs only the minimal margin
        t = (pending + 0.5) / pieces
        q = a + t[:, None] * (b - a)
        poses = (
            np.broadcast_to(resting, (len(q), 3))
            if grasp_rel is None
            else compose(tip_poses(world.robot, q), grasp_rel)
        )
        clear = _cleared(parts, q, np.asarray(poses), margin)
        if budget is not None:
            budget.spend_checks(len(q))
        if clear.all():
            return True
        # a midpoint that is not valid rejects the move at once (halving would only find it later)
        if margin <= min_margin or not _all_valid(world, q[~clear], np.asarray(poses)[~clear], budget):
            return False
        pending = (2.0 * pending[~clear])[:, None] + np.array([0.0, 1.0])
        pending = pending.reshape(-1)
        level += 1
    return True


def _cleared(parts: list[tuple[PackedWorld, int]], q: np.ndarray, poses: np.ndarray, margin: float) -> np.ndarray:
    """Which configurations pass every part of the validity test with ``margin`` (m) to spare."""
    clear = np.ones(len(q), dtype=bool)
    for packed, joints in parts:
        rows = np.flatnonzero(clear)
        if len(rows):
            part = dataclasses.replace(packed, rounding=margin)
            clear[rows] = clearly_valid(part, np.ascontiguousarray(q[rows, :joints]), poses[rows])
    return clear


def _all_valid(world: World, q: np.ndarray, poses: np.ndarray, budget: CheckBudget | None) -> bool:
    """Whether every configuration is valid beyond rounding (the compiled first pass alone: one that only
    touches is taken as invalid, which can only reject a move, never accept one)."""
    if budget is not None:
        budget.spend_checks(len(q))
    return bool(clearly_valid(packed_world(world), q, poses).all())


def _margin_parts(
    world: World,
    a: np.ndarray,
    b: np.ndarray,
    grasp_rel: np.ndarray | None,
    *,
    min_margin: float,
    budget: CheckBudget | None,
) -> list[tuple[PackedWorld, int]] | None:
    """The validity tests a margin is asked of, with the joints each takes: the whole test in a transit; in a
    transfer, :func:`clew_ros.core.collision.packed_carrying`'s two parts, once the pair they leave out (the
    last link and the object it holds, at a fixed distance during the move) has its least margin at ``a``.
    ``None`` when it has not, or when ``a`` or ``b`` leaves the joint limits."""
    ends = np.stack([a, b])
    if np.any(ends < world.robot.joint_lower) or np.any(ends > world.robot.joint_upper):
        return None
    if grasp_rel is None:
        return [(packed_world(world), world.robot.dof)]
    pose = compose(tip_poses(world.robot, a[None]), grasp_rel)
    if budget is not None:
        budget.spend_checks(1)
    if not clearly_valid(dataclasses.replace(packed_world(world), rounding=min_margin), a[None], pose)[0]:
        return None
    without_object, links_but_last = packed_carrying(world)
    return [(without_object, world.robot.dof), (links_but_last, world.robot.dof - 1)]


def interpolate(waypoints: np.ndarray, step_rad: float) -> np.ndarray:
    """Configurations along straight joint-space pieces, at most ``step_rad`` apart per joint."""
    out = [waypoints[:1]]
    for a, b in itertools.pairwise(waypoints):
        count = max(1, math.ceil(np.max(np.abs(b - a)) / step_rad))
        t = np.arange(1, count + 1)[:, None] / count
        out.append(a + t * (b - a))
    return np.concatenate(out)


def path_valid(
    world: World, waypoints: np.ndarray, *, object_pose: np.ndarray | None = None, grasp_rel: np.ndarray | None = None
) -> bool:
    """The validator's check of a path: its straight pieces at :data:`CHECK_STEP_RAD` per joint at most, the
    object resting at ``object_pose`` (a transit) or carried as ``grasp_rel`` (a transfer)."""
    q = interpolate(np.asarray(waypoints, dtype=float), CHECK_STEP_RAD)
    poses = object_pose if grasp_rel is None else compose(tip_poses(world.robot, q), grasp_rel)
    return bool(is_valid(world, q, np.atleast_2d(np.asarray(poses, dtype=float))).all())
