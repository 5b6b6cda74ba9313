"""The shortest way round the obstacles on a joint-space lattice, for arms of few joints.

Shortcuts only straighten a path within its own way round the obstacles, and
the way round RRT-Connect finds for a blocked move of the improvement is often
a long one (:meth:`clew_ros.core.improve._Improver.connect` takes this one
instead when it is shorter). On an arm of at most :data:`MAX_JOINTS` joints
the joint space is small enough for a lattice: joint ``j`` takes the values
``lower_j + k step`` and an edge moves one joint by one step. In joint travel
(the L1 metric) a staircase is as long as the diagonal it follows, so the
lattice's shortest path (A*, :func:`clew_ros.core.kernel.lattice_search`)
follows the shortest way round, at the lattice's resolution.

Only nodes that could lie on a path shorter than the caller's bound (inside
the L1 ellipse ``|q - a| + |q - b| < bound``) are checked, all in one call;
the edges are checked lazily, as in Bohlin and Kavraki's lazy PRM: the search
takes an unchecked edge between two valid nodes as clear, the unchecked edges
of the path it finds are checked together, and it searches again while one of
them is blocked. Every check is a straight move checked continuously with a
margin (:func:`clew_ros.core.continuous.straight_moves_clear`), so the path
returned is valid at any checking resolution. The true ends join the lattice
through the corners of their cells, by straight moves checked the same way.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable
from typing import Protocol

import numpy as np

from clew_ros.core.continuous import straight_moves_clear
from clew_ros.core.kernel import EDGE_BLOCKED, EDGE_CLEAR, EDGE_UNKNOWN, lattice_search
from clew_ros.core.world import World

__all__ = [
    "MAX_JOINTS",
    "MAX_NODES",
    "MIN_STEP_RAD",
    "NODE_SHARE",
    "KnownNodes",
    "LatticeBudget",
    "lattice_route",
    "lattice_step",
]

#: Arms of more joints than this get no lattice (one of :data:`MAX_NODES` nodes would be too coarse).
MAX_JOINTS = 3
#: Cells of a lattice: its step is the one that fills the joint limits with this many (a joint's values include
#: both ends, so a 3-joint arm with limits of +-pi gets 21^3 = 9,261 nodes 0.31 rad apart, a 2-joint one 90^2).
MAX_NODES = 8_000
#: A routing starts only when checking its nodes takes at most this share of its allowance (the rest is for the
#: edges and the searches: a routing that found its path took 1.5 to 3 times its nodes' checks).
NODE_SHARE = 0.35
#: The finest step (rad) of a lattice (a 2-joint arm's lattice is finer than :data:`MAX_NODES` needs).
MIN_STEP_RAD = 0.05


class LatticeBudget(Protocol):
    """What :func:`lattice_route` charges its work to: ``check_work`` units a configuration checked (what
    :func:`clew_ros.core.continuous.straight_moves_clear` charges, a call at a time), the units ``spent`` so
    far, and the clock's stop test."""

    check_work: float
    spent: int

    def spend(self, units: int) -> None: ...

    def spend_move_checks(self, configurations: int) -> None: ...

    def stop(self) -> bool: ...


class KnownNodes:
    """Which nodes of a lattice were checked, and which of those are valid, in one mode (the object resting at
    one pose or held one way) and with one margin: routings in the same mode check only the others."""

    def __init__(self) -> None:
        self._checked: np.ndarray | None = None
        self._valid: np.ndarray | None = None

    def states(self, size: int) -> tuple[np.ndarray, np.ndarray]:
        """The arrays ``checked`` and ``valid`` over the ``size`` nodes, to read and write."""
        if self._checked is None or self._valid is None or len(self._checked) != size:
            self._checked, self._valid = np.zeros(size, dtype=bool), np.zeros(size, dtype=bool)
        return self._checked, self._valid


