"""Shortcuts (step 5 of :mod:`clew_ros.planar.improve`): a sub-path of one segment replaced by one straight
joint-space move, greedily, then in random batches scored and checked in one compiled call each (a partial
shortcut evens out one joint), and goal shortcuts that end the last transfer sooner on the goal."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from clew_ros.core.improve import joint_travel, pruned_path, without_repeats
from clew_ros.planar.improve.base import _ImproverBase
from clew_ros.planar.improve.pieces import _Piece
from clew_ros.planar.kernel import shortcuts
from clew_ros.planar.regrasp import goal_holds_near


@dataclass
class _Shortcuts:
    """Shortcuts of one path (``K`` of them), each replacing the stretch between a point on piece ``first`` and
    one on piece ``last`` (``first < last``) by ``paths`` ``(K, partial_pieces + 2, n)``: its first point, the
    new waypoints and its last point, padded with the last (zero moves). ``gain``: joint travel saved (rad)."""

    first: np.ndarray
    last: np.ndarray
    paths: np.ndarray
    gain: np.ndarray
    fewer: np.ndarray  # a straight one that drops waypoints: as long, it is still better

    def improving(self, travel_eps: float) -> np.ndarray:
        """The shortcuts that would make the path better (gains within ``travel_eps`` rad count as none), the largest
        gain first."""
        rows = np.flatnonzero((self.gain > travel_eps) | (self.fewer & (self.gain >= -travel_eps)))
        return rows[np.argsort(-self.gain[rows], kind="stable")]


def _draw_shortcuts(waypoints: np.ndarray, rng: np.random.Generator, count: int, partial_pieces: int) -> _Shortcuts:
    """``count`` shortcuts of a path drawn at random, a third of each kind: two waypoints joined straight; two points
    along the path (by joint travel) joined straight; and between two such points at most
    :attr:`ImproveSettings.partial_pieces` pieces apart, one joint (drawn) moving evenly along the path while the others
    move as before (a *partial* shortcut: a joint that went back and forth there goes straight). Draws that replace
    nothing (both points on one piece, or a partial one spanning more pieces) come back with ``gain`` -inf. The draws
    come from ``rng``; the paths and gains from one compiled call (:func:`clew_ros.planar.kernel.shortcuts`)."""
    return _Shortcuts(*shortcuts(waypoints, rng.random((count, 6)), partial_pieces))


class _Shortcutting(_ImproverBase):
    """The shortcut stage of the improver."""

    def try_shortcut(self, index: int, first: int, last: int, a: np.ndarray, b: np.ndarray) -> bool:
        """Replace waypoints ``first..last`` (inclusive, ``first < last``) of piece ``index`` by ``a``,
        ``b`` (points on the pieces before ``first`` and after ``last``) joined straight."""
        piece = self.pieces[index]
        w = piece.waypoints
        self.budget.spend(math.ceil(self.settings.shortcut_try_work + self.settings.waypoint_work * len(w)))
        joined = [*w[:first], a, b, *w[last + 1 :]]
        new = pruned_path(without_repeats(joined))
        old_score = (0, joint_travel([w]), len(w))
        if not self.better(old_score, (0, joint_travel([new]), len(new))):
            return False
        if not self.clear(piece, a, b):
            return False
        piece.waypoints = new
        self.shortcuts += 1
        self.reserve()
        return True

    def greedy_shortcuts(self) -> None:
        """Along each segment, from its first waypoint: a straight move to the farthest later waypoint that
        is clear (the last, else halfway there, a quarter, ...), then on from there; the longest segments
        (in joint travel) first."""
        order = np.argsort([-joint_travel([p.waypoints]) for p in self.pieces], kind="stable")
        for index in order.tolist():
            piece = self.pieces[index]
            i = 0
            while i < len(piece.waypoints) - 2:
                if not self.budget.left():
                    return
                last = len(piece.waypoints) - 1
                span = last - i
                while span >= 2 and not self.try_shortcut(
                    index, i + 1, i + span - 1, piece.waypoints[i], piece.waypoints[i + span]
                ):
                    if not self.budget.left():
                        return
                    span //= 2
                i += 1

    def random_shortcuts(self) -> None:
        """Batches of :attr:`ImproveSettings.shortcut_batch` shortcuts of one segment (:func:`_draw_shortcuts`; the
        segment drawn by its joint travel), until the work is spent or :attr:`ImproveSettings.idle_batches` batches in a
        row changed nothing. Those of a batch that would make the path better are checked in one call; the clear ones
        are taken, the largest gain first, as long as they do not overlap one taken."""
        rng = self.ctx.rng
        idle = 0
        changed = True
        travels = np.zeros(0)
        while self.budget.left() and idle < self.settings.idle_batches:
            if changed:  # how much each piece could still gain
                travels = np.array([joint_travel([p.waypoints]) if len(p.waypoints) > 2 else 0.0 for p in self.pieces])
            if travels.sum() <= 0:
                return
            index = int(rng.choice(len(self.pieces), p=travels / travels.sum()))
            self.budget.spend(self.settings.batch_work)  # drawing, scoring and splicing them, besides the checks
            piece = self.pieces[index]
            changed = self.take_shortcuts(
                piece, _draw_shortcuts(piece.waypoints, rng, self.settings.shortcut_batch, self.settings.partial_pieces)
            )
            idle = 0 if changed else idle + 1

    def take_shortcuts(self, piece: _Piece, drawn: _Shortcuts) -> bool:
        """Check the shortcuts of ``drawn`` that would make ``piece``'s path better (every move of all of them
        in one call of the continuous check) and take the clear ones that do not overlap, the largest gain
        first. Returns whether the path changed."""
        rows = drawn.improving(self.settings.travel_eps)
        if not len(rows):
            return False
        paths = drawn.paths[rows]
        starts, ends = paths[:, :-1].reshape(-1, paths.shape[2]), paths[:, 1:].reshape(-1, paths.shape[2])
        owner = np.repeat(np.arange(len(rows)), paths.shape[1] - 1)
        moving = np.max(np.abs(ends - starts), axis=1) > 1e-12
        clear = np.ones(len(starts), dtype=bool)
        if moving.any():
            clear[moving] = self.moves_clear(piece, starts[moving], ends[moving])
        if self.budget.stopped:
            return False
        blocked = np.bincount(owner[~clear], minlength=len(rows)) > 0
        taken: list[int] = []
        for k in np.flatnonzero(~blocked).tolist():  # the largest gain first
            first, last = drawn.first[rows[k]], drawn.last[rows[k]]
            if all(last < drawn.first[rows[t]] or first > drawn.last[rows[t]] for t in taken):
                taken.append(k)
        if not taken:
            return False
        w = list(piece.waypoints)
        for k in sorted(taken, key=lambda t: -drawn.first[rows[t]]):  # from the path's end: indices stay true
            first, last = int(drawn.first[rows[k]]), int(drawn.last[rows[k]])
            w[first + 1 : last + 1] = list(paths[k])
        new = pruned_path(without_repeats(w))
        if not self.better(
            (0, joint_travel([piece.waypoints]), len(piece.waypoints)), (0, joint_travel([new]), len(new))
        ):
            return False
        piece.waypoints = new
        self.shortcuts += len(taken)
        self.reserve()
        return True

    def goal_shortcuts(self) -> bool:
        """The object may end anywhere on the goal (within its tolerances), and a redundant arm, or one whose
        goal leaves the object's angle free, holds it there in many ways. From each waypoint of the last
        transfer but its end, the configuration inverse kinematics finds from there putting the object on
        the goal, held as that transfer holds it (:func:`clew_ros.planar.regrasp.goal_holds_near`, valid with
        the margin), joined straight, ends the transfer when that makes it shorter: the shortest clear one
        (one batch of inverse kinematics and one call of the continuous check; once is enough, since a
        second batch from the waypoints kept would find the same). Returns whether the plan changed."""
        if not self.goal_shortcut(self.pieces[-1]):
            return False
        self.shortcuts += 1
        self.reserve()
        return True

    def goal_shortcut(self, piece: _Piece) -> bool:
        """:meth:`goal_shortcuts` of ``piece``, a transfer ending on the goal (the plan's last, or a proposal's):
        whether its waypoints changed (the caller counts the shortcut when it keeps it)."""
        if piece.kind != "transfer" or piece.grasp_rel is None or len(piece.waypoints) < 2 or not self.budget.left():
            return False
        w = piece.waypoints
        seeds = w[:-1]
        holding = np.broadcast_to(piece.grasp_rel, (len(seeds), 3))
        held, ok, effort = goal_holds_near(
            self.world, holding, seeds, self.goal, margin_m=self.min_margin, settings=self.settings.regrasp
        )
        self.budget.spend_checks(effort.checks, effort.calls)
        self.budget.spend(math.ceil(self.settings.ik_work * effort.steps))
        steps = np.abs(np.diff(w, axis=0)).sum(axis=1)
        travel = np.cumsum(steps) - steps + np.abs(held - seeds).sum(axis=1)  # to each seed, then to the goal
        rows = np.flatnonzero(ok & (travel < steps.sum() - self.settings.travel_eps))
        if not len(rows):
            return False
        if self.world.robot.dof >= self.ctx.many.straight_probe_joints:
            best = self.shortest_clear(piece, seeds, held, rows[np.argsort(travel[rows], kind="stable")])
            if best is None:
                return False
        else:
            clear = self.moves_clear(piece, seeds[rows], held[rows])
            if self.budget.stopped or not clear.any():
                return False
            best = rows[clear][np.argmin(travel[rows[clear]])]
        piece.waypoints = without_repeats([*w[: best + 1], held[best]])  # a waypoint on the goal already: itself
        return True

    def shortest_clear(self, piece: _Piece, seeds: np.ndarray, held: np.ndarray, order: np.ndarray) -> int | None:
        """The first row of ``order`` (shortest first) whose move ``seeds[row] -> held[row]`` is clear, checked
        :attr:`ImproveSettings.many_goal_batch` at a time, the budget asked before each call (arms of many joints:
        all of a long last transfer's candidates in one compiled call took 4 s near the slot, past the time
        limit); None when none is, or the budget or the clock ran out."""
        for first in range(0, len(order), self.settings.many_goal_batch):
            if not self.budget.left():
                return None
            rows = order[first : first + self.settings.many_goal_batch]
            clear = self.moves_clear(piece, seeds[rows], held[rows])
            if self.budget.stopped:
                return None
            if clear.any():
                return int(rows[int(np.argmax(clear))])
        return None

    def shorten(self) -> None:
        """Pruning, then shortcuts: to the goal, greedy, random (and random again after goal shortcuts)."""
        self.prune()
        self.goal_shortcuts()
        self.greedy_shortcuts()
        self.random_shortcuts()
        if self.goal_shortcuts():
            self.random_shortcuts()
