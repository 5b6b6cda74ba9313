"""clew_ros.batch.worker: a job gives exactly clew_plan's plan for that world and seed."""

from __future__ import annotations

import json
import pickle
from pathlib import Path

import pytest
from helpers.batch_cli import CONFIG, clew_plan_text, without_wall_time

from clew_ros.batch.jobs import load_worlds, make_jobs
from clew_ros.batch.worker import JobOutcome, JobSpec, run_job


def _spec(world: Path, seed: int) -> JobSpec:
    (job,) = make_jobs(load_worlds([world.resolve()]), [seed])
    return JobSpec(job.key, job.world.parameters, seed, None, None, timeout_s=60.0)


def test_a_job_plans_what_clew_plan_plans(tmp_path: Path) -> None:
    outcome = run_job(_spec(CONFIG / "single_transfer.yaml", 2))
    assert outcome.code == "SUCCEEDED"
    assert outcome.success
    assert outcome.error is None
    assert outcome.transfers is not None
    assert outcome.transfers >= 1
    assert outcome.joint_travel_rad is not None
    assert outcome.landmarks == len(json.loads(outcome.plan_json)["landmarks"])
    assert without_wall_time(outcome.plan_json) == without_wall_time(
        clew_plan_text(CONFIG / "single_transfer.yaml", 2, tmp_path / "p.json")
    )
    assert pickle.loads(pickle.dumps(outcome)) == outcome  # it travels between processes


def test_a_failed_job_has_its_outcome_code(unreachable_fast: Path) -> None:
    outcome = run_job(_spec(unreachable_fast, 0))
    assert outcome.code in ("TIME_LIMIT", "NO_PATH_AT_RESOLUTION")
    assert not outcome.success
    assert outcome.transfers is None
    assert outcome.joint_travel_rad is None
    assert outcome.error is None  # a planner outcome, not a failure of the job
    assert isinstance(outcome, JobOutcome)


def test_an_invalid_world_raises_naming_the_parameter() -> None:
    spec = _spec(CONFIG / "single_transfer.yaml", 0)
    broken = JobSpec(spec.key, {"world": {}}, 0, None, None, 60.0)
    with pytest.raises(ValueError, match="world"):
        run_job(broken)
