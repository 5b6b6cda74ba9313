"""The shortest way round the obstacles on a joint-space lattice, for arms of few joints; and where to put the
object down between two grasps.

Shortcuts only straighten a path within its own way round the obstacles, and
the way round RRT-Connect finds for a blocked move of the improvement is often
a long one (:meth:`clew_ros.planar.improve._Improver.connect` takes this one
instead when it is shorter). On an arm of at most ``max_joints`` joints
the joint space is small enough for a lattice: joint ``j`` takes the values
``lower_j + k step`` and an edge moves one joint by one step. In joint travel
(the L1 metric) a staircase is as long as the diagonal it follows, so the
lattice's shortest path (A*, :func:`clew_ros.planar.kernel.lattice_search`)
follows the shortest way round, at the lattice's resolution.

Only nodes that could lie on a path shorter than the caller's bound (inside
the L1 ellipse ``|q - a| + |q - b| < bound``) are checked, all in one call;
the edges are checked lazily, as in Bohlin and Kavraki's lazy PRM: the search
takes an unchecked edge between two valid nodes as clear, the unchecked edges
of the path it finds are checked together, and it searches again while one of
them is blocked. Every check is a straight move checked continuously with a
margin (:func:`clew_ros.planar.continuous.straight_moves_clear`), so the path
returned is valid at any checking resolution. The true ends join the lattice
through the corners of their cells, by straight moves checked the same way.

**Where to put the object down** (:func:`lattice_regrasp`, a 3-joint arm). A plan that regrasps twice or
more, or once where the object was put down far from where it had to be, keeps its releases: shortcuts
never move one, and in clutter a straight-move proposal (:mod:`clew_ros.planar.regrasp`) for another one
finds its moves blocked. With the first grasp (its configuration and how it holds the object) and the last
one (the configuration it ends at) fixed, one regrasp between them is a search over two lattices, one per
grasp: a transfer to any lattice node ``r`` of the first (the release: where the object is then put down
follows), the transit to the configuration holding the object there as the last grasp does (on a 3-joint
arm a tip frame fixes it up to the elbow, :func:`pose_configurations`), and a transfer on the second. A
Dijkstra search from each end (:func:`clew_ros.planar.kernel.lattice_costs`) gives every node's joint travel
to it, so every release's total is one numpy expression; the best are screened, and the best that passes
has its lattice edges checked (lazily, as above), then its regrasp's moves continuously.

The tuning is :class:`LatticeSettings`.
"""

from __future__ import annotations

import dataclasses
import itertools
import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from clew_ros.planar.collision import packed_world
from clew_ros.planar.continuous import ContinuousSettings, straight_moves_clear
from clew_ros.planar.kernel import (
    EDGE_BLOCKED,
    EDGE_CLEAR,
    EDGE_UNKNOWN,
    lattice_costs,
    lattice_path,
    lattice_repair,
    lattice_search,
    release_totals,
    screen_routes,
)
from clew_ros.planar.kinematics import compose, relative, tip_poses, wrap_angle
from clew_ros.planar.regrasp import route_waypoints, screen_samples
from clew_ros.planar.world import Robot, World

__all__ = [
    "KnownNodes",
    "LatticeBudget",
    "LatticeSettings",
    "LatticeWork",
    "grasp_configurations",
    "lattice_regrasp",
    "lattice_route",
    "lattice_step",
    "pose_configurations",
]


