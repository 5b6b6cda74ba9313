"""A proof that the object cannot reach its goal placement: the goal enclosed by obstacles.

Not an idea of the paper (docs/algorithm.md lists it among the departures); the spatial counterpart of
the planar proof (:mod:`clew_ros.planar.passage`, "the free workspace separates start and goal"). It holds
whatever the arm does:

* The object contains the ball of radius ``r_in`` about its centre (a box: half its smallest side; a
  cylinder: the smaller of its radius and half its height). Wherever the object is, resting or held, it lies
  inside ``bounds`` and meets no obstacle, except that it may touch a support from above, sinking at most
  ``world.placement_tolerance`` into it. So its centre stays in ``F``, the points at least
  ``r = r_in - placement_tolerance`` from every obstacle and at least ``r_in`` inside the bounds.
* The centre moves continuously (carried by the tcp, or resting), so it stays in the connected part of ``F``
  where it starts. The goal is reached only with the centre within ``goal_tolerance`` of the goal's centre.
* A grid of cubic cells around the goal: a cell is **blocked** only when every point of it lies outside
  ``F`` (its centre nearer an obstacle than ``r`` less the cell's half-diagonal, or the whole cell within
  ``r_in`` of the bounds' faces). A path of the centre visits a chain of unblocked cells, each sharing at
  least a corner with the next. The cells reached that way from every unblocked cell that meets the goal's
  ball are flooded (26 neighbours); when the flood stays inside the grid (it touches none of its outer
  cells) and never reaches a cell that holds the start's centre, no plan exists.

Each approximation errs the safe way: a cell is blocked only when no point of it is free, the seeds are
every cell whose centre is within ``goal_tolerance`` plus the half-diagonal of the goal's centre, the
start's cells every one within half a cell (plus a margin) of it, and ``r`` is shrunk by
:attr:`EnclosureSettings.margin_m`. So it can fail to refuse, never refuse a world that has a plan. The
flood costs tens of milliseconds; it is tried only when every one of 26 rays from the goal's centre (along
the axes, the face and the cube diagonals) meets an obstacle within the grid (an open side is found in
well under a millisecond, and a grid with an open side could prove nothing).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from clew_ros.spatial.placements import MovableObject
from clew_ros.spatial.scene import Obstacle
from clew_ros.spatial.transforms import pose_matrix
from clew_ros.spatial.world import SpatialWorld

__all__ = ["EnclosureSettings", "enclosure_refusal", "inscribed_radius", "obstacle_distance"]

Points = NDArray[np.float64]


@dataclass(frozen=True)
class EnclosureSettings:
    """The grid of :func:`enclosure_refusal`."""

    #: Largest cell edge (m): walls a board thick (2 cm) grown by the object's radius block whole layers of
    #: 1 cm cells; finer costs eight times the cells per halving.
    cell_m: float = 0.01
    #: Largest cell edge relative to ``r`` (ratio): a cell is blocked where its centre is within ``r`` less
    #: its half-diagonal (0.87 edges) of an obstacle, so the edge must stay well below ``r`` for thin walls to
    #: block a layer.
    cell_ratio: float = 0.5
    #: Half the side of the cube of cells around the goal's centre (m): an enclosure wider than this is not
    #: proven. 0.3 m holds a box around any object the generated families draw (under 0.15 m a side).
    window_m: float = 0.3
    #: At most this many cells along each axis of the grid (count): a thin object's small cells shrink the
    #: window instead of growing the grid (61 cells: 0.23 M cells, tens of milliseconds).
    max_cells: int = 61
    #: How much smaller than ``r`` (m) the distances are compared with: room for rounding.
    margin_m: float = 1e-6
    #: Radii below this (m) prove nothing worth the grid.
    min_radius_m: float = 1e-3


_DEFAULT = EnclosureSettings()

#: The 26 directions from a cell to its neighbours, unit length.
_DIRECTIONS = np.array(
    [(i, j, k) for i in (-1, 0, 1) for j in (-1, 0, 1) for k in (-1, 0, 1) if (i, j, k) != (0, 0, 0)], dtype=float
)
_DIRECTIONS /= np.linalg.norm(_DIRECTIONS, axis=1)[:, None]


def inscribed_radius(thing: MovableObject) -> float:
    """The radius (m) of the largest ball about the object's centre that lies inside it."""
    if thing.shape == "box":
        return float(min(thing.size)) / 2
    return float(min(thing.size[0] / 2, thing.size[1]))


def obstacle_distance(obstacle: Obstacle, points: Points) -> NDArray[np.float64]:
    """The distance (m) from each point (k, 3) to ``obstacle`` (0 inside it)."""
    local = (points - obstacle.pose[:3, 3]) @ obstacle.pose[:3, :3]
    if obstacle.shape == "box":
        out = np.maximum(np.abs(local) - np.asarray(obstacle.size) / 2, 0.0)
        return np.asarray(np.linalg.norm(out, axis=1), dtype=np.float64)
    if obstacle.shape == "cylinder":
        height, radius = obstacle.size
        radial = np.maximum(np.hypot(local[:, 0], local[:, 1]) - radius, 0.0)
        axial = np.maximum(np.abs(local[:, 2]) - height / 2, 0.0)
        return np.asarray(np.hypot(radial, axial), dtype=np.float64)
    return np.asarray(np.maximum(np.linalg.norm(local, axis=1) - obstacle.size[0], 0.0), dtype=np.float64)


