"""EXPLORE: place the next landmark as far as possible from the existing ones (paper 1.2, 1.3.4).

The search space is the paper's ``[landmark] x [grasp] x R^(k n)``: a
candidate is a landmark ``L_i``, a grasp ``g_j`` reached from it by
SEARCH_TRANSIT (or ``L_i``'s own grasp, kept without a transit), and the genes
of a transfer Manhattan path. The genetic algorithm maximises the distance
from the transfer's end to the nearest landmark, evaluating the transfers of a
whole population in one batch (each individual has its own start and grasp).
Transits are computed once per (landmark, grasp) pair and cached; the new
pairs of one step are searched together, one island of a batch each.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass
from types import MappingProxyType
from typing import Any

import numpy as np

from clew_ros.core.genetic import minimize
from clew_ros.core.manhattan import ManhattanPaths
from clew_ros.core.space import Approach, Mode, PlanningContext, TransitRequest
from clew_ros.core.tree import Landmark, LandmarkTree

__all__ = ["Candidate", "Exploration", "Explorer"]


@dataclass
class Candidate:
    """A transit's end: the configuration ``start`` holding ``grasp`` at landmark ``parent``'s placement, where
    a transfer (EXPLORE's or SEARCH's) starts."""

    parent: int
    grasp: int
    start: np.ndarray  # (n,) joints holding the grasp
    grasp_rel: np.ndarray  # (p,) the object's pose in the tool's frame
    transit: np.ndarray | None  # None: the parent's grasp is kept


@dataclass
class Exploration:
    """One EXPLORE step's result: the new landmark's fields and its distance to the others."""

    fields: dict[str, Any]  # LandmarkTree.add's keywords
    distance: float
    #: whether every (landmark, grasp) pair's transit had been searched when this step chose: EXPLORE's
    #: search covered the landmark space, so ``distance`` is the paper's epsilon_n
    covered: bool = True
    #: whether the new landmark's transfer moved the object (by ``SearchSettings.moved_m`` at least, as
    #: :meth:`~clew_ros.core.space.Space.goal_distance` measures it): a step whose best path could not
    #: (a spatial transfer that found no stable placement to end at stays where it started) has found
    #: nothing of the reachable space, so its ``distance`` proves nothing
    moved: bool = True


class Explorer:
    """EXPLORE with its transit cache, for one planning run."""

    def __init__(self, ctx: PlanningContext, tree: LandmarkTree) -> None:
        self.ctx = ctx
        self.tree = tree
        self._transits: dict[tuple[int, int], Candidate | None] = {}
        self._aimed: dict[tuple[int, int, bytes], Candidate | None] = {}  # SEARCH's transits aimed at cells
        #: transit searches run so far (retries of failed pairs included)
        self.transit_searches = 0

    @property
    def transits(self) -> Mapping[tuple[int, int], Candidate | None]:
        """The transits searched so far, by ``(landmark id, grasp)`` (``None``: none found), read only."""
        return MappingProxyType(self._transits)

    def candidate(self, landmark_id: int, grasp: int, approach: Approach | None = None) -> Candidate | None:
        """The single manipulation path's transit part from a landmark to a grasp (cached).

        With ``approach`` (the space's aim of SEARCH's regrasp towards the
        goal, :meth:`~clew_ros.core.space.RegraspAims.aim`) a cached transit, or the landmark's own
        grasp, is used only if its approach is allowed; otherwise a transit
        aiming at those cells is searched once per (landmark, grasp, cells), and
        kept for EXPLORE if the pair had no transit yet (never for the
        landmark's own grasp, which EXPLORE takes without a transit).
        """
        key = (landmark_id, grasp)
        landmark = self.tree[landmark_id]
        if landmark.grasp == grasp and landmark.grasp_rel is not None:  # (every landmark but the root holds one)
            own = self._transits.setdefault(
                key, Candidate(landmark_id, grasp, landmark.joints, landmark.grasp_rel, None)
            )
            if approach is None or self.ctx.space.approach_allows(approach, landmark.grasp_rel):
                return own
            return self._aimed_transit(landmark, grasp, approach)  # the same grasp taken again, another approach
        if approach is None:
            if key not in self._transits:
                self._transits[key] = self._transit(landmark, grasp, None)
            return self._transits[key]
        cached = self._transits.get(key)
        if cached is not None and self.ctx.space.approach_allows(approach, cached.grasp_rel):
            return cached
        found = self._aimed_transit(landmark, grasp, approach)
        if found is not None and cached is None:
            self._transits[key] = found
        return found

    def _aimed_transit(self, landmark: Landmark, grasp: int, approach: Approach) -> Candidate | None:
        """The transit from ``landmark`` to ``grasp`` aimed at ``approach``, searched once per approach."""
        key = (landmark.id, grasp, np.packbits(np.asarray(approach)).tobytes())
        if key not in self._aimed:
            self._aimed[key] = self._transit(landmark, grasp, approach)
        return self._aimed[key]

    def start_candidates(self) -> list[Candidate]:
        """The transits from the start (the root landmark) to every grasp at the object's initial placement,
        searched together and cached for EXPLORE; those found, by grasp."""
        pairs = [(0, g) for g in range(self.ctx.space.grasp_count)]
        self._search_transits([p for p in pairs if p not in self._transits])
        return [c for c in (self._transits.get(p) for p in pairs) if c is not None]

    def forget_failures(self) -> None:
        """Drop the failed transits from the cache, so that EXPLORE tries those pairs again (the GA is
        stochastic: a transit that failed once may succeed with other draws)."""
        self._transits = {key: found for key, found in self._transits.items() if found is not None}

    def _transit(self, landmark: Landmark, grasp: int, approach: Approach | None) -> Candidate | None:
        return self._transits_to([(landmark, grasp)], approach)[0]

    def _search_transits(self, pairs: list[tuple[int, int]]) -> None:
        """The transits of (landmark, grasp) ``pairs`` not yet cached, searched together (one island
        each) and cached."""
        pairs = [(i, g) for i, g in pairs if self.tree[i].grasp != g]
        found = self._transits_to([(self.tree[i], g) for i, g in pairs], None)
        self._transits.update(zip(pairs, found, strict=True))

    def _transits_to(self, pairs: list[tuple[Landmark, int]], approach: Approach | None) -> list[Candidate | None]:
        """SEARCH_TRANSIT from each landmark to its grasp, all at once: the candidates, None where it failed."""
        self.transit_searches += len(pairs)
        results = self.ctx.space.search_transits(
            self.ctx,
            [TransitRequest(landmark.joints, landmark.object_pose, grasp, approach) for landmark, grasp in pairs],
        )
        return [
            Candidate(landmark.id, grasp, result.waypoints[-1], result.grasp_rel, result.waypoints)
            if result.success and result.grasp_rel is not None
            else None
            for (landmark, grasp), result in zip(pairs, results, strict=True)
        ]

    def explore(self) -> Exploration | None:
        """Place one new landmark; ``None`` when no candidate transit succeeded."""
        ctx = self.ctx
        space = ctx.space
        grasps = space.grasp_count
        pairs = [(i, g) for i in range(len(self.tree)) for g in range(grasps)]
        fresh = [p for p in pairs if p not in self._transits]
        known = [p for p in pairs if self._transits.get(p) is not None]
        wanted = ctx.settings.explore_candidates
        order = ctx.rng.permutation(len(fresh))
        chosen = [fresh[i] for i in order[:wanted]]
        # every pair with a transit stays in the pool, whatever its landmark's age: the GA's category
        # gene chooses among them (the paper's [landmark] x [grasp] dimension)
        chosen += known
        self._search_transits([p for p in chosen if p not in self._transits])
        if ctx.termination():
            return None
        candidates = [c for c in (self.candidate(landmark_id, grasp) for landmark_id, grasp in chosen) if c is not None]
        if not candidates:
            return None

        n = space.dof
        k = ctx.settings.manhattan_order
        starts = np.array([c.start for c in candidates])
        rels = np.array([c.grasp_rel for c in candidates])
        features = space.landmark_features(self.tree.joints(), self.tree.object_poses(), ctx.settings.joint_weight)

        def decode(population: np.ndarray) -> tuple[np.ndarray, ManhattanPaths]:
            index = np.clip(population[:, 0].astype(int), 0, len(candidates) - 1)
            genes = population[:, 1:].reshape(-1, k, n)
            return index, ctx.manhattan(starts[index], genes, Mode.held(rels[index]))

        def evaluate(population: np.ndarray) -> np.ndarray:
            _, paths = decode(population)
            ctx.counters.evaluations += len(population)
            ends = space.landmark_features(paths.final, paths.object_poses, ctx.settings.joint_weight)
            nearest: np.ndarray = np.min(np.linalg.norm(ends[:, None] - features[None], axis=2), axis=1)
            return -nearest

        size = ctx.settings.population
        initial = np.empty((size, 1 + k * n))
        initial[:, 0] = ctx.rng.integers(0, len(candidates), size=size)
        initial[:, 1:] = ctx.initial_genes(size).reshape(size, -1)
        genetic = ctx.settings.genetic
        if n >= ctx.many.straight_probe_joints and genetic.generations > ctx.many.explore_generations:
            genetic = dataclasses.replace(genetic, generations=ctx.many.explore_generations)  # (ManyJoints)
        result = minimize(evaluate, initial, ctx.rng, genetic, categories=len(candidates), should_stop=ctx.termination)
        index, paths = decode(result.genes[None])
        chosen_candidate = candidates[int(index[0])]
        fields = {
            "parent": chosen_candidate.parent,
            "joints": paths.final[0].copy(),
            "object_pose": paths.object_poses[0].copy(),
            "grasp": chosen_candidate.grasp,
            "grasp_rel": chosen_candidate.grasp_rel,
            "transit": chosen_candidate.transit,
            "transfer": np.concatenate([chosen_candidate.start[None], paths.waypoints[0, 1:]]),
        }
        covered = len(fresh) <= wanted  # every pair not searched before was searched in this step
        start = self.tree[chosen_candidate.parent].object_pose
        shift = float(space.goal_distance(paths.object_poses[:1], start)[0])
        return Exploration(fields, -result.fitness, covered, moved=shift >= ctx.search.moved_m)
