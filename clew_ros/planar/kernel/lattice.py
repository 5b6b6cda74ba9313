"""The improvement's lattice in joint space, compiled: A* over its nodes (blocked edges never taken), Dijkstra
costs from each end and their repair when an edge is found blocked, and the regrasp search's totals."""

from __future__ import annotations

import heapq

import numpy as np

from clew_ros.planar.kernel.jit import _jit

#: :func:`lattice_search`'s edge states: not checked yet (taken as clear), checked clear, checked blocked.
EDGE_UNKNOWN, EDGE_CLEAR, EDGE_BLOCKED = 0, 1, 2


@_jit
def _lattice_node(
    u: int | np.int64, strides: np.ndarray, lower: np.ndarray, step: float, goal: np.ndarray, k: np.ndarray
) -> float:
    """Node ``u``'s indices into ``k``; returns its joint travel to ``goal``."""
    estimate = 0.0
    rest = u
    for j in range(len(strides)):
        k[j] = rest // strides[j]
        rest %= strides[j]
        estimate += abs(lower[j] + k[j] * step - goal[j])
    return estimate


@_jit
def lattice_path(previous: np.ndarray, last: int) -> np.ndarray:
    """The nodes that led to ``last`` (excluded), first to last."""
    count = 0
    v = previous[last]
    while v >= 0:
        count += 1
        v = previous[v]
    path = np.empty(count, dtype=np.int64)
    v = previous[last]
    for i in range(count - 1, -1, -1):
        path[i] = v
        v = previous[v]
    return path


@_jit
def _lattice_neighbour(
    u: int | np.int64,
    j: int,
    sign: int,
    k: np.ndarray,
    counts: np.ndarray,
    strides: np.ndarray,
    edges: np.ndarray,
) -> int:
    """Node ``u``'s neighbour one step along joint ``j`` (up if ``sign`` > 0; ``u``'s indices ``k``), or -1 when
    that is off the lattice or the edge is blocked."""
    if sign > 0:
        if k[j] + 1 >= counts[j] or edges[u, j] == EDGE_BLOCKED:
            return -1
        return int(u + strides[j])
    if k[j] == 0 or edges[u - strides[j], j] == EDGE_BLOCKED:
        return -1
    return int(u - strides[j])


@_jit
def _lattice_expand(
    u: int | np.int64,
    estimate: float,
    k: np.ndarray,
    counts: np.ndarray,
    strides: np.ndarray,
    lower: np.ndarray,
    step: float,
    goal: np.ndarray,
    edges: np.ndarray,
    cost: np.ndarray,
    previous: np.ndarray,
    heap: list[tuple[float, np.int64]],
) -> None:
    """Relax the edges of node ``u`` (indices ``k``, joint travel ``estimate`` to ``goal``) that are not blocked."""
    g = cost[u] + step
    for j in range(len(counts)):
        for sign in (1, -1):
            v = _lattice_neighbour(u, j, sign, k, counts, strides, edges)
            if v < 0:
                continue
            if g < cost[v]:
                cost[v] = g
                previous[v] = u
                here = lower[j] + k[j] * step
                f = g + estimate - abs(here - goal[j]) + abs(here + sign * step - goal[j])
                heapq.heappush(heap, (f, np.int64(v)))


