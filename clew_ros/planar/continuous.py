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
once, at the start, and left out of the margins below: the compiled check
tests the other links only against the held object). So when the
compiled first pass of the validity test (:func:`clew_ros.planar.kernel.clearly_valid`)
clears the midpoint of a piece ``[t0, t1]`` with every distance past its
threshold by more than ``V (t1 - t0) / 2``, the whole piece is valid, at
any checking resolution.

A long move is first rejected when one of every ``coarse_stride``-th
midpoint of its first level is not valid at all (most blocked moves end
there, at a fraction of the cost). Pieces that fail are halved (the margin
halves with them) down to ``min_margin``; a piece still not cleared rejects
the move, and so does a midpoint that is not valid at all (at once). A move
accepted is therefore valid all along, with at least ``min_margin`` to spare
at every point checked (the improvement and SEARCH's joins ask for
``min_margin_factor`` x ``planner.clearance``). The tuning is :class:`ContinuousSettings`.

The whole check of a move, every level, is one compiled call
(:func:`clew_ros.planar.kernel.moves_clear`), and so is the check of several
moves (:func:`straight_moves_clear`): the improvement checks thousands of
short moves, and the Python around each level was most of their cost.

The check is conservative: ``False`` may also mean "not proven". A caller that counts its work passes a
:class:`CheckBudget` (configurations checked per call, and a stop test asked before each call).
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from clew_ros.planar.collision import is_valid, packed_world
from clew_ros.planar.kernel import moves_clear
from clew_ros.planar.kinematics import compose, tip_poses
from clew_ros.planar.world import World

__all__ = [
    "CHECK_STEP_RAD",
    "CheckBudget",
    "ContinuousSettings",
    "StopOnly",
    "interpolate",
    "path_valid",
    "straight_move_clear",
    "straight_moves_clear",
]

#: The validator's step (rad per joint, interface.md section 2).
CHECK_STEP_RAD = 0.002


@dataclass(frozen=True)
class ContinuousSettings:
    """Tuning of the straight-move check (:func:`straight_moves_clear`)."""

    #: Moves the planner checks this way (the improvement's, SEARCH's joins) keep at least this fraction of
    #: ``planner.clearance`` from everything (m / m): a margin proves a piece clear with fewer halvings, and half
    #: the clearance still lets moves pass where the paper's validity test does.
    min_margin_factor: float = 0.5
    #: Largest margin (m) the first level of a straight-move check asks for: a long move is cut into pieces
    #: short enough to clear with this, so it is not refused for the whole move's motion at once.
    max_margin_m: float = 0.05
    #: A long straight move is first rejected by every this-many-th midpoint of its first level, if one is
    #: invalid (count): most blocked moves end there, at a fraction of the cost.
    coarse_stride: int = 4


class CheckBudget(Protocol):
    """What a check reports its work to, and asks whether to stop."""

    def spend_move_checks(self, configurations: int) -> None:
        """One compiled call of the straight-move check, that checked ``configurations``."""

    def stop(self) -> bool: ...


class StopOnly:
    """A :class:`CheckBudget` that counts nothing and stops when ``stop()`` says so (the time limit or cancel):
    for checks that are not charged to a work budget but must end with the run."""

    def __init__(self, stop: Callable[[], bool]) -> None:
        self._stop = stop

    def spend_move_checks(self, configurations: int) -> None:
        pass

    def stop(self) -> bool:
        return self._stop()


def straight_move_clear(
    world: World,
    a: np.ndarray,
    b: np.ndarray,
    *,
    object_pose: np.ndarray | None = None,
    grasp_rel: np.ndarray | None = None,
    min_margin: float,
    budget: CheckBudget | None = None,
    settings: ContinuousSettings | None = None,
) -> bool:
    """Whether every configuration of the straight joint-space move ``a`` -> ``b`` is valid with at
    least ``min_margin`` (m) to spare, the object resting at ``object_pose`` (transit) or carried as
    ``grasp_rel`` (transfer). Conservative: ``False`` may also mean "not proven" (module docstring)."""
    return bool(
        straight_moves_clear(
            world,
            np.asarray(a, dtype=float).reshape(1, -1),
            np.asarray(b, dtype=float).reshape(1, -1),
            object_pose=object_pose,
            grasp_rel=grasp_rel,
            min_margin=min_margin,
            budget=budget,
            settings=settings,
        )[0]
    )


def straight_moves_clear(
    world: World,
    starts: np.ndarray,
    ends: np.ndarray,
    *,
    object_pose: np.ndarray | None = None,
    grasp_rel: np.ndarray | None = None,
    min_margin: float,
    budget: CheckBudget | None = None,
    every: bool = False,
    settings: ContinuousSettings | None = None,
) -> np.ndarray:
    """:func:`straight_move_clear` of each move ``starts[k] -> ends[k]`` ``(K, n)`` in one compiled call. With
    ``every`` (is every move clear?), the moves after the first that is not clear are not checked and come
    back not clear. All not clear when ``budget`` says stop before the call. ``settings`` default
    :class:`ContinuousSettings`."""
    tuning = settings if settings is not None else ContinuousSettings()
    if budget is not None and budget.stop():
        return np.zeros(len(starts), dtype=bool)
    clear, configurations = moves_clear(
        packed_world(world),
        starts,
        ends,
        grasp_rel=grasp_rel,
        resting=None if grasp_rel is not None else object_pose,
        min_margin=float(min_margin),
        max_margin=tuning.max_margin_m,
        coarse_stride=tuning.coarse_stride,
        every=every,
    )
    if budget is not None:
        budget.spend_move_checks(configurations)
    return clear


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
