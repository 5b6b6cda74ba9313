"""The joint-space lattice (issue 14, plan quality): its compiled A* is a shortest-path search, its routes
join their ends, are valid at any step and are the shortest on the lattice, and the improvement's routing
around blocked moves uses them only to shorten RRT-Connect's paths."""

from __future__ import annotations

import heapq
import itertools
import math

import numpy as np
import pytest
from helpers.random_boxes import random_box_world

from clew_ros.core.settings import PlannerSettings, Termination
from clew_ros.core.space import PlanningContext
from clew_ros.planar.collision import is_valid
from clew_ros.planar.continuous import straight_moves_clear
from clew_ros.planar.improve import ImproveSettings, _Improver, _Piece, joint_travel
from clew_ros.planar.kernel import (
    EDGE_BLOCKED,
    EDGE_CLEAR,
    EDGE_UNKNOWN,
    lattice_costs,
    lattice_repair,
    lattice_search,
    release_totals,
)
from clew_ros.planar.kinematics import compose, relative, tip_poses, wrap_angle
from clew_ros.planar.lattice import (
    KnownNodes,
    LatticeSettings,
    LatticeWork,
    _edges_clear,
    _joins,
    _Lattice,
    grasp_configurations,
    lattice_regrasp,
    lattice_route,
    lattice_step,
    pose_configurations,
)
from clew_ros.planar.space import PlanarSpace

FINE_RAD = 2e-4  # ten times finer than the validator
GRASP_REL = np.array([0.02, 0.0, 0.3])


def _dijkstra(counts, step, edges, sources, source_costs, targets, target_costs) -> float:
    """The reference: Dijkstra over the same lattice, without a heuristic."""
    done = _distances(counts, step, edges, sources, source_costs)
    return min((done.get(int(t), math.inf) + c for t, c in zip(targets, target_costs, strict=True)), default=math.inf)


