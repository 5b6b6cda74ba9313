"""Arms of many joints (issue 46): the plan's postures solved again along its tip's path.

EXPLORE's transfers on a hyper-redundant arm are Manhattan paths that turn every joint in turn, and its
transits end on holds solved from random starts: the arm wanders through postures that the task does not
need, and the shortcuts, which never move a segment's ends (where the object is taken or put down), cannot
take that out. The same tip pose, though, is held by a whole family of postures. :meth:`_ManyJointMoves.resolve`
keeps what the plan does with the object (the tip's path, so every grasp, release and placement, and the
object's path while carried) and solves the postures again: the points of each move, a few centimetres of
sweep apart, in turn by damped least squares for the tip's pose, each seeded with the posture solved before,
so the joints move as little as the tip's path needs and joints that need not move stay nearly still. A
piece's new end is first joined straight to its start (a transit's path is free), else each move straight,
else through its points; where such a point is not clear the posture is pulled back towards the first
plan's there. The result is checked continuously, as every move of the improvement, and kept when better;
the shortcuts then straighten it (the improvement's rounds, :mod:`clew_ros.planar.improve`).
"""

from __future__ import annotations

import itertools
import math

import numpy as np

from clew_ros.core.improve import plan_score, pruned_path, without_repeats
from clew_ros.planar.improve.pieces import _Piece
from clew_ros.planar.improve.shortcuts import _Shortcutting
from clew_ros.planar.inverse import solve_point
from clew_ros.planar.kinematics import tip_poses
from clew_ros.planar.search import sampled_clear


class _BlockedError(Exception):
    """A point of a piece solved again could not be joined clear, even to the first plan's posture."""


class _OutOfWorkError(Exception):
    """The budget ran out (or the time limit or cancel) while postures were solved again."""


