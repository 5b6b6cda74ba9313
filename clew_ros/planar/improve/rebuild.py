"""Rebuilding the manipulation (step 2 of :mod:`clew_ros.planar.improve`): from each placement of the plan,
proposals of straight moves through other grasps, postures and release placements; and fewer transfers (step
4): SEARCH_TRANSFER from the start of a transfer straight to the goal."""

from __future__ import annotations

import math

import numpy as np

from clew_ros.core.improve import plan_score, pruned_path
from clew_ros.planar.improve.pieces import _Piece
from clew_ros.planar.improve.proposals import _Proposals
from clew_ros.planar.regrasp import PlanHints, Proposal, ProposalLimits, propose
from clew_ros.planar.search import search_transfer


class _Rebuilding(_Proposals):
    """The rebuilding and fewer-transfers stages of the improver."""

    def cuts(self) -> list[tuple[int, np.ndarray, np.ndarray]]:
        """Where the plan could be finished differently: ``(kept, configuration, placement)`` for the start
        (no piece kept) and after each transfer but one ending at the goal (the pieces through it kept)."""
        cuts = [(0, self.pieces[0].waypoints[0], np.asarray(self.world.object.initial, dtype=float))]
        for index, piece in enumerate(self.pieces[:-1]):
            if piece.kind == "transfer":
                cuts.append((index + 1, piece.waypoints[-1], piece.end_pose(self.world)))
        return cuts

    def rebuild(self) -> None:
        """Passes of :meth:`rebuild_pass` while they find better plans (or the share of the budget lasts);
        none after a pass that found nothing and met a placement from which every proposal looked blocked."""
        idle = 0
        while idle < self.settings.rebuild_idle_passes and self.budget.left(self.rebuild_share):
            better, blocked = self.rebuild_pass()
            if blocked and not better:
                return
            idle = 0 if better else idle + 1

    def rebuild_pass(self) -> tuple[bool, bool]:
        """From each placement of the plan, earliest first: finish with straight moves through other grasps,
        postures and release placements (:func:`clew_ros.planar.regrasp.propose`) when that is better.
        Proposals with a move that looked blocked are checked too, fewer (:meth:`try_proposals`); a placement
        from which every proposal looked blocked and none made the plan better ends the pass. Returns whether
        the plan got better, and whether such a placement ended the pass."""
        position = 0
        better = False
        while self.budget.left(self.rebuild_share):
            cuts = [cut for cut in self.cuts() if cut[0] >= position]
            if not cuts:
                break
            kept, configuration, placement = cuts[0]
            position = kept + 1
            before = self.pieces[:kept]
            transfers = sum(p.kind == "transfer" for p in before)
            score = plan_score(self.pieces)
            if transfers + 1 > score[0]:
                break
            after = self.pieces[kept:]
            own = [(int(p.grasp), p.waypoints[0]) for p in after[1:2] if p.grasp is not None]
            hints = np.array([p.waypoints[-1] for p in after[:-1] if p.kind == "transfer"]).reshape(
                -1, len(configuration)
            )
            found, blocked = False, True
            tried: list[Proposal] = []
            for grasps in (1, 2):  # a plan with fewer transfers is better: two only when none with one worked
                if found or transfers + grasps > score[0] or not self.budget.left(self.rebuild_share):
                    break
                proposals, effort = propose(
                    self.world,
                    configuration,
                    placement,
                    self.goal,
                    self.ctx.rng,
                    hints=PlanHints(tuple(own), hints, self.pieces[-1].waypoints[-1:]),
                    one_transfer=grasps == 1,
                    two_transfers=grasps == 2,
                    margin_m=self.min_margin,
                    limits=ProposalLimits(
                        self.budget.stop, self.proposal_checks(), self.settings.ik_work / self.budget.check_work
                    ),
                    restarts=self.restarts,
                    settings=self.settings.regrasp,
                )
                self.budget.spend_checks(effort.checks, effort.calls)
                self.budget.spend(
                    self.settings.move_call_work * effort.screens
                )  # the Python around each compiled screen
                self.budget.spend(math.ceil(self.settings.ik_work * effort.steps))
                found = self.try_proposals(proposals, kept, placement, routed=False)
                blocked &= bool(proposals) and all(p.blocked for p in proposals)
                tried += proposals
            if tried:  # routing is dear: only after every proposal that looked clear, for those still better
                tried.sort(key=lambda p: (len(p.grasps), p.rank))  # fewer transfers always win: those first
                found |= self.try_proposals(tried, kept, placement, routed=True)
            better |= found
            if blocked and not found:
                return better, True  # every way from here looked blocked: cluttered, leave the budget to shortcuts
        return better, False

    def proposal_checks(self) -> int:
        """Configurations :func:`clew_ros.planar.regrasp.propose` may check (its inverse-kinematics steps count
        too): :attr:`ImproveSettings.propose_share` of what is left of the rebuilding's share of the budget."""
        left = self.rebuild_share * self.budget.total - self.budget.spent
        return max(0, int(self.settings.propose_share * left / self.budget.check_work))

    def fewer_transfers(self) -> None:
        """From the start of each transfer but the last, earliest first: carry the object to the goal. An
        attempt starts only when the work it may take (every individual of every round) fits in
        :attr:`ImproveSettings.transfer_share` of the budget."""
        planner = self.ctx.settings
        attempt = self.settings.evaluation_work * planner.population * planner.generations * planner.search_rounds
        transfers = [i for i, p in enumerate(self.pieces) if p.kind == "transfer"]
        for index in transfers[:-1]:
            if (
                not self.budget.left(self.settings.transfer_share)
                or self.budget.spent + attempt > self.settings.transfer_share * self.budget.total
            ):
                return
            piece = self.pieces[index]
            assert piece.grasp_rel is not None
            before = self.ctx.counters.evaluations
            result = search_transfer(self.world, self.ctx, piece.waypoints[0], piece.grasp_rel, self.goal, joins=False)
            self.budget.spend(self.settings.evaluation_work * (self.ctx.counters.evaluations - before))
            if not result.success:
                continue
            carried = _Piece("transfer", piece.grasp, pruned_path(result.waypoints), piece.start_pose, piece.grasp_rel)
            candidate = [*self.pieces[:index], carried]
            if self.better(plan_score(self.pieces), plan_score(candidate)):
                self.pieces = candidate
                self.reserve()
                return