@_jit
def lattice_search(
    counts: np.ndarray,
    lower: np.ndarray,
    step: float,
    edges: np.ndarray,
    sources: np.ndarray,
    source_costs: np.ndarray,
    targets: np.ndarray,
    target_costs: np.ndarray,
    goal: np.ndarray,
    bound: float,
) -> tuple[np.ndarray, float, int]:
    """Compiled A* over a joint-space lattice, in joint travel (L1).

    Node ``u`` has index ``k_j`` along joint ``j`` (``u = sum_j k_j stride_j``, the last joint fastest) and
    the configuration ``lower + k step``; an edge moves one joint by one step. ``edges[u, j]`` is the state
    of the edge from ``u`` to its neighbour one step up joint ``j``: :data:`EDGE_BLOCKED` is never taken, the
    others are. Paths start at one of ``sources`` (at ``source_costs``: the joint travel from the true
    start) and end at one of ``targets`` (``target_costs`` more to the true end ``goal``, at least the joint
    travel from the target to it), shorter than ``bound``. The heuristic, the joint travel left to ``goal``,
    is then admissible and consistent. Returns the
    shortest path's nodes (none when no path is shorter than ``bound``), its cost and the nodes expanded.
    """
    n = len(counts)
    strides = np.empty(n, dtype=np.int64)
    total = 1
    for j in range(n - 1, -1, -1):
        strides[j] = total
        total *= counts[j]
    cost = np.full(total + 1, np.inf)  # the last entry: the true end, reached from a target
    previous = np.full(total + 1, -1, dtype=np.int64)
    extra = np.full(total, np.inf)
    for i in range(len(targets)):
        extra[targets[i]] = min(extra[targets[i]], target_costs[i])
    k = np.empty(n, dtype=np.int64)
    heap = [(0.0, np.int64(0)) for _ in range(0)]
    for i in range(len(sources)):
        if source_costs[i] < cost[sources[i]]:
            cost[sources[i]] = source_costs[i]
            f = source_costs[i] + _lattice_node(sources[i], strides, lower, step, goal, k)
            heapq.heappush(heap, (f, np.int64(sources[i])))
    expanded = 0
    while heap:
        f, u = heapq.heappop(heap)
        if f >= bound:
            break
        if u == total:
            return lattice_path(previous, total), cost[total], expanded
        estimate = _lattice_node(u, strides, lower, step, goal, k)
        if f > cost[u] + estimate + 1e-9:
            continue  # a stale entry
        expanded += 1
        if cost[u] + extra[u] < cost[total]:
            cost[total] = cost[u] + extra[u]
            previous[total] = u
            heapq.heappush(heap, (cost[total], np.int64(total)))
        _lattice_expand(u, estimate, k, counts, strides, lower, step, goal, edges, cost, previous, heap)
    return np.empty(0, dtype=np.int64), np.inf, expanded


@_jit
def _strides(counts: np.ndarray) -> tuple[np.ndarray, int]:
    """A lattice's node-number strides (the last joint fastest) and its node count."""
    n = len(counts)
    strides = np.empty(n, dtype=np.int64)
    total = 1
    for j in range(n - 1, -1, -1):
        strides[j] = total
        total *= counts[j]
    return strides, total


@_jit
def _flood(
    heap: list[tuple[float, np.int64]],
    counts: np.ndarray,
    strides: np.ndarray,
    step: float,
    edges: np.ndarray,
    cost: np.ndarray,
    previous: np.ndarray,
    bound: float,
) -> int:
    """Dijkstra's loop of :func:`lattice_costs` and :func:`lattice_repair` from the entries of ``heap``, updating
    ``cost`` and ``previous`` in place; the nodes expanded."""
    n = len(counts)
    k = np.empty(n, dtype=np.int64)
    expanded = 0
    while heap:
        f, u = heapq.heappop(heap)
        if f > cost[u]:
            continue  # a stale entry
        expanded += 1
        rest = u
        for j in range(n):
            k[j] = rest // strides[j]
            rest %= strides[j]
        g = f + step
        if g >= bound:
            continue
        for j in range(n):
            for sign in (1, -1):
                v = _lattice_neighbour(u, j, sign, k, counts, strides, edges)
                if v < 0:
                    continue
                if g < cost[v]:
                    cost[v] = g
                    previous[v] = u
                    heapq.heappush(heap, (g, np.int64(v)))
    return expanded


@_jit
def lattice_costs(
    counts: np.ndarray, step: float, edges: np.ndarray, sources: np.ndarray, source_costs: np.ndarray, bound: float
) -> tuple[np.ndarray, np.ndarray, int]:
    """Compiled Dijkstra over a joint-space lattice (the nodes and edges of :func:`lattice_search`), in joint
    travel: from ``sources`` (at ``source_costs``), the least cost of every node reached below ``bound``
    (``inf`` for a node not reached; a source keeps its own cost even when that is not below ``bound``) and
    the node it is reached from (-1 for a node not reached or reached at its own source cost), and the
    nodes expanded."""
    strides, total = _strides(counts)
    cost = np.full(total, np.inf)
    previous = np.full(total, -1, dtype=np.int64)
    heap = [(0.0, np.int64(0)) for _ in range(0)]
    for i in range(len(sources)):
        if source_costs[i] < cost[sources[i]]:
            cost[sources[i]] = source_costs[i]
            heapq.heappush(heap, (source_costs[i], np.int64(sources[i])))
    return cost, previous, _flood(heap, counts, strides, step, edges, cost, previous, bound)


