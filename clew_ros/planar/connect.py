"""RRT-Connect in one mode of the manipulation: join configurations when the straight move is blocked.

Two trees grow towards each other (Kuffner and LaValle's RRT-Connect): the
first from the start, the second from one or several goal configurations (its
roots), taking turns. Each round draws a configuration within the joint
limits, extends one tree one step towards it (at most ``step_rad`` per
joint), then extends the other tree greedily towards the new node; they
have met when it reaches that node. Every extension is a straight joint-space
move checked continuously (:func:`clew_ros.planar.continuous.straight_move_clear`),
so the path found is valid at any checking resolution. :func:`shortened` then
joins each waypoint straight to the farthest later one that the caller's
``clear(a, b)`` accepts.

The rounds are compiled (:func:`clew_ros.planar.kernel.connect_rounds`),
``rounds_per_call`` to a call: a round in Python cost several times its
checks (the nearest node, the step, the calls), and routing the improvement's
blocked moves needs hundreds of rounds. The configurations are drawn from the
caller's generator and the work is bounded by rounds and work units, not
seconds: the same seed gives the same path. The tuning is :class:`ConnectSettings`.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from clew_ros.planar.collision import packed_world
from clew_ros.planar.continuous import ContinuousSettings, StopOnly, straight_move_clear
from clew_ros.planar.kernel import MoveCheck, Rounds, Trees, connect_rounds
from clew_ros.planar.world import World

__all__ = ["Clear", "ConnectSettings", "RoutingBudget", "join", "rrt_connect", "shortened"]


@dataclass(frozen=True)
class ConnectSettings:
    """Tuning of :func:`rrt_connect` and :func:`join`."""

    #: Largest joint step (rad, largest joint difference) of one tree extension: long enough to cross the joint
    #: space in a few steps, short enough that a step is seldom blocked where a shorter one would pass.
    step_rad: float = 0.35
    #: Rounds per compiled call (count): the clock's stop test and the budget are asked between calls, so a
    #: call stays short, and its Python around it small beside its checks.
    rounds_per_call: int = 32


#: ``clear(a, b)``: whether the straight joint-space move ``a -> b`` is valid all along.
Clear = Callable[[np.ndarray, np.ndarray], bool]


class RoutingBudget(Protocol):
    """What :func:`rrt_connect` charges its work to: ``check_work`` units a configuration checked and
    ``round_work`` a round, what it may spend (:meth:`allowance`), and the clock's stop test."""

    check_work: float
    round_work: float

    def allowance(self) -> float:
        """Work units the routing may still spend."""

    def spend(self, units: float) -> None: ...

    def stop(self) -> bool: ...


class _Unbounded:
    """The budget of a routing bounded by its rounds and the clock only."""

    check_work = 1.0
    round_work = 1.0

    def __init__(self, stop: Callable[[], bool]) -> None:
        self.stop = stop

    def allowance(self) -> float:
        return math.inf

    def spend(self, units: float) -> None:
        pass


def _branch(parents: np.ndarray, nodes: np.ndarray, node: int) -> list[np.ndarray]:
    """The nodes from the root to ``node``."""
    branch = []
    while node >= 0:
        branch.append(nodes[node].copy())
        node = int(parents[node])
    return branch[::-1]