def _distances(counts, step, edges, sources, source_costs) -> dict[int, float]:
    """Each node's least cost from the sources, over edges not blocked (those reached)."""
    strides = np.cumprod(np.r_[counts[1:], 1][::-1])[::-1]
    best = {int(s): float(c) for s, c in zip(sources, source_costs, strict=True)}
    heap = [(c, s) for s, c in best.items()]
    heapq.heapify(heap)
    done: dict[int, float] = {}
    while heap:
        cost, u = heapq.heappop(heap)
        if u in done:
            continue
        done[u] = cost
        k = [(u // int(s)) % int(c) for s, c in zip(strides, counts, strict=True)]
        for j, stride in enumerate(strides.tolist()):
            for v, ok in ((u + stride, k[j] + 1 < counts[j]), (u - stride, k[j] > 0)):
                if not ok or edges[min(u, v), j] == EDGE_BLOCKED:
                    continue
                if cost + step < best.get(v, math.inf):
                    best[v] = cost + step
                    heapq.heappush(heap, (cost + step, v))
    return done


def _tree_edge(counts: np.ndarray, u: int, v: int) -> tuple[int, int]:
    """The edge (lower node, joint) between neighbours ``u`` and ``v``."""
    strides = np.cumprod(np.r_[counts[1:], 1][::-1])[::-1]
    return min(u, v), int(np.flatnonzero(strides == abs(u - v))[0])


def _random_lattice(rng: np.random.Generator, dims: int, high: int, blocked: float, count: int, dearest: float):
    """A lattice of ``dims`` joints of 3 to ``high - 1`` values each, each edge blocked with probability ``blocked``,
    and ``count`` sources at costs up to ``dearest``: counts, edges, sources, their costs."""
    counts = rng.integers(3, high, dims).astype(np.int64)
    size = int(np.prod(counts))
    edges = np.where(rng.random((size, dims)) < blocked, EDGE_BLOCKED, EDGE_UNKNOWN).astype(np.uint8)
    return counts, edges, rng.choice(size, count, replace=False), rng.uniform(0, dearest, count)


@pytest.mark.parametrize("dims", [2, 3])
def test_the_compiled_lattice_costs_are_each_node_s_least_cost_and_lead_back_to_a_source(dims) -> None:
    rng = np.random.default_rng(10 + dims)
    step = 0.25
    for trial in range(20):
        counts, edges, sources, source_costs = _random_lattice(rng, dims, 8, 0.35, 2, 0.2)
        size = int(np.prod(counts))
        bound = math.inf if trial % 2 else 1.0
        cost, previous, expanded = lattice_costs(counts, step, edges, sources, source_costs, bound)
        expected = np.full(size, np.inf)
        for node, c in _distances(counts, step, edges, sources, source_costs).items():
            expected[node] = c if c < bound else np.inf
        assert np.allclose(cost, expected, rtol=0, atol=1e-9, equal_nan=False)
        assert expanded == np.count_nonzero(np.isfinite(cost))
        for reached in np.flatnonzero(np.isfinite(cost)).tolist():  # back to a source, one edge a step
            node = reached
            while previous[node] >= 0:
                u, node = node, int(previous[node])
                assert edges[_tree_edge(counts, u, node)] != EDGE_BLOCKED
            assert node in sources.tolist()
        for node in np.flatnonzero(np.isfinite(cost)).tolist():
            assert previous[node] < 0 or cost[node] == pytest.approx(cost[previous[node]] + step, abs=1e-9)


@pytest.mark.parametrize("dims", [2, 3])
def test_the_repaired_lattice_costs_are_those_of_a_search_from_scratch_after_edges_are_blocked(dims) -> None:
    rng = np.random.default_rng(30 + dims)
    step = 0.25
    for trial in range(20):
        # a source may be reached cheaper through another
        counts, edges, sources, source_costs = _random_lattice(rng, dims, 9, 0.15, 3, 0.6)
        size = int(np.prod(counts))
        bound = math.inf if trial % 2 else 1.5
        cost, previous, _ = lattice_costs(counts, step, edges, sources, source_costs, bound)
        for _ in range(4):  # block edges of the search's tree (those that change costs) and one at random
            taken = np.flatnonzero(previous >= 0).tolist()
            for v in rng.choice(taken, min(3, len(taken)), replace=False).tolist() if taken else []:
                edges[_tree_edge(counts, v, int(previous[v]))] = EDGE_BLOCKED
            edges[int(rng.integers(size)), int(rng.integers(dims))] = EDGE_BLOCKED
            lattice_repair(counts, step, edges, sources, source_costs, bound, cost, previous)
            fresh, _, _ = lattice_costs(counts, step, edges, sources, source_costs, bound)
            assert np.array_equal(np.isfinite(cost), np.isfinite(fresh))
            assert np.allclose(cost[np.isfinite(cost)], fresh[np.isfinite(fresh)], rtol=0, atol=1e-9)
            for node in np.flatnonzero(previous >= 0).tolist():  # each step back: a clear edge, one step less
                assert edges[_tree_edge(counts, node, int(previous[node]))] != EDGE_BLOCKED
                assert cost[node] == pytest.approx(cost[previous[node]] + step, abs=1e-9)
            for node in np.flatnonzero(np.isfinite(cost) & (previous < 0)).tolist():  # the rest: at a source's cost
                assert node in sources.tolist()
                assert cost[node] == pytest.approx(float(source_costs[sources.tolist().index(node)]), abs=1e-12)


def test_release_totals_add_the_first_cost_the_put_down_and_the_cheapest_corner_on() -> None:
    rng = np.random.default_rng(4)
    size, count, corners_per = 50, 12, 8
    first_cost, last_cost = rng.uniform(0, 3, size), rng.uniform(0, 3, size)
    last_cost[rng.random(size) < 0.3] = np.inf
    releases = rng.choice(size, count, replace=False)
    put = rng.uniform(0, 1, (2, count))
    corners = rng.integers(0, size, (2, count, corners_per))
    join = rng.uniform(0, 0.5, (2, count, corners_per))
    totals, joined = release_totals(first_cost, last_cost, releases, put, corners, join)
    for e, r in itertools.product(range(2), range(count)):
        via = [last_cost[corners[e, r, c]] + join[e, r, c] for c in range(corners_per)]
        assert totals[e, r] == pytest.approx(first_cost[releases[r]] + put[e, r] + min(via))
        if np.isfinite(min(via)):
            assert joined[e, r] == corners[e, r, int(np.argmin(via))]


def test_pose_configurations_put_the_tip_at_the_frame_and_one_is_the_configuration_it_came_from() -> None:
    world, rng = random_box_world(5, 3, 0.02)
    robot = world.robot
    q = rng.uniform(robot.joint_lower, robot.joint_upper, (500, 3))
    tips = tip_poses(robot, q)
    near = q + rng.normal(0.0, 0.2, q.shape)
    solved, ok = pose_configurations(robot, tips, near)
    assert ok.any(axis=0).all()  # a frame the arm reaches: one elbow at least
    for side in range(2):
        got = tip_poses(robot, solved[side][ok[side]])
        assert np.abs(got[:, :2] - tips[ok[side], :2]).max() < 1e-9
        assert np.abs(wrap_angle(got[:, 2] - tips[ok[side], 2])).max() < 1e-9
        inside = (solved[side] >= robot.joint_lower) & (solved[side] <= robot.joint_upper)
        assert np.array_equal(ok[side], inside.all(axis=1) & ok[side])
    nearest = np.minimum(np.abs(solved[0] - q).sum(axis=1), np.abs(solved[1] - q).sum(axis=1))
    assert nearest.max() < 1e-9
    far = np.array([[5.0, 0.0, 0.0]])  # out of reach: no configuration
    assert not pose_configurations(robot, far, np.zeros((1, 3)))[1].any()


def test_grasp_configurations_hold_each_grasp_point_at_every_approach_within_the_limits() -> None:
    world, rng = random_box_world(5, 3, 0.02)
    robot = world.robot
    pose = np.asarray(world.object.initial, dtype=float)
    near = rng.uniform(robot.joint_lower, robot.joint_upper)
    q, which, rels = grasp_configurations(world, pose, near, 12)
    assert len(q)
    assert set(which.tolist()) <= set(range(len(world.object.grasps)))
    assert np.all((q >= robot.joint_lower) & (q <= robot.joint_upper))
    tips = tip_poses(robot, q)
    points = compose(pose, np.c_[world.object.grasps[which], np.zeros(len(which))])[:, :2]
    assert np.abs(tips[:, :2] - points).max() < 1e-9  # the tip on the grasp point it names
    held = compose(tips, rels)  # the object where it rests, held as each one's relative pose says
    assert np.abs(held[:, :2] - pose[:2]).max() < 1e-9
    assert np.abs(wrap_angle(held[:, 2] - pose[2])).max() < 1e-9
    approach = np.round(wrap_angle(tips[:, 2] - pose[2]) / (2 * np.pi / 12)) % 12
    assert len({(int(g), int(a)) for g, a in zip(which, approach, strict=True)}) > len(world.object.grasps)


@pytest.mark.parametrize("dims", [2, 3])
def test_the_compiled_lattice_search_finds_the_shortest_path_through_edges_that_are_not_blocked(dims) -> None:
    rng = np.random.default_rng(dims)
    step = 0.25
    for trial in range(30):
        counts = rng.integers(3, 9, dims).astype(np.int64)
        size = int(np.prod(counts))
        edges = np.where(rng.random((size, dims)) < 0.35, EDGE_BLOCKED, EDGE_UNKNOWN).astype(np.uint8)
        sources, targets = rng.choice(size, 2, replace=False), rng.choice(size, 3, replace=False)
        # as lattice_route calls it: the true end ``goal`` near the targets, each target's cost at least its
        # joint travel to it (the heuristic, the joint travel left to ``goal``, stays admissible)
        goal = rng.uniform(0.0, 1.0, dims) * (counts - 1) * step
        at = np.stack(np.unravel_index(targets, tuple(counts)), axis=1) * step
        source_costs, target_costs = rng.uniform(0, 0.2, 2), np.abs(at - goal).sum(axis=1) + rng.uniform(0, 0.1, 3)
        bound = math.inf if trial % 3 else 2.0
        path, cost, _ = lattice_search(
            counts, np.zeros(dims), step, edges, sources, source_costs, targets, target_costs, goal, bound
        )
        expected = _dijkstra(counts, step, edges, sources, source_costs, targets, target_costs)
        if expected >= bound:
            assert len(path) == 0
            assert cost == math.inf
            continue
        assert cost == pytest.approx(expected, abs=1e-9)
        start, end = int(np.flatnonzero(sources == path[0])[0]), int(np.flatnonzero(targets == path[-1])[0])
        assert cost == pytest.approx(source_costs[start] + step * (len(path) - 1) + target_costs[end], abs=1e-9)
        strides = np.cumprod(np.r_[counts[1:], 1][::-1])[::-1]
        for u, v in itertools.pairwise(path.tolist()):
            j = int(np.flatnonzero(strides == abs(v - u))[0])
            assert edges[min(u, v), j] != EDGE_BLOCKED


class _Counter:
    """A budget that only counts (``lattice_route``'s protocol)."""

    check_work = 1.0

    def __init__(self) -> None:
        self.spent = 0

    def spend(self, units: int) -> None:
        self.spent += units

    def spend_move_checks(self, configurations: int) -> None:
        self.spent += configurations

    def spend_checks(self, configurations: int, calls: int = 1) -> None:
        self.spent += configurations + calls

    def stop(self) -> bool:
        return False


def _route(world, a, b, transfer, shorter_than, budget=None, known=None, allowance=1e9, expansion_work=0.2):
    return lattice_route(
        world,
        a,
        b,
        object_pose=np.asarray(world.object.initial, dtype=float),
        grasp_rel=GRASP_REL if transfer else None,
        min_margin=5e-4,
        shorter_than=shorter_than,
        work=LatticeWork(budget or _Counter(), allowance, expansion_work),
        nodes_known=known,
    )


def _valid_at_a_fine_step(world, path, transfer) -> bool:
    rest = np.asarray(world.object.initial, dtype=float)
    for u, v in itertools.pairwise(path):
        steps = max(1, int(np.ceil(np.max(np.abs(v - u)) / FINE_RAD)))
        fine = u + np.linspace(0.0, 1.0, steps + 1)[:, None] * (v - u)
        poses = compose(tip_poses(world.robot, fine), GRASP_REL) if transfer else rest
        if not is_valid(world, fine, poses).all():
            return False
    return True


def _blocked_pairs(world, rng, transfer, count):
    """Pairs of valid configurations whose straight move is blocked."""
    joints = world.robot.dof
    rest = np.asarray(world.object.initial, dtype=float)
    q = rng.uniform(-2.8, 2.8, (400, joints))
    poses = compose(tip_poses(world.robot, q), GRASP_REL) if transfer else rest
    q = q[is_valid(world, q, poses)]
    pairs = []
    for a, b in zip(q[0::2], q[1::2], strict=False):
        if not _valid_at_a_fine_step(world, [a, b], transfer):
            pairs.append((a, b))
        if len(pairs) == count:
            break
    return pairs


@pytest.mark.parametrize(("seed", "joints", "width"), [(1, 2, 0.0), (2, 3, 0.04), (3, 3, 0.02)])
def test_lattice_routes_join_their_ends_are_valid_at_a_fine_step_and_are_the_lattice_s_shortest(
    seed, joints, width
) -> None:
    world, rng = random_box_world(seed, joints, width)
    routed = 0
    for a, b in _blocked_pairs(world, rng, transfer=False, count=6):
        first, second = _Counter(), _Counter()
        known = KnownNodes()
        path = _route(world, a, b, False, 40.0, first, known)
        if path is None:
            continue
        routed += 1
        assert np.array_equal(path[0], a)
        assert np.array_equal(path[-1], b)
        assert joint_travel([path]) < 40.0
        assert _valid_at_a_fine_step(world, path, False)
        # the nodes checked before are not checked again: the same route for less work
        again = _route(world, a, b, False, 40.0, second, known)
        assert again is not None
        assert np.array_equal(again, path)
        assert second.spent < first.spent
        # the shortest on the lattice: none shorter than it
        assert _route(world, a, b, False, joint_travel([path]) - 1e-9) is None
    assert routed >= 2


@pytest.mark.parametrize(("seed", "joints"), [(2, 2), (3, 3)])
def test_lattice_routes_carrying_the_object_are_valid_with_it(seed, joints) -> None:
    world, rng = random_box_world(seed, joints, 0.03)
    routed = 0
    for a, b in _blocked_pairs(world, rng, transfer=True, count=5):
        path = _route(world, a, b, True, 40.0)
        if path is None:
            continue
        routed += 1
        assert np.array_equal(path[0], a)
        assert np.array_equal(path[-1], b)
        assert _valid_at_a_fine_step(world, path, True)
    assert routed >= 1


def test_no_lattice_for_many_joints_or_a_bound_below_the_straight_move() -> None:
    world, _ = random_box_world(4, LatticeSettings().max_joints + 1, 0.02)
    assert lattice_step(world) is None
    a, b = np.zeros(LatticeSettings().max_joints + 1), np.full(LatticeSettings().max_joints + 1, 0.5)
    assert _route(world, a, b, False, 40.0) is None
    assert lattice_step(world, LatticeSettings(max_joints=4)) is not None  # a copy of the settings decides
    small, _ = random_box_world(4, 2, 0.02)
    step = lattice_step(small)
    assert step is not None
    assert step > 0
    coarser = lattice_step(small, LatticeSettings(max_nodes=100, min_step_rad=0.0))
    assert coarser is not None
    assert coarser > step  # fewer cells in the same limits
    assert _route(small, np.zeros(2), np.full(2, 0.5), False, 1.0) is None  # 1.0 rad is the straight move's travel


def test_a_routing_stops_within_its_allowance(monkeypatch) -> None:
    """Nothing is checked when the nodes alone would not fit; a routing whose nodes fit but whose first search
    spends the rest stops right after it (no edge checked, no second search) and finds nothing."""
    calls = {"searches": 0, "edge checks": 0}

    def counted(name, function):
        def call(*args, **kwargs):
            calls[name] += 1
            return function(*args, **kwargs)

        return call

    monkeypatch.setattr("clew_ros.planar.lattice.lattice_search", counted("searches", lattice_search))
    monkeypatch.setattr("clew_ros.planar.lattice._edges_clear", counted("edge checks", _edges_clear))
    world, rng = random_box_world(2, 3, 0.04)
    tried = 0
    for a, b in _blocked_pairs(world, rng, transfer=False, count=4):
        counter = _Counter()
        assert _route(world, a, b, False, 40.0, counter, allowance=50.0) is None
        assert counter.spent == 0  # checking the nodes would not fit: nothing checked
        calls.update({"searches": 0, "edge checks": 0})
        if _route(world, a, b, False, 40.0) is None:
            continue
        assert calls["searches"] >= 1  # the premise: the whole routing searches, then checks edges
        assert calls["edge checks"] >= 1
        nodes = len(_Lattice(world, lattice_step(world)).inside(a, b, 40.0))
        calls.update({"searches": 0, "edge checks": 0})
        part = _Counter()
        allowance = (
            1.01 * nodes / LatticeSettings().node_share
        )  # the nodes fit; any search (1e6 units a node) spends the rest
        assert _route(world, a, b, False, 40.0, part, allowance=allowance, expansion_work=1e6) is None
        assert calls == {"searches": 1, "edge checks": 0}
        assert part.spent >= 1e6
        tried += 1
    assert tried >= 1


def test_a_lattice_route_is_as_short_as_dijkstra_over_every_node_and_edge_checked() -> None:
    """The lazy checks lose nothing: the route is as short as the shortest path over the ellipse with every
    node and edge checked first (the same joins of the ends)."""
    world, rng = random_box_world(1, 2, 0.0)
    rest = np.asarray(world.object.initial, dtype=float)
    lattice = _Lattice(world, lattice_step(world))
    compared = 0

    def clear(starts: np.ndarray, ends: np.ndarray) -> np.ndarray:
        return straight_moves_clear(world, starts, ends, object_pose=rest, grasp_rel=None, min_margin=5e-4)

    for a, b in _blocked_pairs(world, rng, transfer=False, count=4):
        path = _route(world, a, b, False, 12.0)
        if path is None:
            continue
        nodes = lattice.inside(a, b, 12.0)
        q = lattice.configurations(lattice.indices(nodes))
        valid = np.zeros(lattice.size, dtype=bool)
        valid[nodes[clear(q, q)]] = True
        edges = np.full((lattice.size, 2), EDGE_BLOCKED, dtype=np.uint8)
        index = lattice.indices(nodes)
        for j, stride in enumerate(lattice.strides.tolist()):
            up = nodes[(index[:, j] + 1 < lattice.counts[j]) & valid[nodes]]
            up = up[valid[up + stride]]
            low = lattice.configurations(lattice.indices(up))
            ok = clear(low, lattice.configurations(lattice.indices(up + stride)))
            edges[up[ok], j] = EDGE_CLEAR
        joins = _joins(lattice, nodes[valid[nodes]], a, b, clear)
        assert joins is not None
        expected = _dijkstra(lattice.counts, lattice.step, edges, *joins)
        assert joint_travel([path]) == pytest.approx(expected, abs=1e-9)
        compared += 1
    assert compared >= 2


def test_a_routed_move_is_the_lattice_s_when_shorter_than_rrt_connect_s_and_within_the_bound() -> None:
    """``_Improver.connect`` on an arm with a lattice: the path joins the move's ends, is valid at a fine step,
    is never longer than RRT-Connect's path alone (the same generator), is shorter on some moves, and is
    RRT-Connect's when no lattice path is shorter than ``longest``."""
    world, rng = random_box_world(2, 3, 0.04)
    rest = np.asarray(world.object.initial, dtype=float)
    shorter = 0
    for trial, (a, b) in enumerate(_blocked_pairs(world, rng, transfer=False, count=8)):
        piece = _Piece("transit", None, np.array([a, b]), rest, None)

        def routed(
            longest: float = math.inf, lattice: bool = True, seed: int = trial, piece=piece, a=a, b=b
        ) -> np.ndarray | None:
            tuning = ImproveSettings(lattice=LatticeSettings(max_joints=0 if not lattice else 3))  # 0: no lattice
            settings = PlannerSettings(seed=seed, improve_time=5.0)
            ctx = PlanningContext(PlanarSpace(world), settings, np.random.default_rng([seed, 1]), Termination(30))
            return _Improver(world, ctx, [piece], world.object.goal, tuning).connect(piece, a, b, longest)

        alone, path = routed(lattice=False), routed()
        if alone is None:
            continue
        assert path is not None
        assert np.array_equal(path[0], a)
        assert np.array_equal(path[-1], b)
        assert _valid_at_a_fine_step(world, path, False)
        assert joint_travel([path]) <= joint_travel([alone]) + 1e-12
        if joint_travel([path]) < joint_travel([alone]) - 1e-9:
            shorter += 1
            # the proposal's bound: none shorter than the lattice's own path, so RRT-Connect's comes back
            assert np.array_equal(routed(longest=joint_travel([path])), alone)
    assert shorter >= 2


OTHER_REL = np.array([0.02, 0.0, -1.4])  # a second grasp: another angle between the tip and the object


def _regrasp(world, a, b, *, budget=None, shorter_than=40.0, allowance=1e9):
    """lattice_regrasp from ``a`` holding the object as GRASP_REL to ``b`` holding it as OTHER_REL."""
    return lattice_regrasp(
        world,
        a,
        GRASP_REL,
        b,
        OTHER_REL,
        min_margin=5e-4,
        shorter_than=shorter_than,
        work=LatticeWork(budget or _Counter(), allowance, expansion_work=0.2, release_work=0.1),
        screen_step_rad=0.1,
    )


def _valid_held_at_a_fine_step(world, path, grasp_rel=None, resting=None) -> bool:
    for u, v in itertools.pairwise(path):
        steps = max(1, int(np.ceil(np.max(np.abs(v - u)) / FINE_RAD)))
        fine = u + np.linspace(0.0, 1.0, steps + 1)[:, None] * (v - u)
        poses = compose(tip_poses(world.robot, fine), grasp_rel) if grasp_rel is not None else resting
        if not is_valid(world, fine, poses).all():
            return False
    return True


@pytest.mark.parametrize("seed", [6, 7, 8])
def test_a_lattice_regrasp_puts_the_object_down_once_holds_it_as_asked_and_is_valid_at_a_fine_step(seed) -> None:
    world, rng = random_box_world(seed, 3, 0.02)
    q = rng.uniform(-2.8, 2.8, (600, 3))
    firsts = q[is_valid(world, q, compose(tip_poses(world.robot, q), GRASP_REL))]
    lasts = q[is_valid(world, q, compose(tip_poses(world.robot, q), OTHER_REL))]
    found = 0
    for a, b in zip(firsts[:6], lasts[:6], strict=False):
        ways = _regrasp(world, a, b)
        if ways is None:
            continue
        found += 1
        carried, put_down, held = ways
        assert np.array_equal(carried[0], a)
        assert np.array_equal(held[-1], b)
        assert np.array_equal(carried[-1], put_down[0])
        assert np.array_equal(put_down[-1], held[0])
        assert joint_travel([carried, put_down, held]) < 40.0
        # the object stays where the first grasp put it down, and the second holds it there as asked
        resting = compose(tip_poses(world.robot, carried[-1:]), GRASP_REL)[0]
        assert np.allclose(relative(tip_poses(world.robot, held[:1])[0], resting), OTHER_REL, atol=1e-9)
        assert _valid_held_at_a_fine_step(world, carried, grasp_rel=GRASP_REL)
        assert _valid_held_at_a_fine_step(world, put_down, resting=resting)
        assert _valid_held_at_a_fine_step(world, held, grasp_rel=OTHER_REL)
        # the shortest on its graph: nothing below its travel
        travel = joint_travel([carried, put_down, held])
        assert _regrasp(world, a, b, shorter_than=travel - 1e-9) is None
    assert found >= 2


def test_no_lattice_regrasp_but_on_three_joints_or_beyond_its_allowance() -> None:
    for joints in (2, 4):
        world, _ = random_box_world(4, joints, 0.02)
        a = np.zeros(joints)
        assert _regrasp(world, a, a + 0.5) is None
    world, _ = random_box_world(6, 3, 0.02)
    budget = _Counter()
    a, b = np.array([0.5, 0.5, 0.5]), np.array([-0.5, 1.0, -0.5])
    assert _regrasp(world, a, b, budget=budget, allowance=1000.0) is None
    assert budget.spent == 0  # checking the nodes alone would take more than its share: nothing done
