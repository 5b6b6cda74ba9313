"""The benchmark suite runs end to end (``--quick``) and writes every column; speed is not checked."""

import csv
import importlib.util
import json
import subprocess
import sys
from pathlib import Path

import pytest

from benchmarks.run import COLUMNS, DOC_BEGIN, DOC_END, QUICK_WORLDS
from benchmarks.worlds import JOINT_COUNTS, OBSTACLE_COUNTS, generated_worlds, write_world
from clew_ros.planar.world import load_world

ROOT = Path(__file__).resolve().parents[2]


def test_generated_worlds_are_valid_and_as_specified(tmp_path):
    worlds = {w.name: w for w in generated_worlds()}
    for n in JOINT_COUNTS:
        robot = worlds[f"joints_{n}"].parameters["world"]["robot"]
        assert len(robot["link_lengths"]) == n
        assert sum(robot["link_lengths"]) == pytest.approx(1.7)
        assert all(a >= b for a, b in zip(robot["link_lengths"], robot["link_lengths"][1:], strict=False))
        assert robot["joint_upper"][0] == pytest.approx(3.14159)
        assert set(robot["joint_upper"][1:]) == {2.8}
    for m in OBSTACLE_COUNTS:
        assert worlds[f"obstacles_{m}"].obstacles == m
    # written out, a generated world loads with the same checks as a config file (start and goal valid)
    path = write_world(worlds["obstacles_32"], tmp_path)
    assert len(load_world(path).obstacles) == 32


def test_quick_suite_writes_every_column(tmp_path):
    """``suite --quick`` through the entry (the CI smoke run, about 30 s): every output written, every column filled;
    no speed asserted."""
    out = tmp_path / "bench"
    doc = tmp_path / "doc.md"
    doc.write_text(f"# Benchmarks\n\nkept\n\n{DOC_BEGIN}\nold\n{DOC_END}\n\nkept too\n")
    done = subprocess.run(
        [sys.executable, "-m", "benchmarks", "suite", "--quick", "--out", str(out), "--doc", str(doc)],
        check=False,
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert done.returncode == 0, done.stderr[-2000:]
    with (out / "benchmarks.csv").open(newline="") as handle:
        reader = csv.DictReader(handle)
        assert reader.fieldnames == COLUMNS
        rows = {r["world"]: r for r in reader}
    assert set(rows) == set(QUICK_WORLDS.split(","))
    assert rows["obstacles_2"]["same_as"] == "joints_3"
    for row in rows.values():
        for column in (
            "world",
            "series",
            "joints",
            "obstacles",
            "seeds",
            "time_limit_s",
            "success_rate",
            "median_s",
            "p90_s",
            "median_cpu_s",
            "p90_cpu_s",
            "landmarks_median",
            "evaluations_median",
            "collision_checks_median",
            "checks_per_s",
            "checks_per_cpu_s",
            "peak_rss_mb",
            "rss_growth_mb",
            "peer_note",
        ):
            assert row[column] != "", (row["world"], column)
        assert int(row["seeds"]) == 2
        assert 0.0 <= float(row["success_rate"]) <= 1.0
        assert 0.0 < float(row["median_s"]) <= float(row["p90_s"]) <= float(row["time_limit_s"]) + 1.0
        assert float(row["evaluations_median"]) > 0
        assert float(row["collision_checks_median"]) > 0
        assert float(row["checks_per_s"]) > 0
        assert float(row["peak_rss_mb"]) > 0
        if float(row["success_rate"]) > 0:
            assert row["median_success_s"] != ""
            assert row["grasps_median"] != ""
            assert row["valid_plans"] != ""
    report = json.loads((out / "benchmarks.json").read_text())
    assert report["machine"]["nproc"] >= 1
    assert report["machine"]["cpu_model"]
    # throughput: batched is_valid and the per-configuration shapely loop, same answers, both measured
    assert set(report["throughput"]) == {"figure1", "obstacles_32"}
    for t in report["throughput"].values():
        assert t["agree"] == t["configs"] > 0
        assert t["batched"]["per_s"] > 0
        assert t["loop"]["per_s"] > 0
        assert t["ratio_batched_over_loop"] > 0
        assert all(v["per_s"] > 0 for v in t["intervals"].values())
    # peer on figure1: the project's side always, OMPL's when the bench extra is installed
    figure1 = rows["figure1"]
    assert int(figure1["peer_problems"]) > 0
    assert 0.0 <= float(figure1["project_success_rate"]) <= 1.0
    assert float(figure1["project_median_s"]) > 0
    if importlib.util.find_spec("ompl") is None:
        assert figure1["ompl_success_rate"] == "n/a"
        assert "n/a" in figure1["peer_note"]
    else:
        assert 0.0 <= float(figure1["ompl_success_rate"]) <= 1.0
        assert float(figure1["ompl_median_s"]) > 0
        assert float(figure1["time_ratio_project_over_ompl"]) > 0
        assert report["peer"]["figure1"]["ompl_checker"] == "is_valid"
    for other in set(rows) - {"figure1"}:
        assert rows[other]["peer_problems"] == ""
        assert rows[other]["peer_note"] == "not in the peer selection"
    # profile, Markdown report, plot, and the doc updated between its markers only
    assert report["profile"]["by_file"]
    assert "ncalls" in report["profile"]["tottime"]
    assert (out / "profile_figure1.txt").stat().st_size > 0
    markdown = (out / "benchmarks.md").read_text()
    assert "| world | n | obs |" in markdown
    assert "### Collision throughput" in markdown
    text = doc.read_text()
    assert text.startswith("# Benchmarks\n\nkept\n")
    assert text.endswith("kept too\n")
    assert "\nold\n" not in text
    assert markdown.strip() in text
    if importlib.util.find_spec("matplotlib") is not None:
        png = out / "benchmarks_scaling.png"
        assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
        assert (tmp_path / "benchmarks_scaling.png").read_bytes() == png.read_bytes()