def rrt_connect(
    world: World,
    start: np.ndarray,
    goals: np.ndarray,
    rng: np.random.Generator,
    *,
    object_pose: np.ndarray | None = None,
    grasp_rel: np.ndarray | None = None,
    min_margin: float,
    rounds: int,
    budget: RoutingBudget,
    settings: ConnectSettings | None = None,
    moves: ContinuousSettings | None = None,
) -> np.ndarray | None:
    """Waypoints ``(m, n)`` from ``start`` ``(n,)`` to one of ``goals`` ``(g, n)``, the object resting at
    ``object_pose`` (a transit) or carried as ``grasp_rel`` (a transfer), every move clear
    (:func:`clew_ros.planar.continuous.straight_move_clear` with ``min_margin``); ``None`` when the trees did
    not meet within ``rounds`` rounds or ``budget``'s allowance, or its stop test said so (asked before each
    ``rounds_per_call`` rounds). Configurations are drawn within the joint limits, that many at a time.
    ``settings`` default :class:`ConnectSettings`, ``moves`` (the check of each extension) default
    :class:`~clew_ros.planar.continuous.ContinuousSettings`."""
    tuning = settings if settings is not None else ConnectSettings()
    check = moves if moves is not None else ContinuousSettings()
    step_rad, per_call = tuning.step_rad, tuning.rounds_per_call
    lower, upper = world.robot.joint_lower, world.robot.joint_upper
    n = len(lower)
    roots = [np.asarray(start, dtype=float)[None], np.atleast_2d(np.asarray(goals, dtype=float))]
    if roots[1].size == 0 or roots[1].shape[1] != n or roots[0].shape[1] != n:
        expected = f"expected ({n},) and (g >= 1, {n}) configurations"
        raise ValueError(f"start, goals: {expected}, got {roots[0].shape[1:]} and {roots[1].shape}")
    most = 2 + math.ceil(float(np.max(upper - lower)) / step_rad)  # nodes one round may add to a tree
    capacity = max(len(roots[1]), 1) + per_call * most
    nodes = np.zeros((2, capacity, n))
    parents = np.full((2, capacity), -1, dtype=np.int64)
    sizes = np.array([1, len(roots[1])], dtype=np.int64)
    nodes[0, :1], nodes[1, : sizes[1]] = roots
    state = np.zeros(4, dtype=np.int64)  # tree extended first, node grown, node reached, met
    packed = packed_world(world)
    mode = {"resting": None if grasp_rel is not None else object_pose, "grasp_rel": grasp_rel}
    check_moves = MoveCheck(min_margin, check.max_margin_m, check.coarse_stride)
    done = 0
    while done < rounds:
        allowed = budget.allowance()
        if allowed <= 0 or budget.stop():
            return None
        if int(sizes.max()) + per_call * most > nodes.shape[1]:  # room for what the next call may add
            nodes = np.concatenate([nodes, np.zeros_like(nodes)], axis=1)
            parents = np.concatenate([parents, np.full_like(parents, -1)], axis=1)
        targets = rng.uniform(lower, upper, size=(min(per_call, rounds - done), n))
        done += len(targets)
        budget.spend(
            connect_rounds(
                packed,
                Trees(nodes, parents, sizes),
                state,
                targets,
                Rounds(step_rad, allowed, budget.check_work, budget.round_work),
                **mode,
                check=check_moves,
            )
        )
        if state[3]:
            first, grown, reached = (int(v) for v in state[:3])
            halves = [
                _branch(parents[first], nodes[first], grown),
                _branch(parents[1 - first], nodes[1 - first], reached),
            ]
            if first == 1:
                halves.reverse()
            return np.array([*halves[0], *halves[1][::-1][1:]])
    return None


def shortened(clear: Clear, path: np.ndarray, spent: Callable[[], bool] | None = None) -> np.ndarray:
    """``path`` with each waypoint joined straight to the farthest later one that is clear; once ``spent()``
    says the work is spent, the rest is kept as it is."""
    kept = [path[0]]
    i = 0
    while i < len(path) - 1:
        j = len(path) - 1
        while j > i + 1 and ((spent is not None and spent()) or not clear(path[i], path[j])):
            j -= 1
        kept.append(path[j])
        i = j
    return np.array(kept)


def join(
    world: World,
    start: np.ndarray,
    targets: np.ndarray,
    rng: np.random.Generator,
    *,
    object_pose: np.ndarray | None = None,
    grasp_rel: np.ndarray | None = None,
    min_margin: float,
    rounds: int,
    stop: Callable[[], bool],
    settings: ConnectSettings | None = None,
    moves: ContinuousSettings | None = None,
) -> np.ndarray | None:
    """Waypoints from ``start`` to one of ``targets`` ``(g, n)``, the object resting at ``object_pose`` (a transit)
    or carried as ``grasp_rel`` (a transfer): :func:`rrt_connect` with every move checked continuously
    (:func:`clew_ros.planar.continuous.straight_move_clear`, ``min_margin`` from everything), then
    :func:`shortened`; ``None`` when the trees did not meet. ``settings`` and ``moves`` as :func:`rrt_connect`'s."""
    budget = StopOnly(stop)

    def clear(a: np.ndarray, b: np.ndarray) -> bool:
        return straight_move_clear(
            world,
            a,
            b,
            object_pose=object_pose,
            grasp_rel=grasp_rel,
            min_margin=min_margin,
            budget=budget,
            settings=moves,
        )

    path = rrt_connect(
        world,
        start,
        targets,
        rng,
        object_pose=object_pose,
        grasp_rel=grasp_rel,
        min_margin=min_margin,
        rounds=rounds,
        budget=_Unbounded(stop),
        settings=settings,
        moves=moves,
    )
    return None if path is None else shortened(clear, path, stop)
