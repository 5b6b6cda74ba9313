"""Offline planning in a spatial world: a parameter tree to a checked spatial :class:`~clew_ros.core.plan.Plan`.

What ``clew_plan``, ``clew_batch`` and the node share for ``world.kind: spatial``
(:mod:`clew_ros.planar.offline` is the planar world's): :func:`problem_from_parameters`
(the world, the planner settings with the command line's overrides;
:class:`~clew_ros.core.errors.ParameterError` names the parameter at fault) and
:func:`plan_problem` (one run, its plan file validated by
:func:`clew_ros.spatial.plan.validate_plan`; a planner that raises gives an
``INTERNAL_ERROR`` plan instead of an exception).
"""

from __future__ import annotations

import dataclasses
import threading
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from clew_ros.core.clew import PlanResult, Progress
from clew_ros.core.improve import pruned_path
from clew_ros.core.plan import Plan
from clew_ros.core.settings import Outcome, PlannerSettings, Termination
from clew_ros.core.tree import LandmarkTree
from clew_ros.spatial.inverse import IKSettings, InverseKinematics
from clew_ros.spatial.plan import WORLD_KIND, validate_plan
from clew_ros.spatial.space import plan
from clew_ros.spatial.world import SpatialWorld, spatial_world_from_parameters

__all__ = ["SpatialProblem", "checked_plan", "failed_plan", "plan_problem", "problem_from_parameters", "warm_up"]


@dataclass(frozen=True)
class SpatialProblem:
    """A spatial world and the settings to plan it with."""

    world: SpatialWorld
    settings: PlannerSettings


def problem_from_parameters(
    parameters: Mapping[str, Any],
    folder: Path,
    *,
    seed: int | None = None,
    time_limit: float | None = None,
    improve_time: float | None = None,
) -> SpatialProblem:
    """The problem of a ``ros__parameters`` tree with ``world.kind: spatial`` (paths read relative to
    ``folder``, the parameter file's); ``seed``, ``time_limit`` (s) and ``improve_time`` (s) override
    ``planner.*`` when not ``None``."""
    world = spatial_world_from_parameters(parameters, folder)
    settings = PlannerSettings.from_parameters(parameters, seed=seed, time_limit=time_limit, improve_time=improve_time)
    return SpatialProblem(world, settings)


def warm_up(world: SpatialWorld) -> float:
    """The spatial kernels compiled (or loaded from numba's cache) on ``world``'s arrays before a plan's clock
    starts: validity, a free interval, forward and inverse kinematics, the improvement's pruning (loading it from
    the cache took a quarter of a second). Returns the seconds it took."""
    started = time.monotonic()
    start = np.asarray(world.initial, dtype=float)[None]
    world.checker.valid(start)
    world.checker.classify(start)  # the band kernel, whether or not the start lies near a contact
    _ = world.checker.tier  # the exact geometry's shapes (the meshes as BVHs)
    world.checker.free_intervals(start, 0)
    ik = InverseKinematics(world.robot, IKSettings(seeds=1, max_iterations=2))
    ik.solve(ik.tcp_poses(start)[0], np.random.default_rng(0))
    pruned_path(np.repeat(start, 3, axis=0))
    return time.monotonic() - started


def checked_plan(world: SpatialWorld, result: PlanResult) -> Plan:
    """The ``clew-plan/1`` plan of a spatial run (``"world_kind": "spatial"``, 6-number poses), validated by
    :func:`clew_ros.spatial.plan.validate_plan`: a success that fails it becomes ``INTERNAL_ERROR``."""
    planned = dataclasses.replace(Plan.from_result(world, result), world_kind=WORLD_KIND)
    if world.object is None and planned.success:
        planned = dataclasses.replace(planned, final_object_pose=None)
    if not planned.success:
        return planned
    problems = validate_plan(world, planned)
    if not problems:
        return planned
    return planned.failed(
        Outcome.INTERNAL_ERROR, "internal error: the plan failed validation: " + "; ".join(problems[:3])
    )


def failed_plan(world: SpatialWorld, settings: PlannerSettings, message: str, elapsed_s: float) -> Plan:
    """The ``INTERNAL_ERROR`` plan of a run that could not finish: no segments, the start as the only landmark."""
    pose = np.asarray(world.object.initial if world.object is not None else np.zeros(6), dtype=float)
    stats = {"time_s": round(elapsed_s, 4), "seed": settings.seed}
    result = PlanResult(Outcome.INTERNAL_ERROR, message, [], None, LandmarkTree(world.initial, pose), stats)
    return dataclasses.replace(Plan.from_result(world, result), world_kind=WORLD_KIND)


def plan_problem(
    problem: SpatialProblem,
    *,
    cancel: threading.Event | None = None,
    progress: Callable[[Progress], None] | None = None,
) -> Plan:
    """Plan ``problem`` within its time limit (or until ``cancel`` is set) and return the checked plan; a
    planner that raises (a bug) gives an ``INTERNAL_ERROR`` plan naming the error."""
    started = time.monotonic()
    world, settings = problem.world, problem.settings
    try:
        result = plan(world, settings, termination=Termination(settings.time_limit, cancel), progress=progress)
        return checked_plan(world, result)
    except Exception as error:  # noqa: BLE001 - a bug in the planner: reported in the plan, not raised
        return failed_plan(world, settings, f"internal error: {error!r}", time.monotonic() - started)
