"""Proposals checked (step 2 of :mod:`clew_ros.planar.improve`): each move of a proposal of
:func:`clew_ros.planar.regrasp.propose` checked continuously, straight or through a detour, or routed by
RRT-Connect (and the lattice) when it looked blocked; a proposal kept when it makes the plan better."""

from __future__ import annotations

import math

import numpy as np

from clew_ros.core.improve import RoutingShare, joint_travel, plan_score
from clew_ros.planar.connect import rrt_connect, shortened
from clew_ros.planar.improve.lattice import _LatticeUse
from clew_ros.planar.improve.pieces import _Piece
from clew_ros.planar.improve.shortcuts import _Shortcutting
from clew_ros.planar.kinematics import relative, tip_poses
from clew_ros.planar.lattice import lattice_step
from clew_ros.planar.regrasp import ROUTES, Proposal, route_waypoints


def _alike(a: Proposal, b: Proposal, alike_rad: float) -> bool:
    """Whether two proposals take the same grasps at key configurations within ``alike_rad``
    (rad) of each other."""
    return a.grasps == b.grasps and float(np.max(np.abs(a.keys - b.keys))) <= alike_rad


class _Proposals(_Shortcutting, _LatticeUse):
    """The checking of proposals: their moves routed and checked continuously."""

    def try_proposals(self, proposals: list[Proposal], kept: int, placement: np.ndarray, *, routed: bool) -> bool:
        """Check ``proposals`` (after the first ``kept`` pieces) in their order: if ``routed``, those with a move that
        looked blocked (routed by :meth:`connect`), else the others. Each whose moves are clear and that makes the plan
        better replaces the plan's end, and the later ones must beat it. At most :attr:`ImproveSettings.rebuild_tries`
        failures among those whose moves all looked clear and :attr:`ImproveSettings.blocked_tries` among the others.
        Returns whether the plan got better."""
        before = self.pieces[:kept]
        transfers = sum(p.kind == "transfer" for p in before)
        travel_before = joint_travel([p.waypoints for p in before])
        failed: list[Proposal] = []
        failures = {False: 0, True: 0}  # by whether the proposal looked blocked
        limits = {False: self.settings.rebuild_tries, True: self.settings.blocked_tries}
        better = False
        for proposal in proposals:
            if (proposal.blocked > 0) != routed:
                continue  # those that looked clear first, those with a blocked move to route in a call of their own
            score = plan_score(self.pieces)
            if not self.better(score, (transfers + len(proposal.grasps), travel_before + proposal.travel, 0)):
                continue
            if any(_alike(proposal, other, self.settings.alike_rad) for other in failed) or self.known_blocked(
                proposal
            ):
                continue  # as good as one that failed: try something else
            blocked = proposal.blocked > 0
            if blocked and self.routing_gave_nothing():
                failures[blocked] = limits[blocked]  # routing around blocked moves never worked here
            if failures[blocked] >= limits[blocked]:
                break
            if not self.budget.left(self.rebuild_share):
                break
            self.routings = 0
            fewer = transfers + len(proposal.grasps) < score[0]  # then any travel makes the plan better
            slack = math.inf if fewer else score[1] - travel_before - proposal.travel
            tail = self.checked_tail(proposal, placement, slack)
            # compared where it could end on the goal, as the plan's last transfer
            ended_sooner = tail is not None and self.goal_shortcut(tail[-1])
            accepted = tail is not None and self.better(score, plan_score(before + tail))
            if self.routings:
                self.connected[accepted] += 1
            if tail is not None and accepted:
                self.shortcuts += ended_sooner  # a straight move accepted only with the proposal
                self.pieces = before + tail
                self.reserve()
                self.rebuilt += 1
                better = True
                continue
            failed.append(proposal)
            failures[blocked] += 1
        return better

    def routing_gave_nothing(self) -> bool:
        """Whether routing blocked moves looks hopeless here (a cluttered world): no routed proposal made the plan
        better, and :attr:`ImproveSettings.connect_probes` routings found no path or
        :attr:`ImproveSettings.routed_probes` routed proposals did not
        (a routing found no path or one too long, or another move stayed blocked)."""
        return self.connected[1] == 0 and (
            self.connect_failed >= self.settings.connect_probes or self.connected[0] >= self.settings.routed_probes
        )

    def proposal_moves(self, proposal: Proposal) -> list[tuple[str, np.ndarray, np.ndarray]]:
        """``(kind, start, end)`` of each move of ``proposal`` (a transit, then a transfer, ...)."""
        keys = proposal.keys
        return [("transit" if k % 2 == 0 else "transfer", keys[k], keys[k + 1]) for k in range(len(keys) - 1)]

    def known_blocked(self, proposal: Proposal) -> bool:
        """Whether a move of ``proposal`` is like one found blocked before (:attr:`ImproveSettings.move_alike_rad`)."""
        return any(
            kind == other_kind
            and float(np.max(np.abs(a - other_a))) <= self.settings.move_alike_rad
            and float(np.max(np.abs(b - other_b))) <= self.settings.move_alike_rad
            for kind, a, b in self.proposal_moves(proposal)
            for other_kind, other_a, other_b in self.blocked_moves
        )

    def checked_tail(self, proposal: Proposal, placement: np.ndarray, slack: float = math.inf) -> list[_Piece] | None:
        """``proposal``'s moves as pieces, the object starting at ``placement``, each move checked
        continuously (:meth:`route`), the shortest first (they are the cheapest to check, and the ones
        near the object, leaving or taking a grasp, are short); ``None`` if a move stays blocked. ``slack``:
        the joint travel (rad) the moves may add to the proposal's straight moves for it to still make the plan
        better; each move taken longer than straight uses some, and what is left bounds the lattice's path of
        a move routed around what blocks it (:meth:`connect`)."""
        pieces: list[_Piece] = []
        keys = proposal.keys
        pose = np.asarray(placement, dtype=float)
        for step, grasp in enumerate(proposal.grasps):
            start, hold, end = keys[2 * step], keys[2 * step + 1], keys[2 * step + 2]
            grasp_rel = relative(tip_poses(self.world.robot, hold[None])[0], pose)  # as plan.replay computes it
            transfer = _Piece("transfer", grasp, np.array([hold, end]), pose, grasp_rel)
            pieces += [_Piece("transit", None, np.array([start, hold]), pose, None), transfer]
            pose = transfer.end_pose(self.world)
        for index in np.argsort([joint_travel([p.waypoints]) for p in pieces], kind="stable"):
            piece = pieces[index]
            a, b = piece.waypoints[0], piece.waypoints[-1]
            path = self.route(piece, a, b, proposal.routes[index])
            if path is None and proposal.routes[index] < 0 and not self.budget.stop():
                path = self.connect(piece, a, b, float(np.abs(b - a).sum()) + slack)
                self.routings += 1
                self.connect_failed += path is None
            if path is None:
                self.blocked_moves.append((piece.kind, a, b))
                return None
            piece.waypoints = path
            slack -= joint_travel([path]) - float(np.abs(b - a).sum())
        return pieces

    def connect(self, piece: _Piece, a: np.ndarray, b: np.ndarray, longest: float = math.inf) -> np.ndarray | None:
        """A path from ``a`` to ``b`` in ``piece``'s mode around what blocks the straight move: RRT-Connect
        (:func:`clew_ros.planar.connect.rrt_connect`, each extension checked continuously), then shortened greedily. At
        most :attr:`ImproveSettings.connect_steps` rounds and :attr:`ImproveSettings.connect_share` of the budget;
        ``None`` when the trees did not meet. On an arm with a lattice
        (:func:`clew_ros.planar.lattice.lattice_step`), the
        lattice's shortest path (:meth:`lattice`) replaces it when it is shorter than both it and ``longest`` (rad: the
        proposal's bound), within :attr:`ImproveSettings.connect_share` of the budget more."""
        limit = self.budget.spent + self.settings.connect_share * self.budget.total

        def clear(p: np.ndarray, q: np.ndarray) -> bool:
            return self.clear(piece, p, q)

        path = rrt_connect(
            self.world,
            a,
            np.asarray(b, dtype=float)[None],
            self.ctx.rng,
            object_pose=piece.start_pose,
            grasp_rel=piece.grasp_rel,
            min_margin=self.min_margin,
            rounds=self.settings.connect_steps,
            budget=RoutingShare(self.budget, limit),
            settings=self.settings.connect,
            moves=self.settings.moves,
        )
        if path is None:
            return None
        path = shortened(clear, path, lambda: self.budget.spent > limit)
        if lattice_step(self.world, self.settings.lattice) is None or self.budget.stop():
            return path
        bound = min(longest, joint_travel([path])) - self.settings.travel_eps
        shortest = self.lattice(
            piece, a, b, bound, min(self.settings.connect_share * self.budget.total, self.budget.units_left())
        )
        return path if shortest is None else shortest

    def route(self, piece: _Piece, a: np.ndarray, b: np.ndarray, hint: int) -> np.ndarray | None:
        """Waypoints from ``a`` to ``b`` in ``piece``'s mode, each move checked continuously: the ways of
        :data:`clew_ros.planar.regrasp.ROUTES` (the one that looked clear, ``hint``, first; all as long in
        joint travel), then through a configuration drawn inside the box ``[a, b]`` (as long too), then
        through one drawn around the middle (:attr:`ImproveSettings.detours` tries each); ``None`` when none is
        clear."""
        ways = [hint] if hint >= 0 else []
        for way in [*ways, *(w for w in range(len(ROUTES)) if w != hint)]:
            path = route_waypoints(a, b, way)
            if self.budget.stop():
                return None
            if self.path_clear(piece, path):
                return path
        n = len(a)
        lower, upper = self.world.robot.joint_lower, self.world.robot.joint_upper
        spread = 0.25 * float(np.max(np.abs(b - a))) + 0.1
        for monotone in (True, False):
            for _ in range(self.settings.detours):
                if self.budget.stop():
                    return None
                if monotone:
                    via = a + self.ctx.rng.uniform(0.0, 1.0, size=n) * (b - a)
                else:
                    via = np.clip(0.5 * (a + b) + self.ctx.rng.normal(0.0, spread, size=n), lower, upper)
                if self.path_clear(piece, np.array([a, via, b])):
                    return np.array([a, via, b])
        return None