class _ManyJointMoves(_Shortcutting):
    """The many-joint stage of the improver (arms of at least ``ManyJoints.straight_probe_joints`` joints)."""

    def resolve_postures(self) -> bool:
        """:meth:`resolve` of the whole plan; else, when a piece could not be joined, of the pieces before it
        (returning to its start) and of those after it, and when the whole was not better, of the pieces before
        the last and of the last. Whether the plan got better."""
        count = len(self.pieces)
        better, failed = self.resolve(0, count)
        if better or count < 2:
            return better
        split = count - 1 if failed is None else failed
        if split > 0:
            better |= self.resolve(0, split)[0]
        if split + 1 < count or failed is None:
            better |= self.resolve(split if failed is None else split + 1, count)[0]
        return better

    def resolve(self, first: int, stop: int) -> tuple[bool, int | None]:
        """Pieces ``first`` to ``stop`` - 1 with their tip's path kept and their postures solved again
        (:meth:`resolved_piece`); when pieces follow, the last one's postures are pulled back towards the first
        plan's, all the way at its end, where the next piece starts. Kept when every move is clear and the plan
        better. Whether it was, and the piece that could not be joined (None when none did not, or the work ran
        out)."""
        previous = self.pieces[first].waypoints[0]
        new: list[_Piece] = []
        for index in range(first, stop):
            piece = self.pieces[index]
            returns = index == stop - 1 and stop < len(self.pieces)
            try:
                waypoints = self.resolved_piece(piece, previous, returns)
            except _BlockedError:
                return False, index
            except _OutOfWorkError:
                return False, None
            if returns:  # its last point was solved from the next piece's start itself: that start, exactly
                following = self.pieces[stop].waypoints[0]
                if float(np.max(np.abs(waypoints[-1] - following))) > self.settings.resolve_error_m:
                    return False, None
                waypoints[-1] = following
            new.append(_Piece(piece.kind, piece.grasp, waypoints, piece.start_pose, piece.grasp_rel))
            previous = waypoints[-1]
        candidate = [*self.pieces[:first], *new, *self.pieces[stop:]]
        if not self.better(plan_score(self.pieces), plan_score(candidate)):
            return False, None
        self.pieces = candidate
        self.reserve()
        return True, None

    def resolved_piece(self, piece: _Piece, start: np.ndarray, returns: bool) -> np.ndarray:
        """``piece``'s waypoints solved again from ``start``: the points of each of its moves
        (:attr:`ImproveSettings.resolve_step_m` of sweep apart) in turn (:meth:`chained`), pulled back towards the
        first plan's postures by shares growing to 1 at its end if ``returns``; joined from ``start`` to the
        farthest solved point a straight move reaches clear (:meth:`farthest_clear`: the last first, so a piece
        becomes one straight move where it can), and on from there; a point that no move reaches clear is solved
        again nearer the first plan's posture (:meth:`pulled`), and the points after it are solved at least as
        near. Raises :class:`_BlockedError` or :class:`_OutOfWorkError`."""
        robot = self.world.robot
        reach = np.cumsum(robot.link_lengths[::-1])[::-1]  # R_j: the links from joint j on
        w = piece.waypoints
        moves = [
            a + np.linspace(0.0, 1.0, count + 1)[1:, None] * (b - a)
            for a, b in itertools.pairwise(w)
            for count in [max(1, math.ceil(float(np.abs(b - a) @ reach) / self.settings.resolve_step_m))]
        ]
        if not moves:
            return np.array([start])
        old = np.vstack(moves)
        tips = tip_poses(robot, old)
        pull = np.arange(1, len(old) + 1) / len(old) if returns else np.zeros(len(old))
        path = [start]
        floor = 0.0  # once pulled towards the first plan's postures, the piece's later points stay as near
        done = 0
        chain = np.zeros((0, robot.dof))
        while done < len(old):
            if not self.budget.left():
                raise _OutOfWorkError
            if not len(chain):
                chain = self.chained(path[-1], tips[done:], old[done:], np.maximum(pull[done:], floor))
            joined = self.farthest_clear(piece, path[-1], chain)
            if joined:
                path.append(chain[joined - 1])
                chain = chain[joined:]
                done += joined
                continue
            pulled = self.pulled(piece, path[-1], tips[done], old[done])
            if pulled is None:
                raise _BlockedError
            path.append(pulled[0])
            floor = max(floor, pulled[1])
            done += 1
            chain = chain[:0]
        return pruned_path(without_repeats(path))

    def farthest_clear(self, piece: _Piece, q: np.ndarray, chain: np.ndarray) -> int:
        """How many points of ``chain`` the straight move from ``q`` to its farthest clear one passes: the last
        tried first, then halfway, a quarter, ... (0: not even the first). The moves are first screened together
        at configurations ``ManyJoints.screen_step_rad`` apart (one batched check, charged): the continuous check
        of a long blocked move near a contact costs far more (it took 90 % of the budget on 27-joint plans whose
        first plan was kept), and runs only on those the screen finds valid."""
        counts = []
        joined = len(chain)
        while joined:
            counts.append(joined)
            joined //= 2
        if not counts:
            return 0
        ends = chain[np.array(counts) - 1]
        starts = np.broadcast_to(q, ends.shape)
        step = self.ctx.many.screen_step_rad
        screened = sampled_clear(
            self.world, starts, ends, object_pose=piece.start_pose, grasp_rel=piece.grasp_rel, step_rad=step
        )
        samples = int((np.ceil(np.abs(ends - starts).max(axis=1) / step) + 1).sum())
        self.budget.spend_checks(samples)
        for count, ok in zip(counts, screened, strict=True):
            if not self.budget.left():
                raise _OutOfWorkError
            if ok and self.clear_in_pieces(piece, q, chain[count - 1]):
                return count
        return 0

    def clear_in_pieces(self, piece: _Piece, a: np.ndarray, b: np.ndarray) -> bool:
        """Whether the straight move ``a -> b`` is clear in ``piece``'s mode, checked in pieces of at most
        ``ManyJoints.check_sweep_m`` of sweep, the budget asked before each (one compiled check of a long many-joint
        move near a contact can take a second). Raises :class:`_OutOfWorkError` when the budget runs out."""
        reach = np.cumsum(self.world.robot.link_lengths[::-1])[::-1]
        count = max(1, math.ceil(float(np.abs(b - a) @ reach) / self.ctx.many.check_sweep_m))
        points = a + np.linspace(0.0, 1.0, count + 1)[:, None] * (b - a)
        for start, end in itertools.pairwise(points):
            if not self.budget.left():
                raise _OutOfWorkError
            if not self.clear(piece, start, end):
                return False
        return True

    def chained(self, q: np.ndarray, tips: np.ndarray, old: np.ndarray, pull: np.ndarray) -> np.ndarray:
        """Configurations ``(k, n)`` for the tip poses ``tips`` ``(m, 3)`` in turn, each solved from the one
        before (the first from ``q``) pulled by ``pull`` ``(m,)`` (shares) towards ``old`` ``(m, n)``, up to the
        first not reached (``k <= m``), charged to the budget."""
        robot = self.world.robot
        solved = np.empty((len(tips), robot.dof))
        steps = 0
        count = 0
        for tip, towards, share in zip(tips, old, pull, strict=True):
            solution = solve_point(
                robot,
                (q + share * (towards - q))[None],
                tip[None, :2],
                angles=tip[None, 2],
                angle_tolerance=0.0,
                tolerance_m=0.1 * self.settings.resolve_error_m,
            )
            steps += solution.steps + 1
            if solution.error[0] > self.settings.resolve_error_m:
                break
            q = solved[count] = solution.q[0]
            count += 1
        self.budget.spend(math.ceil(self.settings.ik_work * steps + self.settings.resolve_call_work * len(tips)))
        return solved[:count]

    def pulled(self, piece: _Piece, q: np.ndarray, tip: np.ndarray, old: np.ndarray) -> tuple[np.ndarray, float] | None:
        """A configuration for the tip pose ``tip`` joined clear to ``q``: solved from seeds pulled from ``q``
        towards ``old`` (the first plan's there, which holds that pose) by the shares of
        :attr:`ImproveSettings.resolve_pulls`, the first clear, or ``old`` itself; with the share. None when none
        is clear."""
        robot = self.world.robot
        shares = np.asarray(self.settings.resolve_pulls, dtype=float)[:, None]
        seeds = q + shares * (old - q)
        solution = solve_point(
            robot,
            seeds,
            np.broadcast_to(tip[:2], (len(seeds), 2)),
            angles=np.full(len(seeds), tip[2]),
            angle_tolerance=0.0,
            tolerance_m=0.1 * self.settings.resolve_error_m,
        )
        self.budget.spend(math.ceil(self.settings.ik_work * (solution.steps + len(seeds))))
        for k in np.flatnonzero(solution.error <= self.settings.resolve_error_m).tolist():
            if self.clear_in_pieces(piece, q, solution.q[k]):
                return solution.q[k], float(shares[k, 0])
        if self.clear_in_pieces(piece, q, old):
            return old, 1.0
        return None
