"""RRT-Connect in one mode of the manipulation: join configurations when the straight move is blocked.

Two trees grow towards each other (Kuffner and LaValle's RRT-Connect): the
first from the start, the second from one or several goal configurations (its
roots), taking turns. Each round draws a configuration within the joint
limits, extends one tree one step towards it (at most ``step_rad`` per
joint), then extends the other tree greedily towards the new node; they
have met when it reaches that node. Every extension is a straight joint-space
move accepted by the caller's ``clear(a, b)`` (a continuous check:
:func:`clew_ros.core.continuous.straight_move_clear`), so the path found is valid
at any checking resolution. :func:`shortened` then joins each waypoint
straight to the farthest later one that is clear.

The configurations are drawn from the caller's generator and the work is
bounded by rounds, not seconds: the same seed gives the same path.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from clew_ros.core.continuous import straight_move_clear
from clew_ros.core.world import World

__all__ = ["STEP_RAD", "Clear", "join", "rrt_connect", "shortened"]

#: Largest joint step (rad, largest joint difference) of one tree extension.
STEP_RAD = 0.35

#: ``clear(a, b)``: whether the straight joint-space move ``a -> b`` is valid all along.
Clear = Callable[[np.ndarray, np.ndarray], bool]


class _Tree:
    """Nodes and their parents (-1 for a root)."""

    def __init__(self, roots: np.ndarray) -> None:
        self.nodes = [np.asarray(root, dtype=float) for root in roots]
        self.parents = [-1] * len(self.nodes)

    def branch(self, node: int) -> list[np.ndarray]:
        """The nodes from the root to ``node``."""
        branch = []
        while node >= 0:
            branch.append(self.nodes[node])
            node = self.parents[node]
        return branch[::-1]

    def extend(self, clear: Clear, target: np.ndarray, step_rad: float, *, greedy: bool = False) -> int | None:
        """Grow from the node nearest ``target`` towards it by steps of at most ``step_rad`` (one step, or
        while clear when ``greedy``); the index of the last node added (of the node itself when it is the
        target), ``None`` when not even one step was clear."""
        near = int(np.argmin(np.max(np.abs(np.array(self.nodes) - target), axis=1)))
        added = None
        while True:
            q = self.nodes[near]
            gap = float(np.max(np.abs(target - q)))
            if gap <= 1e-12:
                return added if added is not None else near
            step = target if gap <= step_rad else q + (step_rad / gap) * (target - q)
            if not clear(q, step):
                return added
            self.nodes.append(step)
            self.parents.append(near)
            near = added = len(self.nodes) - 1
            if not greedy:
                return added


def rrt_connect(
    clear: Clear,
    start: np.ndarray,
    goals: np.ndarray,
    rng: np.random.Generator,
    *,
    limits: tuple[np.ndarray, np.ndarray],
    rounds: int,
    stop: Callable[[], bool],
    step_rad: float = STEP_RAD,
) -> np.ndarray | None:
    """Waypoints ``(m, n)`` from ``start`` ``(n,)`` to one of ``goals`` ``(g, n)``, every move ``clear``; ``None``
    when the trees did not meet within ``rounds`` rounds or ``stop()`` said so (asked before each round).
    Configurations are drawn within ``limits`` (the joints' lower and upper limits)."""
    from_start = _Tree(np.asarray(start, dtype=float)[None])
    trees = [from_start, _Tree(np.atleast_2d(np.asarray(goals, dtype=float)))]
    for _ in range(rounds):
        if stop():
            return None
        target = rng.uniform(*limits)
        grown = trees[0].extend(clear, target, step_rad)
        if grown is not None:
            meeting = trees[0].nodes[grown]
            reached = trees[1].extend(clear, meeting, step_rad, greedy=True)
            if reached is not None and np.array_equal(trees[1].nodes[reached], meeting):
                halves = [trees[0].branch(grown), trees[1].branch(reached)]
                if trees[0] is not from_start:
                    halves.reverse()
                return np.array([*halves[0], *halves[1][::-1][1:]])
        trees.reverse()
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


class _Stopping:
    """The check budget of :func:`join`: counts nothing, stops a check between its levels when ``stop()``
    says so (the time limit or cancel)."""

    def __init__(self, stop: Callable[[], bool]) -> None:
        self._stop = stop

    def spend_checks(self, configurations: int, calls: int = 1) -> None:
        pass

    def stop(self) -> bool:
        return self._stop()


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
) -> np.ndarray | None:
    """Waypoints from ``start`` to one of ``targets`` ``(g, n)``, the object resting at ``object_pose`` (a transit)
    or carried as ``grasp_rel`` (a transfer): :func:`rrt_connect` with every move checked continuously
    (:func:`clew_ros.core.continuous.straight_move_clear`, ``min_margin`` from everything), then
    :func:`shortened`; ``None`` when the trees did not meet."""

    budget = _Stopping(stop)

    def clear(a: np.ndarray, b: np.ndarray) -> bool:
        return straight_move_clear(
            world, a, b, object_pose=object_pose, grasp_rel=grasp_rel, min_margin=min_margin, budget=budget
        )

    limits = (world.robot.joint_lower, world.robot.joint_upper)
    path = rrt_connect(clear, start, targets, rng, limits=limits, rounds=rounds, stop=stop)
    return None if path is None else shortened(clear, path, stop)