def lattice_step(world: World) -> float | None:
    """The lattice's step (rad) for ``world``'s arm: :data:`MAX_NODES` cells within the joint limits, at
    least :data:`MIN_STEP_RAD`; ``None`` for an arm of more than :data:`MAX_JOINTS` joints."""
    robot = world.robot
    if robot.dof > MAX_JOINTS:
        return None
    volume = float(np.prod(np.asarray(robot.joint_upper) - np.asarray(robot.joint_lower)))
    return float(max(MIN_STEP_RAD, (volume / MAX_NODES) ** (1.0 / robot.dof)))


_Clear = Callable[[np.ndarray, np.ndarray], np.ndarray]


class _Lattice:
    def __init__(self, world: World, step: float) -> None:
        self.lower = np.asarray(world.robot.joint_lower, dtype=float)
        upper = np.asarray(world.robot.joint_upper, dtype=float)
        self.step = step
        self.counts = np.floor((upper - self.lower) / step + 1e-9).astype(np.int64) + 1
        self.strides = np.cumprod(np.r_[self.counts[1:], 1][::-1])[::-1].astype(np.int64)
        self.size = math.prod(int(c) for c in self.counts)

    def indices(self, nodes: np.ndarray) -> np.ndarray:
        return np.stack([(nodes // s) % c for s, c in zip(self.strides, self.counts, strict=True)], axis=1)

    def configurations(self, indices: np.ndarray) -> np.ndarray:
        return self.lower + np.asarray(indices, dtype=float) * self.step

    def corners(self, q: np.ndarray) -> np.ndarray:
        """The nodes at the corners of the cell holding ``q`` (fewer at the lattice's upper ends)."""
        low = np.clip(np.floor((q - self.lower) / self.step).astype(np.int64), 0, self.counts - 1)
        high = np.clip(low + 1, 0, self.counts - 1)
        picks = np.array(sorted(set(itertools.product(*zip(low, high, strict=True)))), dtype=np.int64)
        return picks @ self.strides

    def inside(self, a: np.ndarray, b: np.ndarray, bound: float) -> np.ndarray:
        """The nodes ``q`` with ``|q - a| + |q - b| < bound`` (L1), as node numbers."""
        per_joint = []
        for j in range(len(self.counts)):
            values = self.lower[j] + np.arange(self.counts[j]) * self.step
            per_joint.append(np.abs(values - a[j]) + np.abs(values - b[j]))
        total = per_joint[0]
        for values in per_joint[1:]:
            total = (total[..., None] + values).reshape(-1)  # node numbers: the last joint fastest
        return np.flatnonzero(total < bound)

    def block_nodes(self, edges: np.ndarray, nodes: np.ndarray) -> None:
        """Block every edge of ``nodes``."""
        edges[nodes, :] = EDGE_BLOCKED
        index = self.indices(nodes)
        for j, stride in enumerate(self.strides):
            edges[nodes[index[:, j] > 0] - stride, j] = EDGE_BLOCKED


def lattice_route(
    world: World,
    a: np.ndarray,
    b: np.ndarray,
    *,
    object_pose: np.ndarray | None,
    grasp_rel: np.ndarray | None,
    min_margin: float,
    shorter_than: float,
    budget: LatticeBudget,
    allowance: float,
    expansion_work: float,
    nodes_known: KnownNodes | None = None,
) -> np.ndarray | None:
    """Waypoints from ``a`` to ``b`` in one mode (the object resting at ``object_pose``, or held as
    ``grasp_rel``), every move clear with ``min_margin`` (m) to spare: the shortest lattice path between
    them (module docstring), through the lattice's nodes. ``None`` when there is none shorter than
    ``shorter_than`` rad of joint travel, the arm has no lattice (:func:`lattice_step`), checking the nodes
    that could lie on such a path would take more than :data:`NODE_SHARE` of ``allowance`` work units (those
    checked in the same mode before are not counted), the routing has spent
    ``allowance`` units (it stops between calls), or ``budget`` says stop. Each search costs
    ``expansion_work`` units a node it expands. ``nodes_known``: the nodes checked by earlier routings in the
    same mode with the same margin (not checked again); those this routing checks are added to it."""
    step = lattice_step(world)
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    if step is None or float(np.abs(b - a).sum()) >= shorter_than:
        return None
    lattice = _Lattice(world, step)
    nodes = lattice.inside(a, b, shorter_than)
    limit = budget.spent + allowance

    def spent() -> bool:
        return budget.stop() or budget.spent >= limit

    def clear(starts: np.ndarray, ends: np.ndarray) -> np.ndarray:
        return straight_moves_clear(
            world,
            np.ascontiguousarray(starts, dtype=float),
            np.ascontiguousarray(ends, dtype=float),
            object_pose=object_pose,
            grasp_rel=grasp_rel,
            min_margin=min_margin,
            budget=budget,
        )

    known = nodes_known if nodes_known is not None else KnownNodes()
    checked, valid = known.states(lattice.size)
    todo = nodes[~checked[nodes]]
    if not len(nodes) or len(todo) * budget.check_work > NODE_SHARE * allowance:
        return None
    if len(todo):
        q = lattice.configurations(lattice.indices(todo))
        ok = clear(q, q)  # a move that does not move: the configuration, with the margin
        checked[todo], valid[todo] = not budget.stop(), ok  # a check the clock stopped: nothing learnt
    edges = np.full((lattice.size, len(lattice.counts)), EDGE_BLOCKED, dtype=np.uint8)
    usable = nodes[valid[nodes]]
    edges[usable] = EDGE_UNKNOWN  # an edge out of a node outside the ellipse or not valid stays blocked
    lattice.block_nodes(edges, nodes[~valid[nodes]])
    joins = _joins(lattice, usable, a, b, clear)
    while joins is not None and not spent():
        path, _, expanded = lattice_search(lattice.counts, lattice.lower, step, edges, *joins, b, shorter_than)
        budget.spend(math.ceil(expansion_work * expanded))
        if not len(path) or spent():
            return None
        if _edges_clear(lattice, path, edges, clear):  # checked: the path stands, however much that took
            return np.concatenate([a[None], lattice.configurations(lattice.indices(path)), b[None]])
    return None


def _joins(
    lattice: _Lattice, usable: np.ndarray, a: np.ndarray, b: np.ndarray, clear: _Clear
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray] | None:
    """How ``a`` and ``b`` join the lattice: the corners of their cells among ``usable`` nodes reached by a clear
    straight move, and each one's joint travel to its end (sources, their costs, targets, theirs); ``None``
    when an end joins none."""
    inside = np.zeros(lattice.size, dtype=bool)
    inside[usable] = True
    joins = []
    for point, leaving in ((a, True), (b, False)):
        corners = lattice.corners(point)
        corners = corners[inside[corners]]
        at = lattice.configurations(lattice.indices(corners))
        away = np.broadcast_to(point, at.shape)
        ok = clear(away, at) if leaving else clear(at, away)
        if not ok.any():
            return None
        joins += [corners[ok], np.abs(at[ok] - point).sum(axis=1)]
    return joins[0], joins[1], joins[2], joins[3]


def _edges_clear(lattice: _Lattice, path: np.ndarray, edges: np.ndarray, clear: _Clear) -> bool:
    """Check the edges of ``path`` the search took as clear without a check, in one call, and record what was
    found (a blocked edge is not taken again). Whether the whole path is clear. Its nodes were checked: a
    path shorter than the bound stays inside the ellipse (the joint travel to a node and on to the end is at
    least the node's two L1 distances to the ends)."""
    base = np.minimum(path[:-1], path[1:])
    axis = np.argmax(np.abs(path[1:] - path[:-1])[:, None] == lattice.strides[None], axis=1)
    unchecked = np.flatnonzero(edges[base, axis] == EDGE_UNKNOWN)
    if not len(unchecked):
        return True
    low = lattice.indices(base[unchecked])
    high = low.copy()
    high[np.arange(len(unchecked)), axis[unchecked]] += 1
    ok = clear(lattice.configurations(low), lattice.configurations(high))
    edges[base[unchecked], axis[unchecked]] = np.where(ok, EDGE_CLEAR, EDGE_BLOCKED)
    return bool(ok.all())
