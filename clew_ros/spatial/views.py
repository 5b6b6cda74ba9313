"""What the spatial planner's helper modules ask of :class:`clew_ros.spatial.space.SpatialSpace` (protocols,
so that they need not import the space that imports them)."""

from __future__ import annotations

from typing import Protocol

import numpy as np
from numpy.typing import NDArray

from clew_ros.spatial.checker import SpatialChecker
from clew_ros.spatial.inverse import InverseKinematics
from clew_ros.spatial.world import SpatialWorld

__all__ = ["HeldObjectView"]


class HeldObjectView(Protocol):
    """The world, its grasps, the tcp's inverse kinematics and the checker of the object held by a grasp."""

    @property
    def world(self) -> SpatialWorld: ...

    def grasp_rel(self, grasp: int) -> NDArray[np.float64]: ...

    def ik(self, seeds: int) -> InverseKinematics: ...

    def transfer_checker(self, grasp_rel: NDArray[np.float64]) -> SpatialChecker: ...
