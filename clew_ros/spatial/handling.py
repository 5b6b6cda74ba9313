"""How a plan handles the object, as a robot cell needs it: no dragging.

A carried object near a support (its lowest point within ``band_m`` above the support's top, its centre over
it) may move only a little sideways: it leaves a support by lifting off and is set down from above. A plan
*drags* when, in one stretch of its transfers spent near a support, the object's centre moves more than
``slide_m`` horizontally from where the stretch began (checked at the validator's samples).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from clew_ros.core.plan import Plan
from clew_ros.spatial.plan import replay
from clew_ros.spatial.world import SpatialWorld

__all__ = ["DragSettings", "drag_problems", "slides"]


@dataclass(frozen=True)
class DragSettings:
    """What counts as dragging."""

    #: the object is near a support while its lowest point is at most this far (m) above the support's top
    band_m: float = 0.005
    #: ... and its centre may move at most this far (m, horizontally) in one stretch spent near a support
    slide_m: float = 0.01


def _lowest(world: SpatialWorld, poses: NDArray[np.float64]) -> NDArray[np.float64]:
    """The lowest point's height (m) of the object at each of ``poses`` (k, 4, 4)."""
    assert world.object is not None
    shape = world.object.shape
    if shape.shape == "box":
        half = np.asarray(shape.size) / 2
        # the lowest corner: the half extents along each axis, projected on z
        return np.asarray(poses[:, 2, 3] - np.abs(poses[:, 2, :3]) @ half)
    height, radius = shape.size
    axis_z = poses[:, 2, 2]
    across = np.sqrt(np.clip(1.0 - axis_z**2, 0.0, 1.0))
    return np.asarray(poses[:, 2, 3] - np.abs(axis_z) * height / 2 - across * radius)


def slides(
    world: SpatialWorld, poses: NDArray[np.float64], settings: DragSettings
) -> list[tuple[str, int, int, float]]:
    """The stretches of ``poses`` (k, 4, 4: the carried object, in order) spent near a support: (the support's
    name, the first and last index, how far the centre moved horizontally from the first, m)."""
    low = _lowest(world, poses)
    xy = poses[:, :2, 3]
    out = []
    for support in world.supports:
        above = low - support.top
        near = support.contains(xy) & (above <= settings.band_m) & (above >= -settings.band_m)  # not under it
        edges = np.flatnonzero(np.diff(np.r_[0, near.astype(np.int8), 0]))
        for first, end in zip(edges[::2], edges[1::2], strict=True):
            moved = float(np.max(np.linalg.norm(xy[first:end] - xy[first], axis=1)))
            out.append((support.name, int(first), int(end - 1), moved))
    return out


def drag_problems(world: SpatialWorld, plan: Plan, settings: DragSettings | None = None) -> list[str]:
    """Where ``plan`` drags the object (see the module docstring): one problem per stretch, naming the
    segment, the support and how far the object slid. Empty: no dragging (or no object)."""
    settings = settings or DragSettings()
    if world.object is None or not plan.success:
        return []
    problems = []
    for motion in replay(world, plan):
        if motion.kind != "transfer" or motion.object_matrices is None:
            continue
        for name, _first, _last, moved in slides(world, motion.object_matrices, settings):
            if moved > settings.slide_m:
                problems.append(
                    f"segment {motion.index}: the object slides {moved * 1000:.1f} mm within "
                    f"{settings.band_m * 1000:.0f} mm of support {name!r} (at most {settings.slide_m * 1000:.0f} mm)"
                )
    return problems