def _reach(obstacle: Obstacle) -> float:
    """The radius (m) of a ball about the obstacle's centre that holds it."""
    if obstacle.shape == "box":
        return float(np.linalg.norm(obstacle.size)) / 2
    if obstacle.shape == "cylinder":
        return math.hypot(obstacle.size[0] / 2, obstacle.size[1])
    return float(obstacle.size[0])


def _open(
    world: SpatialWorld, near: list[Obstacle], goal: Points, *, r: float, r_bounds: float, window: float, step: float
) -> bool:
    """Whether one of the 26 rays from ``goal`` stays free (at least ``r`` from every obstacle, ``r_bounds``
    inside the bounds) at every ``step`` out to the grid's edge."""
    ts = np.arange(1, math.ceil(window * math.sqrt(3) / step) + 1) * step
    points = goal + (_DIRECTIONS[:, None, :] * ts[None, :, None])
    inside = np.all(np.abs(points - goal) <= window, axis=2)  # (26, T): the part within the grid
    free = np.ones(points.shape[:2], dtype=bool)
    flat = points.reshape(-1, 3)
    for obstacle in near:
        free &= (obstacle_distance(obstacle, flat) >= r).reshape(free.shape)
    if world.bounds is not None:
        low, high = world.bounds[:3] + r_bounds, world.bounds[3:] - r_bounds
        free &= np.all((points >= low) & (points <= high), axis=2)
    return bool(np.any(np.all(free | ~inside, axis=1)))


def _extent(obstacle: Obstacle) -> Points:
    """Half the extents (m) along world x, y, z of a box about the obstacle's centre that holds it."""
    rotation = np.abs(obstacle.pose[:3, :3])
    if obstacle.shape == "box":
        return np.asarray(rotation @ (np.asarray(obstacle.size) / 2), dtype=np.float64)
    if obstacle.shape == "cylinder":
        height, radius = obstacle.size
        return np.asarray(rotation @ np.array([radius, radius, height / 2]), dtype=np.float64)
    return np.full(3, obstacle.size[0])


class _Grid:
    """Cells of edge ``cell`` centred on ``centre`` + ``cell`` * (i - m, j - m, k - m), i, j, k in 0..2m."""

    def __init__(self, centre: Points, cell: float, m: int) -> None:
        self.centre, self.cell, self.m = centre, cell, m
        self.axis = (np.arange(2 * m + 1) - m) * cell
        self.shape = (2 * m + 1,) * 3

    def block(self, lo: Points, hi: Points) -> tuple[slice, slice, slice] | None:
        """The index ranges of the cells whose centres lie within ``[lo, hi]`` (world, m); ``None``: none."""
        first = np.maximum(np.ceil((lo - self.centre) / self.cell - 1e-9).astype(int) + self.m, 0)
        last = np.minimum(np.floor((hi - self.centre) / self.cell + 1e-9).astype(int) + self.m, 2 * self.m)
        if np.any(first > last):
            return None
        return slice(first[0], last[0] + 1), slice(first[1], last[1] + 1), slice(first[2], last[2] + 1)

    def centres(self, where: tuple[slice, slice, slice]) -> Points:
        """The centres (k, 3) of the cells of a block, in C order."""
        x, y, z = (self.axis[w] + c for w, c in zip(where, self.centre, strict=True))
        return np.stack(np.meshgrid(x, y, z, indexing="ij"), axis=-1).reshape(-1, 3)


def _dilate(cells: NDArray[np.bool_]) -> NDArray[np.bool_]:
    """``cells`` and their 26 neighbours."""
    out = cells.copy()
    for axis in range(3):
        grown = out.copy()
        low = [slice(None)] * 3
        high = [slice(None)] * 3
        low[axis], high[axis] = slice(None, -1), slice(1, None)
        grown[tuple(low)] |= out[tuple(high)]
        grown[tuple(high)] |= out[tuple(low)]
        out = grown
    return out


def _flood(reached: NDArray[np.bool_], free: NDArray[np.bool_]) -> NDArray[np.bool_] | None:
    """The free cells 26-connected to ``reached`` through free cells; ``None`` once they touch the grid's
    outer cells. Each step grows only the box around what is reached so far."""
    last = np.array(reached.shape) - 1
    while True:
        found = np.argwhere(reached)
        low, high = found.min(axis=0), found.max(axis=0)
        if np.any(low == 0) or np.any(high == last):
            return None
        box = tuple(slice(a - 1, b + 2) for a, b in zip(low, high, strict=True))
        grown = _dilate(reached[box]) & free[box]
        if np.array_equal(grown, reached[box]):
            return reached
        reached = reached.copy()
        reached[box] = grown


