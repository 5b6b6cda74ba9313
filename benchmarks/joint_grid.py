"""A lattice over a 2-joint arm's joint space: which nodes and edges are valid in one mode, and the
shortest paths between them (joint travel, L1). The grid search of :mod:`benchmarks.reference`.

* **Lattice.** Joint ``j`` takes the values ``lower_j + k h`` (``k = 0, 1, ...`` up to
  ``upper_j``); nodes are 4-connected: an edge moves one joint by one step ``h``. In the L1
  metric (joint travel, the sum over joints of ``|dq|``) a staircase is as short as the
  diagonal it follows, so the 4-connected lattice measures joint travel exactly: a lattice path
  is a shortest one wherever the free space leaves room for its staircase.
* **Mode.** A transit (the object resting at a placement) or a transfer (the object held as
  ``grasp_rel``). The validity test is interface.md section 1 through the compiled first pass
  :func:`clew_ros.planar.kernel.clearly_valid` (valid beyond rounding; anything doubtful counts as
  invalid, so the lattice errs on the safe side), over whole windows of the lattice per call.
* **Edges.** An edge between two valid nodes is valid when its midpoint is clear by the motion
  bound of :func:`clew_ros.planar.continuous.straight_move_clear` (every point of the arm and the
  carried object moves at most ``h R_j`` along it; half of that from the midpoint): valid at any
  checking step. In a transfer the last link and the object it holds do not move relative to each
  other, so that pair is left out of the margin test (it is checked where the grasp is made) and
  the other links are tested against the object separately. An edge not cleared so is checked at
  the configurations :func:`clew_ros.planar.plan.validate_plan` samples (every 0.002 rad, the same
  arithmetic), so lattice paths pass the validator.
* **Off-lattice points** (the start, grasp configurations, exact goal configurations) join the
  lattice through the corners of their cell, by straight moves checked like the validator does.
* **Shortest paths.** Dijkstra (compiled) from sources with initial costs.
"""

from __future__ import annotations

import dataclasses
import heapq
import math
from dataclasses import dataclass

import numba
import numpy as np

from clew_ros.planar.collision import packed_carrying, packed_world
from clew_ros.planar.kernel import PackedWorld, clearly_valid
from clew_ros.planar.kinematics import compose, tip_poses, transform_points
from clew_ros.planar.plan import CHECK_STEP_RAD
from clew_ros.planar.world import World

__all__ = ["Box", "Graph", "Lattice", "Mode", "dense_clear", "shortest_paths", "trace"]


@dataclass(frozen=True)
class Lattice:
    """Node values of each joint (rad): ``axes[j][k] = lower_j + k step_rad``."""

    axes: tuple[np.ndarray, np.ndarray]
    step_rad: float

    @classmethod
    def for_world(cls, world: World, step_rad: float) -> Lattice:
        robot = world.robot
        if robot.dof != 2:
            raise ValueError(f"the grid reference plans 2-joint arms only; world {world.name!r} has {robot.dof}")
        if not step_rad > 0:
            raise ValueError(f"step_rad: expected a step > 0 rad, got {step_rad}")
        axes = []
        for low, high in zip(robot.joint_lower, robot.joint_upper, strict=True):
            count = math.floor((float(high) - float(low)) / step_rad + 1e-9) + 1
            axes.append(float(low) + step_rad * np.arange(count))
        return cls((axes[0], axes[1]), float(step_rad))

    @property
    def shape(self) -> tuple[int, int]:
        return (len(self.axes[0]), len(self.axes[1]))

    @property
    def full(self) -> Box:
        return Box(0, self.shape[0], 0, self.shape[1])

    def node(self, i: int, j: int) -> np.ndarray:
        return np.array([self.axes[0][i], self.axes[1][j]])

    def nodes(self, box: Box) -> np.ndarray:
        """Configurations of the nodes of ``box``, ``(ni * nj, 2)``, row-major (joint 1 slowest)."""
        a, b = np.meshgrid(self.axes[0][box.i0 : box.i1], self.axes[1][box.j0 : box.j1], indexing="ij")
        return np.stack([a.ravel(), b.ravel()], axis=1)

    def corners(self, point: np.ndarray) -> np.ndarray:
        """Lattice indices ``(c, 2)`` of the corners of the cell holding ``point`` (distinct)."""
        index = []
        for axis, value in zip(self.axes, point, strict=True):
            k = int(np.clip(np.searchsorted(axis, value, side="right") - 1, 0, len(axis) - 1))
            index.append(sorted({k, min(k + 1, len(axis) - 1)}))
        return np.array([(i, j) for i in index[0] for j in index[1]], dtype=np.int64)

    def box_around(self, points: np.ndarray, margin_rad: float) -> Box:
        """The smallest box of nodes holding ``points`` ``(m, 2)`` grown by ``margin_rad``, clipped."""
        low = np.min(points, axis=0) - margin_rad
        high = np.max(points, axis=0) + margin_rad
        bounds = []
        for axis, lo, hi in zip(self.axes, low, high, strict=True):
            bounds.append(int(np.clip(np.searchsorted(axis, lo, side="right") - 1, 0, len(axis) - 1)))
            bounds.append(int(np.clip(np.searchsorted(axis, hi, side="left"), 0, len(axis) - 1)) + 1)
        return Box(bounds[0], bounds[1], bounds[2], bounds[3])


