"""``python -m benchmarks.reference [--worlds NAME|PATH ...] [--seeds N] [--step RAD]``: a brute-force grid
reference planner for 2-joint worlds, and how far the planner's plans are from it (issue 14).

**The reference** (:func:`reference_plan`) searches joint space on a lattice of step ``h``
(:mod:`benchmarks.joint_grid`, default 0.02 rad) for the plan of least joint travel (sum over
joints of ``|dq|``, rad), with at most ``max_transfers`` transfers (default 2: one regrasp):

* a *mode* is a transit with the object resting at a placement, or a transfer holding grasp
  ``g`` as ``grasp_rel``; each mode has its own lattice of valid nodes and edges;
* a grasp is made at an exact configuration: the two elbow solutions (two joints: at most two
  per placement and grasp, within the joint limits) that put the tip on the grasp point;
* a transfer ends at the goal (a lattice node whose object pose is within the goal tolerances, or
  an exact configuration putting the object's origin on the goal), or at a *release*: a lattice
  node where the object is put down; a transit at that placement then reaches a grasp
  configuration of any grasp (another one, or the same with the other elbow) and a new transfer
  starts. Release nodes are every ``release_stride``-th lattice node of each joint (subsampled);
* the search is best-first over these steps, on estimated totals: joint travel so far, plus
  (releases) the straight joint distance to the grasp configuration, plus (a last transfer) the
  straight joint distance from the grasp to the nearest exact goal configuration less
  ``goal_slack_rad``; it stops when no open step is estimated below the best plan found. A
  transfer that may still regrasp is searched over the whole lattice (its release nodes); other
  searches run in a window around their ends, grown until no path leaving it could be shorter.
  ``max_expansions`` whole-lattice searches and ``max_releases`` releases at most
  (``capped`` says whether a cap cut the search short).

**Error bound.** On its graph (lattice, grasp, goal and start configurations, subsampled
releases) the reference is the shortest plan, up to the estimates' slack. Against the continuous
problem, its travel exceeds the shortest plan's through the same modes by at most ``2 h`` per
off-lattice end of a segment (the start, each grasp configuration, which ends a transit and starts
a transfer, an exact goal configuration: each joins the lattice at a corner of its cell, at most
``h`` of travel, and back): ``8 h`` for one transfer, ``12 h`` (0.24 rad at 0.02 rad) with one
regrasp; plus what a release restricted to the subsampled nodes costs; passages
narrower than about ``h`` in joint space (or cleared by less than the motion bound of an edge)
are not found. Every plan it returns is checked with :func:`clew_ros.planar.plan.validate_plan`
(its lattice paths are listed node by node, so the validator checks exactly the configurations
the lattice did, or edges cleared continuously).

**The report** (``main``): per world (``config/figure1.yaml``, ``config/single_transfer.yaml``, the
``joints_2`` family world, and any world names or YAML files given), the reference's travel and
transfers next to the planner's over seeds ``0..N-1``, each run exactly as ``clew_plan WORLD
--seed S`` plans (:func:`clew_ros.core.clew.plan`, then :func:`clew_ros.planar.plan.checked_plan`):
median travel ratio planner / reference, the share of runs with transfers at most the
reference's + 1, and the first plan's travel against the improved one's. "capped" after the
reference's figure: a cap cut its search short (the plan is the best it found).
"""

from __future__ import annotations

import argparse
import heapq
import itertools
import math
import statistics
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from benchmarks.joint_grid import Graph, Lattice, Mode, shortest_paths, trace
from clew_ros.core.plan import Plan, PlanSegment
from clew_ros.planar.collision import check_start_and_goal, packed_world
from clew_ros.planar.kernel import clearly_valid
from clew_ros.planar.kinematics import compose, relative, tip_poses, transform_points, wrap_angle
from clew_ros.planar.plan import replay, validate_plan
from clew_ros.planar.world import World

__all__ = ["DEFAULT_WORLDS", "ReferenceResult", "ReferenceSettings", "main", "reference_plan"]