@_jit
def _losing(strides: np.ndarray, edges: np.ndarray, previous: np.ndarray) -> np.ndarray:
    """Which nodes' way back to a source (by ``previous``) takes a blocked edge: one pass, each chain followed
    until a node already known."""
    total = len(previous)
    state = np.zeros(total, dtype=np.int8)  # 0 not known yet, 1 keeps its cost, 2 loses it
    chain = np.empty(total, dtype=np.int64)
    for v in range(total):
        length = 0
        u = np.int64(v)
        while state[u] == 0:
            p = previous[u]
            if p < 0:  # a source at its own cost, or a node not reached: either stands
                state[u] = 1
                break
            j = 0
            while j < len(strides) - 1 and strides[j] != abs(u - p):  # the joint of the edge (p is a neighbour)
                j += 1
            if edges[min(u, p), j] == EDGE_BLOCKED:
                state[u] = 2
                break
            chain[length] = u
            length += 1
            u = p
        for i in range(length):
            state[chain[i]] = state[u]
    lose: np.ndarray = state == 2
    return lose


@_jit
def lattice_repair(
    counts: np.ndarray,
    step: float,
    edges: np.ndarray,
    sources: np.ndarray,
    source_costs: np.ndarray,
    bound: float,
    cost: np.ndarray,
    previous: np.ndarray,
) -> int:
    """:func:`lattice_costs`' ``cost`` and ``previous`` brought up to date in place after edges were blocked (and
    none unblocked), as a search from scratch would give them (ties apart): the nodes whose way back to a source
    takes a blocked edge lose their cost, and Dijkstra's loop runs again from their neighbours that kept theirs
    (blocking only makes costs higher, so those are still least). Returns the nodes expanded again."""
    n = len(counts)
    strides, _ = _strides(counts)
    lose = _losing(strides, edges, previous)
    lost = np.flatnonzero(lose)
    cost[lost] = np.inf
    previous[lost] = -1
    for i in range(len(sources)):
        if lose[sources[i]]:
            cost[sources[i]] = min(cost[sources[i]], source_costs[i])
    heap = [(0.0, np.int64(0)) for _ in range(0)]
    k = np.empty(n, dtype=np.int64)
    for v in lost:
        rest = v
        for j in range(n):
            k[j] = rest // strides[j]
            rest %= strides[j]
        for j in range(n):
            for sign in (1, -1):
                u = _lattice_neighbour(v, j, sign, k, counts, strides, edges)  # the edge is the same both ways
                if u >= 0 and not lose[u] and cost[u] + step < min(bound, cost[v]):
                    cost[v] = cost[u] + step
                    previous[v] = u
        if cost[v] < np.inf:
            heapq.heappush(heap, (cost[v], np.int64(v)))
    return _flood(heap, counts, strides, step, edges, cost, previous, bound)


@_jit
def release_totals(
    first_cost: np.ndarray,
    last_cost: np.ndarray,
    releases: np.ndarray,
    put_travel: np.ndarray,
    corners: np.ndarray,
    join_travel: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """The regrasp search's totals (:func:`clew_ros.planar.lattice.lattice_regrasp`): for each elbow ``e`` and
    release ``r``, the joint travel ``first_cost[releases[r]] + put_travel[e, r]`` plus the least over the
    corners ``c`` of ``last_cost[corners[e, r, c]] + join_travel[e, r, c]``, and the corner that gives it (the
    first of equals)."""
    sides, count, nearby = corners.shape
    totals = np.empty((sides, count))
    joined = np.empty((sides, count), dtype=np.int64)
    for e in range(sides):
        for r in range(count):
            best = np.inf
            pick = corners[e, r, 0]
            for c in range(nearby):
                via = last_cost[corners[e, r, c]] + join_travel[e, r, c]
                if via < best:
                    best = via
                    pick = corners[e, r, c]
            joined[e, r] = pick
            totals[e, r] = first_cost[releases[r]] + put_travel[e, r] + best
    return totals, joined
