"""clew_ros.batch.runner on the local pool: failed jobs are recorded with their reason and the batch goes
on; retries; a job that hangs is stopped. The faults come from helpers.batch_faults (run in the pool's
worker processes)."""

from __future__ import annotations

import threading
from pathlib import Path

import pytest
from helpers.batch_cli import CONFIG, index_lines
from helpers.batch_faults import FAULT_DIR_VARIABLE, faulty_job

from clew_ros.batch.executors import Finished, LocalPool
from clew_ros.batch.jobs import load_worlds, make_jobs
from clew_ros.batch.runner import has_valid_output, run_batch
from clew_ros.batch.worker import JobSpec
from clew_ros.core.plan import Plan


def test_failed_jobs_are_recorded_with_their_reason_after_retries(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv(FAULT_DIR_VARIABLE, str(tmp_path))
    jobs = make_jobs(load_worlds([(CONFIG / "single_transfer.yaml").resolve()]), [0, 1, 2, 3])
    out = tmp_path / "out"
    report = run_batch(jobs, out, LocalPool(2, job_function=faulty_job), retries=1)
    assert report.complete
    assert report.ran == 4
    assert report.retried == 3  # seeds 1, 2 and 3 once each
    records = {record["seed"]: record for record in index_lines(out)}
    assert len(index_lines(out)) == 4

    assert records[0]["code"] == "SUCCEEDED"
    assert records[0]["attempts"] == 1
    assert records[0]["error"] is None

    assert records[1]["code"] == "INTERNAL_ERROR"
    assert records[1]["attempts"] == 2
    assert "worker process died" in records[1]["error"]
    assert "exit code 3" in records[1]["error"]

    assert records[2]["code"] == "INTERNAL_ERROR"
    assert records[2]["attempts"] == 2
    assert "RuntimeError: injected fault" in records[2]["error"]

    assert records[3]["code"] == "SUCCEEDED"  # died once, planned on the retry
    assert records[3]["attempts"] == 2

    for job in jobs:  # every job has its plan file, failed ones too
        plan = Plan.read(out / job.plan_path)
        assert plan.code == records[job.seed]["code"]
        assert has_valid_output(job, records[job.seed], out)
    assert Plan.read(out / jobs[1].plan_path).message.startswith("internal error: the worker process died")


def test_a_job_that_hangs_is_stopped_after_its_time_limit_and_grace(tmp_path: Path, unreachable_fast: Path) -> None:
    jobs = make_jobs(load_worlds([unreachable_fast.resolve()]), [0, 4, 5])  # time limit 0.5 s; seed 4 hangs
    out = tmp_path / "out"
    report = run_batch(jobs, out, LocalPool(2, job_function=faulty_job), grace_s=1.0)
    assert report.complete
    records = {record["seed"]: record for record in index_lines(out)}
    assert records[4]["code"] == "INTERNAL_ERROR"
    assert "timed out" in records[4]["error"]
    assert "1.5 s" in records[4]["error"]
    for seed in (0, 5):
        assert records[seed]["code"] in ("TIME_LIMIT", "NO_PATH_AT_RESOLUTION")
        assert records[seed]["error"] is None


class _StoppedExecutor:
    """An executor (no processes) whose first wait is interrupted by a stop request, and whose jobs then
    fail the way workers hit by the same Ctrl-C or SIGTERM would."""

    capacity = 2
    description = "scripted"

    def __init__(self, stop: threading.Event) -> None:
        self.stop = stop
        self.submitted: list[JobSpec] = []

    def start(self) -> None:
        pass

    def submit(self, spec: JobSpec) -> None:
        self.submitted.append(spec)

    def wait(self, timeout_s: float) -> list[Finished]:
        self.stop.set()
        return [
            Finished(spec, failure="the worker process died while planning (killed by SIGTERM)")
            for spec in self.submitted
        ]

    def close(self) -> None:
        pass


def test_failures_after_a_stop_request_are_dropped_not_recorded(tmp_path: Path) -> None:
    jobs = make_jobs(load_worlds([(CONFIG / "single_transfer.yaml").resolve()]), [0, 1, 2])
    stop = threading.Event()
    report = run_batch(jobs, tmp_path, _StoppedExecutor(stop), stop=stop, retries=3)
    assert report.stopped
    assert report.dropped == 2
    assert report.ran == 0
    assert report.retried == 0
    assert index_lines(tmp_path) == []
