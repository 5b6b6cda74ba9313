"""Offline planning: a parameter file (or its parsed tree) to a checked :class:`~clew_ros.core.plan.Plan`.

The one path ``clew_plan`` and ``clew_batch`` share, so that a batch job
gives exactly the plan ``clew_plan WORLD --seed S`` gives:

- :func:`problem_from_parameters`: the world (start
  and goal checked) and the planner settings with the command line's
  overrides; :class:`~clew_ros.core.errors.ParameterError` names the
  parameter at fault.
- :func:`plan_problem`: one run, validated by
  :func:`~clew_ros.planar.plan.checked_plan`; a planner that raises gives an
  ``INTERNAL_ERROR`` plan (:func:`failed_plan`) instead of an exception.

The caller warms the compiled kernel (:func:`clew_ros.planar.kernel.warm_up`)
before the first plan, so that no plan's clock pays for compiling it.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

from clew_ros.core.clew import PlanResult, Progress
from clew_ros.core.plan import Plan
from clew_ros.core.settings import Outcome, PlannerSettings, Termination
from clew_ros.core.tree import LandmarkTree
from clew_ros.planar.collision import check_start_and_goal
from clew_ros.planar.plan import checked_plan
from clew_ros.planar.space import plan
from clew_ros.planar.world import World, world_from_parameters

__all__ = ["Problem", "failed_plan", "plan_problem", "problem_from_parameters"]


@dataclass(frozen=True)
class Problem:
    """A world whose start and goal are valid, and the settings to plan it with."""

    world: World
    settings: PlannerSettings


def problem_from_parameters(
    parameters: Mapping[str, Any],
    *,
    seed: int | None = None,
    time_limit: float | None = None,
    improve_time: float | None = None,
) -> Problem:
    """The problem of a ``ros__parameters`` tree; ``seed``, ``time_limit`` (s) and ``improve_time`` (s)
    override ``planner.*`` when not ``None``.

    Raises :class:`~clew_ros.core.errors.ParameterError` naming the parameter at fault.
    """
    world = check_start_and_goal(world_from_parameters(parameters))
    settings = PlannerSettings.from_parameters(parameters, seed=seed, time_limit=time_limit, improve_time=improve_time)
    return Problem(world, settings)


def failed_plan(world: World, settings: PlannerSettings, message: str, elapsed_s: float) -> Plan:
    """The ``INTERNAL_ERROR`` plan of a run that could not finish (``message`` says why; ``elapsed_s``
    its time): no segments, the start as the only landmark, stats ``time_s`` and ``seed``."""
    result = PlanResult(
        Outcome.INTERNAL_ERROR,
        message,
        [],
        None,
        LandmarkTree(world.robot.initial, world.object.initial),
        {"time_s": round(elapsed_s, 4), "seed": settings.seed},
    )
    return Plan.from_result(world, result)


def plan_problem(
    problem: Problem,
    *,
    cancel: threading.Event | None = None,
    progress: Callable[[Progress], None] | None = None,
) -> Plan:
    """Plan ``problem`` within its time limit (or until ``cancel`` is set) and return the checked plan.

    A planner that raises (a bug) gives an ``INTERNAL_ERROR`` plan naming the error;
    :class:`KeyboardInterrupt` passes through.
    """
    started = time.monotonic()
    world, settings = problem.world, problem.settings
    try:
        result = plan(world, settings, termination=Termination(settings.time_limit, cancel), progress=progress)
        return checked_plan(world, result)
    except Exception as error:  # noqa: BLE001 - a bug in the planner: reported in the plan, not raised
        return failed_plan(world, settings, f"internal error: {error!r}", time.monotonic() - started)
