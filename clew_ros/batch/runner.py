"""The driver of a batch: which jobs are left, running them on an executor, and each job's plan file and
index line written as it finishes.

A job is done when the index has its line, with the job's fingerprint, and
its plan file is there, parses, and names the job's world, seed and outcome
(with ``record``: and its recording is there too): such jobs are skipped, so
rerunning the same command resumes. A finished job's plan file is written
first (to a temporary name, synced, renamed), then its recording (a
temporary folder, renamed; :mod:`clew_ros.batch.recording`), then its index
line (:mod:`clew_ros.batch.index`): a driver killed at any point loses only
the jobs in flight. A job whose worker failed (the job
raised, the worker died, the job ran past its time limit + grace) gets an
``INTERNAL_ERROR`` plan saying why, and is tried again up to ``retries``
times first. Setting ``stop`` ends the batch after the jobs finished so far;
the jobs in flight are dropped and run again on resume.
"""

from __future__ import annotations

import contextlib
import datetime
import math
import threading
import time
from collections import deque
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from clew_ros.batch.executors import Executor, Finished
from clew_ros.batch.files import UnsafeNameError, check_file_names, write_private
from clew_ros.batch.index import COLUMNS, Index
from clew_ros.batch.jobs import Job
from clew_ros.batch.progress import ProgressBar
from clew_ros.batch.recording import has_recording, recording_files, write_recording
from clew_ros.batch.worker import JobOutcome, JobSpec
from clew_ros.core.errors import PlanFileError
from clew_ros.core.files import private_folders
from clew_ros.core.plan import Plan
from clew_ros.kinds import failed_plan

__all__ = ["DEFAULT_GRACE_S", "BatchReport", "has_valid_output", "job_spec", "run_batch"]

#: Seconds a job may run past its time limit before it is stopped and recorded as timed out.
DEFAULT_GRACE_S = 60.0
#: How often (s) the driver looks at ``stop`` while it waits for jobs.
_POLL_S = 0.2


@dataclass
class BatchReport:
    """What a run of the batch did: ``total`` jobs, ``done_before`` skipped (done by an earlier run),
    ``ran`` finished now, ``retried`` attempts repeated, ``dropped`` in flight when it stopped,
    ``stopped`` whether ``stop`` ended it, and the index ``records`` of the batch's jobs done."""

    total: int
    done_before: int = 0
    ran: int = 0
    retried: int = 0
    dropped: int = 0
    stopped: bool = False
    repaired_bytes: int = 0
    skipped_lines: int = 0
    records: list[dict[str, Any]] = field(default_factory=list)

    @property
    def complete(self) -> bool:
        """Whether every job of the batch has its plan and index line."""
        return len(self.records) == self.total


def has_valid_output(job: Job, record: dict[str, Any] | None, out_dir: Path, *, recording: bool = False) -> bool:
    """Whether ``job`` is done: ``record`` (its index line) has its fingerprint and plan path, and the
    plan file parses and names the job's world, seed and outcome; with ``recording``, the record also
    names the job's recording and that folder holds one."""
    if record is None or record.get("fingerprint") != job.fingerprint or record.get("plan") != job.plan_path.as_posix():
        return False
    if recording and (
        record.get("recording") != job.recording_path.as_posix() or not has_recording(out_dir / job.recording_path)
    ):
        return False
    try:
        plan = Plan.read(out_dir / job.plan_path)
    except PlanFileError:
        return False
    return plan.world == job.world.name and plan.stats.get("seed") == job.seed and plan.code == record.get("code")


def _write_atomically(path: Path, text: str) -> None:
    """``text`` into ``path`` whole or not at all (a temporary file of mode 0600, synced, renamed over it;
    missing folders made 0700)."""
    private_folders(path.parent)
    partial = path.with_name(f".{path.name}.partial")
    write_private(partial, text.encode("utf-8"))
    partial.replace(path)


def _finite(value: float | None) -> float | None:
    return value if value is None or math.isfinite(value) else None


def _record(job: Job, outcome: JobOutcome, attempts: int, *, recorded: bool) -> dict[str, Any]:
    """The index line of ``job`` (columns in :data:`~clew_ros.batch.index.COLUMNS` order); ``recorded``:
    its recording was written."""
    record = {
        "job": job.key,
        "world": job.world.name,
        "world_path": str(job.world.path),
        "seed": job.seed,
        "code": outcome.code,
        "success": outcome.success,
        "message": outcome.message,
        "plan_time_s": _finite(outcome.plan_time_s),
        "wall_time_s": _finite(outcome.wall_time_s),
        "landmarks": outcome.landmarks,
        "transfers": outcome.transfers,
        "joint_travel_rad": _finite(outcome.joint_travel_rad),
        "plan": job.plan_path.as_posix(),
        "recording": job.recording_path.as_posix() if recorded else None,
        "attempts": attempts,
        "error": outcome.error,
        "fingerprint": job.fingerprint,
        "finished": datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds"),
    }
    assert tuple(record) == COLUMNS
    return record


def job_spec(job: Job, grace_s: float, *, record: bool = False) -> JobSpec:
    """What a worker gets of ``job``; it is given up ``grace_s`` (s) after its time limit; ``record``:
    the worker records the run."""
    return JobSpec(
        key=job.key,
        parameters=job.world.parameters,
        folder=str(job.world.path.resolve().parent),
        seed=job.seed,
        time_limit_s=job.time_limit_s,
        improve_time_s=job.improve_time_s,
        timeout_s=job.settings.time_limit + grace_s,
        record=record,
    )


@dataclass
class _Running:
    job: Job
    attempts: int
    submitted: float
    submitted_ns: int  # wall clock (ns since the epoch)


