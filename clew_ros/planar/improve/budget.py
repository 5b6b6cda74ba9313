"""The improvement's budget, counted in work units, not seconds (the same seed gives the same plan on any
machine): :class:`_Budget` (work spent and left, the clock's stop test), :class:`_RoutingShare` (a routing's part
of it) and :func:`check_work` (what a configuration check costs in a world)."""

from __future__ import annotations

import math

from clew_ros.core.space import PlanningContext
from clew_ros.planar.improve.settings import ImproveSettings
from clew_ros.planar.world import World, world_of

__all__ = ["check_work"]


class _Budget:
    """Work units left, and the clock's stop test (time limit, cancel)."""

    def __init__(self, ctx: PlanningContext, total: float, settings: ImproveSettings) -> None:
        self.ctx = ctx
        self.settings = settings
        self.total = total
        self.spent = 0
        self.evaluations_at_start = ctx.counters.evaluations
        self.stopped = False
        self.check_work = settings.batch_check_share * check_work(world_of(ctx), settings)
        self.reserve = 0  # work the final check of the segments changed so far will take

    def spend(self, units: int) -> None:
        self.spent += units

    def spend_checks(self, configurations: int, calls: int = 1) -> None:
        """Charge ``configurations`` checked in ``calls`` calls of the compiled check."""
        self.spent += math.ceil(configurations * self.check_work) + calls * self.settings.call_work

    def spend_move_checks(self, configurations: int) -> None:
        """Charge one call of the compiled straight-move check that checked ``configurations``."""
        self.spent += math.ceil(configurations * self.check_work) + self.settings.move_call_work

    def units_left(self) -> float:
        """Work units left of the budget, the final check's reserve kept out."""
        return self.total - self.reserve - self.spent

    def left(self, share: float = 1.0) -> bool:
        """Whether work is left (within ``share`` of the budget) and the clock allows more."""
        if self.stop():
            return False
        return self.spent + self.reserve < share * self.total

    def stop(self) -> bool:
        if not self.stopped and self.ctx.termination():
            self.stopped = True
        return self.stopped


class _RoutingShare:
    """A routing's part of the budget (:class:`clew_ros.planar.connect.RoutingBudget`): what is left of the
    budget, and at most until ``limit`` units are spent; each compiled call of its rounds costs
    :attr:`ImproveSettings.move_call_work` more."""

    def __init__(self, budget: _Budget, limit: float) -> None:
        self.budget = budget
        self.round_work = budget.settings.round_work
        self.limit = limit
        self.check_work = budget.check_work

    def allowance(self) -> float:
        return min(self.limit - self.budget.spent, self.budget.units_left())

    def spend(self, units: float) -> None:
        self.budget.spend(math.ceil(units) + self.budget.settings.move_call_work)

    def stop(self) -> bool:
        return self.budget.stop()


def check_work(world: World, settings: ImproveSettings | None = None) -> float:
    """How much one configuration check costs in ``world`` relative to figure1's, at least 1 (the budget charges
    :attr:`ImproveSettings.batch_check_share` units for each): its cost in joints
    (:attr:`ImproveSettings.self_pair_joints`, :attr:`ImproveSettings.obstacles_per_joint`) over figure1's
    (:attr:`ImproveSettings.reference_cost`). Measured with the compiled check's broad phase (valid configurations,
    docs/benchmarks.md): within a factor of two of the time a check takes on every benchmark world, where counting the
    pairs of pieces compared (as before the broad phase) charged obstacles_32 five times too much. ``settings``: the
    default :class:`ImproveSettings` when not given."""
    settings = ImproveSettings() if settings is None else settings
    n = world.robot.dof
    pairs = (n - 1) * (n - 2) / 2 if world.robot.self_collision else 0.0
    cost = n + settings.self_pair_joints * pairs + len(world.obstacles) / settings.obstacles_per_joint
    return max(1.0, cost / settings.reference_cost)
