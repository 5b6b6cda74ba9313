"""``benchmarks.spatial_checker`` prints its table for a robot, with no violation of the exact reference."""

from __future__ import annotations

import importlib.util

import pytest

pytest.importorskip("trimesh")

from benchmarks import spatial_checker


def test_one_robot_quick(capsys: pytest.CaptureFixture[str]) -> None:
    args = ["--robots", "panda", "--batch", "128", "--seconds", "0.05", "--intervals", "4", "--ik-poses", "3"]
    assert spatial_checker.main([*args, "--agreement-seconds", "2", "--agreement-max", "2000"]) == 0
    out = capsys.readouterr().out
    rows = {
        cells[0]: cells[1]
        for line in out.splitlines()
        if line.startswith("| ") and len(cells := [c.strip() for c in line.split("|")[1:-1]]) == 2
    }
    assert float(rows["validity checks per CPU second, batch of 128 as drawn"].replace(",", "")) > 0
    assert float(rows["free intervals per CPU second (4 valid configurations x 7 joints)"].replace(",", "")) > 0
    assert "over the URDF's geometry: mean" in out
    if importlib.util.find_spec("pinocchio") and importlib.util.find_spec("coal"):
        agreement = rows["agreement: configurations / checker valid / reference free / valid but colliding"]
        assert agreement.split(" / ")[-1] == "0"
