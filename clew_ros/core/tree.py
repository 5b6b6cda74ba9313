"""The landmark tree (paper 1.2) and ``history_of``.

A landmark is a configuration in CP ∩ CG: the object rests at a placement and
the arm holds one of its grasps (the root holds none). Each landmark but the
root is reached from its parent by a single manipulation path: a transit to
its grasp (``None`` when it keeps its parent's grasp) and a transfer.
The tree is a plain value shared by the planner, the node's markers, the
recorder and the renderer.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = ["Landmark", "LandmarkTree", "Segment", "append_path", "append_step"]


@dataclass(frozen=True, eq=False)
class Landmark:
    id: int
    parent: int | None
    joints: np.ndarray  # (n,) rad
    object_pose: np.ndarray  # (3,) where the object rests
    grasp: int | None  # held grasp index
    grasp_rel: np.ndarray | None  # (3,) object pose in the end-effector frame
    transit: np.ndarray | None  # (m, n) from the parent's joints to the grasp; None: parent's grasp kept
    transfer: np.ndarray | None  # (m, n) carrying the object to this landmark


@dataclass
class Segment:
    kind: str  # "transit" or "transfer"
    grasp: int | None
    waypoints: list[np.ndarray]


def append_path(segments: list[Segment], kind: str, grasp: int | None, waypoints: np.ndarray | None) -> None:
    """Append waypoints to ``segments``, merging with the last segment when kind and grasp agree.

    A new transfer always starts a new segment unless it continues the same
    grasp without a transit in between; repeated waypoints are dropped.
    """
    if waypoints is None or len(waypoints) == 0:
        return
    last = segments[-1] if segments else None
    if last is None or last.kind != kind or last.grasp != grasp:
        start = [last.waypoints[-1]] if last is not None else [waypoints[0]]
        last = Segment(kind, grasp, start)
        segments.append(last)
    for point in waypoints:
        if np.max(np.abs(point - last.waypoints[-1])) > 1e-12:
            last.waypoints.append(np.asarray(point, dtype=float))


def append_step(
    segments: list[Segment], grasp: int | None, transit: np.ndarray | None, transfer: np.ndarray | None
) -> None:
    """Append one manipulation path: a transit to ``grasp`` (``transit`` None: the held grasp is kept)
    then the transfer holding it."""
    if transit is not None:
        append_path(segments, "transit", None, transit)
        # a regrasp of the same grasp index is a new grasp: force a new segment
        segments.append(Segment("transfer", grasp, [segments[-1].waypoints[-1]]))
    append_path(segments, "transfer", grasp, transfer)


class LandmarkTree:
    """Landmarks indexed by id, with their parent links."""

    def __init__(self, root_joints: np.ndarray, root_object_pose: np.ndarray) -> None:
        root = Landmark(
            0, None, np.asarray(root_joints, float), np.asarray(root_object_pose, float), None, None, None, None
        )
        self.landmarks: list[Landmark] = [root]

    def __len__(self) -> int:
        return len(self.landmarks)

    def __getitem__(self, index: int) -> Landmark:
        return self.landmarks[index]

    def __iter__(self) -> Iterator[Landmark]:
        return iter(self.landmarks)

    def add(self, **fields: Any) -> Landmark:
        landmark = Landmark(id=len(self.landmarks), **fields)
        self.landmarks.append(landmark)
        return landmark

    def lineage(self, landmark_id: int) -> list[Landmark]:
        """Landmarks from the root to ``landmark_id`` inclusive."""
        chain = []
        current: int | None = landmark_id
        while current is not None:
            chain.append(self.landmarks[current])
            current = self.landmarks[current].parent
        return chain[::-1]

    def history_of(self, landmark_id: int) -> list[Segment]:
        """The manipulation path from the root to the landmark, as plan segments."""
        root = self.landmarks[0]
        segments = [Segment("transit", None, [root.joints.copy()])]
        for landmark in self.lineage(landmark_id)[1:]:
            append_step(segments, landmark.grasp, landmark.transit, landmark.transfer)
        return segments

    def joints(self) -> np.ndarray:
        """The landmarks' joints ``(L, n)``, by id."""
        return np.array([lm.joints for lm in self.landmarks])

    def object_poses(self) -> np.ndarray:
        """Where the object rests at each landmark ``(L, p)``, by id."""
        return np.array([lm.object_pose for lm in self.landmarks])
