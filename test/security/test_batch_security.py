"""clew_batch: file names sent back by workers are checked before any write; what it writes is private
(files 0600, folders 0700); a local Ray is refused while the machine has a network, unless the operator says
it is trusted; a crafted index line does not stop a resume."""

from __future__ import annotations

import json
import os
import stat
import subprocess
import sys
from pathlib import Path

import pytest
from helpers.batch_cli import CONFIG

from clew_ros.batch.executors import Finished, network_interfaces_up
from clew_ros.batch.files import UnsafeNameError, check_file_name
from clew_ros.batch.index import Index
from clew_ros.batch.jobs import load_worlds, make_jobs
from clew_ros.batch.recording import write_recording
from clew_ros.batch.runner import run_batch
from clew_ros.batch.worker import JobOutcome, JobSpec
from clew_ros.cli.batch import main as clew_batch
from clew_ros.planar.offline import failed_plan

UNSAFE = ["../escaped", "/tmp/absolute", "a/b", "..", ".", "", "nul\x00name", "back\\slash", "x" * 300, 7, None]


@pytest.mark.parametrize("name", UNSAFE, ids=repr)
def test_unsafe_names_are_refused(name: object) -> None:
    with pytest.raises(UnsafeNameError, match="is not a plain file name"):
        check_file_name(name)


def test_write_recording_writes_nothing_for_an_unsafe_name(tmp_path: Path) -> None:
    folder = tmp_path / "out" / "recordings" / "world" / "seed_0"
    with pytest.raises(UnsafeNameError):
        write_recording(folder, {"metadata.yaml": b"ok", "../../../escaped": b"x"})
    assert not (tmp_path / "escaped").exists()
    assert not (tmp_path / "out").exists()


class _SendsBack:
    """An executor (no processes) whose workers answer every job with a recording under ``names``."""

    capacity = 4
    description = "scripted"

    def __init__(self, jobs: list, names: list[str]) -> None:
        self.by_key = {job.key: job for job in jobs}
        self.names = names
        self.submitted: list[JobSpec] = []

    def start(self) -> None:
        pass

    def submit(self, spec: JobSpec) -> None:
        self.submitted.append(spec)

    def wait(self, timeout_s: float) -> list[Finished]:
        del timeout_s
        finished = []
        for spec in self.submitted:
            job = self.by_key[spec.key]
            plan = failed_plan(job.world.problem.world, job.settings, "scripted", 0.0)
            files = dict.fromkeys(self.names, b"from the worker")
            finished.append(Finished(spec, outcome=JobOutcome.from_plan(spec.key, plan, 0.0, recording=files)))
        self.submitted = []
        return finished

    def close(self) -> None:
        pass


def test_a_worker_cannot_write_outside_its_folder(tmp_path: Path) -> None:
    jobs = make_jobs(load_worlds([(CONFIG / "single_transfer.yaml").resolve()]), [0, 1])
    out = tmp_path / "out"
    names = ["metadata.yaml", "../../../../escaped.txt"]
    report = run_batch(jobs, out, _SendsBack(jobs, names), record=True)
    assert report.ran == 2
    assert not (tmp_path / "escaped.txt").exists()
    assert not list(tmp_path.rglob("escaped.txt"))
    for record in report.records:
        assert record["code"] == "INTERNAL_ERROR"
        assert "'../../../../escaped.txt' is not a plain file name" in record["message"]


def _modes(root: Path) -> dict[str, int]:
    return {str(path.relative_to(root)): stat.S_IMODE(path.stat().st_mode) for path in root.rglob("*")}


def test_index_plans_and_recordings_are_private(tmp_path: Path) -> None:
    jobs = make_jobs(load_worlds([(CONFIG / "single_transfer.yaml").resolve()]), [0])
    out = tmp_path / "out"
    previous = os.umask(0o022)
    try:
        run_batch(jobs, out, _SendsBack(jobs, ["metadata.yaml", "run_0.mcap"]), record=False)
        write_recording(out / "recordings" / "w" / "seed_0", {"metadata.yaml": b"x", "run_0.mcap": b"y"})
    finally:
        os.umask(previous)
    modes = _modes(out)
    assert stat.S_IMODE(out.stat().st_mode) == 0o700
    assert modes["index.jsonl"] == 0o600
    assert modes["recordings/w/seed_0/run_0.mcap"] == 0o600
    for name, mode in modes.items():
        is_dir = (out / name).is_dir()
        assert mode == (0o700 if is_dir else 0o600), (name, oct(mode))


def test_an_old_world_readable_index_becomes_private(tmp_path: Path) -> None:
    tmp_path.joinpath("index.jsonl").write_text("")
    tmp_path.joinpath("index.jsonl").chmod(0o644)
    with Index.open(tmp_path):
        pass
    assert stat.S_IMODE(tmp_path.joinpath("index.jsonl").stat().st_mode) == 0o600


def test_crafted_index_lines_are_skipped(tmp_path: Path) -> None:
    good = {"job": "w/seed_0", "code": "SUCCEEDED"}
    lines = [
        json.dumps(good).encode(),
        b"[" * 100_000 + b"]" * 100_000,
        b'{"job": "w/seed_1", "wall_time_s": NaN}',
        b"\xff\xfe\x00 binary",
        b'{"job": ' + b"9" * 5000 + b"}",
    ]
    tmp_path.joinpath("index.jsonl").write_bytes(b"\n".join(lines) + b"\n")
    with Index.open(tmp_path) as index:
        assert list(index.records) == ["w/seed_0"]
        assert index.skipped_lines == 4


def _batch_command(out: Path, *extra: str) -> list[str]:
    return [sys.executable, "-m", "clew_ros.cli.batch", str(CONFIG / "single_transfer.yaml"), "--seeds", "1",
            "--out", str(out), "--ray", *extra]  # fmt: skip


def test_a_local_ray_is_refused_outside_a_private_network_namespace(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Here (when this machine has a network): refused, nothing written. Inside ``unshare --net`` with only
    loopback up (when it can be made): not refused (without Ray installed, the next check speaks)."""
    from benchmarks.batch import IN_PRIVATE_NETWORK, private_network_unavailable

    if not network_interfaces_up() and private_network_unavailable():
        pytest.skip("no network interface up here to refuse, and no private network namespace to compare")
    if network_interfaces_up():
        out = tmp_path / "out"
        code = clew_batch([str(CONFIG / "single_transfer.yaml"), "--seeds", "1", "--out", str(out), "--ray"])
        err = capsys.readouterr().err
        assert code == 2
        assert "clew_batch: invalid input: --ray: a local Ray probes outside addresses" in err
        assert "--ray-allow-network" in err
        assert not out.exists()
    if not private_network_unavailable():
        result = subprocess.run(
            [*IN_PRIVATE_NETWORK, *_batch_command(tmp_path / "private")],
            capture_output=True, text=True, timeout=300, check=False,
        )  # fmt: skip
        assert "probes outside addresses" not in result.stderr
        if result.returncode == 2:
            assert "needs Ray, which is not installed" in result.stderr, result.stderr
        else:
            assert result.returncode == 0, result.stderr


def test_the_operator_can_allow_a_network(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setitem(sys.modules, "ray", None)  # no Ray started here: import ray fails
    world = str(CONFIG / "single_transfer.yaml")
    code = clew_batch([world, "--seeds", "1", "--out", str(tmp_path), "--ray", "--ray-allow-network"])
    err = capsys.readouterr().err
    assert "probes outside addresses" not in err
    assert code == 2
    assert "needs Ray" in err
