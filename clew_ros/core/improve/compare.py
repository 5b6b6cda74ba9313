"""Which plan is better: joint travel, a plan's score and the order on scores.

A plan is better when it has fewer transfers; with as many, when its joint travel (the sum over joints of the
absolute motion, rad) is shorter by more than a tolerance; with both equal, when it has fewer waypoints. Every
improvement keeps a change only when it makes the plan better in this order, so the plan returned is never worse
than the first.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Protocol

import numpy as np

from clew_ros.core.tree import Segment

__all__ = ["PathPiece", "Score", "better", "joint_travel", "plan_score"]

#: A plan's score: (transfers, joint travel (rad), waypoints).
Score = tuple[int, float, int]


class PathPiece(Protocol):
    """One segment of a plan as an improvement sees it: its kind (``"transit"`` or ``"transfer"``), the grasp
    a transfer holds (``None`` in a transit) and its waypoints ``(m, n)``; whatever else a space keeps with it
    (where the object rests, how it is held) is opaque here."""

    kind: str
    grasp: int | None
    waypoints: np.ndarray


def joint_travel(segments: Sequence[Segment] | Sequence[np.ndarray]) -> float:
    """Sum over joints of the absolute motion (rad) along segments (or waypoint arrays ``(m, n)``)."""
    total = 0.0
    for segment in segments:
        waypoints = np.asarray(segment.waypoints if isinstance(segment, Segment) else segment, dtype=float)
        if len(waypoints) > 1:
            total += float(np.abs(np.diff(waypoints, axis=0)).sum())
    return total


def plan_score(pieces: Sequence[PathPiece]) -> Score:
    """``(transfers, joint travel, waypoints)`` of a plan's pieces."""
    return (
        sum(p.kind == "transfer" for p in pieces),
        joint_travel([p.waypoints for p in pieces]),
        sum(len(p.waypoints) for p in pieces),
    )


def better(old: Score, new: Score, travel_eps: float) -> bool:
    """Whether ``new`` is better than ``old``: lexicographic (transfers, travel, waypoints), travel within
    ``travel_eps`` (rad) counting as equal."""
    if new[0] != old[0]:
        return new[0] < old[0]
    if abs(new[1] - old[1]) > travel_eps:
        return new[1] < old[1]
    return new[2] < old[2]
