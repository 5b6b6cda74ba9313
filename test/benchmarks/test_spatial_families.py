"""``benchmarks.spatial_families`` plans generated spatial worlds, validates the plans and counts them against the
witness; its table counts a failure at the limit and gives the unsolvable family's outcomes. No speed is checked."""

from __future__ import annotations

import dataclasses

import pytest

pytest.importorskip("trimesh")
pytest.importorskip("urdf_parser_py")

from benchmarks import spatial_families
from benchmarks.__main__ import COMMANDS
from benchmarks.spatial_families import FamilyRun


def _cells(line: str) -> list[str]:
    return [cell.strip() for cell in line.strip().strip("|").split("|")]


def _run(family: str, success: bool, time_s: float, transfers: int | None, *, solvable: bool = True) -> FamilyRun:
    return FamilyRun(
        family=family, robot="panda", world_seed=0, seed=0, dof=7, solvable=solvable,
        outcome="SUCCEEDED" if success else ("NO_PATH_AT_RESOLUTION" if not solvable else "TIME_LIMIT"),
        success=success, time_s=time_s, transfers=transfers, witness_transfers=1 if solvable else None,
        valid=True if success else None, message="",
    )  # fmt: skip


def test_the_table_counts_failures_at_the_limit_needless_regrasps_and_the_unsolvable_outcomes() -> None:
    runs = [
        _run("spatial_table", True, 0.2, 1),
        _run("spatial_table", True, 0.4, 3),  # two more grasps than the witness: a needless regrasp
        _run("spatial_table", False, 10.0, None),
        dataclasses.replace(_run("spatial_table", True, 0.1, 1), valid=False),  # refused by the validator
        _run("spatial_unsolvable", False, 0.05, None, solvable=False),
        _run("spatial_unsolvable", False, 0.07, None, solvable=False),
    ]
    lines = spatial_families.rows(runs, time_limit_s=10.0)
    table = {tuple(_cells(line)[:2]): _cells(line)[2:] for line in lines[2:]}
    assert table["spatial_table", "panda"] == ["4", "50%", "5.200", "10.000", "2 / 1", "1/2", "2/3"]
    unsolvable = table["spatial_unsolvable", "panda"]
    assert unsolvable[:3] == ["2", "NO_PATH_AT_RESOLUTION 2", "0.060"]  # timed as they came, not at the limit
    assert table["solvable", "all"] == table["spatial_table", "panda"]


def test_a_tiny_run_plans_a_table_world_valid_with_the_witness_transfers(capsys: pytest.CaptureFixture[str]) -> None:
    assert "spatial_families" in COMMANDS
    arguments = ["--families", "spatial_table", "--robots", "panda", "--worlds", "1", "--seeds", "1"]
    assert spatial_families.main(arguments) == 0
    out = capsys.readouterr().out
    rows = [_cells(line) for line in out.splitlines() if line.startswith("| spatial_table | panda |")]
    assert len(rows) == 1
    runs, success, _, _, transfers, lean, valid = rows[0][2:]
    assert (runs, success, lean, valid) == ("1", "100%", "1/1", "1/1")  # validated by validate_plan at 0.002 rad
    plan_transfers, witness = (int(v) for v in transfers.split(" / "))
    assert 1 <= plan_transfers <= witness + 1


def test_bad_counts_are_refused_by_name(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit):
        spatial_families.main(["--worlds", "0"])
    assert "--worlds and --seeds: expected at least 1" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        spatial_families.main(["--families", "spatial_attic"])
    assert "--families: invalid choice: 'spatial_attic'" in capsys.readouterr().err
