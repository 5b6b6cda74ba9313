"""The improvement's budget, counted in work units, not seconds, so that the same seed gives the same plan on any
machine: :class:`WorkBudget` (units spent and left, shares of it, the final check's reserve, the clock's stop
test) and :class:`RoutingShare` (a routing's part of it). What a check costs in units is the space's cost model
(:class:`WorkCosts`; the planar one: :func:`clew_ros.planar.improve.budget.check_work`)."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

__all__ = ["RoutingShare", "WorkBudget", "WorkCosts"]


@dataclass(frozen=True)
class WorkCosts:
    """What the checks an improvement makes cost, in work units (a space's cost model fills them in: the budget
    only adds them up)."""

    #: one configuration checked in a batched compiled call
    check: float = 1.0
    #: one call of the configuration check from Python, besides its configurations
    call: int = 0
    #: one call of the straight-move check, besides its configurations
    move_call: int = 0
    #: one round of a routing (RRT-Connect) besides its checks
    round: float = 1.0


class WorkBudget:
    """``total`` work units, what is spent and left of them, and the clock's stop test ``stop`` (the planner's
    time limit and cancel: the only thing that ends an improvement by the clock, and sticky once true)."""

    def __init__(self, total: float, costs: WorkCosts, stop: Callable[[], bool]) -> None:
        self.total = total
        self.costs = costs
        self.check_work = costs.check
        self.spent = 0
        self.stopped = False
        self.reserve = 0  # work kept out of the budget (the final check of what changed so far)
        self._stop = stop

    def spend(self, units: int) -> None:
        self.spent += units

    def spend_checks(self, configurations: int, calls: int = 1) -> None:
        """Charge ``configurations`` checked in ``calls`` calls of the configuration check."""
        self.spent += math.ceil(configurations * self.check_work) + calls * self.costs.call

    def spend_move_checks(self, configurations: int) -> None:
        """Charge one call of the straight-move check that checked ``configurations``."""
        self.spent += math.ceil(configurations * self.check_work) + self.costs.move_call

    def units_left(self) -> float:
        """Work units left of the budget, the reserve kept out."""
        return self.total - self.reserve - self.spent

    def left(self, share: float = 1.0) -> bool:
        """Whether work is left within ``share`` of the budget (the reserve counted as spent) and the clock allows
        more."""
        if self.stop():
            return False
        return self.spent + self.reserve < share * self.total

    def stop(self) -> bool:
        """Whether the clock stopped the improvement (once true, always true)."""
        if not self.stopped and self._stop():
            self.stopped = True
        return self.stopped


class RoutingShare:
    """A routing's part of ``budget`` (what a routing such as :func:`clew_ros.planar.connect.rrt_connect` charges
    to): what is left of the budget, and at most until ``limit`` units are spent; each compiled call of its rounds
    costs :attr:`WorkCosts.move_call` more."""

    def __init__(self, budget: WorkBudget, limit: float) -> None:
        self.budget = budget
        self.round_work = budget.costs.round
        self.limit = limit
        self.check_work = budget.check_work

    def allowance(self) -> float:
        return min(self.limit - self.budget.spent, self.budget.units_left())

    def spend(self, units: float) -> None:
        self.budget.spend(math.ceil(units) + self.budget.costs.move_call)

    def stop(self) -> bool:
        return self.budget.stop()