@dataclass(frozen=True)
class Box:
    """Nodes ``[i0, i1) x [j0, j1)`` of a lattice."""

    i0: int
    i1: int
    j0: int
    j1: int

    @property
    def shape(self) -> tuple[int, int]:
        return (self.i1 - self.i0, self.j1 - self.j0)

    def exit_margin(self, lattice: Lattice, points: np.ndarray) -> float:
        """Least distance (rad) from the bounding box of ``points`` to a side of this box that a path could
        leave by (sides on the lattice's edge do not count); ``inf`` when the box is the whole lattice."""
        low, high = np.min(points, axis=0), np.max(points, axis=0)
        margins = [math.inf]
        for axis, (start, stop), lo, hi in zip(
            lattice.axes, ((self.i0, self.i1), (self.j0, self.j1)), low, high, strict=True
        ):
            if start > 0:
                margins.append(float(lo - axis[start]))
            if stop < len(axis):
                margins.append(float(axis[stop - 1] - hi))
        return max(0.0, min(margins))


@dataclass(frozen=True)
class Mode:
    """Where the object is: resting at ``placement`` (transit, ``grasp_rel`` None) or held as
    ``grasp_rel`` with grasp ``grasp`` (transfer; ``placement`` is where it was taken)."""

    placement: np.ndarray  # (3,)
    grasp: int | None = None
    grasp_rel: np.ndarray | None = None  # (3,) object pose in the end-effector frame

    @property
    def kind(self) -> str:
        return "transit" if self.grasp_rel is None else "transfer"

    def object_poses(self, world: World, q: np.ndarray) -> np.ndarray:
        """The object's pose ``(B, 3)`` at configurations ``q`` ``(B, 2)``."""
        if self.grasp_rel is None:
            return np.broadcast_to(self.placement, (len(q), 3))
        poses: np.ndarray = compose(tip_poses(world.robot, q), self.grasp_rel)
        return poses

    def reach_radii(self, world: World) -> np.ndarray:
        """``R_j``: how far any point that joint ``j`` moves can be from it (m)."""
        lengths = np.asarray(world.robot.link_lengths, dtype=float)
        radii = np.cumsum(lengths[::-1])[::-1]
        if self.grasp_rel is not None:
            held = transform_points(self.grasp_rel, world.object.polygon)
            radii = radii + float(np.max(np.linalg.norm(held, axis=-1)))
        return radii


def _margin_worlds(world: World, mode: Mode, margin_m: float) -> list[tuple[PackedWorld, int]]:
    """The validity tests that must pass with ``margin_m`` to spare (and how many joints each takes): in a
    transfer all but the pair of the last link and the object it holds
    (:func:`clew_ros.planar.collision.packed_carrying`)."""
    if mode.grasp_rel is None:
        return [(dataclasses.replace(packed_world(world), rounding=margin_m), 2)]
    without_object, links_but_last = packed_carrying(world)
    return [
        (dataclasses.replace(without_object, rounding=margin_m), 2),
        (dataclasses.replace(links_but_last, rounding=margin_m), 1),
    ]


def _clear_with_margin(world: World, mode: Mode, q: np.ndarray, margin_m: float) -> np.ndarray:
    poses = np.ascontiguousarray(mode.object_poses(world, q))
    clear = np.ones(len(q), dtype=bool)
    for packed, joints in _margin_worlds(world, mode, margin_m):
        rows = np.flatnonzero(clear)
        if len(rows):
            clear[rows] = clearly_valid(packed, np.ascontiguousarray(q[rows, :joints]), poses[rows])
    return clear


