"""What runs in a worker process: one job (:func:`run_job`), and the local pool's worker loop (:func:`serve`).

A job travels as a :class:`JobSpec` (the world's parameter tree, not its
path, so that a Ray worker on another machine needs no shared folder for a
planar world; a spatial world's URDF, SRDF and scene files are read from the
world file's folder, which such a worker must see at the same path) and
comes back as a :class:`JobOutcome` holding the plan file's text (and, with
``--record``, the recording's files); only the driver writes files. Each
worker process warms the compiled kernel once (:func:`prepare`), before its
first job, so that no job's time pays for it.

Jobs plan with ``planner.threads`` 1: a batch keeps every core busy with
processes, and the plan does not depend on the thread count (the planner
computes every individual alone), so a job's plan file is byte for byte what
``clew_plan`` writes for that world and seed, ``stats.time_s`` aside.

This module imports the planner only inside its functions: a worker process
starts by importing it, and the job function passed to it decides the rest.
"""

from __future__ import annotations

import os
import signal
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass, replace
from multiprocessing.connection import Connection
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from clew_ros.core.plan import Plan

__all__ = ["JobFunction", "JobOutcome", "JobSpec", "prepare", "run_job", "run_prepared", "serve"]


@dataclass(frozen=True)
class JobSpec:
    """One job as a worker gets it: ``key`` (its name), the world's ``parameters`` tree, the ``seed``,
    the overrides (s; ``None``: the file's), ``timeout_s``, after which the driver gives up on it, and
    whether to ``record`` the run (``clew_batch --record``)."""

    key: str
    parameters: Mapping[str, Any]
    seed: int
    time_limit_s: float | None
    improve_time_s: float | None
    timeout_s: float
    record: bool = False
    #: the world file's folder: where the relative paths of a spatial world (URDF, SRDF, scene file) start
    folder: str = "."


@dataclass(frozen=True)
class JobOutcome:
    """What a job produced: the plan file's text and the figures the index keeps.

    ``plan_time_s`` is the planner's own time (the plan's ``stats.time_s``), ``wall_time_s`` the
    job's time in its worker (reading the world, planning, checking). ``error`` says why the job
    failed (``INTERNAL_ERROR``: the planner raised, the worker died, the job timed out), else ``None``.
    ``recording`` holds the run's recording, file name -> content (:mod:`clew_ros.batch.recording`),
    when the job was to record it.
    """

    key: str
    plan_json: str
    code: str
    success: bool
    message: str
    plan_time_s: float | None
    wall_time_s: float
    landmarks: int
    transfers: int | None
    joint_travel_rad: float | None
    error: str | None = None
    recording: Mapping[str, bytes] | None = None

    @classmethod
    def from_plan(
        cls, key: str, plan: Plan, wall_time_s: float, recording: Mapping[str, bytes] | None = None
    ) -> JobOutcome:
        """The outcome of job ``key`` that made ``plan`` in ``wall_time_s`` (and ``recording``)."""
        stats = plan.stats
        time_s = stats.get("time_s")
        travel = stats.get("joint_travel_rad")
        return cls(
            key=key,
            plan_json=plan.to_json(),
            code=plan.code or "INTERNAL_ERROR",
            success=plan.success,
            message=plan.message,
            plan_time_s=None if time_s is None else float(time_s),
            wall_time_s=round(wall_time_s, 4),
            landmarks=len(plan.landmarks),
            transfers=int(stats.get("transfers", plan.grasp_count)) if plan.success else None,
            joint_travel_rad=None if travel is None or not plan.success else float(travel),
            error=plan.message if plan.code == "INTERNAL_ERROR" else None,
            recording=recording,
        )


#: A function that runs one job in a worker process (:func:`run_job`; tests pass wrappers of it).
JobFunction = Callable[[JobSpec], JobOutcome]


def run_job(spec: JobSpec) -> JobOutcome:
    """Plan one job as ``clew_plan`` would (same world, seed and settings; one thread) and return its
    outcome; with ``spec.record``, record the run too (after the wall time is taken).

    Raises :class:`~clew_ros.core.errors.ParameterError` for an invalid world (the driver checked it
    before, so only a world that changed on the way). A run that cannot be recorded keeps its plan,
    without a recording (``recording`` ``None``: the driver tries once more, else the job is redone by
    the next run); its time counts in the job's time-out (time limit + grace).
    """
    from clew_ros.kinds import kind_of, plan_problem, problem_from_parameters

    started, started_ns = time.monotonic(), time.time_ns()
    problem = problem_from_parameters(
        spec.parameters,
        Path(spec.folder),
        seed=spec.seed,
        time_limit=spec.time_limit_s,
        improve_time=spec.improve_time_s,
    )
    kind_of(problem).warm_up_worker(problem)  # what the kind compiles once per process
    plan = plan_problem(replace(problem, settings=replace(problem.settings, threads=1)))
    wall_time_s = time.monotonic() - started
    recording = None
    if spec.record:
        from clew_ros.batch.recording import recording_files

        try:
            recording = recording_files(
                spec.parameters, problem.world, problem.settings, plan, start_ns=started_ns, folder=Path(spec.folder)
            )
        except Exception:  # noqa: BLE001 - the plan is kept; the driver records it, or leaves it for the next run
            recording = None
    return JobOutcome.from_plan(spec.key, plan, wall_time_s, recording)


def prepare() -> None:
    """Ready this process for jobs: compile the kernel, or load numba's cache (once per process)."""
    from clew_ros.planar.kernel import warm_up

    warm_up()


def run_prepared(job_function: JobFunction, spec: JobSpec) -> JobOutcome:
    """:func:`prepare` (a no-op after the first time), then ``job_function(spec)``: a Ray task's body."""
    prepare()
    return job_function(spec)


def serve(connection: Connection, job_function: JobFunction) -> None:
    """A local pool worker: prepare, say ``("ready", pid)``, then answer every :class:`JobSpec` received
    with ``("done", JobOutcome)`` or ``("error", reason)`` until ``None`` or the driver is gone.

    SIGINT is ignored: a Ctrl-C in the terminal reaches the whole process group, and the driver
    decides what happens to the jobs in flight.
    """
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    prepare()
    try:
        connection.send(("ready", os.getpid()))
        while True:
            spec = connection.recv()
            if spec is None:
                return
            try:
                answer: tuple[str, Any] = ("done", job_function(spec))
            except Exception as error:  # noqa: BLE001 - any failure of a job is its outcome, not the worker's end
                answer = ("error", f"{type(error).__name__}: {error}")
            connection.send(answer)
    except (EOFError, OSError):  # the driver is gone: nothing left to do
        return