@dataclass(frozen=True)
class LatticeSettings:
    """Tuning of the lattice (:func:`lattice_step`, :func:`lattice_route`, :func:`lattice_regrasp`)."""

    #: Arms of more joints than this get no lattice (count): one of :attr:`max_nodes` nodes would be too coarse.
    max_joints: int = 3
    #: Cells of a lattice (count): its step is the one that fills the joint limits with this many (a joint's
    #: values include both ends, so a 3-joint arm with limits of +-pi gets 21^3 = 9,261 nodes 0.31 rad apart, a
    #: 2-joint one 90^2). 20,000 or 4,000 made obstacles_32 and obstacles_24 no better (docs/benchmarks.md).
    max_nodes: int = 8_000
    #: A routing starts only when checking its nodes takes at most this share of its allowance (ratio): the rest
    #: is for the edges and the searches (a routing that found its path took 1.5 to 3 times its nodes' checks).
    node_share: float = 0.35
    #: The finest step (rad) of a lattice: a 2-joint arm's lattice is finer than :attr:`max_nodes` needs.
    min_step_rad: float = 0.05
    #: :func:`lattice_regrasp`: of a round's best regrasps not found blocked, this many are taken (count); those
    #: of them not screened before are screened (one compiled call for the moves putting the object down, one for
    #: the joins), enough that a call's work outweighs the Python around it.
    regrasp_screened: int = 32
    #: :func:`lattice_regrasp`: rounds of searching and checking at most (count; a round that finds an edge of its
    #: paths blocked repairs its searches, :func:`clew_ros.planar.kernel.lattice_repair`); its allowance of work ends
    #: it sooner in a cluttered world.
    regrasp_rounds: int = 256
    #: :func:`lattice_regrasp`: a search brought up to date after edges were found blocked
    #: (:func:`clew_ros.planar.kernel.lattice_repair`) passes over every node once, at about this share of an
    #: expansion's cost a node (ratio; measured: 0.04 ms on 9,261 nodes, an expansion 0.23 us).
    repair_pass_share: float = 1.0 / 64.0


# a regrasp's state in lattice_regrasp: not screened, passed the screen, blocked (by the screen or the check)
_UNKNOWN, _SCREENED, _BLOCKED = 0, 1, 2


class LatticeBudget(Protocol):
    """What :func:`lattice_route` charges its work to: ``check_work`` units a configuration checked (what
    :func:`clew_ros.planar.continuous.straight_moves_clear` charges, a call at a time), the units ``spent`` so
    far, and the clock's stop test."""

    check_work: float
    spent: int

    def spend(self, units: int) -> None: ...

    def spend_move_checks(self, configurations: int) -> None: ...

    def spend_checks(self, configurations: int, calls: int = 1) -> None: ...

    def stop(self) -> bool: ...


@dataclass(frozen=True)
class LatticeWork:
    """What a lattice search (:func:`lattice_route`, :func:`lattice_regrasp`) may spend and what it charges: the
    ``budget`` it charges its work to, the work units it may spend there (``allowance``), and the units a node it
    expands (``expansion_work``) and, in :func:`lattice_regrasp`, a release each round (``release_work``) cost."""

    budget: LatticeBudget
    allowance: float
    expansion_work: float
    release_work: float = 0.0


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


def lattice_step(world: World, settings: LatticeSettings | None = None) -> float | None:
    """The lattice's step (rad) for ``world``'s arm: ``max_nodes`` cells within the joint limits, at least
    ``min_step_rad``; ``None`` for an arm of more than ``max_joints`` joints (``settings`` default
    :class:`LatticeSettings`)."""
    tuning = settings if settings is not None else LatticeSettings()
    robot = world.robot
    if robot.dof > tuning.max_joints:
        return None
    volume = float(np.prod(np.asarray(robot.joint_upper) - np.asarray(robot.joint_lower)))
    return float(max(tuning.min_step_rad, (volume / tuning.max_nodes) ** (1.0 / robot.dof)))


_Clear = Callable[[np.ndarray, np.ndarray], np.ndarray]