ROOT = Path(__file__).absolute().parents[1]
#: The 2-joint worlds the report covers by default: names of benchmarks.worlds worlds.
DEFAULT_WORLDS = ("figure1", "single_transfer", "joints_2")


@dataclass(frozen=True)
class ReferenceSettings:
    """How hard the reference searches (module docstring)."""

    step_rad: float = 0.02  # lattice step (rad)
    max_transfers: int = 2  # transfers at most (2: one regrasp)
    release_stride: int = 3  # release candidates: every this many lattice nodes per joint
    max_expansions: int = 16  # transfers searched over the whole lattice
    max_releases: int = 80  # releases tried
    window_rad: float = 0.5  # first margin (rad) of a windowed search
    goal_slack_rad: float = 0.2  # taken off the straight distance to an exact goal configuration


@dataclass
class ReferenceResult:
    """The reference plan (``None``: none found) and how the search went."""

    world: str
    plan: Plan | None
    travel: float  # rad; inf without a plan
    transfers: int
    problems: list[str]  # validate_plan's findings (empty: valid)
    expansions: int
    releases: int
    capped: bool
    time_s: float
    settings: ReferenceSettings = field(default_factory=ReferenceSettings)


# --------------------------------------------------------------------------- closed-form grasps


def two_link_ik(
    world: World, points: np.ndarray, *, last: np.ndarray | None = None, offset: np.ndarray | float = 0.0
) -> np.ndarray:
    """Configurations ``(B, K, 2)`` (NaN: none) whose chain end is at ``points`` ``(B, 2)``: both elbows,
    each joint shifted by whole turns into its limits. ``last``/``offset`` ``(B,)``: a virtual last link
    of this length, turned by ``offset`` from link 2 (a carried object's origin); joint 2 stays the real one."""
    robot = world.robot
    v = np.asarray(points, float).reshape(-1, 2) - robot.base
    l1 = float(robot.link_lengths[0])
    l2 = np.full(len(v), float(robot.link_lengths[1])) if last is None else np.asarray(last, float)
    squared = np.sum(v * v, axis=1)
    cosine = (squared - l1 * l1 - l2 * l2) / (2.0 * l1 * l2)
    cosine = np.where(np.abs(cosine) <= 1.0 + 1e-12, np.clip(cosine, -1.0, 1.0), np.nan)
    elbow = np.array([1.0, -1.0])[None, :] * np.arccos(cosine)[:, None]  # (B, 2)
    q1 = np.arctan2(v[:, 1], v[:, 0])[:, None] - np.arctan2(
        l2[:, None] * np.sin(elbow), l1 + l2[:, None] * np.cos(elbow)
    )
    q2 = elbow - np.asarray(offset, float).reshape(-1, 1)
    turns = 2.0 * math.pi * np.array([(a, b) for a in (-1, 0, 1) for b in (-1, 0, 1)], dtype=float)  # (9, 2)
    q = np.stack([q1, q2], axis=-1)[:, :, None, :] + turns[None, None]  # (B, 2, 9, 2)
    inside = np.all((q >= robot.joint_lower) & (q <= robot.joint_upper), axis=-1)
    q[~inside] = np.nan
    configurations: np.ndarray = q.reshape(len(v), -1, 2)
    return configurations


