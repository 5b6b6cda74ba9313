"""The plan as the planar improvement sees it: pieces (a segment, the object's pose at its start, the grasp's
relative pose). Their joint travel, score and the order that says which plan is better: :mod:`clew_ros.core.improve`."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from clew_ros.core.space import Improvement
from clew_ros.core.tree import Segment
from clew_ros.planar.kinematics import compose, relative, tip_poses
from clew_ros.planar.world import World

__all__ = ["Improvement"]


@dataclass
class _Piece:
    """One segment as the improvement sees it: the object's pose at its start, the grasp's relative pose."""

    kind: str
    grasp: int | None
    waypoints: np.ndarray  # (m, n)
    start_pose: np.ndarray  # (3,) where the object is when the segment starts
    grasp_rel: np.ndarray | None  # (3,) object in the end-effector frame (transfer)

    def end_pose(self, world: World) -> np.ndarray:
        if self.grasp_rel is None:
            return self.start_pose
        end: np.ndarray = compose(tip_poses(world.robot, self.waypoints[-1:]), self.grasp_rel)[0]
        return end

    def with_waypoints(self, waypoints: np.ndarray) -> _Piece:
        """This piece through other waypoints (the object's pose at its start and the grasp kept)."""
        return _Piece(self.kind, self.grasp, waypoints, self.start_pose, self.grasp_rel)

    def segment(self) -> Segment:
        return Segment(self.kind, self.grasp, [w.copy() for w in self.waypoints])


def _pieces(world: World, segments: list[Segment]) -> list[_Piece]:
    """The plan's segments with the object carried along (as :func:`clew_ros.planar.plan.replay` does)."""
    pose = np.asarray(world.object.initial, dtype=float)
    pieces = []
    for segment in segments:
        waypoints = np.array(segment.waypoints, dtype=float)
        grasp_rel = None
        if segment.kind == "transfer":
            grasp_rel = relative(tip_poses(world.robot, waypoints[:1])[0], pose)
        piece = _Piece(segment.kind, segment.grasp, waypoints, pose, grasp_rel)
        pose = piece.end_pose(world)
        pieces.append(piece)
    return pieces


def _span_key(one: _Piece, two: _Piece, length: int) -> bytes:
    """What :meth:`_Improver.lattice_regrasps` knows a span by: where its first transfer starts, where its last
    ends, and how many pieces from one to the other."""
    key: bytes = one.waypoints[0].tobytes() + two.waypoints[-1].tobytes() + length.to_bytes(8, "little")
    return key
