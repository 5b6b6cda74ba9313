"""Lattice use (steps 3 and 6 of :mod:`clew_ros.planar.improve`, on an arm of three joints): a move routed on the
joint-space lattice, one regrasp placed where the lattice finds it shortest, and the first grasp searched again
(:mod:`clew_ros.planar.lattice`)."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from clew_ros.core.improve import joint_travel, plan_score, pruned_path
from clew_ros.planar.improve.base import _ImproverBase
from clew_ros.planar.improve.pieces import _Piece, _span_key
from clew_ros.planar.lattice import (
    KnownNodes,
    LatticeWork,
    grasp_configurations,
    lattice_regrasp,
    lattice_route,
    lattice_step,
)


class _LatticeUse(_ImproverBase):
    """The improver's searches on the joint-space lattice."""

    def lattice(
        self, piece: _Piece, a: np.ndarray, b: np.ndarray, shorter_than: float, allowance: float
    ) -> np.ndarray | None:
        """The lattice's shortest path from ``a`` to ``b`` in ``piece``'s mode, shorter than ``shorter_than``
        rad, within ``allowance`` work units (:func:`clew_ros.planar.lattice.lattice_route`, the nodes checked in
        this mode before not checked again), without its collinear waypoints; ``None`` if none was found."""
        known = self.known(piece.kind, piece.start_pose if piece.grasp_rel is None else piece.grasp_rel)
        path = lattice_route(
            self.world,
            a,
            b,
            object_pose=piece.start_pose,
            grasp_rel=piece.grasp_rel,
            min_margin=self.min_margin,
            shorter_than=shorter_than,
            work=LatticeWork(self.budget, allowance, self.settings.expansion_work),
            nodes_known=known,
            settings=self.settings.lattice,
            moves=self.settings.moves,
        )
        return None if path is None else pruned_path(path)

    def known(self, kind: str, mode: np.ndarray) -> KnownNodes:
        """The lattice nodes checked so far in one mode: a transit's object pose or a transfer's grasp."""
        return self.known_nodes.setdefault(kind.encode() + np.asarray(mode, dtype=float).tobytes(), KnownNodes())

    def lattice_regrasps(self) -> bool:
        """On a 3-joint arm: from the start of a transfer to the end of a later one, one regrasp placed where the
        lattice finds it shortest (:func:`clew_ros.planar.lattice.lattice_regrasp`), replacing every transfer and
        transit between, when that makes the plan better. The longest spans (most pieces) first; each search within
        :attr:`ImproveSettings.regrasp_share` of the budget (its last round may run past it), and new ones only while
        less than :attr:`ImproveSettings.regrasp_total_share` of it is spent, the final check's reserve counted. Returns
        whether the plan changed."""
        if self.world.robot.dof != 3 or lattice_step(self.world, self.settings.lattice) is None:
            return False
        changed = False
        while True:
            transfers = [i for i, p in enumerate(self.pieces) if p.kind == "transfer"]
            spans = sorted(
                ((i, j) for k, i in enumerate(transfers) for j in transfers[k + 1 :]), key=lambda s: (s[0] - s[1], s[0])
            )
            for i, j in spans:
                if not self.budget.left(self.settings.regrasp_total_share):
                    return changed
                one, two = self.pieces[i], self.pieces[j]
                key = _span_key(one, two, j - i)
                if key in self.regrasps_tried or one.grasp_rel is None or two.grasp_rel is None:
                    continue
                self.regrasps_tried.add(key)
                fewer = sum(p.kind == "transfer" for p in self.pieces[i : j + 1]) > 2
                bound = math.inf if fewer else joint_travel([p.waypoints for p in self.pieces[i : j + 1]])
                allowance = min(self.settings.regrasp_share * self.budget.total, self.budget.units_left())
                regrasped = self.regrasped(one, two, bound, allowance)
                if regrasped is None:
                    continue
                if self.take([*self.pieces[:i], *regrasped, *self.pieces[j + 1 :]], regrasped):
                    changed = True
                    break  # the spans of the new plan
            else:
                return changed

    def lattice_first_grasps(self) -> bool:
        """On a 3-joint arm: the plan's transit to its first grasp routed again on the lattice
        (:meth:`first_transit`), then the plan from its start to the end of its last transfer again with another first
        grasp (:func:`clew_ros.planar.lattice.grasp_configurations` at the start): the transit to it routed on the
        lattice, then one regrasp on the lattice as :meth:`lattice_regrasps` places it (a plan of one transfer is
        left alone: two are never better). The grasps whose joint travel from the start and on to the last
        transfer's end is least first, those only that come below the plan's travel there (any, when it has more
        than two transfers); each within :attr:`ImproveSettings.regrasp_share` of the budget, none started once
        :attr:`ImproveSettings.regrasp_total_share` is spent. Returns whether the plan changed."""
        pieces = self.pieces
        transfers = [i for i, p in enumerate(pieces) if p.kind == "transfer"]
        if (
            self.world.robot.dof != 3
            or lattice_step(self.world, self.settings.lattice) is None
            or len(transfers) < 2  # one transfer: two, with a regrasp, are never better
            or pieces[0].kind != "transit"
            or transfers[0] != 1
            or pieces[transfers[-1]].grasp_rel is None
            or not self.budget.left(self.settings.regrasp_total_share)
        ):
            return False
        changed = self.first_transit()
        pieces = self.pieces
        j = transfers[-1]
        start, last, two = pieces[0].waypoints[0], pieces[j].waypoints[-1], pieces[j]
        assert two.grasp_rel is not None  # checked above
        span = joint_travel([p.waypoints for p in pieces[: j + 1]])
        fewer = len(transfers) > 2  # then any way with 2 is better, however long
        q, which, rels = grasp_configurations(
            self.world, pieces[0].start_pose, start, self.settings.first_grasp_approaches
        )
        on = np.abs(last - q).sum(axis=1)
        bound = np.abs(q - start).sum(axis=1) + on
        hopeful = np.flatnonzero(bound < (math.inf if fewer else span))
        if not len(hopeful):
            return changed
        hopeful = hopeful[self.moves_clear(pieces[0], q[hopeful], q[hopeful])]  # taking the object: clear
        for k in hopeful[np.argsort(bound[hopeful], kind="stable")].tolist():
            if not self.budget.left(self.settings.regrasp_total_share):
                return changed
            key = b"first" + q[k].tobytes() + last.tobytes()
            if key in self.regrasps_tried:
                continue
            self.regrasps_tried.add(key)
            allowance = min(self.settings.regrasp_share * self.budget.total, self.budget.units_left())
            limit = self.budget.spent + allowance
            transit = self.lattice(pieces[0], start, q[k], math.inf if fewer else span - on[k], allowance)
            if transit is None:
                continue
            one = _Piece("transfer", int(which[k]), q[k][None], pieces[0].start_pose, rels[k])
            shorter = math.inf if fewer else span - joint_travel([transit])
            regrasped = self.regrasped(one, two, shorter, limit - self.budget.spent)
            taken = _Piece("transit", None, transit, pieces[0].start_pose, None)
            if regrasped is not None and self.take([taken, *regrasped, *pieces[j + 1 :]], regrasped):
                return True
        return changed

    def regrasped(
        self, one: _Piece, two: _Piece, shorter_than: float, allowance: float
    ) -> tuple[_Piece, _Piece, _Piece] | None:
        """From where transfer ``one`` starts (its grasp) to where transfer ``two`` ends, one regrasp placed on the
        lattice (:func:`clew_ros.planar.lattice.lattice_regrasp`) within ``allowance`` work units, shorter than
        ``shorter_than`` rad: the transfer, the put-down transit and the transfer, or ``None``."""
        assert one.grasp_rel is not None  # transfers
        assert two.grasp_rel is not None
        found = lattice_regrasp(
            self.world,
            one.waypoints[0],
            one.grasp_rel,
            two.waypoints[-1],
            two.grasp_rel,
            min_margin=self.min_margin,
            shorter_than=shorter_than,
            work=LatticeWork(self.budget, allowance, self.settings.flood_work, self.settings.release_work),
            screen_step_rad=self.settings.regrasp.screen_step_rad,
            nodes_known=(self.known("transfer", one.grasp_rel), self.known("transfer", two.grasp_rel)),
            settings=self.settings.lattice,
            moves=self.settings.moves,
        )
        if found is None:
            return None
        carried = _Piece("transfer", one.grasp, pruned_path(found[0]), one.start_pose, one.grasp_rel)
        pose = carried.end_pose(self.world)
        put_down = _Piece("transit", None, found[1], pose, None)
        return carried, put_down, _Piece("transfer", two.grasp, pruned_path(found[2]), pose, two.grasp_rel)

    def take(self, candidate: list[_Piece], regrasped: tuple[_Piece, _Piece, _Piece]) -> bool:
        """Make ``candidate``, a plan holding the pieces ``regrasped`` placed on the lattice, the plan if it is
        better; their span is then marked searched (a search from the same ends would find them again)."""
        if not self.better(plan_score(self.pieces), plan_score(candidate)):
            return False
        self.pieces = candidate
        self.regrasps_tried.add(_span_key(regrasped[0], regrasped[2], 2))
        self.reserve()
        self.rebuilt += 1
        return True

    def first_transit(self) -> bool:
        """The plan's first transit (to its first grasp) routed again on the lattice, kept when shorter."""
        first = self.pieces[0]
        key = b"transit" + first.waypoints[0].tobytes() + first.waypoints[-1].tobytes()
        if key in self.regrasps_tried:
            return False
        self.regrasps_tried.add(key)
        travel = joint_travel([first.waypoints])
        allowance = min(self.settings.regrasp_share * self.budget.total, self.budget.units_left())
        path = self.lattice(first, first.waypoints[0], first.waypoints[-1], travel, allowance)
        if path is None or joint_travel([path]) >= travel:
            return False
        self.pieces = [replace(first, waypoints=path), *self.pieces[1:]]
        self.reserve()
        return True
