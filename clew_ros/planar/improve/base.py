"""The improver's state and what every stage uses: the plan's pieces, the budget, the margin, straight moves
checked continuously and charged to the budget, the final check's reserve, and the pruning."""

from __future__ import annotations

import math

import numpy as np

from clew_ros.core.improve import Score, WorkBudget, better, joined_regrasps, joint_travel, pruned_path
from clew_ros.core.space import PlanningContext
from clew_ros.planar.continuous import straight_moves_clear
from clew_ros.planar.improve.budget import work_costs
from clew_ros.planar.improve.final import _dense_count
from clew_ros.planar.improve.pieces import _Piece
from clew_ros.planar.improve.settings import ImproveSettings
from clew_ros.planar.lattice import KnownNodes
from clew_ros.planar.world import World


class _ImproverBase:
    """What the stages of :class:`clew_ros.planar.improve._Improver` share (``settings``: the improvement's
    tuning, the default :class:`ImproveSettings` when not given)."""

    def __init__(
        self,
        world: World,
        ctx: PlanningContext,
        pieces: list[_Piece],
        goal: np.ndarray,
        settings: ImproveSettings | None = None,
    ) -> None:
        self.settings = ImproveSettings() if settings is None else settings
        self.ctx = ctx
        self.world = world
        self.pieces = pieces
        self.first = [p.waypoints for p in pieces]
        self.goal = goal
        joints = world.robot.dof
        scale = 1.0
        if joints >= ctx.many.straight_probe_joints:
            scale = (joints / self.settings.many_budget_joints) ** self.settings.many_budget_power
        total = ctx.settings.improve_time * self.settings.work_per_second * scale
        self.budget = WorkBudget(total, work_costs(self.world, self.settings), ctx.termination)
        self.min_margin = self.settings.moves.min_margin_factor * ctx.settings.clearance
        self.shortcuts = 0
        self.rebuilt = 0
        self.blocked_moves: list[tuple[str, np.ndarray, np.ndarray]] = []  # (kind, start, end) found blocked
        self.connected = [0, 0]  # proposals with a move routed by connect that did not make the plan better, that did
        self.connect_failed = 0  # routings by connect that found no path
        self.routings = 0  # routings by connect for the proposal being checked
        self.rebuild_share = (
            self.settings.rebuild_share
        )  # of the budget, the rebuilding may start in (all of it after a round)
        # the inverse kinematics' restarts draw from a generator of their own: the run's stream stays the releases'
        self.restarts = np.random.default_rng([ctx.settings.seed, self.settings.restart_stream])
        self.known_nodes: dict[bytes, KnownNodes] = {}  # per mode: the lattice nodes checked so far
        # the spans lattice_regrasps searched (their ends, their length), the first grasps lattice_first_grasps tried
        self.regrasps_tried: set[bytes] = set()

    def better(self, old: Score, new: Score) -> bool:
        """Whether score ``new`` is better than ``old`` (:func:`clew_ros.core.improve.better`)."""
        return better(old, new, self.settings.travel_eps)

    def clear(self, piece: _Piece, a: np.ndarray, b: np.ndarray) -> bool:
        """Whether the straight move ``a -> b`` is clear in ``piece``'s mode."""
        return self.path_clear(piece, np.array([a, b], dtype=float))

    def path_clear(self, piece: _Piece, path: np.ndarray) -> bool:
        """Whether every move of ``path`` is clear in ``piece``'s mode (one call of the check; it stops at the
        first move that is not)."""
        path = np.asarray(path, dtype=float)
        return bool(self.moves_clear(piece, path[:-1], path[1:], every=True).all())

    def moves_clear(self, piece: _Piece, starts: np.ndarray, ends: np.ndarray, *, every: bool = False) -> np.ndarray:
        """Which straight moves ``starts[k] -> ends[k]`` are clear in ``piece``'s mode, with the improver's
        margin, charged to the budget (:func:`clew_ros.planar.continuous.straight_moves_clear`, one call)."""
        return straight_moves_clear(
            self.world,
            starts,
            ends,
            object_pose=piece.start_pose,
            grasp_rel=piece.grasp_rel,
            min_margin=self.min_margin,
            budget=self.budget,
            every=every,
            settings=self.settings.moves,
        )

    def reserve(self) -> None:
        """Keep the work of the final check of the segments changed so far out of the budget
        (:attr:`ImproveSettings.dense_work`)."""
        count = sum(
            _dense_count(piece.waypoints)
            for index, piece in enumerate(self.pieces)
            if index >= len(self.first) or not np.array_equal(piece.waypoints, self.first[index])
        )
        self.budget.reserve = math.ceil(self.settings.dense_work * self.budget.check_work * count)

    def prune(self) -> None:
        """Back-and-forth pruning (free): regrasps in place joined, collinear waypoints and loops dropped."""
        self.pieces = joined_regrasps(self.pieces, self.settings.same_rad)
        for piece in self.pieces:
            pruned = pruned_path(piece.waypoints)
            if self.better(
                (0, joint_travel([piece.waypoints]), len(piece.waypoints)), (0, joint_travel([pruned]), len(pruned))
            ):
                piece.waypoints = pruned
        self.reserve()