def grasp_configurations(world: World, placements: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Valid configurations holding a grasp of the object resting at ``placements`` ``(B, 3)``:
    ``(row, grasp, q)``, ``row`` indexing the placements, ``q`` ``(M, 2)`` with the tip on the grasp."""
    placements = np.asarray(placements, float).reshape(-1, 3)
    grasps = world.object.grasps
    points = transform_points(placements, grasps)  # (B, G, 2)
    q = two_link_ik(world, points.reshape(-1, 2)).reshape(len(placements), len(grasps), -1, 2)
    found = ~np.isnan(q[..., 0])
    row, grasp, _ = np.nonzero(found)
    chosen = q[found]
    ok = clearly_valid(packed_world(world), np.ascontiguousarray(chosen), np.ascontiguousarray(placements[row]))
    return row[ok], grasp[ok], chosen[ok]


def goal_configurations(world: World, grasp_rel: np.ndarray, goal: np.ndarray) -> np.ndarray:
    """Configurations ``(B, K, 2)`` (NaN: none) that hold the object, carried as ``grasp_rel`` ``(B, 3)``,
    with its origin exactly on the goal and its orientation within the goal's tolerance."""
    grasp_rel = np.asarray(grasp_rel, float).reshape(-1, 3)
    l2 = float(world.robot.link_lengths[1])
    arm = np.stack([l2 + grasp_rel[:, 0], grasp_rel[:, 1]], axis=1)  # joint 2 to the object's origin
    goals = np.broadcast_to(goal[:2], (len(grasp_rel), 2))
    configurations = two_link_ik(
        world, goals, last=np.hypot(arm[:, 0], arm[:, 1]), offset=np.arctan2(arm[:, 1], arm[:, 0])
    )  # (B, K, 2)
    theta = configurations.sum(axis=2) + grasp_rel[:, 2:3]
    off = np.abs(wrap_angle(theta - goal[2])) > world.goal_angle_tolerance
    configurations[off] = np.nan
    return configurations


def goal_reached_many(world: World, poses: np.ndarray, goal: np.ndarray) -> np.ndarray:
    """Object poses ``(B, 3)`` within the goal tolerances, with 1e-9 to spare (as the validator measures)."""
    distance = np.hypot(poses[:, 0] - goal[0], poses[:, 1] - goal[1])
    angle = np.abs(wrap_angle(poses[:, 2] - goal[2]))
    reached: np.ndarray = (distance <= world.goal_tolerance - 1e-9) & (angle <= world.goal_angle_tolerance)
    return reached


# --------------------------------------------------------------------------- the search


@dataclass
class _Entry:
    """A grasp made: transfer ``depth`` (1 = the first) starts at ``start`` in ``mode``."""

    depth: int
    mode: Mode
    start: np.ndarray
    cost: float  # joint travel so far (rad)
    segments: list[PlanSegment]  # the plan up to ``start``


@dataclass
class _Expanded:
    """A transfer searched over the whole lattice: its releases, best estimate first."""

    entry: _Entry
    graph: Graph
    dist: np.ndarray
    pred: np.ndarray
    candidates: np.ndarray  # flat node numbers
    estimates: np.ndarray
    next: int = 0


@dataclass
class _Route:
    """A path found by a windowed or whole-lattice search: its cost and configurations."""

    cost: float
    waypoints: np.ndarray


def _l1(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    distance: np.ndarray = np.abs(np.asarray(a) - np.asarray(b)).sum(axis=-1)
    return distance


def plan_segment(kind: str, grasp: int | None, waypoints: np.ndarray) -> PlanSegment:
    keep = np.ones(len(waypoints), dtype=bool)
    keep[1:] = np.any(waypoints[1:] != waypoints[:-1], axis=1)  # repeated configurations
    return PlanSegment(kind, grasp, np.array(waypoints[keep]))


class _Search:
    def __init__(self, world: World, settings: ReferenceSettings) -> None:
        self.world = world
        self.settings = settings
        self.goal = np.asarray(world.object.goal, float)
        self.lattice = Lattice.for_world(world, settings.step_rad)
        self.nodes = self.lattice.nodes(self.lattice.full)
        self.tips = tip_poses(world.robot, self.nodes)
        self.heap: list[tuple[float, int, Any]] = []
        self.counter = itertools.count()
        self.best: tuple[float, list[PlanSegment]] | None = None
        self.expansions = 0
        self.releases = 0
        self.capped = False

    @property
    def best_cost(self) -> float:
        return math.inf if self.best is None else self.best[0]

    def push(self, priority: float, item: Any) -> None:
        if priority < self.best_cost:
            heapq.heappush(self.heap, (priority, next(self.counter), item))

    def run(self) -> None:
        self.start()
        while self.heap:
            priority, _, item = heapq.heappop(self.heap)
            if priority >= self.best_cost:
                break
            if isinstance(item, _Expanded):
                self.release(item)
            elif item.depth < self.settings.max_transfers and self.expansions < self.settings.max_expansions:
                self.expand(item)
            else:
                self.capped |= item.depth < self.settings.max_transfers
                self.finish(item)

    # -- the steps ---------------------------------------------------------------------------------

    def start(self) -> None:
        """The first transit: from the start configuration to every grasp of the object's start placement."""
        placement = np.asarray(self.world.object.initial, float)
        _, grasps, targets = grasp_configurations(self.world, placement[None])
        start = np.asarray(self.world.robot.initial, float)
        left = self.estimates(1, placement, targets)
        routes = self.windowed(Mode(placement), start=start, on_lattice=False, cost=0.0, targets=targets, left=left)
        for grasp, target, route in zip(grasps, targets, routes, strict=True):
            if route is not None:
                segments = [plan_segment("transit", None, route.waypoints)]
                self.enter(1, placement, int(grasp), target, cost=route.cost, segments=segments)

    def enter(
        self, depth: int, placement: np.ndarray, grasp: int, q: np.ndarray, *, cost: float, segments: list[PlanSegment]
    ) -> None:
        grasp_rel = relative(tip_poses(self.world.robot, q[None])[0], placement)  # as plan.replay computes it
        estimate = float(self.estimates(depth, placement, q[None])[0])
        if math.isfinite(estimate):
            self.push(cost + estimate, _Entry(depth, Mode(placement, grasp, grasp_rel), q, cost, segments))

    def estimates(self, depth: int, placements: np.ndarray, q: np.ndarray) -> np.ndarray:
        """Estimated joint travel left after grasping at ``q`` ``(M, 2)`` (object at ``placements``):
        for a last transfer the distance to the nearest exact goal configuration less the slack
        (``inf``: none), else 0."""
        if depth < self.settings.max_transfers or not len(q):
            return np.zeros(len(q))
        placements = np.broadcast_to(placements, (len(q), 3))
        grasp_rel = relative(tip_poses(self.world.robot, q), placements)
        goals = goal_configurations(self.world, grasp_rel, self.goal)  # (M, K, 2)
        distance = np.nanmin(np.where(np.isnan(goals[..., 0]), np.inf, _l1(goals, q[:, None, :])), axis=1)
        estimates: np.ndarray = np.maximum(0.0, distance - self.settings.goal_slack_rad)
        return estimates

    def goal_targets(self, mode: Mode) -> tuple[np.ndarray, np.ndarray]:
        """The goal of a transfer: lattice nodes (flat over the whole lattice) and exact configurations."""
        assert mode.grasp_rel is not None
        nodes = np.flatnonzero(goal_reached_many(self.world, compose(self.tips, mode.grasp_rel), self.goal))
        exact = goal_configurations(self.world, mode.grasp_rel, self.goal)[0]
        return nodes, exact[~np.isnan(exact[:, 0])]

    def expand(self, entry: _Entry) -> None:
        """A transfer that may regrasp again: the whole lattice; its best way to the goal, and its releases."""
        self.expansions += 1
        lattice = self.lattice
        graph = Graph.build(self.world, entry.mode, lattice, lattice.full)
        sources, travel = graph.join(self.world, entry.start, leaving=True)
        dist, pred = shortest_paths(graph, sources, entry.cost + travel)
        goal_nodes, exact = self.goal_targets(entry.mode)
        route = self.best_route(graph, dist=dist, pred=pred, start=entry.start, goal_nodes=goal_nodes, exact=exact)
        if route is not None:
            self.found(entry, route)
        stride = self.settings.release_stride
        index = np.arange(len(dist))
        sampled = ((index // lattice.shape[1]) % stride == 0) & ((index % lattice.shape[1]) % stride == 0)
        candidates = np.flatnonzero(sampled & np.isfinite(dist))
        assert entry.mode.grasp_rel is not None
        placements = compose(self.tips[candidates], entry.mode.grasp_rel)
        row, grasp, q = grasp_configurations(self.world, placements)
        keep = (grasp != entry.mode.grasp) | (_l1(q, self.nodes[candidates[row]]) > 0.1)  # not the same grasp again
        row, q = row[keep], q[keep]
        left = self.estimates(entry.depth + 1, placements[row], q)
        total = dist[candidates[row]] + _l1(q, self.nodes[candidates[row]]) + left
        best = np.full(len(candidates), np.inf)
        np.minimum.at(best, row, total)
        order = np.argsort(best, kind="stable")
        order = order[np.isfinite(best[order])]
        expanded = _Expanded(entry, graph, dist, pred, candidates[order], best[order])
        if len(order):
            self.push(float(expanded.estimates[0]), expanded)

    def release(self, expanded: _Expanded) -> None:
        """Put the object down at the expanded transfer's next release node, and grasp it again."""
        node = int(expanded.candidates[expanded.next])
        expanded.next += 1
        if self.releases >= self.settings.max_releases:
            self.capped = True
            return
        self.releases += 1
        if expanded.next < len(expanded.candidates):
            self.push(float(expanded.estimates[expanded.next]), expanded)
        entry = expanded.entry
        carried = np.concatenate([entry.start[None], trace(expanded.graph, expanded.pred, node)])
        cost = float(expanded.dist[node])
        q_release = carried[-1]
        assert entry.mode.grasp_rel is not None
        placement = compose(tip_poses(self.world.robot, q_release[None]), entry.mode.grasp_rel)[0]
        _, grasps, targets = grasp_configurations(self.world, placement[None])
        keep = (grasps != entry.mode.grasp) | (_l1(targets, q_release) > 0.1)
        grasps, targets = grasps[keep], targets[keep]
        left = self.estimates(entry.depth + 1, placement, targets)
        routes = self.windowed(Mode(placement), start=q_release, on_lattice=True, cost=cost, targets=targets, left=left)
        done = [*entry.segments, plan_segment("transfer", entry.mode.grasp, carried)]
        for grasp, target, route in zip(grasps, targets, routes, strict=True):
            if route is not None:
                segments = [*done, plan_segment("transit", None, route.waypoints)]
                self.enter(entry.depth + 1, placement, int(grasp), target, cost=route.cost, segments=segments)

    def finish(self, entry: _Entry) -> None:
        """A last transfer: its shortest way to the goal, in a window."""
        goal_nodes, exact = self.goal_targets(entry.mode)
        if not len(goal_nodes) and not len(exact):
            return
        route = self.windowed_goal(entry, goal_nodes, exact)
        if route is not None:
            self.found(entry, route)

    def found(self, entry: _Entry, route: _Route) -> None:
        if route.cost < self.best_cost:
            self.best = (route.cost, [*entry.segments, plan_segment("transfer", entry.mode.grasp, route.waypoints)])

    # -- searches on the lattice ------------------------------------------------------------------

    def best_route(
        self,
        graph: Graph,
        *,
        dist: np.ndarray,
        pred: np.ndarray,
        start: np.ndarray,
        goal_nodes: np.ndarray,
        exact: np.ndarray,
    ) -> _Route | None:
        """The cheapest way to a goal node (lattice indices over the whole lattice) or exact goal configuration."""
        best: _Route | None = None
        flat = np.zeros(0, dtype=np.int64)
        if len(goal_nodes):
            flat = graph.flat(np.stack(np.divmod(goal_nodes, self.lattice.shape[1]), axis=1))
            flat = flat[flat >= 0]
        if len(flat) and np.isfinite(dist[flat]).any():
            node = int(flat[np.argmin(dist[flat])])
            best = _Route(float(dist[node]), np.concatenate([start[None], trace(graph, pred, node)]))
        for point in exact:
            corners, travel = graph.join(self.world, point, leaving=False)
            if not len(corners):
                continue
            costs = dist[corners] + travel
            k = int(np.argmin(costs))
            if math.isfinite(costs[k]) and (best is None or costs[k] < best.cost):
                path = trace(graph, pred, int(corners[k]))
                best = _Route(float(costs[k]), np.concatenate([start[None], path, point[None]]))
        return best

    def windowed(
        self,
        mode: Mode,
        *,
        start: np.ndarray,
        on_lattice: bool,
        cost: float,
        targets: np.ndarray,
        left: np.ndarray,
    ) -> list[_Route | None]:
        """Shortest transit (or transfer) paths from ``start`` to each of ``targets`` ``(T, 2)``, in a window
        around them grown until no path leaving it could be shorter, or could matter (``left``: each
        target's estimated travel after it, against the best plan so far)."""
        margin = self.settings.window_rad
        while True:
            box = self.lattice.box_around(np.concatenate([start[None], targets]), margin)
            graph = Graph.build(self.world, mode, self.lattice, box)
            dist, pred = self.sources(graph, start, on_lattice, cost)
            routes: list[_Route | None] = []
            pending = False
            for target, after in zip(targets, left, strict=True):
                corners, travel = graph.join(self.world, target, leaving=False)
                costs = dist[corners] + travel if len(corners) else np.array([np.inf])
                k = int(np.argmin(costs))
                if math.isfinite(costs[k]):
                    path = trace(graph, pred, int(corners[k]))
                    routes.append(_Route(float(costs[k]), self.joined(start, on_lattice, path, target)))
                else:
                    routes.append(None)
                leaving = (
                    cost + float(_l1(start, target)) + 2.0 * box.exit_margin(self.lattice, np.stack([start, target]))
                )
                if costs[k] > leaving + 1e-9 and leaving + after < self.best_cost:
                    pending = True
            if not pending or box == self.lattice.full:
                return routes
            margin *= 2.0

    def windowed_goal(self, entry: _Entry, goal_nodes: np.ndarray, exact: np.ndarray) -> _Route | None:
        """:meth:`windowed` for a last transfer: to the goal's lattice nodes and exact configurations."""
        goal_points = np.concatenate([self.nodes[goal_nodes], exact]).reshape(-1, 2)
        nearest = float(np.min(_l1(goal_points, entry.start)))
        margin = self.settings.window_rad
        while True:
            box = self.lattice.box_around(np.concatenate([entry.start[None], goal_points]), margin)
            graph = Graph.build(self.world, entry.mode, self.lattice, box)
            dist, pred = self.sources(graph, entry.start, False, entry.cost)
            route = self.best_route(graph, dist=dist, pred=pred, start=entry.start, goal_nodes=goal_nodes, exact=exact)
            found = math.inf if route is None else route.cost
            everything = np.concatenate([entry.start[None], goal_points])
            leaving = entry.cost + nearest + 2.0 * box.exit_margin(self.lattice, everything)
            if found <= leaving + 1e-9 or leaving >= self.best_cost or box == self.lattice.full:
                return route
            margin *= 2.0

    def sources(self, graph: Graph, start: np.ndarray, on_lattice: bool, cost: float) -> tuple[np.ndarray, np.ndarray]:
        if on_lattice:
            index = np.round([(start[k] - self.lattice.axes[k][0]) / self.lattice.step_rad for k in range(2)]).astype(
                np.int64
            )
            return shortest_paths(graph, graph.flat(index[None]), np.array([cost]))
        corners, travel = graph.join(self.world, start, leaving=True)
        return shortest_paths(graph, corners, cost + travel)

    @staticmethod
    def joined(start: np.ndarray, on_lattice: bool, path: np.ndarray, target: np.ndarray) -> np.ndarray:
        return np.concatenate([path if on_lattice else np.concatenate([start[None], path]), target[None]])


def succeeded_plan(
    world: World, segments: tuple[PlanSegment, ...], message: str, stats: dict[str, Any] | None = None
) -> Plan:
    """A succeeded plan of ``segments`` in ``world``, its final object pose where replaying them puts it."""
    probe = Plan(world.name, tuple(world.robot.joint_names), True, "", segments=segments)
    final = list(replay(world, probe, None))[-1].object_poses[-1]
    return Plan(
        world.name,
        tuple(world.robot.joint_names),
        True,
        message,
        "SUCCEEDED",
        segments,
        np.array(final),
        stats=stats or {},
    )


def reference_plan(world: World, settings: ReferenceSettings | None = None) -> ReferenceResult:
    """The grid reference plan of a 2-joint ``world`` (module docstring), validated.

    Raises ``ValueError`` for a world whose arm does not have 2 joints.
    """
    settings = settings or ReferenceSettings()
    started = time.perf_counter()
    search = _Search(world, settings)
    search.run()
    elapsed = time.perf_counter() - started
    if search.best is None:
        return ReferenceResult(
            world.name, None, math.inf, 0, [], search.expansions, search.releases, search.capped, elapsed, settings
        )
    segments = tuple(search.best[1])
    travel = float(sum(np.abs(np.diff(s.waypoints, axis=0)).sum() for s in segments))
    transfers = sum(s.kind == "transfer" for s in segments)
    plan = succeeded_plan(
        world,
        segments,
        f"grid reference: joint travel {travel:.3f} rad, {transfers} transfer(s), step {settings.step_rad} rad",
        {"joint_travel_rad": round(travel, 6), "transfers": transfers, "time_s": round(elapsed, 3)},
    )
    problems = validate_plan(world, plan)
    return ReferenceResult(
        world.name,
        plan,
        travel,
        transfers,
        problems,
        search.expansions,
        search.releases,
        search.capped,
        elapsed,
        settings,
    )


# --------------------------------------------------------------------------- the report


def load_worlds(names: list[str]) -> list[tuple[World, dict[str, Any]]]:
    """Worlds by benchmark name (:mod:`benchmarks.worlds`) or parameter file path, with their parameters."""
    from benchmarks.worlds import all_worlds, select
    from clew_ros.planar.world import read_parameter_file, world_from_parameters

    worlds = []
    known = None
    for name in names:
        if name.endswith((".yaml", ".yml")) or Path(name).exists():
            parameters = read_parameter_file(name)
        else:
            known = known if known is not None else all_worlds()
            matches = select(known, name) or _generated(name)
            if not matches:
                raise ValueError(f"--worlds: no benchmark world named {name!r} (give a name or a YAML file)")
            parameters = matches[0].parameters
        worlds.append((check_start_and_goal(world_from_parameters(parameters)), parameters))
    return worlds


def _generated(name: str) -> list[Any]:
    """``joints_N`` or ``obstacles_M`` for any ``N`` >= 2 or ``M`` >= 2 (:mod:`benchmarks.worlds` lists a few):
    figure1's task with ``N`` joints, or joints_3 with ``M`` obstacles in all; or ``FAMILY_S``, world ``S`` of a
    :mod:`clew_ros.worlds` family, as ``clew_world FAMILY --seed S`` writes it (shapes2_60, arm7_62, ...)."""
    from benchmarks.worlds import joints_world, obstacles_world
    from clew_ros.worlds import FAMILIES, generate

    family, _, count = name.rpartition("_")
    if not count.isdigit():
        return []
    if family in FAMILIES:
        return [generate(family, int(count))]
    if int(count) < 2:
        return []
    make = {"joints": joints_world, "obstacles": obstacles_world}.get(family)
    return [] if make is None else [make(int(count))]


@dataclass
class PlannerRuns:
    """The planner's runs on one world: per successful seed, travel and transfers (improved and first)."""

    seeds: int
    travel: list[float]
    transfers: list[int]
    first_travel: list[float]
    first_transfers: list[int]
    invalid: int


def planner_runs(world: World, parameters: dict[str, Any], seeds: int, **overrides: Any) -> PlannerRuns:
    """Plan ``world`` with seeds ``0..seeds-1`` exactly as ``clew_plan WORLD --seed S`` does."""
    from clew_ros.core.settings import PlannerSettings, Termination
    from clew_ros.planar.plan import checked_plan
    from clew_ros.planar.space import plan

    runs = PlannerRuns(seeds, [], [], [], [], 0)
    for seed in range(seeds):
        settings = PlannerSettings.from_parameters(parameters, seed=seed, **overrides)
        result = plan(world, settings, termination=Termination(settings.time_limit))
        checked = checked_plan(world, result)
        if result.success and not checked.success:
            runs.invalid += 1
        if not checked.success:
            continue
        stats = checked.stats
        runs.travel.append(float(stats["joint_travel_rad"]))
        runs.transfers.append(int(stats["transfers"]))
        runs.first_travel.append(float(stats["first_joint_travel_rad"]))
        runs.first_transfers.append(int(stats["first_transfers"]))
    return runs


HEADER = (
    "| world | reference rad (transfers) | reference s | found | travel rad, median (first plan) "
    "| ratio to reference | transfers <= ref + 1 | gain over first plan |\n|---|---|---|---|---|---|---|---|"
)


def report_row(reference: ReferenceResult, runs: PlannerRuns) -> str:
    """One Markdown row: the reference next to the planner's runs."""
    ref = f"{reference.travel:.2f} ({reference.transfers})" if reference.plan is not None else "none"
    if reference.problems:
        ref += " INVALID"
    if reference.capped:
        ref += " capped"
    found = f"{len(runs.travel)}/{runs.seeds}" + (f", {runs.invalid} invalid" if runs.invalid else "")
    if not runs.travel:
        return f"| {reference.world} | {ref} | {reference.time_s:.1f} | {found} | | | | |"
    median, first = statistics.median(runs.travel), statistics.median(runs.first_travel)
    ratio = f"{median / reference.travel:.2f}x" if reference.plan is not None else ""
    within = (
        f"{sum(t <= reference.transfers + 1 for t in runs.transfers) / len(runs.transfers):.0%}"
        if reference.plan is not None
        else ""
    )
    return (
        f"| {reference.world} | {ref} | {reference.time_s:.1f} | {found} | {median:.2f} ({first:.2f}) | {ratio} "
        f"| {within} | {first / median:.2f}x |"
    )


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m benchmarks.reference", description=__doc__.split("\n\n")[0])
    parser.add_argument(
        "--worlds",
        nargs="+",
        default=list(DEFAULT_WORLDS),
        help=f"benchmark world names or YAML parameter files (default {' '.join(DEFAULT_WORLDS)})",
    )
    parser.add_argument("--seeds", type=int, default=10, help="planner seeds 0..N-1 per world (default 10; 0: none)")
    parser.add_argument("--step", type=float, default=ReferenceSettings.step_rad, help="lattice step (rad)")
    parser.add_argument("--max-transfers", type=int, default=ReferenceSettings.max_transfers)
    parser.add_argument("--time-limit", type=float, default=None, help="overrides planner.time_limit (s)")
    parser.add_argument("--improve-time", type=float, default=None, help="overrides planner.improve_time (s)")
    parser.add_argument("--plans", type=Path, default=None, help="write each reference plan here as WORLD.json")
    args = parser.parse_args(argv)
    if args.step <= 0 or args.max_transfers < 1 or args.seeds < 0:
        print("benchmarks.reference: --step > 0, --max-transfers >= 1 and --seeds >= 0 expected", file=sys.stderr)
        return 2
    try:
        worlds = load_worlds(args.worlds)
    except (ValueError, OSError) as error:
        print(f"benchmarks.reference: {error}", file=sys.stderr)
        return 2
    from clew_ros.planar.kernel import warm_up

    warm_up()
    settings = ReferenceSettings(step_rad=args.step, max_transfers=args.max_transfers)
    print(HEADER, flush=True)
    for world, parameters in worlds:
        if world.robot.dof != 2:
            print(f"| {world.name} | not a 2-joint world | | | | | | |", flush=True)
            continue
        reference = reference_plan(world, settings)
        if args.plans is not None and reference.plan is not None:
            reference.plan.write(args.plans / f"{world.name}.json")
        runs = planner_runs(world, parameters, args.seeds, time_limit=args.time_limit, improve_time=args.improve_time)
        print(report_row(reference, runs), flush=True)
        for problem in reference.problems[:3]:
            print(f"  reference plan of {world.name}: {problem}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
