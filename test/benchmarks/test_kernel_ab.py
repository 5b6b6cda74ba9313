"""``benchmarks.kernel_ab`` loads a revision's kernel beside this one and compares them in one process."""

import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

from benchmarks.kernel_ab import ROOT, baseline_kernel, compare
from benchmarks.worlds import all_worlds, select
from clew_ros.planar.collision import check_start_and_goal
from clew_ros.planar.world import world_from_parameters


def _in_a_repository() -> bool:
    if shutil.which("git") is None:
        return False
    return subprocess.run(["git", "rev-parse", "HEAD"], cwd=ROOT, capture_output=True, check=False).returncode == 0


@pytest.mark.skipif(not _in_a_repository(), reason="needs git and a git checkout (the benchmark reads a revision)")
def test_the_kernel_of_a_revision_runs_beside_this_one_with_the_same_numbers(tmp_path):
    """HEAD's kernel, loaded from git as a package of its own, gives this code's numbers (transit and
    transfer, intervals, decoding, the validity first pass and straight moves), and every figure is a positive rate;
    no speed is asserted."""
    base = baseline_kernel("HEAD", tmp_path)
    assert Path(base.__file__).is_relative_to(tmp_path)  # kernel_baseline.py, or kernel_baseline/ (a package)
    assert base.intervals.__module__.startswith("kernel_baseline")  # not this code's kernel
    world = check_start_and_goal(world_from_parameters(select(all_worlds(), "figure1")[0].parameters))
    rows = compare(world, base, configs=300, repeats=1)
    assert [row["mode"] for row in rows] == ["transit", "transfer"]
    for row in rows:
        assert row["same"], row
        assert row["configurations"] >= 24
        for name in ("b24", "decode24", "valid24", "moves24"):
            assert np.isfinite(row[name]["after_over_before"])
            assert row[name]["before"] > 0
            assert row[name]["after"] > 0
