"""Arms of many joints (issue 46): segment ends moved along the arm's redundancy.

A segment's end points are where the arm takes or releases the object; the shortcuts never move them, so
a plan can be no shorter than the joint travel between them. On a hyper-redundant arm the first plan's ends
come from EXPLORE's Manhattan paths and from holds solved from random starts, far apart in joint space,
while the same tip pose (the same grasp of the object at the same place) is held by a whole family of
configurations. :meth:`_ManyJointMoves.move_ends` moves each end within that family, towards the
waypoints on either side of it: inverse kinematics for the end's tip pose, seeded from points on the
straight line between those two neighbours (damped least squares stays near its seed, so the answer is
near the line), the nearest valid answer whose two moves are clear kept. The object is then held or put
down exactly where it was, so the rest of both segments stays valid; the shortcuts then straighten the
segments between the new ends, and the two alternate while they gain (:meth:`_ManyJointMoves.many_joints`).
"""

from __future__ import annotations

import itertools
import math

import numpy as np

from clew_ros.core.improve.pieces import _Piece, _score, _without_repeats
from clew_ros.core.improve.shortcuts import _Shortcutting
from clew_ros.core.inverse import solve_point
from clew_ros.core.kernel import pruned_path
from clew_ros.core.kinematics import tip_poses
from clew_ros.core.regrasp import _Kinematics


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

    def many_joints(self) -> None:
        """Rounds of :meth:`move_ends` then the shortcuts (greedy, random), while a round makes the plan
        better and work is left (at most :attr:`ImproveSettings.end_rounds`)."""
        for _ in range(self.settings.end_rounds):
            score = _score(self.pieces)
            if not self.budget.left() or not self.move_ends():
                return
            self.shorten()
            if not self.better(score, _score(self.pieces)):
                return

    def move_ends(self) -> bool:
        """:meth:`move_end` of every end shared by two segments, the plan's order. Whether the plan changed."""
        changed = False
        for index in range(len(self.pieces) - 1):
            if not self.budget.left():
                break
            changed |= self.move_end(index)
        if changed:
            self.reserve()
        return changed

    def move_end(self, index: int) -> bool:
        """Move the configuration where piece ``index`` ends and the next begins to one with the same tip pose
        nearer (joint travel) the straight line between its neighbours (the waypoint before it and the one
        after), when both moves to it are clear. Whether it moved."""
        one, two = self.pieces[index], self.pieces[index + 1]
        end = one.waypoints[-1]
        before = one.waypoints[-2] if len(one.waypoints) > 1 else end
        after = two.waypoints[1] if len(two.waypoints) > 1 else end
        seeds = self.end_seeds(before, after, end)
        tip = tip_poses(self.world.robot, end[None])[0]
        kinematics = _Kinematics(self.world, self.min_margin, settings=self.settings.regrasp)
        reached = self.settings.end_error_m
        q, error = kinematics.solve(
            seeds,
            tip[:2],
            reached,
            angles=np.full(len(seeds), tip[2]),
            angle_tolerance=0.0,
            tolerance_m=0.1 * reached,
        )
        travel = np.abs(q - before).sum(axis=1) + np.abs(after - q).sum(axis=1)
        old = float(np.abs(end - before).sum() + np.abs(after - end).sum())
        rows = np.flatnonzero((error <= reached) & (travel < old - self.settings.end_gain_rad))
        if len(rows):
            pose = one.end_pose(self.world)
            valid = kinematics.valid(q[rows], np.broadcast_to(pose, (len(rows), 3)))
            rows = rows[valid]
        self.budget.spend_checks(kinematics.effort.checks, kinematics.effort.calls)
        self.budget.spend(math.ceil(self.settings.ik_work * kinematics.effort.steps))
        for row in rows[np.argsort(travel[rows], kind="stable")][: self.settings.end_tries].tolist():
            if not self.budget.left():
                return False
            moved = q[row]
            if self.clear(one, before, moved) and self.clear(two, moved, after):
                one.waypoints = np.vstack([one.waypoints[:-1], moved[None]])
                two.waypoints = np.vstack([moved[None], two.waypoints[1:]])
                return True
        return False

    def end_seeds(self, before: np.ndarray, after: np.ndarray, end: np.ndarray) -> np.ndarray:
        """Seeds of :meth:`move_end`'s inverse kinematics: :attr:`ImproveSettings.end_line_seeds` points evenly
        along the straight line ``before -> after`` (its ends included), and as many drawn around them
        (:attr:`ImproveSettings.end_spread_rad` per joint, from the improvement's restarts generator), and the end
        itself drawn around."""
        line = np.linspace(0.0, 1.0, self.settings.end_line_seeds)[:, None]
        points = np.vstack([before + line * (after - before), end[None]])
        drawn = points + self.restarts.normal(0.0, self.settings.end_spread_rad, size=points.shape)
        return np.vstack([points, drawn])

    def resolve(self, first: int, stop: int) -> tuple[bool, int | None]:
        """Pieces ``first`` to ``stop`` - 1 with their tip's path kept and their postures solved again: the points
        of each move (:attr:`ImproveSettings.resolve_step_m` of sweep apart) in turn by inverse kinematics for their
        tip pose, seeded with the configuration solved before (:meth:`chained`), so the joints move as little as the
        tip's path needs (the postures the first plan wandered through without moving the tip are left out); when
        pieces follow, the last piece's seeds are pulled back towards the first plan's postures, all the way at its
        end, where the next piece starts. A move's solved end is joined straight when that is clear, else through its
        points; a point not joined clear is pulled towards the first plan's posture there (:meth:`pulled`). Kept when
        every move is clear and the plan better. Whether it was, and the piece that could not be joined (None when
        none, or the work ran out)."""
        robot = self.world.robot
        reach = np.cumsum(robot.link_lengths[::-1])[::-1]  # R_j: the links from joint j on
        previous = self.pieces[first].waypoints[0]
        new: list[_Piece] = []
        for index in range(first, stop):
            piece = self.pieces[index]
            w = piece.waypoints
            counts = [
                max(1, math.ceil(float(np.abs(b - a) @ reach) / self.settings.resolve_step_m))
                for a, b in itertools.pairwise(w)
            ]
            back = np.concatenate([np.arange(1, c + 1) / c for c in counts]) if counts else np.zeros(0)
            if index == stop - 1 and stop < len(self.pieces):
                back = np.arange(1, len(back) + 1) / max(1, len(back))  # back to the first plan's end posture
            else:
                back = np.zeros(len(back))
            path = [previous]
            offset = 0
            floor = 0.0  # pulled once towards the first plan's postures, the piece's later points stay as near
            for a, b, count in zip(w[:-1], w[1:], counts, strict=True):
                old = a + np.linspace(0.0, 1.0, count + 1)[1:, None] * (b - a)
                tips = tip_poses(robot, old)
                pull = np.maximum(back[offset : offset + count], floor)
                offset += count
                if not self.budget.left():
                    return False, None
                chain = self.chained(path[-1], tips, old, pull)
                if len(chain) == count and self.clear(piece, path[-1], chain[-1]):
                    path.append(chain[-1])
                    continue
                done = 0
                while done < count:
                    if not self.budget.left():
                        return False, None
                    window = slice(done, done + self.settings.resolve_window)
                    chain = self.chained(path[-1], tips[window], old[window], np.maximum(pull[window], floor))
                    clear = np.zeros(0, dtype=bool)
                    if len(chain):
                        clear = self.moves_clear(piece, np.array([path[-1], *chain[:-1]]), chain, every=True)
                    joined = int(np.argmin(clear)) if not clear.all() else len(clear)
                    path.extend(chain[:joined])
                    done += joined
                    if done == count or joined == len(tips[window]):
                        continue
                    pulled = self.pulled(piece, path[-1], tips[done], old[done])
                    if pulled is None:
                        return False, index
                    floor = max(floor, pulled[1])
                    path.append(pulled[0])
                    done += 1
            previous = path[-1]
            waypoints = pruned_path(_without_repeats(path))
            new.append(_Piece(piece.kind, piece.grasp, waypoints, piece.start_pose, piece.grasp_rel))
        candidate = [*self.pieces[:first], *new, *self.pieces[stop:]]
        if not self.better(_score(self.pieces), _score(candidate)):
            return False, None
        self.pieces = candidate
        self.reserve()
        return True, None

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
                tolerance_m=0.1 * self.settings.end_error_m,
            )
            steps += solution.steps + 1
            if solution.error[0] > self.settings.end_error_m:
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
            tolerance_m=0.1 * self.settings.end_error_m,
        )
        self.budget.spend(math.ceil(self.settings.ik_work * (solution.steps + len(seeds))))
        for k in np.flatnonzero(solution.error <= self.settings.end_error_m).tolist():
            if self.clear(piece, q, solution.q[k]):
                return solution.q[k], float(shares[k, 0])
        if self.clear(piece, q, old):
            return old, 1.0
        return None
