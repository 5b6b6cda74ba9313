"""The benchmark suite runs end to end (``--quick``) and writes every column; speed is not checked."""

import csv
import importlib.util
import json
import subprocess
import sys
from pathlib import Path

import pytest

from benchmarks.families import JOINT_COUNTS, OBSTACLE_COUNTS, generated_worlds, write_world
from benchmarks.run import COLUMNS
from clew_ros.core.world import load_world

ROOT = Path(__file__).resolve().parents[1]


def test_generated_worlds_are_valid_and_as_specified(tmp_path):
    worlds = {w.name: w for w in generated_worlds()}
    for n in JOINT_COUNTS:
        robot = worlds[f"joints_{n}"].parameters["world"]["robot"]
        assert len(robot["link_lengths"]) == n
        assert sum(robot["link_lengths"]) == pytest.approx(1.7)
        assert all(a >= b for a, b in zip(robot["link_lengths"], robot["link_lengths"][1:]))
        assert robot["joint_upper"][0] == pytest.approx(3.14159) and set(robot["joint_upper"][1:]) == {2.8}
    for m in OBSTACLE_COUNTS:
        assert worlds[f"obstacles_{m}"].obstacles == m
    # written out, a generated world loads with the same checks as a config file (start and goal valid)
    path = write_world(worlds["obstacles_32"], tmp_path)
    assert len(load_world(path).obstacles) == 32


@pytest.mark.slow
def test_quick_suite_writes_every_column(tmp_path):
    out = tmp_path / "bench"
    done = subprocess.run([sys.executable, "-m", "benchmarks.run", "--quick", "--out", str(out)], cwd=ROOT,
                          capture_output=True, text=True, timeout=170)
    assert done.returncode == 0, done.stderr[-2000:]
    with open(out / "benchmarks.csv", newline="") as handle:
        reader = csv.DictReader(handle)
        assert reader.fieldnames == COLUMNS
        rows = list(reader)
    assert {r["world"] for r in rows} == {"single_transfer", "figure1", "obstacles_8"}
    for row in rows:
        for column in ("world", "seeds", "time_limit_s", "success_rate", "median_s", "p90_s", "checks_per_s",
                       "peak_rss_mb"):
            assert row[column] != "", (row["world"], column)
    report = json.loads((out / "benchmarks.json").read_text())
    assert set(report["throughput"]) == {"figure1", "obstacles_32"}
    assert all(t["agree"] == t["configs"] for t in report["throughput"].values())
    figure1 = next(r for r in rows if r["world"] == "figure1")
    if importlib.util.find_spec("ompl") is None:
        assert figure1["ompl_success_rate"] == "n/a" and "n/a" in figure1["peer_note"]
    else:
        assert float(figure1["ompl_success_rate"]) >= 0.0
    assert figure1["project_success_rate"] != ""
