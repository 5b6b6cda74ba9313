"""A parameter file of either kind of world to a checked plan: what ``clew_plan`` and ``clew_batch`` share.

``world.kind`` (``planar``, the default, or ``spatial``) picks the world's own offline path,
:mod:`clew_ros.planar.offline` or :mod:`clew_ros.spatial.offline`; this package only dispatches, so that a
batch job gives exactly the plan ``clew_plan WORLD --seed S`` gives, whatever the world.
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

from clew_ros.core.clew import Progress
from clew_ros.core.errors import WorldError
from clew_ros.core.plan import Plan
from clew_ros.planar import offline as planar
from clew_ros.planar.kernel import warm_up as planar_warm_up
from clew_ros.spatial import offline as spatial

__all__ = ["AnyProblem", "failed_plan", "plan_problem", "problem_from_parameters", "warm_up", "world_kind"]

#: A problem of either kind of world.
AnyProblem = planar.Problem | spatial.SpatialProblem


def world_kind(parameters: Mapping[str, Any]) -> str:
    """``world.kind`` of a ``ros__parameters`` tree: ``planar`` (the default) or ``spatial``."""
    tree = parameters.get("world") if isinstance(parameters, Mapping) else None
    kind = tree.get("kind", "planar") if isinstance(tree, Mapping) else "planar"
    if kind not in ("planar", "spatial"):
        raise WorldError("world.kind", f"expected 'planar' or 'spatial', got {kind!r:.40}")
    return str(kind)


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
    overrides: dict[str, Any] = {"seed": seed, "time_limit": time_limit, "improve_time": improve_time}
    if world_kind(parameters) == "spatial":
        return spatial.problem_from_parameters(parameters, folder, **overrides)
    return planar.problem_from_parameters(parameters, **overrides)


def warm_up(problem: AnyProblem) -> float:
    """The compiled kernels ``problem`` plans with, compiled (or loaded from numba's cache) before a plan's
    clock starts, so that no plan pays for compiling them; the seconds it took."""
    if isinstance(problem, spatial.SpatialProblem):
        return spatial.warm_up(problem.world)
    return planar_warm_up()


def plan_problem(
    problem: AnyProblem,
    *,
    cancel: threading.Event | None = None,
    progress: Callable[[Progress], None] | None = None,
) -> Plan:
    """One run of ``problem`` within its time limit (or until ``cancel``), its plan checked in its world."""
    if isinstance(problem, spatial.SpatialProblem):
        return spatial.plan_problem(problem, cancel=cancel, progress=progress)
    return planar.plan_problem(problem, cancel=cancel, progress=progress)


def failed_plan(problem: AnyProblem, message: str, elapsed_s: float) -> Plan:
    """The ``INTERNAL_ERROR`` plan of a run of ``problem`` that could not finish."""
    if isinstance(problem, spatial.SpatialProblem):
        return spatial.failed_plan(problem.world, problem.settings, message, elapsed_s)
    return planar.failed_plan(problem.world, problem.settings, message, elapsed_s)
