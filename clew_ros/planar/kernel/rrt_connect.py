"""RRT-Connect, compiled: rounds in which two trees (from the start, from the goals) take turns growing toward a
target and toward each other, every step a checked straight move, while the work spent is within its allowance."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from clew_ros.planar.kernel.jit import _jit
from clew_ros.planar.kernel.moves import _mode, _move_clear
from clew_ros.planar.kernel.packed import Mode, Model, MoveCheck, PackedWorld, Rounds, Trees, _arg, _named, plain


@_jit
def _extend(
    trees: Trees,
    which: int,
    target: np.ndarray,
    step_rad: float,
    greedy: bool,
    mode: Mode,
    check: MoveCheck,
    checked: np.ndarray,
    model: Model,
) -> int:
    """Grow tree ``which`` (``nodes[which, :sizes[which]]``) from its node nearest ``target`` (largest joint
    difference, the first of equals) towards it by steps of at most ``step_rad``: one step, or while clear
    when ``greedy``. Returns the last node added (the nearest itself when it is the target), -1 when not
    even one step was clear."""
    nodes, parents, sizes = trees
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
        if not _move_clear(nodes[which, near], step, mode, check, checked, model):
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
    trees: tuple[Any, ...],
    state: np.ndarray,
    targets: np.ndarray,
    rounds: tuple[Any, ...],
    mode: tuple[Any, ...],
    check: tuple[Any, ...],
    world: tuple[Any, ...],
) -> float:
    """Rounds of RRT-Connect, one per row of ``targets``, while the work spent (``round_work`` a round,
    ``check_work`` a configuration checked) is within ``allowed``; returns the work spent. ``state``:
    ``[tree extended first, node grown, node reached, met]``; tree 0 grows from the start, tree 1 from the
    goals, and they take turns. ``trees``, ``rounds``, ``mode``, ``check``: a :class:`~.packed.Trees`,
    :class:`~.packed.Rounds`, :class:`~.packed.Mode` and :class:`~.packed.MoveCheck` as plain tuples; ``world``:
    :attr:`~.packed.PackedWorld.plain`."""
    model = _named(world)
    named_trees, named_mode, named_check = Trees(*trees), Mode(*mode), MoveCheck(*check)
    step_rad, allowed, check_work, round_work = Rounds(*rounds)
    nodes = named_trees.nodes
    checked = np.zeros(1, np.int64)
    spent = 0.0
    for k in range(targets.shape[0]):
        if spent >= allowed:
            break
        first = state[0]
        checked[0] = 0
        grown = _extend(named_trees, first, targets[k], step_rad, False, named_mode, named_check, checked, model)
        if grown >= 0:
            reached = _extend(
                named_trees, 1 - first, nodes[first, grown], step_rad, True, named_mode, named_check, checked, model
            )
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
    trees: Trees,
    state: np.ndarray,
    targets: np.ndarray,
    rounds: Rounds,
    *,
    resting: np.ndarray | None,
    grasp_rel: np.ndarray | None,
    check: MoveCheck,
) -> float:
    """Compiled rounds of RRT-Connect (:func:`clew_ros.planar.connect.rrt_connect` keeps the ``trees``: ``nodes``
    ``(2, capacity, n)``, ``parents`` ``(2, capacity)`` int64, ``sizes`` ``(2,)`` int64 (each at least 1), and
    ``state`` ``(4,)`` int64, all updated in place; room for every node the rounds may add), one per row of
    ``targets``, while the work spent is within ``rounds.allowed``; the object at ``resting`` or held as
    ``grasp_rel`` (give one), every step a straight move checked as ``check`` says. Returns the work spent."""
    rounds = Rounds(float(rounds.step_rad), float(rounds.allowed), float(rounds.check_work), float(rounds.round_work))
    check = MoveCheck(float(check.min_margin), float(check.max_margin), int(check.coarse_stride))
    mode = plain(_mode(resting, grasp_rel))
    return float(_connect_rounds(plain(trees), state, _arg(targets), plain(rounds), mode, plain(check), world.plain))
