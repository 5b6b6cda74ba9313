"""``benchmarks.check_cost`` times batched checks and prints their cost against the budget's charge."""

from __future__ import annotations

import pytest

from benchmarks import check_cost
from clew_ros.planar.improve import ImproveSettings


def test_every_world_gets_a_row_per_kind_with_its_configurations_and_ratios(capsys: pytest.CaptureFixture[str]) -> None:
    assert check_cost.main(["--worlds", "figure1", "obstacles_8", "--batch", "300"]) == 0
    rows = [line.split("|")[1:-1] for line in capsys.readouterr().out.splitlines() if line.startswith("| ")]
    rows = [[cell.strip() for cell in row] for row in rows if row[0].strip() != "world"]
    assert [(row[0], row[2]) for row in rows] == [
        ("figure1", "still"),
        ("figure1", "moves"),
        ("obstacles_8", "still"),
        ("obstacles_8", "moves"),
    ]
    for world, work, kind, configurations, per_us, ratios in rows:
        assert float(work) >= 1.0
        # still: each configuration once; moves: every sample along 0.3 rad moves, more than one a move
        assert int(configurations) == 300 if kind == "still" else int(configurations) > 300, world
        assert float(per_us) > 0.0
        charged_one, now = (float(r) for r in ratios.split("/"))
        assert now == pytest.approx(
            charged_one / ImproveSettings().batch_check_share, abs=0.011 / ImproveSettings().batch_check_share
        )
