"""Obstacles and bounds of a spatial world, from parameters (interface.md section 1b).

An obstacle is a ``shape_msgs/SolidPrimitive``: ``box`` (``size`` = full extents ``[x, y, z]``),
``cylinder`` (``[height, radius]`` along its own z) or ``sphere`` (``[radius]``), at a ``pose``
``[x, y, z, roll, pitch, yaw]`` in ``world`` (m, rad).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from clew_ros.core.errors import WorldError, short_repr
from clew_ros.spatial.transforms import pose_matrix

__all__ = ["SHAPES", "Obstacle", "bounds_from_parameters", "make_obstacle", "obstacles_from_parameters"]

#: Each shape and the number of its ``size`` values.
SHAPES = {"box": 3, "cylinder": 2, "sphere": 1}


@dataclass(frozen=True, eq=False)
class Obstacle:
    """A primitive obstacle: ``shape``, ``size`` (SolidPrimitive dimensions, m) and its 4x4 ``pose`` in
    ``world``."""

    name: str
    shape: str
    size: tuple[float, ...]
    pose: NDArray[np.float64]


def _numbers(value: Any, parameter: str, count: int, what: str) -> list[float]:
    try:
        out = [float(v) for v in value]
    except (TypeError, ValueError):
        raise WorldError(parameter, f"expected {what}, got {short_repr(value)}") from None
    if len(out) != count or not all(math.isfinite(v) for v in out):
        raise WorldError(parameter, f"expected {what} ({count} finite numbers), got {short_repr(value)}")
    return out


def make_obstacle(name: str, shape: Any, size: Any, pose: NDArray[np.float64], parameter: str) -> Obstacle:
    """An obstacle, checked; ``parameter`` (``world.obstacles.<name>``) names it in errors."""
    if shape not in SHAPES:
        raise WorldError(f"{parameter}.shape", f"expected one of {', '.join(SHAPES)}, got {short_repr(shape)}")
    dims = {"box": "[x, y, z] full extents", "cylinder": "[height, radius]", "sphere": "[radius]"}[shape]
    values = _numbers(size, f"{parameter}.size", SHAPES[shape], f"a {shape} size {dims}")
    if not all(v > 0.0 for v in values):
        raise WorldError(f"{parameter}.size", f"expected positive sizes {dims}, got {values}")
    return Obstacle(name, shape, tuple(values), pose)


def obstacles_from_parameters(world: Mapping[str, Any]) -> tuple[Obstacle, ...]:
    """The obstacles ``world.obstacle_names`` lists, each from ``world.obstacles.<name>.shape / .size /
    .pose``."""
    names = world.get("obstacle_names", [])
    if isinstance(names, str) or not all(isinstance(n, str) for n in names):
        raise WorldError("world.obstacle_names", f"expected a list of names, got {short_repr(names)}")
    if len(set(names)) != len(names):
        raise WorldError("world.obstacle_names", "expected distinct names")
    table = world.get("obstacles", {}) or {}
    if not isinstance(table, Mapping):
        raise WorldError("world.obstacles", f"expected a mapping of obstacles, got {short_repr(table)}")
    out = []
    for name in names:
        parameter = f"world.obstacles.{name}"
        entry = table.get(name)
        if not isinstance(entry, Mapping):
            raise WorldError(parameter, "expected shape, size and pose (world.obstacle_names lists it)")
        for key in ("shape", "size", "pose"):
            if key not in entry:
                raise WorldError(f"{parameter}.{key}", "missing")
        pose = pose_matrix(_numbers(entry["pose"], f"{parameter}.pose", 6, "a pose [x, y, z, roll, pitch, yaw]"))
        out.append(make_obstacle(name, entry["shape"], entry["size"], pose, parameter))
    return tuple(out)


def bounds_from_parameters(world: Mapping[str, Any]) -> NDArray[np.float64] | None:
    """``world.bounds`` ``[xmin, ymin, zmin, xmax, ymax, zmax]`` (m), or ``None`` when absent."""
    if "bounds" not in world:
        return None
    values = np.array(_numbers(world["bounds"], "world.bounds", 6, "[xmin, ymin, zmin, xmax, ymax, zmax]"))
    if np.any(values[:3] >= values[3:]):
        raise WorldError("world.bounds", f"expected each minimum below its maximum, got {values.tolist()}")
    return values


def obstacle_arrays(obstacles: Sequence[Obstacle]) -> dict[str, NDArray[Any]]:
    """The obstacles packed for the kernels: kind (0 box, 1 cylinder, 2 sphere), rotation (local to world),
    position, dims (box half extents; cylinder radius, half height; sphere radius) and bounding radius."""
    kind = np.array([list(SHAPES).index(o.shape) for o in obstacles], dtype=np.int64)
    dims = np.zeros((len(obstacles), 3))
    bound = np.zeros(len(obstacles))
    for i, o in enumerate(obstacles):
        if o.shape == "box":
            dims[i] = np.asarray(o.size) / 2
        elif o.shape == "cylinder":
            dims[i, :2] = o.size[1], o.size[0] / 2
        else:
            dims[i, 0] = o.size[0]
        bound[i] = float(np.linalg.norm(dims[i])) if o.shape != "sphere" else o.size[0]
    rot = np.array([o.pose[:3, :3] for o in obstacles]).reshape(-1, 3, 3)
    pos = np.array([o.pose[:3, 3] for o in obstacles]).reshape(-1, 3)
    return {"obs_kind": kind, "obs_r": rot, "obs_t": pos, "obs_dims": dims, "obs_bound": bound}