class _Lattice:
    def __init__(self, world: World, step: float) -> None:
        self.lower = np.array(world.robot.joint_lower, dtype=float)  # writable, as kernel.warm_up compiles it
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
    work: LatticeWork,
    nodes_known: KnownNodes | None = None,
    step: float | None = None,
    settings: LatticeSettings | None = None,
    moves: ContinuousSettings | None = None,
) -> np.ndarray | None:
    """Waypoints from ``a`` to ``b`` in one mode (the object resting at ``object_pose``, or held as
    ``grasp_rel``), every move clear with ``min_margin`` (m) to spare: the shortest lattice path between
    them (module docstring), through the lattice's nodes. ``None`` when there is none shorter than
    ``shorter_than`` rad of joint travel, the arm has no lattice (:func:`lattice_step`), checking the nodes
    that could lie on such a path would take more than ``node_share`` of ``work.allowance`` work units (those
    checked in the same mode before are not counted), the routing has spent
    ``work.allowance`` units (it stops between calls), or ``work.budget`` says stop. Each search costs
    ``work.expansion_work`` units a node it expands. ``nodes_known``: the nodes checked by earlier routings in the
    same mode with the same margin (not checked again); those this routing checks are added to it. ``step``:
    the lattice's step (rad), :func:`lattice_step` unless given (a benchmark's finer lattice). ``settings``
    default :class:`LatticeSettings`; ``moves``: the straight-move check's settings (default
    :class:`~clew_ros.planar.continuous.ContinuousSettings`)."""
    tuning = settings if settings is not None else LatticeSettings()
    step = lattice_step(world, tuning) if step is None else step
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    if step is None or float(np.abs(b - a).sum()) >= shorter_than:
        return None
    lattice = _Lattice(world, step)
    nodes = lattice.inside(a, b, shorter_than)
    budget, allowance = work.budget, work.allowance
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
            settings=moves,
        )

    known = nodes_known if nodes_known is not None else KnownNodes()
    checked, valid = known.states(lattice.size)
    if not len(nodes) or np.count_nonzero(~checked[nodes]) * budget.check_work > tuning.node_share * allowance:
        return None
    layer = _layer(lattice, nodes, clear, checked=checked, valid=valid, budget=budget)
    edges = layer.edges
    joins = _joins(lattice, layer.usable, a, b, clear)
    while joins is not None and not spent():
        path, _, expanded = lattice_search(lattice.counts, lattice.lower, step, edges, *joins, b, shorter_than)
        budget.spend(math.ceil(work.expansion_work * expanded))
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
    sources = _join(lattice, usable, a, clear, leaving=True)
    targets = _join(lattice, usable, b, clear, leaving=False)
    if sources is None or targets is None:
        return None
    return sources[0], sources[1], targets[0], targets[1]


def _join(
    lattice: _Lattice, usable: np.ndarray, point: np.ndarray, clear: _Clear, *, leaving: bool
) -> tuple[np.ndarray, np.ndarray] | None:
    """The corners of ``point``'s cell among ``usable`` nodes reached by a clear straight move (from ``point`` if
    ``leaving``, else to it), and each one's joint travel to it; ``None`` when it joins none."""
    corners = lattice.corners(point)
    corners = corners[np.isin(corners, usable)]
    at = lattice.configurations(lattice.indices(corners))
    away = np.broadcast_to(point, at.shape)
    ok = clear(away, at) if leaving else clear(at, away)
    if not ok.any():
        return None
    return corners[ok], np.abs(at[ok] - point).sum(axis=1)


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


