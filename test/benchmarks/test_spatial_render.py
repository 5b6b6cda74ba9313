"""``benchmarks.spatial_render`` prints its figures for a small picture; no speed is checked."""

from __future__ import annotations

import re

import pytest

pytest.importorskip("trimesh")
pytest.importorskip("urdf_parser_py")

from benchmarks import spatial_render


def test_quick_run(capsys: pytest.CaptureFixture[str]) -> None:
    assert spatial_render.main(["--size", "160", "--frames", "3", "--repeats", "1"]) == 0
    out = capsys.readouterr().out
    assert re.search(r"panda_two_tables, 160x120 px, robot \d+ triangles a pose", out)
    for label in ("world alone", "still of 3 frames", "GIF, per frame"):
        assert re.search(rf"{re.escape(label)}.* +[\d.]+ s CPU", out), label
