"""The kinds of world, each one adapter (:class:`WorldKind`) registered once, and what every kind shares.

``planar`` (:class:`~clew_ros.kinds.planar.PlanarKind`) and ``spatial``
(:class:`~clew_ros.kinds.spatial.SpatialKind`) are registered here. The code above the planner asks a
world's kind (:func:`kind_of`), a parameter tree's (:func:`kind_of_parameters`) or a name's
(:func:`kind_named`); a new kind is one package with its adapter plus one :func:`register` call here.

The offline path ``clew_plan`` and ``clew_batch`` share (:func:`problem_from_parameters`,
:func:`warm_up`, :func:`plan_problem`, :func:`failed_plan`) dispatches on the kind, so that a batch job
gives exactly the plan ``clew_plan WORLD --seed S`` gives, whatever the world.
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

from clew_ros.core.clew import Progress
from clew_ros.core.plan import Plan
from clew_ros.kinds.base import (
    DEFAULT_KIND,
    WorldKind,
    kind_named,
    kind_of,
    kind_of_parameters,
    kinds,
    register,
    unregister,
)
from clew_ros.kinds.planar import PlanarKind
from clew_ros.kinds.spatial import SpatialKind
from clew_ros.planar.offline import Problem
from clew_ros.spatial.offline import SpatialProblem

__all__ = [
    "DEFAULT_KIND",
    "AnyProblem",
    "WorldKind",
    "failed_plan",
    "kind_named",
    "kind_of",
    "kind_of_parameters",
    "kinds",
    "plan_problem",
    "problem_from_parameters",
    "register",
    "unregister",
    "warm_up",
    "world_kind",
]

#: An offline problem of a registered kind (a world and the settings to plan it with).
AnyProblem = Problem | SpatialProblem

register(PlanarKind())
register(SpatialKind())


def world_kind(parameters: Mapping[str, Any]) -> str:
    """``world.kind`` of a ``ros__parameters`` tree (:data:`DEFAULT_KIND` when it names none); an unknown
    kind raises :class:`~clew_ros.core.errors.WorldError` naming ``world.kind``."""
    return kind_of_parameters(parameters).name


def problem_from_parameters(
    parameters: Mapping[str, Any],
    folder: Path,
    *,
    seed: int | None = None,
    time_limit: float | None = None,
    improve_time: float | None = None,
) -> AnyProblem:
    """The problem of a ``ros__parameters`` tree, of its ``world.kind``; ``folder``: where its relative paths
    start (the parameter file's folder). Raises :class:`~clew_ros.core.errors.ParameterError` naming the
    parameter at fault."""
    kind = kind_of_parameters(parameters)
    problem: AnyProblem = kind.problem_from_parameters(
        parameters, folder, seed=seed, time_limit=time_limit, improve_time=improve_time
    )
    return problem


def warm_up(problem: AnyProblem) -> float:
    """The compiled kernels ``problem`` plans with, compiled (or loaded from numba's cache) before a plan's
    clock starts, so that no plan pays for compiling them; the seconds it took."""
    return kind_of(problem).warm_up(problem)


def plan_problem(
    problem: AnyProblem,
    *,
    cancel: threading.Event | None = None,
    progress: Callable[[Progress], None] | None = None,
) -> Plan:
    """One run of ``problem`` within its time limit (or until ``cancel``), its plan checked in its world."""
    return kind_of(problem).plan_problem(problem, cancel=cancel, progress=progress)


def failed_plan(problem: AnyProblem, message: str, elapsed_s: float) -> Plan:
    """The ``INTERNAL_ERROR`` plan of a run of ``problem`` that could not finish."""
    return kind_of(problem).failed_plan(problem, message, elapsed_s)
