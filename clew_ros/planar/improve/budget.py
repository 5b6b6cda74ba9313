"""The planar cost model of the improvement's work budget (:class:`clew_ros.core.improve.WorkBudget`, counted
in work units, not seconds, so the same seed gives the same plan on any machine): :func:`check_work` (what a
configuration check costs in a world) and :func:`work_costs` (what each kind of check is charged)."""

from __future__ import annotations

from clew_ros.core.improve import WorkCosts
from clew_ros.planar.improve.settings import ImproveSettings
from clew_ros.planar.world import World

__all__ = ["check_work", "work_costs"]


def work_costs(world: World, settings: ImproveSettings) -> WorkCosts:
    """The planar cost model of the improvement's checks in ``world``: a configuration checked costs
    :attr:`ImproveSettings.batch_check_share` x :func:`check_work` units, a call of the configuration check
    :attr:`ImproveSettings.call_work`, of the straight-move check :attr:`ImproveSettings.move_call_work`, a round of
    RRT-Connect :attr:`ImproveSettings.round_work`."""
    return WorkCosts(
        check=settings.batch_check_share * check_work(world, settings),
        call=settings.call_work,
        move_call=settings.move_call_work,
        round=settings.round_work,
    )


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
