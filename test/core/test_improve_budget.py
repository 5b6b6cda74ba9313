"""The improvement's work budget (:mod:`clew_ros.core.improve.budget`) and the order on plans
(:mod:`clew_ros.core.improve.compare`)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from clew_ros.core.improve import RoutingShare, WorkBudget, WorkCosts, better, joint_travel
from clew_ros.core.tree import Segment


def test_a_budget_charges_checks_by_its_costs_and_leaves_work_within_a_share() -> None:
    budget = WorkBudget(1000.0, WorkCosts(check=0.3, call=20, move_call=5, round=2.0), lambda: False)
    budget.spend_checks(10, calls=2)  # ceil(3.0) + 2 x 20
    assert budget.spent == 43
    budget.spend_move_checks(7)  # ceil(2.1) + 5
    assert budget.spent == 51
    assert budget.left(share=0.06)
    assert not budget.left(share=0.05)
    budget.reserve = 900
    assert budget.units_left() == 1000 - 900 - 51
    assert budget.left()
    assert not budget.left(share=0.95)
    budget.spend(49)
    assert not budget.left()


def test_the_clock_stops_a_budget_for_good_and_a_routing_share_with_it() -> None:
    ticks = iter([False, True, False])
    budget = WorkBudget(math.inf, WorkCosts(), lambda: next(ticks))
    share = RoutingShare(budget, limit=100.0)
    assert budget.left()
    assert not budget.left()
    assert budget.stopped
    assert share.stop()  # sticky: the third answer is never asked for
    assert not budget.left()


def test_a_routing_share_spends_from_the_budget_up_to_its_limit() -> None:
    budget = WorkBudget(1000.0, WorkCosts(check=0.5, move_call=20, round=2.0), lambda: False)
    budget.spend(100)
    share = RoutingShare(budget, limit=300.0)
    assert (share.check_work, share.round_work) == (0.5, 2.0)
    assert share.allowance() == 200.0  # its limit, less what the budget spent
    share.spend(10.2)  # ceil, and a compiled call
    assert budget.spent == 100 + 11 + 20
    budget.reserve = 800
    assert share.allowance() == 1000 - 800 - 131  # what the budget has left, when less


def test_fewer_transfers_win_then_shorter_travel_then_fewer_waypoints() -> None:
    eps = 1e-9
    assert better((2, 10.0, 8), (1, 50.0, 90), eps)
    assert not better((1, 50.0, 90), (2, 10.0, 8), eps)
    assert better((1, 10.0, 8), (1, 9.0, 20), eps)
    assert not better((1, 10.0, 8), (1, 10.0 + 1e-12, 7 + 20), eps)
    assert better((1, 10.0, 8), (1, 10.0 + 1e-12, 7), eps)  # travel within eps: as long
    assert not better((1, 10.0, 8), (1, 10.0, 8), eps)  # never better than itself


def test_joint_travel_sums_the_absolute_motion_of_segments_or_arrays() -> None:
    a = np.array([[0.0, 0.0], [1.0, -1.0], [1.0, 1.0]])
    assert joint_travel([a]) == pytest.approx(4.0)
    assert joint_travel([Segment("transit", None, list(a)), a[:1]]) == pytest.approx(4.0)
