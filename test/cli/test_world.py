"""clew_world end to end: the files it writes, its exit codes, and clew_plan on what it wrote."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from clew_ros.cli.world import main
from clew_ros.core.plan import Plan
from clew_ros.planar.collision import check_start_and_goal
from clew_ros.planar.plan import validate_plan
from clew_ros.planar.world import load_world
from clew_ros.worlds import FAMILIES
from clew_ros.worlds.spatial import SPATIAL_FAMILIES

ROOT = Path(__file__).resolve().parents[2]


def run(module: str, *args: object, timeout: float = 300) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", module, *map(str, args)],
        capture_output=True,
        text=True,
        timeout=timeout,
        cwd=ROOT,
        env=dict(os.environ),
    )


def test_list_prints_every_family_on_a_line(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["--list"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert [line.split()[0] for line in lines] == [*FAMILIES, *SPATIAL_FAMILIES]
    assert all(len(line.split(None, 1)[1]) > 20 for line in lines)


def test_writes_the_world_and_its_witness(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    output = tmp_path / "deep" / "pocket.yaml"
    assert main(["pocket", "--seed", "3", "-o", str(output)]) == 0
    world = check_start_and_goal(load_world(output))
    witness = Plan.read(tmp_path / "deep" / "pocket.witness.json")
    assert validate_plan(world, witness) == []
    assert "pocket_3" in capsys.readouterr().err


def test_no_witness(tmp_path: Path) -> None:
    output = tmp_path / "w.yaml"
    assert main(["unsolvable", "--seed", "0", "-o", str(output), "--no-witness"]) == 0
    assert [p.name for p in tmp_path.iterdir()] == ["w.yaml"]
    assert "# expected: unsolvable" in output.read_text()


@pytest.mark.parametrize(
    ("args", "expected"),
    [
        (["shelf", "-o", "w.yaml"], "FAMILY: unknown family 'shelf': expected one of shapes2,"),
        (["-o", "w.yaml"], "FAMILY: expected one of shapes2,"),
        (["shapes2"], "--output: expected the parameter file"),
        (["shapes2", "--seed", "-4", "-o", "w.yaml"], "--seed: expected an integer >= 0, got -4"),
    ],
)
def test_bad_arguments_exit_2_naming_the_argument(
    args: list[str], expected: str, tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(tmp_path)
    assert main(args) == 2
    assert expected in capsys.readouterr().err
    assert not list(tmp_path.iterdir())


def test_an_unwritable_output_exits_2(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    (tmp_path / "file").write_text("")
    assert main(["shapes2", "-o", str(tmp_path / "file" / "w.yaml")]) == 2
    assert "--output: cannot write" in capsys.readouterr().err


def test_a_non_integer_seed_exits_2() -> None:
    done = run("clew_ros.cli.world", "shapes2", "--seed", "x", "-o", "w.yaml")
    assert done.returncode == 2
    assert "--seed" in done.stderr


def test_clew_plan_solves_a_generated_two_joint_world(tmp_path: Path) -> None:
    """One seed of the 2-joint family, planned as a user would with a generous limit; no timing asserted."""
    world_file = tmp_path / "shapes2_0.yaml"
    made = run("clew_ros.cli.world", "shapes2", "--seed", "0", "-o", world_file)
    assert made.returncode == 0, made.stderr
    plan_file = tmp_path / "plan.json"
    planned = run("clew_ros.cli.plan", world_file, "-o", plan_file, "--seed", "0", "--time-limit", "120", "-q")
    assert planned.returncode == 0, planned.stderr
    document = json.loads(plan_file.read_text())
    assert document["code"] == "SUCCEEDED"
    assert validate_plan(load_world(world_file), document) == []
