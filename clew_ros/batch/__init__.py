"""Batch planning: many (world, seed) jobs planned in parallel into a dataset (``clew_batch``).

- :mod:`~clew_ros.batch.jobs`: the jobs (world files, seeds, derived seeds, where plans go);
- :mod:`~clew_ros.batch.worker`: one job in a worker process, as ``clew_plan`` plans it;
- :mod:`~clew_ros.batch.executors`: where jobs run (a local pool of processes, or Ray);
- :mod:`~clew_ros.batch.index`: ``index.jsonl``, one complete line per job;
- :mod:`~clew_ros.batch.runner`: the driver (resume, retries, a clean stop);
- :mod:`~clew_ros.batch.recording`: ``--record``, each job's run recorded as the node would (needs ROS),
  by :mod:`~clew_ros.batch.plan_recording` (a plan recorded as a run, with the node's message builders);
- :mod:`~clew_ros.batch.progress` and :mod:`~clew_ros.batch.summary`: what the command shows.

Importing this package imports neither Ray (only ``--ray`` does) nor ROS (only ``--record`` does).
"""

from clew_ros.batch.errors import BatchError, BatchInputError, ExecutorError, ExecutorUnavailableError
from clew_ros.batch.executors import Executor, Finished, LocalPool, RayExecutor
from clew_ros.batch.index import COLUMNS, Index
from clew_ros.batch.jobs import BatchWorld, Job, collect_world_paths, derived_seeds, load_worlds, make_jobs
from clew_ros.batch.runner import BatchReport, run_batch
from clew_ros.batch.worker import JobOutcome, JobSpec, run_job

__all__ = [
    "COLUMNS",
    "BatchError",
    "BatchInputError",
    "BatchReport",
    "BatchWorld",
    "Executor",
    "ExecutorError",
    "ExecutorUnavailableError",
    "Finished",
    "Index",
    "Job",
    "JobOutcome",
    "JobSpec",
    "LocalPool",
    "RayExecutor",
    "collect_world_paths",
    "derived_seeds",
    "load_worlds",
    "make_jobs",
    "run_batch",
    "run_job",
]
