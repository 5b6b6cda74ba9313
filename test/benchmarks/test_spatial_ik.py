"""``benchmarks.spatial_ik`` prints its figures for a shipped robot and a random one; no speed is checked."""

from __future__ import annotations

import re

import pytest

pytest.importorskip("trimesh")
pytest.importorskip("urdf_parser_py")

from benchmarks import spatial_ik


def test_quick_run(capsys: pytest.CaptureFixture[str]) -> None:
    assert spatial_ik.main(["--robots", "ur5", "--targets", "10", "--seeds", "8", "--random-robots", "1"]) == 0
    out = capsys.readouterr().out
    rows = [line for line in out.splitlines() if " dof " in line and "solve_rows" not in line]
    assert [row.split()[0] for row in rows] == ["ur5", "random"]
    for row in rows:
        solved = re.search(r"  solved +([\d.]+)%", row)
        assert solved is not None
        assert float(solved.group(1)) >= 30.0  # 8 seeds only: a smoke run, the figures come from 200 targets
        assert "unreachable solved 0%" in row
    assert re.search(r"random.* solve_rows: level face met +[\d.]+%", out)  # inverse.solve_rows, the same kernel
    assert re.search(r"ur5 +in a 30-box scene: collision-free solved +[\d.]+%", out)