def valid(world: World, mode: Mode, q: np.ndarray) -> np.ndarray:
    """Configurations ``q`` ``(B, 2)`` valid beyond rounding in ``mode`` (doubtful counts as invalid)."""
    if not len(q):
        return np.zeros(0, dtype=bool)
    return clearly_valid(packed_world(world), q, np.ascontiguousarray(mode.object_poses(world, q)))


def dense_clear(world: World, mode: Mode, starts: np.ndarray, ends: np.ndarray) -> np.ndarray:
    """Whether each straight move ``starts[k] -> ends[k]`` is valid at both ends and at every
    configuration :func:`clew_ros.planar.plan.validate_plan` checks on it (``a + t (b - a)``,
    ``t = i / count``, ``count = ceil(max |b - a| / 0.002)``), per move ``(K,)``."""
    starts, ends = np.asarray(starts, float).reshape(-1, 2), np.asarray(ends, float).reshape(-1, 2)
    counts = np.maximum(1, np.ceil(np.max(np.abs(ends - starts), axis=1) / CHECK_STEP_RAD)).astype(np.int64)
    clear = valid(world, mode, starts)
    for count in np.unique(counts[clear]):
        rows = np.flatnonzero(clear & (counts == count))
        t = np.arange(1, count + 1)[:, None] / count  # as plan.interpolate computes it
        a, b = starts[rows][:, None, :], ends[rows][:, None, :]
        q = (a + t[None] * (b - a)).reshape(-1, 2)
        clear[rows] = valid(world, mode, q).reshape(len(rows), count).all(axis=1)
    return clear


@dataclass
class Graph:
    """A window of the lattice in one mode: valid nodes and edges (``ok0`` along joint 1 between
    nodes ``(i, j)`` and ``(i + 1, j)``; ``ok1`` along joint 2)."""

    lattice: Lattice
    box: Box
    mode: Mode
    node_ok: np.ndarray  # (ni, nj) bool
    ok0: np.ndarray  # (ni - 1, nj) bool
    ok1: np.ndarray  # (ni, nj - 1) bool

    @classmethod
    def build(cls, world: World, mode: Mode, lattice: Lattice, box: Box) -> Graph:
        ni, nj = box.shape
        q = lattice.nodes(box)
        node_ok = valid(world, mode, q).reshape(ni, nj)
        grid = q.reshape(ni, nj, 2)
        radii = mode.reach_radii(world)
        rounding = packed_world(world).rounding
        edges = []
        for axis in (0, 1):
            lower = node_ok[:-1, :] if axis == 0 else node_ok[:, :-1]
            upper = node_ok[1:, :] if axis == 0 else node_ok[:, 1:]
            a = grid[:-1, :] if axis == 0 else grid[:, :-1]
            b = grid[1:, :] if axis == 0 else grid[:, 1:]
            ok = lower & upper
            rows = np.flatnonzero(ok)
            a, b = a.reshape(-1, 2)[rows], b.reshape(-1, 2)[rows]
            if len(rows):
                step = float(np.max(np.abs(b - a)))
                margin = 0.5 * step * float(radii[axis]) * (1.0 + 1e-6) + rounding
                cleared = _clear_with_margin(world, mode, a + 0.5 * (b - a), margin)
                doubtful = np.flatnonzero(~cleared)
                cleared[doubtful] = dense_clear(world, mode, a[doubtful], b[doubtful])
                flat = ok.reshape(-1)
                flat[rows] = cleared
            edges.append(ok)
        return cls(lattice, box, mode, node_ok, edges[0], edges[1])

    def flat(self, index: np.ndarray) -> np.ndarray:
        """Flat node numbers in this window of lattice indices ``(c, 2)``; -1 outside the window."""
        i, j = index[:, 0] - self.box.i0, index[:, 1] - self.box.j0
        inside = (i >= 0) & (i < self.box.shape[0]) & (j >= 0) & (j < self.box.shape[1])
        return np.where(inside, i * self.box.shape[1] + j, -1)

    def configuration(self, flat: int) -> np.ndarray:
        i, j = divmod(int(flat), self.box.shape[1])
        return self.lattice.node(self.box.i0 + i, self.box.j0 + j)

    def join(self, world: World, point: np.ndarray, *, leaving: bool) -> tuple[np.ndarray, np.ndarray]:
        """Straight moves between an off-lattice ``point`` and the corners of its cell: the flat node
        numbers reachable and the moves' joint travel. ``leaving``: the move runs from the point to
        the node (else from the node to the point), as the plan will list it."""
        corners = self.lattice.corners(point)
        flat = self.flat(corners)
        keep = flat >= 0
        flat, corners = flat[keep], corners[keep]
        nodes = np.array([self.lattice.node(i, j) for i, j in corners]).reshape(-1, 2)
        starts = np.broadcast_to(point, nodes.shape) if leaving else nodes
        ends = nodes if leaving else np.broadcast_to(point, nodes.shape)
        clear = dense_clear(world, self.mode, starts, ends) if len(nodes) else np.zeros(0, bool)
        travel = np.abs(nodes - point).sum(axis=1)
        return flat[clear], travel[clear]