def enclosure_refusal(
    world: SpatialWorld, goal: Points, start: Points | None = None, settings: EnclosureSettings = _DEFAULT
) -> str | None:
    """Why no plan can bring the object from ``start`` (its pose, 6 numbers; default
    ``world.object.initial``) to ``goal`` (6 numbers): the goal's pocket of free space, closed off by the
    obstacles the message names (see the module docstring); ``None`` when this proves nothing."""
    thing = world.object
    if thing is None:
        return None
    r_in = inscribed_radius(thing.shape)
    r = r_in - world.tolerances["placement_tolerance"] - settings.margin_m
    if r < settings.min_radius_m:
        return None
    cell = min(settings.cell_m, settings.cell_ratio * r)
    m = min(math.ceil(settings.window_m / cell), (settings.max_cells - 1) // 2)
    window = (m + 0.5) * cell
    centre = pose_matrix(list(goal))[:3, 3]
    origin = pose_matrix(list(thing.initial if start is None else start))[:3, 3]
    near = [o for o in world.obstacles if np.linalg.norm(o.pose[:3, 3] - centre) <= _reach(o) + window * math.sqrt(3)]
    if not near or _open(world, near, centre, r=r, r_bounds=r_in, window=window, step=cell / 2):
        return None
    grid = _Grid(centre, cell, m)
    blocked, by_obstacle = _blocked(world, grid, near, r=r, r_in=r_in)
    return _pocket(world, grid, blocked, by_obstacle, origin=origin, r=r, settings=settings)


def _blocked(
    world: SpatialWorld, grid: _Grid, near: list[Obstacle], *, r: float, r_in: float
) -> tuple[NDArray[np.bool_], list[tuple[str, NDArray[np.bool_]]]]:
    """The grid's blocked cells, and those each obstacle blocks (by name): every point of the cell nearer the
    obstacle than ``r``, or within ``r_in`` of the bounds' faces."""
    cell, centre = grid.cell, grid.centre
    half_diagonal = cell * math.sqrt(3) / 2
    blocked = np.zeros(grid.shape, dtype=bool)
    by_obstacle: list[tuple[str, NDArray[np.bool_]]] = []
    for obstacle in near:
        extent = _extent(obstacle) + r
        where = grid.block(obstacle.pose[:3, 3] - extent, obstacle.pose[:3, 3] + extent)
        if where is None:
            continue
        inside = obstacle_distance(obstacle, grid.centres(where)) < r - half_diagonal
        mask = np.zeros(grid.shape, dtype=bool)
        mask[where] = inside.reshape(mask[where].shape)
        blocked |= mask
        by_obstacle.append((obstacle.name, mask))
    if world.bounds is not None:  # the whole cell within r_in of a face: no centre there
        low, high = world.bounds[:3] + r_in, world.bounds[3:] - r_in
        for axis in range(3):
            values = grid.axis + centre[axis]
            outside = (values + cell / 2 < low[axis]) | (values - cell / 2 > high[axis])
            blocked |= outside.reshape([-1 if a == axis else 1 for a in range(3)])
    return blocked, by_obstacle


def _pocket(
    world: SpatialWorld,
    grid: _Grid,
    blocked: NDArray[np.bool_],
    by_obstacle: list[tuple[str, NDArray[np.bool_]]],
    *,
    origin: Points,
    r: float,
    settings: EnclosureSettings,
) -> str | None:
    """The proof's message when the free cells reached from the goal's ball stay inside the grid and off
    ``origin``'s cells; ``None`` otherwise."""
    cell, centre = grid.cell, grid.centre
    half_diagonal = cell * math.sqrt(3) / 2
    free = ~blocked
    reach = world.tolerances["goal_tolerance"] + half_diagonal
    seeds = np.zeros(grid.shape, dtype=bool)
    where = grid.block(centre - reach, centre + reach)
    if where is not None:
        near_goal = np.linalg.norm(grid.centres(where) - centre, axis=1) <= reach
        seeds[where] = near_goal.reshape(seeds[where].shape)
    seeds &= free
    if not seeds.any():
        return None  # no free cell meets the goal's ball: the goal itself collides (another answer says so)
    reached = _flood(seeds, free)
    if reached is None:
        return None  # the flood leaves the grid: not closed off within it
    slack = cell / 2 + settings.margin_m
    where = grid.block(origin - slack, origin + slack)
    if where is not None and reached[where].any():
        return None  # the start lies in the goal's pocket
    rim = _dilate(reached) & blocked
    walls = [name for name, mask in by_obstacle if (rim & mask).any()]
    return (
        f"the goal placement is closed off by {', '.join(repr(w) for w in walls) or 'the bounds'}: the object's "
        f"centre, which keeps {r:.4f} m from every obstacle (the ball inside the object, less "
        f"world.placement_tolerance), can reach no point within world.goal_tolerance of the goal's centre "
        f"from its start (a flood of {int(reached.sum())} cells of {cell:.4f} m around the goal)"
    )