def pose_configurations(robot: Robot, tips: np.ndarray, near: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Both configurations ``(2, B, 3)`` of a 3-joint arm putting its tip at the frames ``tips`` ``(B, 3)``
    (elbow one way, then the other), each joint's angle the one nearest ``near`` ``(B, 3)`` of those ``2 pi``
    apart (else one within the joint limits); and which ``(2, B)`` exist within the joint limits."""
    lengths = np.asarray(robot.link_lengths, dtype=float)
    lower, upper = np.asarray(robot.joint_lower, dtype=float), np.asarray(robot.joint_upper, dtype=float)
    wrist = tips[:, :2] - lengths[2] * np.stack([np.cos(tips[:, 2]), np.sin(tips[:, 2])], axis=1) - robot.base
    cosine = (np.sum(wrist**2, axis=1) - lengths[0] ** 2 - lengths[1] ** 2) / (2.0 * lengths[0] * lengths[1])
    reached = np.abs(cosine) <= 1.0
    elbow = np.arccos(np.clip(cosine, -1.0, 1.0))
    out = np.empty((2, len(tips), 3))
    ok = np.empty((2, len(tips)), dtype=bool)
    for side, q2 in enumerate((elbow, -elbow)):
        q1 = np.arctan2(wrist[:, 1], wrist[:, 0]) - np.arctan2(
            lengths[1] * np.sin(q2), lengths[0] + lengths[1] * np.cos(q2)
        )
        q = np.stack([q1, q2, tips[:, 2] - q1 - q2], axis=1)
        q = near + wrap_angle(q - near)
        for turn in (-2.0 * np.pi, 2.0 * np.pi):  # outside the limits: a turn may bring it back
            outside = (q < lower) | (q > upper)
            q = np.where(outside & (q + turn >= lower) & (q + turn <= upper), q + turn, q)
        out[side] = q
        ok[side] = reached & np.all((q >= lower) & (q <= upper), axis=1)
    return out, ok


def grasp_configurations(
    world: World, pose: np.ndarray, near: np.ndarray, approaches: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A 3-joint arm's configurations ``(K, 3)`` holding the object resting at ``pose``: each grasp point with
    ``approaches`` tip angles evenly around it and both elbows (:func:`pose_configurations`, each joint nearest
    ``near``), those within the joint limits; with each one's grasp (an index of ``world.object.grasps``) and
    the object's pose in the tip's frame. Not checked for collisions."""
    grasps = np.asarray(world.object.grasps, dtype=float)
    pose = np.asarray(pose, dtype=float)
    points = compose(pose, np.c_[grasps, np.zeros(len(grasps))])[:, :2]
    angles = pose[2] + np.arange(approaches) * (2.0 * np.pi / approaches)
    which = np.repeat(np.arange(len(grasps)), approaches)
    tips = np.c_[points[which], np.tile(angles, len(grasps))]
    solved, ok = pose_configurations(world.robot, tips, np.broadcast_to(near, (len(tips), 3)))
    side, row = np.nonzero(ok)
    q = solved[side, row]
    return q, which[row], relative(tips[row], pose)


@dataclasses.dataclass
class _Layer:
    """One grasp's lattice in :func:`lattice_regrasp`: its clear test, edge states and valid nodes, and the
    joint travel from its end to each node with the node it is reached from (up to date unless ``stale``)."""

    clear: _Clear
    edges: np.ndarray
    usable: np.ndarray
    ends: tuple[np.ndarray, np.ndarray] = (np.zeros(0, dtype=np.int64), np.zeros(0))
    cost: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(0))
    previous: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    stale: bool = True


@dataclasses.dataclass
class _Candidates:
    """A round's best regrasps: elbow, row into the round's releases, release node, each in order."""

    sides: np.ndarray
    rows: np.ndarray
    nodes: np.ndarray


