"""The world packed into contiguous float64 arrays (:class:`PackedWorld`), the kernels' only view of it, and
the arrays as the kernels take them (:func:`_arg`, :func:`_poses`)."""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

#: :meth:`PackedWorld.arguments`: the world in the order the interval and decode kernels take it.
_WorldArguments = tuple[
    np.ndarray,
    np.ndarray,
    np.ndarray,
    np.ndarray,
    float,
    bool,
    np.ndarray,
    np.ndarray,
    np.ndarray,
    np.ndarray,
    np.ndarray,
]
#: :attr:`PackedWorld.move_arguments`: the world in the order :func:`~.moves._moves_clear` takes it.
_MoveArguments = tuple[
    np.ndarray,
    np.ndarray,
    np.ndarray,
    np.ndarray,
    float,
    bool,
    np.ndarray,
    np.ndarray,
    np.ndarray,
    np.ndarray,
    np.ndarray,
    np.ndarray,
    np.ndarray,
    float,
]


#: :meth:`PackedWorld.validity_arguments`: the world in the order :func:`~.validity._clearly_valid` takes it.
_ValidityArguments = tuple[
    np.ndarray,
    np.ndarray,
    float,
    bool,
    np.ndarray,
    np.ndarray,
    np.ndarray,
    np.ndarray,
    np.ndarray,
    np.ndarray,
    np.ndarray,
    float,
]


@dataclass(frozen=True, eq=False)
class PackedWorld:
    """A world's geometry as contiguous float64 arrays, the kernel's only view of it."""

    base: np.ndarray  # (2,)
    lengths: np.ndarray  # (n,)
    lower: np.ndarray  # (n,)
    upper: np.ndarray  # (n,)
    link_radius: float
    self_collision: bool
    bounds: np.ndarray  # (4,) xmin, ymin, xmax, ymax
    obstacle_edges: np.ndarray  # (E, 2, 2)
    object_edges: np.ndarray  # (V, 2, 2) object frame
    shrunk_edges: np.ndarray  # (Es, 2, 2) object frame
    obstacle_starts: np.ndarray  # (O + 1,) int64: obstacle o's edges are obstacle_edges[starts[o]:starts[o + 1]]
    obstacle_boxes: np.ndarray  # (O, 4) xmin, ymin, xmax, ymax
    shrunk_starts: np.ndarray  # (parts + 1,) int64, the shrunk object's rings in shrunk_edges
    rounding: float  # distances within this of a threshold are left to the exact test (m)

    @functools.cached_property
    def pairs_per_move(self) -> int:
        """Rough count of piece pairs one free interval checks (for splitting huge batches)."""
        n = len(self.lengths)
        e = len(self.obstacle_edges)
        return 1 + n * (e + n + len(self.shrunk_edges)) + len(self.object_edges) * e

    @functools.cached_property
    def obstacle_groups(self) -> np.ndarray:
        """``(O, 5)``: each obstacle's first and end edge (as floats) and its bounding circle (centre x,
        y, radius), the broad phase of the free intervals."""
        boxes = self.obstacle_boxes.reshape(-1, 4)
        centres = 0.5 * (boxes[:, :2] + boxes[:, 2:])
        radii = 0.5 * np.hypot(boxes[:, 2] - boxes[:, 0], boxes[:, 3] - boxes[:, 1])
        starts = self.obstacle_starts.astype(np.float64)
        groups = np.column_stack([starts[:-1], starts[1:], centres, radii]) if len(boxes) else np.zeros((0, 5))
        return np.ascontiguousarray(groups, dtype=np.float64)

    def arguments(self) -> _WorldArguments:
        return self._arguments

    @functools.cached_property
    def _arguments(self) -> _WorldArguments:
        """Built once: the free intervals are asked for in small batches, thousands of times a plan."""
        return (
            self.base,
            self.lengths,
            self.lower,
            self.upper,
            self.link_radius,
            self.self_collision,
            self.bounds,
            self.obstacle_edges,
            self.obstacle_groups,
            self.object_edges,
            self.shrunk_edges,
        )

    @functools.cached_property
    def move_arguments(self) -> _MoveArguments:
        """The world in the order :func:`~.moves._moves_clear` takes it (built once: it checks one move at a time)."""
        return (self.base, self.lengths, self.lower, self.upper, *self.validity_arguments()[2:])

    def validity_arguments(self) -> _ValidityArguments:
        return (
            self.base,
            self.lengths,
            self.link_radius,
            self.self_collision,
            self.bounds,
            self.obstacle_edges,
            self.obstacle_starts,
            self.obstacle_boxes,
            self.object_edges,
            self.shrunk_edges,
            self.shrunk_starts,
            self.rounding,
        )


def _arg(array: np.ndarray) -> np.ndarray:
    """``array`` as the kernels take it: C-contiguous, aligned, writable float64 (numba compiles one
    version per layout and write flag, so read-only or strided arrays would compile again)."""
    if isinstance(array, np.ndarray) and array.dtype == np.float64 and array.flags.carray:
        return array
    return np.array(array, dtype=np.float64, order="C")


def _poses(poses: np.ndarray, batch: int) -> np.ndarray:
    poses = np.asarray(poses, dtype=np.float64)
    return _arg(poses) if poses.shape == (batch, 3) else np.array(np.broadcast_to(poses, (batch, 3)))
