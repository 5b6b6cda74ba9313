"""The world packed for the kernels: :class:`PackedWorld` (contiguous float64 arrays, built once per world), the
named tuples the kernels take it and their other inputs as (numba reads a named tuple's fields at no cost, so a
kernel takes a handful of these instead of dozens of arrays), and the arrays as the kernels take them
(:func:`_arg`, :func:`_poses`).

What a kernel reads and never writes is its :class:`Model`: the arm's :class:`Chain`, its links' radius and
whether they may collide, the :class:`Scene` it moves in, the object's :class:`Shape` and the world's rounding.
A move is made in a :class:`Mode` (the object resting, or held) and checked as :class:`MoveCheck` says; RRT-Connect
grows :class:`Trees` in :class:`Rounds`; the inverse kinematics solves as :class:`Solving` says. The kernels work
in scratch of their own: :class:`Placed` (one configuration's pieces placed), :class:`IntervalWork` (one free
interval's pieces about the pivot, with their annuli) and :class:`Stadium` (one segment turned against).

numba types a plain tuple of arrays from a fingerprint computed in C, a named tuple in Python: a few microseconds
a call, a fifth of a batch of 24 free intervals. So the compiled entry points take these as plain tuples
(:attr:`PackedWorld.plain`, :func:`plain`) and name them again inside (:func:`_named`, ``Mode(*mode)``), at no cost.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import NDArray

from clew_ros.planar.kernel.jit import _jit

__all__ = [
    "Chain", "IntervalWork", "Mode", "Model", "MoveCheck", "PackedWorld", "Placed", "Rounds", "Scene", "Shape",
    "Solving", "Stadium", "Trees", "plain",
]  # fmt: skip

Array = NDArray[Any]


class Chain(NamedTuple):
    """The arm's kinematics: its base ``(2,)``, link lengths and joint limits ``(n,)`` (rad)."""

    base: Array
    lengths: Array
    lower: Array
    upper: Array


class Scene(NamedTuple):
    """The bounds ``(4,)`` (xmin, ymin, xmax, ymax) and the obstacles: their edges ``(E, 2, 2)``, obstacle ``o``'s
    being ``edges[starts[o]:starts[o + 1]]`` (``starts`` int64), their boxes ``(O, 4)`` and
    :attr:`PackedWorld.obstacle_groups` ``(O, 5)``."""

    bounds: Array
    edges: Array
    starts: Array
    boxes: Array
    groups: Array


class Shape(NamedTuple):
    """The object in its own frame: its edges ``(V, 2, 2)``, and those of the object shrunk by the grasp tolerance
    ``(Es, 2, 2)`` in rings (ring ``k`` is ``shrunk_edges[shrunk_starts[k]:shrunk_starts[k + 1]]``)."""

    edges: Array
    shrunk_edges: Array
    shrunk_starts: Array


class Model(NamedTuple):
    """Everything a kernel reads of the world: the chain, the links' radius (m) and whether non-adjacent links
    may not meet, the scene, the object's shape, and the rounding (m): distances within it of a threshold are
    left to the exact test."""

    chain: Chain
    link_radius: float
    self_collision: bool
    scene: Scene
    shape: Shape
    rounding: float


class Mode(NamedTuple):
    """A move's mode: whether the object is held (``transfer``), held as ``grasp_rel`` or resting at
    ``resting`` (poses ``(3,)``, or ``(M, 3)`` one a move; the one the mode does not use is ignored)."""

    transfer: bool
    grasp_rel: Array
    resting: Array


class MoveCheck(NamedTuple):
    """How a straight move is checked (:class:`clew_ros.planar.continuous.ContinuousSettings`): the clearance (m)
    every configuration keeps at least and at most, and every how many coarse pieces a long move is tried first."""

    min_margin: float
    max_margin: float
    coarse_stride: int


class Trees(NamedTuple):
    """RRT-Connect's two trees: ``nodes (2, capacity, n)``, ``parents (2, capacity)`` and ``sizes (2,)`` (int64)."""

    nodes: Array
    parents: Array
    sizes: Array