def lattice_regrasp(
    world: World,
    first: np.ndarray,
    first_rel: np.ndarray,
    last: np.ndarray,
    last_rel: np.ndarray,
    *,
    min_margin: float,
    shorter_than: float,
    work: LatticeWork,
    screen_step_rad: float,
    nodes_known: tuple[KnownNodes, KnownNodes] | None = None,
    settings: LatticeSettings | None = None,
    moves: ContinuousSettings | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """The shortest way on the lattice (module docstring) to carry the object from ``first`` (holding it as
    ``first_rel``) to ``last`` (holding it as ``last_rel``), putting it down once: a transfer to a lattice
    node (the release), a transit to the configuration holding the object where it then rests as
    ``last_rel`` does (straight or one joint after the other, :data:`clew_ros.planar.regrasp.ROUTES`), and a
    transfer to ``last``. Returns the three moves' waypoints, shorter than ``shorter_than`` rad of joint
    travel in all, every move clear with ``min_margin`` (m) to spare; ``None`` when there is none, the arm
    has not three joints and a lattice, checking the nodes inside the L1 ellipse of ``first`` and ``last``
    in both modes would take more than ``node_share`` of ``work.allowance`` (those of ``nodes_known``, one
    per grasp, not counted), the search has spent ``work.allowance`` work units or ``regrasp_rounds``
    rounds, or ``work.budget`` says stop. Each search costs ``work.expansion_work`` units a node it expands (a
    repair the nodes it expands again and ``repair_pass_share`` of that a node of the lattice for its pass over
    them), and each round ``work.release_work`` units a release (totalling them when a search changed, and picking
    the best). The put-down and join moves are screened about every ``screen_step_rad`` of joint travel
    (:func:`clew_ros.planar.regrasp.screen_samples`). ``settings`` and ``moves`` as :func:`lattice_route`'s."""
    tuning = settings if settings is not None else LatticeSettings()
    step = lattice_step(world, tuning)
    first, last = np.asarray(first, dtype=float), np.asarray(last, dtype=float)
    if step is None or world.robot.dof != 3 or float(np.abs(last - first).sum()) >= shorter_than:
        return None
    search = _RegraspSearch(
        world,
        _Lattice(world, step),
        (first_rel, last_rel),
        min_margin=min_margin,
        work=work,
        screen_step_rad=screen_step_rad,
        settings=tuning,
        moves=moves,
    )
    if not search.layers(first, last, shorter_than, nodes_known or (KnownNodes(), KnownNodes())):
        return None
    for _ in range(tuning.regrasp_rounds):
        if search.spent():
            return None
        found = search.round(shorter_than, work.expansion_work)
        if found is not None or search.exhausted:
            return found
    return None


class _RegraspSearch:
    """The state of one :func:`lattice_regrasp`."""

    def __init__(
        self,
        world: World,
        lattice: _Lattice,
        grasps: tuple[np.ndarray, np.ndarray],
        *,
        min_margin: float,
        work: LatticeWork,
        screen_step_rad: float,
        settings: LatticeSettings,
        moves: ContinuousSettings | None,
    ) -> None:
        budget, allowance = work.budget, work.allowance
        self.world, self.lattice, self.budget = world, lattice, budget
        self.settings, self.moves = settings, moves
        self.screen_step_rad = screen_step_rad  # rad of joint travel between the screen's samples
        (self.first_rel, self.last_rel), self.min_margin = grasps, min_margin
        self.exhausted = False  # no regrasp left below the bound
        self.release_work = work.release_work  # work units a release, each round
        self.totals = self.joined = np.zeros((2, 0))
        self.first, self.last = np.zeros(3), np.zeros(3)
        self.limit = budget.spent + allowance
        self.allowance = allowance
        packed = packed_world(world)
        self.packed = dataclasses.replace(packed, rounding=max(min_margin, packed.rounding))
        self.state = np.zeros((2, lattice.size), dtype=np.int8)  # per elbow and release node: _UNKNOWN ...
        self.put_downs: dict[tuple[int, int], np.ndarray] = {}
        self.first_layer = self.last_layer = _Layer(self.clear_in(None, None), np.zeros((0, 3)), np.zeros(0))
        self.releases = np.zeros(0, dtype=np.int64)
        self.at = self.poses = self.put_travel = self.join_travel = np.zeros(0)
        self.regrasps = self.corners = np.zeros(0)

    def spent(self) -> bool:
        return self.budget.stop() or self.budget.spent >= self.limit

    def clear_in(self, grasp_rel: np.ndarray | None, pose: np.ndarray | None) -> _Clear:
        """Which straight moves are clear, the object held as ``grasp_rel`` or resting at ``pose``."""

        def clear(starts: np.ndarray, ends: np.ndarray) -> np.ndarray:
            return straight_moves_clear(
                self.world,
                np.ascontiguousarray(starts, dtype=float),
                np.ascontiguousarray(ends, dtype=float),
                object_pose=pose,
                grasp_rel=grasp_rel,
                min_margin=self.min_margin,
                budget=self.budget,
                settings=self.moves,
            )

        return clear

    def layers(self, first: np.ndarray, last: np.ndarray, bound: float, known: tuple[KnownNodes, KnownNodes]) -> bool:
        """Check both grasps' nodes inside the ellipse and join ``first`` and ``last`` to theirs: whether both
        joined within the allowance."""
        lattice = self.lattice
        nodes = lattice.inside(first, last, bound)  # a node on a shorter way lies inside
        states = [k.states(lattice.size) for k in known]
        todo = sum(int(np.count_nonzero(~checked[nodes])) for checked, _ in states)
        if not len(nodes) or todo * self.budget.check_work > self.settings.node_share * self.allowance:
            return False
        self.first_layer, self.last_layer = (
            _layer(lattice, nodes, self.clear_in(rel, None), checked=checked, valid=valid, budget=self.budget)
            for rel, (checked, valid) in zip((self.first_rel, self.last_rel), states, strict=True)
        )
        if self.spent():
            return False
        sources = _join(lattice, self.first_layer.usable, first, self.first_layer.clear, leaving=True)
        targets = _join(lattice, self.last_layer.usable, last, self.last_layer.clear, leaving=False)
        if sources is None or targets is None:
            return False
        self.first_layer.ends, self.last_layer.ends = sources, targets
        self.first, self.last = first, last
        self.regrasp_configurations()
        return True

    def regrasp_configurations(self) -> None:
        """For every release (a valid node of the first lattice) where the object is put down, both elbows'
        regrasp configurations, the joint travel to them, the corners of their cells on the second lattice
        and the joint travel to each (infinite for a regrasp the arm cannot reach or a corner off the lattice):
        the same every round, so computed once."""
        lattice, robot = self.lattice, self.world.robot
        self.releases = self.first_layer.usable
        self.at = lattice.configurations(lattice.indices(self.releases))
        self.poses = compose(tip_poses(robot, self.at), self.first_rel)
        self.regrasps, exists = pose_configurations(
            robot, compose(self.poses, relative(self.last_rel, np.zeros(3))), self.at
        )
        self.put_travel = np.where(exists, np.abs(self.regrasps - self.at[None]).sum(axis=2), np.inf)
        low = np.floor((self.regrasps - lattice.lower) / lattice.step).astype(np.int64)
        offsets = np.array(list(itertools.product((0, 1), repeat=len(lattice.counts))), dtype=np.int64)
        index = low[:, :, None, :] + offsets[None, None]  # (2, R, corners, joints)
        inside = np.all((index >= 0) & (index < lattice.counts), axis=3)
        self.corners = np.clip(index, 0, lattice.counts - 1) @ lattice.strides
        travel = np.abs(lattice.configurations(index) - self.regrasps[:, :, None, :]).sum(axis=3)
        self.join_travel = np.where(inside, travel, np.inf)

    def round(self, bound: float, expansion_work: float) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
        """Search both lattices again where an edge was found blocked, screen the best regrasps not screened
        yet, and check the best that passed: its three moves if it stands, else ``None`` (``exhausted`` when
        no regrasp is left below ``bound``)."""
        lattice = self.lattice
        totals_stale = self.first_layer.stale or self.last_layer.stale
        for layer in (self.first_layer, self.last_layer):
            if not layer.stale:
                continue
            if len(layer.cost):  # edges were blocked since the last search: only the costs that took them change
                expanded = lattice.size * self.settings.repair_pass_share + lattice_repair(
                    lattice.counts, lattice.step, layer.edges, *layer.ends, bound, layer.cost, layer.previous
                )
            else:
                layer.cost, layer.previous, expanded = lattice_costs(
                    lattice.counts, lattice.step, layer.edges, *layer.ends, bound
                )
            self.budget.spend(math.ceil(expansion_work * expanded))
            layer.stale = False
        releases, at, poses, regrasps = self.releases, self.at, self.poses, self.regrasps
        self.budget.spend(math.ceil(self.release_work * len(releases)))
        if totals_stale:  # the totals only change with the searches' costs
            self.totals, self.joined = release_totals(
                self.first_layer.cost, self.last_layer.cost, releases, self.put_travel, self.corners, self.join_travel
            )
        joined = self.joined
        total = np.where(self.state[:, releases] == _BLOCKED, np.inf, self.totals).reshape(-1)
        count = min(self.settings.regrasp_screened, len(total))
        order = np.argpartition(total, count - 1)[:count]
        order = order[np.lexsort((order, total[order]))]  # the best, in order (ties: the lower index first)
        order = order[total[order] < bound]
        if not len(order):
            self.exhausted = True
            return None
        sides, rows = np.divmod(order, len(releases))
        best = _Candidates(sides, rows, releases[rows])
        self.screen(best, at, regrasps, poses, joined)
        standing = np.flatnonzero(self.state[best.sides, best.nodes] != _BLOCKED)
        if not len(standing):
            return None
        k = int(standing[0])  # the best that passed the screen: its lattice paths, then its own moves
        side, row, release = int(best.sides[k]), int(best.rows[k]), int(best.nodes[k])
        corner = int(joined[side, row])
        path_first = np.append(lattice_path(self.first_layer.previous, release), release)
        path_last = np.append(lattice_path(self.last_layer.previous, corner), corner)[::-1]
        for layer, path in ((self.first_layer, path_first), (self.last_layer, path_last)):
            layer.stale = not _edges_clear(lattice, path, layer.edges, layer.clear)
        if self.first_layer.stale or self.last_layer.stale or self.spent():
            return None
        regrasp, put_down = regrasps[side, row], self.put_downs[side, release]
        # the dearest check (near contact), once its paths stand; the join to the corner the costs now pick (the
        # screen may have passed another)
        corner_q = lattice.configurations(lattice.indices(np.array([corner])))[0]
        clear = bool(self.clear_in(None, poses[row])(put_down[:-1], put_down[1:]).all()) and bool(
            self.last_layer.clear(regrasp[None], corner_q[None])[0]
        )
        if not clear:
            self.state[side, release] = _BLOCKED
            return None
        return (
            np.concatenate([self.first[None], lattice.configurations(lattice.indices(path_first))]),
            put_down,
            np.concatenate([regrasp[None], lattice.configurations(lattice.indices(path_last)), self.last[None]]),
        )

    def screen(
        self, best: _Candidates, at: np.ndarray, regrasps: np.ndarray, poses: np.ndarray, joined: np.ndarray
    ) -> None:
        """The compiled screen (sampled, as regrasp's proposals) of the moves of those of ``best`` not screened
        yet: putting the object down and taking it again where it then rests, and the join of the regrasp
        configuration to the second lattice."""
        fresh = np.flatnonzero(self.state[best.sides, best.nodes] == _UNKNOWN)
        if not len(fresh):
            return
        sides, rows, nodes = best.sides[fresh], best.rows[fresh], best.nodes[fresh]
        a, b = at[rows], regrasps[sides, rows]
        c = self.lattice.configurations(self.lattice.indices(joined[sides, rows]))
        down, checked = screen_routes(
            self.packed, a, b, screen_samples(a, b, self.screen_step_rad), resting=poses[rows], grasp_rel=None
        )
        held = np.ascontiguousarray(np.broadcast_to(self.last_rel, (len(fresh), 3)))
        join, more = screen_routes(
            self.packed, b, c, screen_samples(b, c, self.screen_step_rad), resting=None, grasp_rel=held
        )
        self.budget.spend_move_checks(int(checked))  # two compiled calls, charged as straight-move checks
        self.budget.spend_move_checks(int(more))
        passed = (down >= 0) & (join >= 0)
        self.state[sides, nodes] = np.where(passed, _SCREENED, _BLOCKED)
        for k in np.flatnonzero(passed).tolist():
            self.put_downs[int(sides[k]), int(nodes[k])] = route_waypoints(a[k], b[k], int(down[k]))


def _layer(
    lattice: _Lattice,
    nodes: np.ndarray,
    clear: _Clear,
    *,
    checked: np.ndarray,
    valid: np.ndarray,
    budget: LatticeBudget,
) -> _Layer:
    """Check the ``nodes`` not ``checked`` yet (in one call), and the edge states that follow: every edge of a
    node of ``nodes`` that is not valid is blocked, the edges out of the valid ones unknown (one leading out of
    ``nodes`` too: a path through it is longer than the bound the ellipse was drawn for), the rest blocked."""
    todo = nodes[~checked[nodes]]
    if len(todo):
        q = lattice.configurations(lattice.indices(todo))
        ok = clear(q, q)  # a move that does not move: the configuration, with the margin
        checked[todo], valid[todo] = not budget.stop(), ok  # a check the clock stopped: nothing learnt
    edges = np.full((lattice.size, len(lattice.counts)), EDGE_BLOCKED, dtype=np.uint8)
    usable = nodes[valid[nodes]]
    edges[usable] = EDGE_UNKNOWN
    lattice.block_nodes(edges, nodes[~valid[nodes]])
    return _Layer(clear, edges, usable)
