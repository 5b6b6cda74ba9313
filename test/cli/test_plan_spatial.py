"""clew_plan and clew_batch on a spatial world (``world.kind: spatial``): the plan file a user gets is a valid
spatial plan, and a batch job gives exactly the plan ``clew_plan --seed S`` gives."""

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from clew_ros.planar.world import read_parameter_file
from clew_ros.spatial.plan import validate_plan
from clew_ros.spatial.world import spatial_world_from_parameters

ROOT = Path(__file__).resolve().parents[2]
WORLD = ROOT / "config" / "spatial" / "panda_table_to_table.yaml"


def _run(module: str, *args: object, cwd: Path) -> subprocess.CompletedProcess[str]:
    command = [sys.executable, "-m", module, *map(str, args)]
    return subprocess.run(command, capture_output=True, text=True, timeout=600, cwd=cwd, env=dict(os.environ))


def _without_clock(path: Path) -> dict:
    plan = json.loads(path.read_text())
    plan["stats"].pop("time_s")
    return plan


def test_clew_plan_writes_a_valid_spatial_plan_and_clew_batch_the_same_one(tmp_path: Path) -> None:
    batch = _run(
        "clew_ros.cli.batch", WORLD, "--seeds", 1, "--jobs", 1, "--time-limit", 60, "--out", "out", cwd=tmp_path
    )
    assert batch.returncode == 0, batch.stderr
    [planned] = sorted((tmp_path / "out" / "plans" / WORLD.stem).glob("*.json"))
    seed = json.loads(planned.read_text())["stats"]["seed"]
    # from another folder: the world's relative paths (URDF, SRDF) are read from the world file's folder
    single = _run("clew_ros.cli.plan", WORLD, "-o", "plan.json", "--seed", seed, "--time-limit", 60, "-q", cwd=tmp_path)
    assert single.returncode == 0, single.stderr
    document = json.loads((tmp_path / "plan.json").read_text())
    assert document["world_kind"] == "spatial"
    assert document["code"] == "SUCCEEDED"
    assert len(document["final_object_pose"]) == 6
    world = spatial_world_from_parameters(read_parameter_file(WORLD), WORLD.parent)
    assert validate_plan(world, document) == []
    assert _without_clock(tmp_path / "plan.json") == _without_clock(planned)


def test_clew_batch_record_checks_a_spatial_worlds_node_parameters_first(tmp_path: Path) -> None:
    """``--record`` on a spatial world times its playback from the world file's node parameters: a bad one is
    refused before any job runs, naming the file and the parameter (the recordings themselves:
    test/batch/test_record.py)."""
    pytest.importorskip("rclpy", reason="--record needs rclpy (the ros extra)")
    robots = (ROOT / "config" / "robots").resolve()
    text = (
        WORLD.read_text()
        .replace("../robots/", f"{robots}/")
        .replace("ros__parameters:\n", "ros__parameters:\n    playback: {rate: -2.0}\n", 1)
    )
    world = tmp_path / "bad_rate.yaml"
    world.write_text(text)
    result = _run("clew_ros.cli.batch", world, "--seeds", 1, "--record", "--out", "out", cwd=tmp_path)
    assert result.returncode == 2, result.stderr
    assert world.name in result.stderr
    assert "playback.rate" in result.stderr
    assert not (tmp_path / "out" / "plans").exists()


def test_a_world_kind_that_is_neither_is_refused_by_name(tmp_path: Path) -> None:
    world = tmp_path / "odd.yaml"
    world.write_text(WORLD.read_text().replace("kind: spatial", "kind: conical"))
    result = _run("clew_ros.cli.plan", world, "-o", "plan.json", cwd=tmp_path)
    assert result.returncode == 2
    assert "world.kind" in result.stderr
    assert "conical" in result.stderr
