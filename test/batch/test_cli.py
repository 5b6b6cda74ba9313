"""clew_batch end to end on the local pool: the plans clew_plan makes, the index, the summary; resume after
a rerun, a torn index line, a SIGKILL of the driver and a Ctrl-C; bad input."""

from __future__ import annotations

import contextlib
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from helpers.batch_cli import (
    CONFIG,
    ROOT,
    batch_command,
    clew_plan_text,
    index_lines,
    run_batch_cli,
    without_wall_time,
)

from benchmarks.batch import group_alive
from clew_ros.batch.index import COLUMNS
from clew_ros.cli.batch import main
from clew_ros.core.plan import Plan
from clew_ros.planar.plan import validate_plan
from clew_ros.planar.world import load_world

#: Long enough that a kill lands mid-batch: every job plans single_transfer (about 0.2-2 s each).
SEEDS_TO_INTERRUPT = 12


def _mtimes(out: Path) -> dict[str, int]:
    return {str(p.relative_to(out)): p.stat().st_mtime_ns for p in sorted((out / "plans").rglob("*.json"))}


def _start_batch(args: list, output: int) -> subprocess.Popen[str]:
    """``clew_batch`` started in a session of its own (so that its whole process group can be killed)."""
    return subprocess.Popen(
        batch_command(*args),
        cwd=ROOT,
        env=dict(os.environ),
        text=True,
        start_new_session=True,
        stdout=output,
        stderr=output,
    )


def _wait_for_index(out: Path, lines: int, process: subprocess.Popen[str], deadline_s: float = 300.0) -> None:
    """Poll until the index holds ``lines`` lines (or fail at the deadline, or if the batch ended)."""
    deadline = time.monotonic() + deadline_s
    while len(index_lines(out)) < lines:
        assert process.poll() is None, "the batch ended before it could be interrupted"
        assert time.monotonic() < deadline, f"the index did not reach {lines} lines in {deadline_s} s"
        time.sleep(0.05)


def test_plans_index_summary_resume_and_a_torn_line(tmp_path: Path, unreachable_fast: Path) -> None:
    out = tmp_path / "out"
    single = CONFIG / "single_transfer.yaml"
    args = [single, unreachable_fast, "--seeds", 2, "--out", out, "--jobs", 2]
    done = run_batch_cli(*args)
    assert done.returncode == 0, done.stderr
    assert "Traceback" not in done.stderr
    records = index_lines(out)
    assert sorted(r["job"] for r in records if r["world"] == "single_transfer") == [  # in the order jobs end
        "single_transfer/seed_0000",
        "single_transfer/seed_0001",
    ]
    assert len(records) == 4
    assert all(tuple(r) == COLUMNS for r in records)
    by_job = {r["job"]: r for r in records}

    # exactly clew_plan's plans (all but the wall time), valid at 0.002 rad
    for seed in (0, 1):
        job = by_job[f"single_transfer/seed_{seed:04d}"]
        assert job["code"] == "SUCCEEDED"
        assert job["success"] is True
        assert job["transfers"] >= 1
        assert job["joint_travel_rad"] > 0
        assert job["plan_time_s"] > 0
        text = (out / job["plan"]).read_text()
        assert without_wall_time(text) == without_wall_time(clew_plan_text(single, seed, tmp_path / "plan.json"))
        assert validate_plan(load_world(single), Plan.from_json(text), step_rad=0.002) == []
    failed = by_job["unreachable_fast/seed_0000"]
    assert failed["code"] in ("TIME_LIMIT", "NO_PATH_AT_RESOLUTION")
    assert failed["success"] is False
    assert failed["error"] is None
    assert json.loads((out / failed["plan"]).read_text())["code"] == failed["code"]

    summary = done.stdout.splitlines()
    assert summary[0].split()[:3] == ["world", "jobs", "ok"]
    assert summary[1].split()[:4] == ["single_transfer", "2", "2", "100"]
    assert summary[2].split()[:4] == ["unreachable_fast", "2", "0", "0"]

    # the same command again: nothing to do, nothing rewritten
    index_before = (out / "index.jsonl").read_bytes()
    mtimes = _mtimes(out)
    again = run_batch_cli(*args)
    assert again.returncode == 0, again.stderr
    assert "4 by an earlier run, 0 now" in again.stderr
    assert (out / "index.jsonl").read_bytes() == index_before
    assert _mtimes(out) == mtimes
    assert again.stdout == done.stdout

    # a torn last line and a lost plan file: the line is cut off, the job without its plan runs again
    with (out / "index.jsonl").open("ab") as stream:
        stream.write(b'{"job": "unreachable_fast/seed_0001", "wor')
    (out / "plans" / "unreachable_fast" / "seed_0000.json").unlink()
    repaired = run_batch_cli(*args)
    assert repaired.returncode == 0, repaired.stderr
    assert "cut off a torn last line" in repaired.stderr
    assert "3 by an earlier run, 1 now" in repaired.stderr
    lines = index_lines(out)  # every line parses
    assert len(lines) == 5
    assert lines[-1]["job"] == "unreachable_fast/seed_0000"
    assert (out / "plans" / "unreachable_fast" / "seed_0000.json").exists()
    assert {k: v for k, v in _mtimes(out).items() if "unreachable_fast/seed_0000" not in k} == {
        k: v for k, v in mtimes.items() if "unreachable_fast/seed_0000" not in k
    }