@numba.njit(cache=True)
def _neighbour(
    u: int, move: int, nj: int, ok0: np.ndarray, ok1: np.ndarray, step0: np.ndarray, step1: np.ndarray
) -> tuple[int, float]:
    """The node one valid edge from flat node ``u`` in direction ``move`` (0, 1: joint 1 up, down; 2, 3:
    joint 2 up, down) and the edge's joint travel; ``-1`` when there is no such edge."""
    i, j = u // nj, u % nj
    if move == 0 and i < ok0.shape[0] and ok0[i, j]:
        return u + nj, step0[i]
    if move == 1 and i > 0 and ok0[i - 1, j]:
        return u - nj, step0[i - 1]
    if move == 2 and j + 1 < nj and ok1[i, j]:
        return u + 1, step1[j]
    if move == 3 and j > 0 and ok1[i, j - 1]:
        return u - 1, step1[j - 1]
    return -1, 0.0


@numba.njit(cache=True)
def _dijkstra(
    ok0: np.ndarray,
    ok1: np.ndarray,
    step0: np.ndarray,
    step1: np.ndarray,
    sources: np.ndarray,
    costs: np.ndarray,
    dist: np.ndarray,
    pred: np.ndarray,
) -> None:
    """Shortest paths on the 4-connected window from ``sources`` (flat node numbers, initial ``costs``)."""
    nj = dist.shape[0] // (ok0.shape[0] + 1)
    heap = [(costs[0], sources[0])]
    for k in range(sources.shape[0]):
        if costs[k] < dist[sources[k]]:
            dist[sources[k]] = costs[k]
            pred[sources[k]] = -1
        heapq.heappush(heap, (costs[k], sources[k]))
    while len(heap) > 0:
        d, u = heapq.heappop(heap)
        if d > dist[u]:
            continue
        for move in range(4):
            v, w = _neighbour(u, move, nj, ok0, ok1, step0, step1)
            if v >= 0 and d + w < dist[v]:
                dist[v] = d + w
                pred[v] = u
                heapq.heappush(heap, (d + w, v))


def shortest_paths(graph: Graph, sources: np.ndarray, costs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Joint travel from the cheapest source to every node of ``graph`` (``inf``: unreachable), and each
    node's predecessor (``-1``: a source or unreached), flat over the window."""
    ni, nj = graph.box.shape
    dist = np.full(ni * nj, np.inf)
    pred = np.full(ni * nj, -1, dtype=np.int64)
    if len(sources):
        axes = graph.lattice.axes
        step0 = np.ascontiguousarray(np.diff(axes[0][graph.box.i0 : graph.box.i1]))
        step1 = np.ascontiguousarray(np.diff(axes[1][graph.box.j0 : graph.box.j1]))
        ok0 = np.ascontiguousarray(graph.ok0) if ni > 1 else np.zeros((0, nj), dtype=bool)
        ok1 = np.ascontiguousarray(graph.ok1) if nj > 1 else np.zeros((ni, 0), dtype=bool)
        _dijkstra(
            ok0,
            ok1,
            step0 if len(step0) else np.zeros(1),
            step1 if len(step1) else np.zeros(1),
            np.asarray(sources, dtype=np.int64),
            np.asarray(costs, dtype=np.float64),
            dist,
            pred,
        )
    return dist, pred


def trace(graph: Graph, pred: np.ndarray, node: int) -> np.ndarray:
    """Configurations ``(m, 2)`` of the lattice path from its source to ``node``."""
    flat = _trace(pred, int(node))[::-1]
    nj = graph.box.shape[1]
    return np.stack(
        [graph.lattice.axes[0][graph.box.i0 + flat // nj], graph.lattice.axes[1][graph.box.j0 + flat % nj]], axis=1
    )


@numba.njit(cache=True)
def _trace(pred: np.ndarray, node: int) -> np.ndarray:
    """Flat node numbers from ``node`` back to its source."""
    count = 1
    u = node
    while pred[u] >= 0:
        u = pred[u]
        count += 1
    out = np.empty(count, dtype=np.int64)
    u = node
    for k in range(count):
        out[k] = u
        u = pred[u]
    return out
