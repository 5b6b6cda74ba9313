"""RRT-Connect, compiled: rounds in which two trees (from the start, from the goals) take turns growing toward a
target and toward each other, every step a checked straight move, while the work spent is within its allowance."""

from __future__ import annotations

import math

import numpy as np

from clew_ros.planar.kernel.jit import _jit
from clew_ros.planar.kernel.moves import _mode, _move_clear
from clew_ros.planar.kernel.packed import PackedWorld, _arg


@_jit
def _extend(
    nodes: np.ndarray,
    parents: np.ndarray,
    sizes: np.ndarray,
    which: int,
    target: np.ndarray,
    step_rad: float,
    greedy: bool,
    transfer: bool,
    grasp_rel: np.ndarray,
    resting: np.ndarray,
    min_margin: float,
    max_margin: float,
    coarse_stride: int,
    checked: np.ndarray,
    base: np.ndarray,
    lengths: np.ndarray,
    lower: np.ndarray,
    upper: np.ndarray,
    r: float,
    self_collision: bool,
    bounds: np.ndarray,
    obstacles: np.ndarray,
    obstacle_starts: np.ndarray,
    boxes: np.ndarray,
    object_edges: np.ndarray,
    shrunk_edges: np.ndarray,
    shrunk_starts: np.ndarray,
    rounding: float,
) -> int:
    """Grow tree ``which`` (``nodes[which, :sizes[which]]``) from its node nearest ``target`` (largest joint
    difference, the first of equals) towards it by steps of at most ``step_rad``: one step, or while clear
    when ``greedy``. Returns the last node added (the nearest itself when it is the target), -1 when not
    even one step was clear."""
    n = nodes.shape[2]
    if sizes[which] == 0:
        return -1
    near = 0
    best = math.inf
    for i in range(sizes[which]):
        far = 0.0
        for j in range(n):
            far = max(far, abs(nodes[which, i, j] - target[j]))
        if far < best:
            near, best = i, far
    added = -1
    step = np.empty(n)
    while True:
        gap = 0.0
        for j in range(n):
            gap = max(gap, abs(target[j] - nodes[which, near, j]))
        if gap <= 1e-12:
            return added if added >= 0 else near
        for j in range(n):
            q = nodes[which, near, j]
            step[j] = target[j] if gap <= step_rad else q + (step_rad / gap) * (target[j] - q)
        if not _move_clear(
            nodes[which, near], step, transfer, grasp_rel, resting, min_margin, max_margin, coarse_stride, checked,
            base, lengths, lower, upper, r, self_collision, bounds, obstacles, obstacle_starts, boxes,
            object_edges, shrunk_edges, shrunk_starts, rounding,
        ):  # fmt: skip
            return added
        added = int(sizes[which])
        nodes[which, added] = step
        parents[which, added] = near
        sizes[which] += 1
        near = added
        if not greedy:
            return added


@_jit
def _connect_rounds(
    nodes: np.ndarray,
    parents: np.ndarray,
    sizes: np.ndarray,
    state: np.ndarray,
    targets: np.ndarray,
    step_rad: float,
    allowed: float,
    check_work: float,
    round_work: float,
    transfer: bool,
    grasp_rel: np.ndarray,
    resting: np.ndarray,
    min_margin: float,
    max_margin: float,
    coarse_stride: int,
    base: np.ndarray,
    lengths: np.ndarray,
    lower: np.ndarray,
    upper: np.ndarray,
    r: float,
    self_collision: bool,
    bounds: np.ndarray,
    obstacles: np.ndarray,
    obstacle_starts: np.ndarray,
    boxes: np.ndarray,
    object_edges: np.ndarray,
    shrunk_edges: np.ndarray,
    shrunk_starts: np.ndarray,
    rounding: float,
) -> float:
    """Rounds of RRT-Connect, one per row of ``targets``, while the work spent (``round_work`` a round,
    ``check_work`` a configuration checked) is within ``allowed``; returns the work spent. ``state``:
    ``[tree extended first, node grown, node reached, met]``; tree 0 grows from the start, tree 1 from the
    goals, and they take turns."""
    checked = np.zeros(1, np.int64)
    spent = 0.0
    for k in range(targets.shape[0]):
        if spent >= allowed:
            break
        first = state[0]
        checked[0] = 0
        grown = _extend(
            nodes, parents, sizes, first, targets[k], step_rad, False, transfer, grasp_rel, resting, min_margin,
            max_margin, coarse_stride, checked, base, lengths, lower, upper, r, self_collision, bounds, obstacles,
            obstacle_starts, boxes, object_edges, shrunk_edges, shrunk_starts, rounding,
        )  # fmt: skip
        if grown >= 0:
            reached = _extend(
                nodes, parents, sizes, 1 - first, nodes[first, grown], step_rad, True, transfer, grasp_rel,
                resting, min_margin, max_margin, coarse_stride, checked, base, lengths, lower, upper, r,
                self_collision, bounds, obstacles, obstacle_starts, boxes, object_edges, shrunk_edges,
                shrunk_starts, rounding,
            )  # fmt: skip
            met = reached >= 0
            for j in range(nodes.shape[2]):
                met = met and nodes[1 - first, reached, j] == nodes[first, grown, j]
            if met:
                state[1], state[2], state[3] = grown, reached, 1
                return spent + round_work + float(checked[0]) * check_work
        spent += round_work + float(checked[0]) * check_work
        state[0] = 1 - first
    return spent


def connect_rounds(
    world: PackedWorld,
    nodes: np.ndarray,
    parents: np.ndarray,
    sizes: np.ndarray,
    state: np.ndarray,
    targets: np.ndarray,
    *,
    step_rad: float,
    allowed: float,
    check_work: float,
    round_work: float,
    resting: np.ndarray | None,
    grasp_rel: np.ndarray | None,
    min_margin: float,
    max_margin: float,
    coarse_stride: int,
) -> float:
    """Compiled rounds of RRT-Connect (:func:`clew_ros.planar.connect.rrt_connect` keeps the trees: ``nodes``
    ``(2, capacity, n)``, ``parents`` ``(2, capacity)`` int64, ``sizes`` ``(2,)`` int64 (each at least 1) and
    ``state`` ``(4,)`` int64, all updated in place; room for every node the rounds may add), one per row of
    ``targets``, while the work spent is within ``allowed``; the object at ``resting`` or held as
    ``grasp_rel`` (give one). Returns the work spent."""
    transfer, held, at_rest = _mode(resting, grasp_rel)
    return float(
        _connect_rounds(
            nodes,
            parents,
            sizes,
            state,
            _arg(targets),
            float(step_rad),
            float(allowed),
            float(check_work),
            float(round_work),
            transfer,
            held,
            at_rest,
            float(min_margin),
            float(max_margin),
            int(coarse_stride),
            *world.move_arguments,
        )
    )