def test_a_sigkilled_driver_loses_only_the_jobs_in_flight(tmp_path: Path) -> None:
    out = tmp_path / "out"
    args = [CONFIG / "single_transfer.yaml", "--seeds", SEEDS_TO_INTERRUPT, "--out", out, "--jobs", 2, "--quiet"]
    process = _start_batch(args, subprocess.DEVNULL)
    try:
        _wait_for_index(out, 3, process)
        process.kill()
        process.wait(30)
        # the orphaned workers finish their job, find the driver gone and exit on their own
        deadline = time.monotonic() + 120
        while group_alive(process.pid):
            assert time.monotonic() < deadline, "the workers of the killed driver did not exit"
            time.sleep(0.1)
    finally:
        _kill_group(process.pid)
    kept = index_lines(out)
    assert 3 <= len(kept) < SEEDS_TO_INTERRUPT
    kept_mtimes = {r["plan"]: (out / r["plan"]).stat().st_mtime_ns for r in kept}

    done = run_batch_cli(*args)
    assert done.returncode == 0, done.stderr
    assert f"{len(kept)} by an earlier run, {SEEDS_TO_INTERRUPT - len(kept)} now" in done.stderr
    lines = index_lines(out)
    assert lines[: len(kept)] == kept  # the finished jobs were not run again
    assert sorted(r["seed"] for r in lines) == list(range(SEEDS_TO_INTERRUPT))  # each job once
    assert {plan: (out / plan).stat().st_mtime_ns for plan in kept_mtimes} == kept_mtimes


def test_ctrl_c_stops_cleanly_and_says_how_to_resume(tmp_path: Path) -> None:
    out = tmp_path / "out"
    args = [CONFIG / "single_transfer.yaml", "--seeds", SEEDS_TO_INTERRUPT, "--out", out, "--jobs", 2]
    process = _start_batch(args, subprocess.PIPE)
    try:
        _wait_for_index(out, 1, process)
        process.send_signal(signal.SIGINT)
        _, stderr = process.communicate(timeout=120)
    finally:
        _kill_group(process.pid)
    assert process.returncode == 130, stderr
    assert "Traceback" not in stderr
    assert "SIGINT: stopping" in stderr
    assert "resume with the same command" in stderr
    assert f"single_transfer.yaml --seeds {SEEDS_TO_INTERRUPT} --out {out} --jobs 2" in stderr
    lines = index_lines(out)
    assert 1 <= len(lines) < SEEDS_TO_INTERRUPT
    for record in lines:  # the index is consistent: every line's plan is there and is the job's
        plan = Plan.read(out / record["plan"])
        assert plan.code == record["code"]
        assert plan.stats["seed"] == record["seed"]
    assert not list((out / "plans").rglob(".*.partial"))


