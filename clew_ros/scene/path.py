"""A plan as a scene draws it: the configurations along it, the object's poses, the gripper, the tip's path.

:func:`plan_motion` replays the plan with the core
(:func:`clew_ros.planar.plan.replay`); :meth:`Motion.tip_pieces` cuts the
tip's path by segment kind (``transit``: the gripper open, ``transfer``:
holding), each kind a colour of the palette.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from clew_ros.core.plan import Plan
from clew_ros.planar.kinematics import joint_positions
from clew_ros.planar.plan import replay
from clew_ros.planar.world import World

__all__ = ["Motion", "TipPiece", "plan_motion"]


@dataclass(frozen=True)
class TipPiece:
    """Rows ``first`` to ``stop - 1`` of a motion's tip path, all of one ``kind`` (a palette key:
    ``transit`` or ``transfer``); consecutive pieces share their boundary row, so the path is unbroken."""

    first: int
    stop: int
    kind: str


@dataclass(frozen=True)
class Motion:
    """A plan replayed: one row per configuration along it.

    ``held[i]`` is the grasp index held at row ``i`` (-1: none);
    ``events`` lists ``(row, "grasp" | "ungrasp", grasp)`` where the gripper changes.
    """

    configurations: np.ndarray  # (M, n) rad
    object_poses: np.ndarray  # (M, 3)
    held: np.ndarray  # (M,) int
    segment: np.ndarray  # (M,) int
    events: list[tuple[int, str, int]]

    def __len__(self) -> int:
        return len(self.configurations)

    def sample(self, count: int, *, before_events: bool = True) -> list[int]:
        """About ``count`` rows evenly spaced along the joint-space path, always with the ends and events.

        With ``before_events`` the row just before each event is included too
        (an animation shows the gripper arrive, then change).
        """
        steps = np.max(np.abs(np.diff(self.configurations, axis=0)), axis=1) if len(self) > 1 else np.zeros(0)
        distance = np.concatenate([[0.0], np.cumsum(steps)])
        if distance[-1] <= 0 or count <= 1:
            rows = {0, len(self) - 1}
        else:
            targets = np.linspace(0.0, distance[-1], max(2, count))
            rows = set(np.searchsorted(distance, targets).clip(0, len(self) - 1).tolist())
        for row, _kind, _grasp in self.events:
            rows.update({max(0, row - 1), row} if before_events else {row})
        return sorted(rows)

    def rest_poses(self) -> list[np.ndarray]:
        """Where the object is put down (after each ungrasp), in order."""
        return [self.object_poses[row] for row, kind, _grasp in self.events if kind == "ungrasp"]

    def tips(self, world: World) -> np.ndarray:
        """The arm's tip at every row: ``(M, 2)`` m."""
        tips: np.ndarray = joint_positions(world.robot, self.configurations)[:, -1]
        return tips

    def tip_pieces(self, upto: int | None = None) -> list[TipPiece]:
        """The tip's path up to row ``upto`` (all of it: ``None``) cut where the gripper closes or opens;
        pieces of fewer than two rows are left out."""
        end = len(self) if upto is None else upto + 1
        if end < 2:
            return []
        held = self.held[:end] >= 0
        pieces: list[TipPiece] = []
        start = 0
        for i in range(1, end + 1):
            if i == end or held[i] != held[start]:
                stop = min(i + 1, end)
                if stop - start > 1:
                    pieces.append(TipPiece(start, stop, "transfer" if held[start] else "transit"))
                start = i
        return pieces


def plan_motion(world: World, plan: Plan, step_rad: float = 0.01) -> Motion | None:
    """``plan`` replayed in ``world`` at ``step_rad`` (rad per joint between rows); ``None`` without segments.

    A plan that does not fit the world raises what the core's replay raises
    (``KeyError``, ``TypeError``, ``ValueError``, ``IndexError``).
    """
    if not plan.segments:
        return None
    configurations, poses, held, segment, events = [], [], [], [], []
    row = 0
    previous_grasp = -1
    for step in replay(world, plan, step_rad):
        index, q, p = step.index, step.configurations, step.object_poses
        grasp_now = int(step.grasp) if step.kind == "transfer" and step.grasp is not None else -1
        if grasp_now != previous_grasp:
            if previous_grasp >= 0:
                events.append((row, "ungrasp", previous_grasp))
            if grasp_now >= 0:
                events.append((row, "grasp", grasp_now))
        previous_grasp = grasp_now
        configurations.append(q)
        poses.append(np.asarray(p))
        held.append(np.full(len(q), grasp_now))
        segment.append(np.full(len(q), index))
        row += len(q)
    return Motion(
        np.concatenate(configurations), np.concatenate(poses), np.concatenate(held), np.concatenate(segment), events
    )