class _Driver:
    """One run of the batch: the queue, the jobs in flight, and what finishing one means."""

    def __init__(
        self,
        out_dir: Path,
        index: Index,
        executor: Executor,
        report: BatchReport,
        *,
        retries: int,
        grace_s: float,
        stop: threading.Event,
        record: bool,
    ) -> None:
        self.out_dir = out_dir
        self.record = record
        self.stop = stop
        self.index = index
        self.executor = executor
        self.report = report
        self.retries = retries
        self.grace_s = grace_s
        self.queue: deque[tuple[Job, int]] = deque()
        self.running: dict[str, _Running] = {}
        self.done: set[str] = set()
        self.successes = 0

    def fill(self) -> None:
        """Submit queued jobs while the executor has room (none once ``stop`` is set)."""
        while self.queue and len(self.running) < self.executor.capacity and not self.stop.is_set():
            job, attempts = self.queue.popleft()
            self.executor.submit(job_spec(job, self.grace_s, record=self.record))
            self.running[job.key] = _Running(job, attempts + 1, time.monotonic(), time.time_ns())

    def finish(self, finished: Finished) -> None:
        """Record a finished job, or queue it again when it failed and has retries left."""
        running = self.running.pop(finished.spec.key)
        job = running.job
        outcome, failure = finished.outcome, finished.failure
        if outcome is not None and outcome.recording is not None:
            try:  # the names come from the worker (a cluster node): checked before anything is written
                check_file_names(outcome.recording)
            except UnsafeNameError as error:
                outcome, failure = None, f"the worker sent back a recording file that was not written: {error}"
        if outcome is None:
            elapsed = time.monotonic() - running.submitted
            plan = failed_plan(job.problem, f"internal error: {failure}", elapsed)
            outcome = JobOutcome.from_plan(job.key, plan, elapsed)
        if outcome.code == "INTERNAL_ERROR" and running.attempts <= self.retries:
            self.report.retried += 1
            self.queue.appendleft((job, running.attempts))
            return
        self.fill()  # the freed worker gets its next job before the files are written (fsync takes ms)
        _write_atomically(self.out_dir / job.plan_path, outcome.plan_json)
        recording = self._recording(job, outcome, running.submitted_ns) if self.record else None
        if recording is not None:
            write_recording(self.out_dir / job.recording_path, recording)
        self.index.append(_record(job, outcome, running.attempts, recorded=recording is not None))
        self.done.add(job.key)
        self.report.ran += 1
        self.successes += outcome.success

    def _recording(self, job: Job, outcome: JobOutcome, submitted_ns: int) -> Mapping[str, bytes] | None:
        """The job's recording: the worker's, or for a job whose worker failed one the driver makes of
        its ``INTERNAL_ERROR`` plan; ``None`` when that fails too (the job is then not done on resume)."""
        if outcome.recording is not None:
            return outcome.recording
        problem = job.problem
        try:
            plan = Plan.from_json(outcome.plan_json)
            return recording_files(
                job.world.parameters,
                problem.world,
                problem.settings,
                plan,
                start_ns=submitted_ns,
                folder=job.world.path.resolve().parent,
            )
        except Exception:  # noqa: BLE001 - a job without its recording is left for the next run
            return None


def run_batch(
    jobs: Sequence[Job],
    out_dir: str | Path,
    executor: Executor,
    *,
    retries: int = 0,
    grace_s: float = DEFAULT_GRACE_S,
    stop: threading.Event | None = None,
    progress: ProgressBar | None = None,
    record: bool = False,
) -> BatchReport:
    """Run every job of ``jobs`` not done yet in ``out_dir`` on ``executor`` (started and closed here).

    ``retries``: further attempts of a job whose worker failed; ``grace_s`` (s): how long past its
    time limit a job may run before it is stopped; ``stop``: set it to end the batch early (the jobs
    in flight are dropped); ``progress``: shown as jobs finish (its ``done_before`` set here);
    ``record``: record each job's run too (:mod:`clew_ros.batch.recording`; the caller checks first
    that it can be done here, :func:`~clew_ros.batch.recording.recording_unavailable`).
    """
    out_dir = Path(out_dir)
    stop = stop or threading.Event()
    with Index.open(out_dir) as index:
        report = BatchReport(len(jobs), repaired_bytes=index.repaired_bytes, skipped_lines=index.skipped_lines)
        driver = _Driver(out_dir, index, executor, report, retries=retries, grace_s=grace_s, stop=stop, record=record)
        done_before = {
            job.key for job in jobs if has_valid_output(job, index.records.get(job.key), out_dir, recording=record)
        }
        report.done_before = len(done_before)
        driver.successes = sum(index.records[key].get("success") is True for key in done_before)
        driver.queue.extend((job, 0) for job in jobs if job.key not in done_before)
        if progress is not None:
            progress.done_before = report.done_before
        if driver.queue and not stop.is_set():
            _drive(driver, progress)
        report.stopped = stop.is_set() and (bool(driver.queue) or bool(driver.running))
        report.dropped = len(driver.running)
        driver.done |= done_before
        report.records = [index.records[job.key] for job in jobs if job.key in driver.done]
    return report


def _drive(driver: _Driver, progress: ProgressBar | None) -> None:
    """Start the executor, run the queue until it is empty or ``stop`` is set, close the executor."""
    executor = driver.executor
    try:
        executor.start()
        while (driver.queue or driver.running) and not driver.stop.is_set():
            driver.fill()
            for finished in executor.wait(_POLL_S):
                if finished.failure is not None and driver.stop.is_set():
                    continue  # its worker may have had the same Ctrl-C / SIGTERM: dropped, not failed
                driver.finish(finished)
                if progress is not None:
                    progress.update(driver.report.ran, driver.successes)
    finally:
        with contextlib.suppress(Exception):
            executor.close()
        if progress is not None:
            progress.close()