def _kill_group(pgid: int) -> None:
    with contextlib.suppress(ProcessLookupError):
        os.killpg(pgid, signal.SIGKILL)


@pytest.mark.parametrize(
    ("arguments", "named"),
    [
        (["missing.yaml", "--seeds", "2"], "missing.yaml: expected a world file"),
        ([str(CONFIG / "figure1.yaml"), "--seeds", "0"], "--seeds: expected an integer >= 1, got 0"),
        ([str(CONFIG / "figure1.yaml"), "--seeds", "2", "--jobs", "0"], "--jobs: expected an integer >= 1"),
        ([str(CONFIG / "figure1.yaml"), "--seeds", "2", "--retries", "-1"], "--retries: expected an integer >= 0"),
        ([str(CONFIG / "figure1.yaml"), "--seeds", "2", "--time-limit", "-1"], "--time-limit: expected"),
        (
            [str(CONFIG / "figure1.yaml"), "--seeds", "2", "--batch-seed", "-5"],
            "--batch-seed: expected an integer >= 0",
        ),
        (["--ray", str(CONFIG / "figure1.yaml"), "--seeds", "2"], "put --ray after the world files"),
        (["a.yaml", "--ray", "not an address", "--seeds", "2"], "--ray: expected a Ray address"),
        (["--generate", "shapes2:x", "--seeds", "1"], "--generate: expected FAMILY:COUNT"),
        (["--generate", "no_such_family:2", "--seeds", "1"], "--generate: "),
    ],
)
def test_bad_input_exits_2_naming_the_argument(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], arguments: list[str], named: str
) -> None:
    assert main([*arguments, "--out", str(tmp_path / "out")]) == 2
    stderr = capsys.readouterr().err
    assert named in stderr
    assert "Traceback" not in stderr
    assert not (tmp_path / "out").exists()


def test_an_invalid_world_exits_2_naming_file_and_parameter(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    bad = tmp_path / "bad.yaml"
    bad.write_text(
        (CONFIG / "figure1.yaml").read_text().replace("initial: [0.0, 1.2, 0.0]", "initial: [0.0, 0.0, 0.0]")
    )
    assert main([str(CONFIG / "single_transfer.yaml"), str(bad), "--seeds", "1", "--out", str(tmp_path / "out")]) == 2
    stderr = capsys.readouterr().err
    assert f"{bad}: world.robot.initial: expected a valid start configuration" in stderr


def test_ray_missing_says_to_install_the_batch_extra(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setitem(sys.modules, "ray", None)  # import ray fails, as without the extra
    out = str(tmp_path / "out")
    # --ray-allow-network: past the refusal of a local Ray on a machine with a network (test/security)
    code = main([str(CONFIG / "single_transfer.yaml"), "--seeds", "1", "--out", out, "--ray", "--ray-allow-network"])
    assert code == 2
    assert "pip install 'clew_ros[batch]'" in capsys.readouterr().err


def test_generated_worlds_are_planned_and_kept_for_the_rerun(tmp_path: Path) -> None:
    """``--generate FAMILY:COUNT``: the worlds clew_world makes (with their witnesses) are written under
    DIR/worlds/ and planned; a rerun plans nothing again and keeps the same world files."""
    out = tmp_path / "out"
    args = ["--generate", "shapes2:2", "--seeds", 1, "--out", out, "--time-limit", 3, "--jobs", 2]
    done = run_batch_cli(*args)
    assert done.returncode == 0, done.stderr
    worlds = sorted((out / "worlds").glob("*.yaml"))
    assert [w.name for w in worlds] == ["shapes2_0000.yaml", "shapes2_0001.yaml"]
    assert all(w.with_suffix(".witness.json").is_file() for w in worlds)
    records = index_lines(out)
    assert sorted(r["job"] for r in records) == ["shapes2_0000/seed_0000", "shapes2_0001/seed_0000"]
    contents = {w: w.read_bytes() for w in worlds}
    again = run_batch_cli(*args)
    assert again.returncode == 0, again.stderr
    assert len(index_lines(out)) == 2  # nothing planned twice
    assert {w: w.read_bytes() for w in worlds} == contents
