"""clew_batch --ray on a real local Ray: the same plans as the local pool.

Ray runs only inside a private network namespace with nothing but loopback up
(``unshare --net``, then ``ip link set lo up``; root needed): a local Ray probes
outside addresses and binds on every interface, and nothing may leave this
machine. Without such a namespace, or without Ray, the test is skipped and says
why.
"""

from __future__ import annotations

import importlib.util
import os
import shutil
import subprocess
import tempfile
from collections.abc import Iterator
from pathlib import Path

import pytest
from helpers.batch_cli import CONFIG, ROOT, batch_command, index_lines, run_batch_cli, without_wall_time

from benchmarks.batch import IN_PRIVATE_NETWORK, private_network_unavailable
from clew_ros.recording import Recording


@pytest.fixture
def ray_temp_dir() -> Iterator[Path]:
    """A short folder of Ray's own (its socket paths must stay under 108 characters), removed after."""
    folder = Path(tempfile.mkdtemp(prefix="clew_ray_", dir="/tmp"))
    yield folder
    shutil.rmtree(folder, ignore_errors=True)


def test_a_local_ray_makes_the_pools_plans(tmp_path: Path, ray_temp_dir: Path) -> None:
    if importlib.util.find_spec("ray") is None:
        pytest.skip("Ray is not installed: pip install 'clew_ros[batch]'")
    reason = private_network_unavailable()
    if reason:
        pytest.skip(f"the Ray part runs only in a private network namespace: {reason}")
    worlds = [CONFIG / "single_transfer.yaml", CONFIG / "figure1.yaml"]
    pool = run_batch_cli(*worlds, "--seeds", 2, "--out", tmp_path / "pool", "--jobs", 2, "--quiet")
    assert pool.returncode == 0, pool.stderr

    env = dict(os.environ, RAY_USAGE_STATS_ENABLED="0", RAY_TMPDIR=str(ray_temp_dir))
    # with --record (when the ros extra is there): the recordings come back from Ray's workers as bytes
    # and the driver writes them
    recorded = importlib.util.find_spec("rclpy") is not None
    ray_args = ("--jobs", 2, "--quiet", "--ray", *(["--record"] if recorded else []))
    command = batch_command(*worlds, "--seeds", 2, "--out", tmp_path / "ray", *ray_args)
    ray = subprocess.run(
        [*IN_PRIVATE_NETWORK, *command], capture_output=True, text=True, timeout=900, cwd=ROOT, env=env
    )
    assert ray.returncode == 0, ray.stderr
    assert "a local Ray on 127.0.0.1" in ray.stderr
    pool_records = {r["job"]: r for r in index_lines(tmp_path / "pool")}
    ray_records = {r["job"]: r for r in index_lines(tmp_path / "ray")}
    assert sorted(ray_records) == sorted(pool_records)
    assert len(ray_records) == 4
    for job, record in ray_records.items():
        assert record["code"] == pool_records[job]["code"] == "SUCCEEDED"
        ray_plan = (tmp_path / "ray" / record["plan"]).read_text()
        pool_plan = (tmp_path / "pool" / record["plan"]).read_text()
        assert without_wall_time(ray_plan) == without_wall_time(pool_plan), job
        assert pool_records[job]["recording"] is None
        if recorded:
            recording = Recording(tmp_path / "ray" / record["recording"])
            assert "/clew_planner/trajectory" in recording.topics, job
