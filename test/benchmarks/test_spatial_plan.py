"""``benchmarks.spatial_plan`` plans its problems and checks every plan at 0.002 rad."""

from __future__ import annotations

import pytest

pytest.importorskip("trimesh")

from benchmarks import spatial_plan


def test_one_problem_one_seed(capsys: pytest.CaptureFixture[str]) -> None:
    assert spatial_plan.main(["--seeds", "1", "--time-limit", "30", "--problems", "table"]) == 0
    summary = [line for line in capsys.readouterr().out.splitlines() if line.startswith("table ")]
    assert len(summary) == 1
    assert "success 1/1" in summary[0]
    assert "transfers 1-1" in summary[0]
    assert summary[0].endswith("invalid pieces 0")