class Rounds(NamedTuple):
    """RRT-Connect's rounds: the longest step (rad), the work they may spend, and what a configuration checked and
    a round cost (work units)."""

    step_rad: float
    allowed: float
    check_work: float
    round_work: float


class Solving(NamedTuple):
    """The inverse kinematics' tuning (:func:`~.kinematics.solve_point`): the angle's tolerance (rad) and weight (m
    a rad), the most steps, the damping (m^2), the largest step of a joint (rad), the error (m) a row stops at, and
    whether a joint that turns all the way round goes on past a limit."""

    angle_tolerance: float
    angle_scale: float
    iterations: int
    damping: float
    max_step: float
    tolerance: float
    full_turns: bool


class Placed(NamedTuple):
    """Scratch for one configuration: its links ``(n, 2, 2)``, the object and the shrunk object placed."""

    links: Array
    shape: Array
    shrunk: Array


class IntervalWork(NamedTuple):
    """Scratch for one free interval: the links, obstacle edges, object edges and shrunk object edges relative to
    the pivot (``(., 2, 2)``) with their annuli (``(., 4)``, :func:`~.contacts._annulus`), and the nearest
    contacts each way (``best``, :func:`~.contacts._nearest`)."""

    links: Array
    link_radii: Array
    obstacle_rel: Array
    obstacle_radii: Array
    object_rel: Array
    object_radii: Array
    shrunk_rel: Array
    shrunk_radii: Array
    best: Array


class Stadium(NamedTuple):
    """A segment ``[a, b]`` relative to the pivot, as a point turning about the pivot meets it: its end points,
    their distances ``ra``, ``rb`` from the pivot, and the segment's nearest and farthest (``near``, ``far``)."""

    ax: float
    ay: float
    bx: float
    by: float
    ra: float
    rb: float
    near: float
    far: float


#: :attr:`PackedWorld.plain`: a :class:`Model` as plain tuples.
_PlainWorld = tuple[tuple[Array, ...], float, bool, tuple[Array, ...], tuple[Array, ...], float]


def plain(packed: tuple[Any, ...]) -> tuple[Any, ...]:
    """A named tuple as a plain one (its named fields too): how it enters a compiled call, typed at once."""
    return tuple(plain(value) if isinstance(value, tuple) else value for value in packed)


@_jit
def _named(world: _PlainWorld) -> Model:
    """:attr:`PackedWorld.plain` named again, inside a compiled call."""
    chain, link_radius, self_collision, scene, shape, rounding = world
    return Model(Chain(*chain), link_radius, self_collision, Scene(*scene), Shape(*shape), rounding)


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

    @functools.cached_property
    def model(self) -> Model:
        """The world as the kernels read it."""
        return Model(
            Chain(self.base, self.lengths, self.lower, self.upper),
            float(self.link_radius),
            bool(self.self_collision),
            Scene(self.bounds, self.obstacle_edges, self.obstacle_starts, self.obstacle_boxes, self.obstacle_groups),
            Shape(self.object_edges, self.shrunk_edges, self.shrunk_starts),
            float(self.rounding),
        )

    @functools.cached_property
    def plain(self) -> _PlainWorld:
        """:attr:`model` as plain tuples, as the compiled entry points take it (built once: the free intervals
        are asked for in small batches, thousands of times a plan)."""
        return plain(self.model)


def _arg(array: np.ndarray) -> np.ndarray:
    """``array`` as the kernels take it: C-contiguous, aligned, writable float64 (numba compiles one
    version per layout and write flag, so read-only or strided arrays would compile again)."""
    if isinstance(array, np.ndarray) and array.dtype == np.float64 and array.flags.carray:
        return array
    return np.array(array, dtype=np.float64, order="C")


def _poses(poses: np.ndarray, batch: int) -> np.ndarray:
    poses = np.asarray(poses, dtype=np.float64)
    return _arg(poses) if poses.shape == (batch, 3) else np.array(np.broadcast_to(poses, (batch, 3)))
