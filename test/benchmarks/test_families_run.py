"""The family benchmark runs end to end on a tiny selection and writes its table; speed is not checked."""

import json
from pathlib import Path

from benchmarks.families_run import HEADER, main
from benchmarks.generated import reference_world


def test_a_tiny_family_run_writes_every_row(tmp_path: Path) -> None:
    out = tmp_path / "out"
    worlds = tmp_path / "worlds"
    args = ["--families", "shapes2,unsolvable", "--worlds", "2", "--seeds", "1", "--time-limit", "2"]
    assert main([*args, "--jobs", "2", "--out", str(out), "--keep-worlds", str(worlds)]) == 0
    report = json.loads((out / "families.json").read_text())
    assert [row["family"] for row in report["rows"]] == ["figure1", "shapes2", "unsolvable"]
    assert sorted(p.name for p in worlds.glob("*.yaml")) == [
        "shapes2_0.yaml",
        "shapes2_1.yaml",
        "unsolvable_0.yaml",
        "unsolvable_1.yaml",
    ]
    assert len(list(worlds.glob("*.witness.json"))) == 4
    rows = {row["family"]: row for row in report["rows"]}
    assert rows["figure1"]["runs"] == 1
    assert rows["shapes2"]["runs"] == 2
    assert rows["shapes2"]["solvable"]
    assert 0.0 <= rows["shapes2"]["success_rate"] <= 1.0
    assert rows["shapes2"]["witness_transfers_median"] >= 1
    assert rows["shapes2"]["witness_travel_median"] > 0
    assert not rows["unsolvable"]["solvable"]
    assert rows["unsolvable"]["success_rate"] is None
    assert rows["unsolvable"]["successes"] == 0  # no plan can exist
    for run in report["runs"]:
        assert run["outcome"] in {"SUCCEEDED", "TIME_LIMIT", "NO_PATH_AT_RESOLUTION"}
        assert run["wall_s"] > 0
    table = (out / "families.md").read_text()
    assert "| " + " | ".join(HEADER) + " |" in table
    assert "unsolvable:" in table


def test_held_out_worlds_start_at_the_first_world_seed(tmp_path: Path) -> None:
    out, worlds = tmp_path / "out", tmp_path / "worlds"
    args = ["--families", "shapes2", "--worlds", "2", "--first-world", "40", "--seeds", "1", "--time-limit", "2"]
    assert main([*args, "--no-figure1", "--out", str(out), "--keep-worlds", str(worlds)]) == 0
    assert sorted(p.name for p in worlds.glob("*.yaml")) == ["shapes2_40.yaml", "shapes2_41.yaml"]
    report = json.loads((out / "families.json").read_text())
    assert report["first_world"] == 40
    assert sorted(w["seed"] for w in report["worlds"]) == [40, 41]


def test_a_config_world_without_a_plan_is_no_solvable_reference() -> None:
    assert reference_world("figure1").solvable
    assert not reference_world("unreachable").solvable
