"""The variants benchmark: a variant replaces the tuning fields it names in its workers (a setting that changes
the plan changes it), and bad variants are refused naming what is wrong; speed is not checked."""

import json
from pathlib import Path

import pytest

from benchmarks.variants import main, parse_variant


def test_a_variant_names_tuning_fields_with_literal_values() -> None:
    assert parse_variant("as_is=") == ("as_is", {})
    assert parse_variant("off=search.join_radius:0,search.join_rounds:30") == (
        "off",
        {"search.join_radius": 0, "search.join_rounds": 30},
    )
    assert parse_variant("starved=improve.work_per_second:0") == ("starved", {"improve.work_per_second": 0})
    for bad, named in [
        ("=search.join_radius:0", "NAME="),
        ("x=search.join_radius", "stage.FIELD:VALUE"),
        ("x=search.no_such:1", "SearchSettings has no no_such"),
        ("x=nowhere.join_radius:1", "no stage 'nowhere'"),
        ("x=improve.WORK_PER_SECOND:1", "ImproveSettings has no WORK_PER_SECOND"),
    ]:
        with pytest.raises(ValueError, match=named):
            parse_variant(bad)


def test_two_variants_plan_the_same_runs_and_a_setting_reaches_the_workers(tmp_path: Path) -> None:
    out = tmp_path / "out"
    args = ["--families", "shapes2", "--config-worlds", "figure1,obstacles_2", "--worlds", "1", "--seeds", "1"]
    # no work per second of planner.improve_time: the improvement cannot shorten the first plan
    variants = ["--variant", "as_is=", "--variant", "starved=improve.work_per_second:0"]
    assert main([*args, *variants, "--time-limit", "3", "--config-limit", "3", "--out", str(out)]) == 0
    report = json.loads((out / "variants.json").read_text())
    as_is, starved = report["runs"]["as_is"], report["runs"]["starved"]
    assert [(r["world"], r["seed"]) for r in as_is] == [(r["world"], r["seed"]) for r in starved]
    assert [r["family"] for r in as_is] == ["shapes2", "figure1", "obstacles_2"]
    assert as_is[1]["success"]
    assert starved[1]["success"]
    assert as_is[1]["first_travel_rad"] == starved[1]["first_travel_rad"]  # the same seed, the same first plan
    assert starved[1]["travel_rad"] == starved[1]["first_travel_rad"]
    assert as_is[1]["travel_rad"] < as_is[1]["first_travel_rad"]
    table = (out / "variants.md").read_text()
    assert "| all | starved |" in table


def test_the_tuning_of_a_variant_replaces_only_its_fields() -> None:
    from benchmarks.variants import tuning_of
    from clew_ros.planar.space import PlanarTuning

    tuning = tuning_of({"search.join_radius": 0.0, "reach.goal_core_fraction": 0.25})
    assert tuning.search.join_radius == 0.0
    assert tuning.reach.goal_core_fraction == 0.25
    assert tuning.search.join_rounds == PlanarTuning().search.join_rounds
    assert tuning.improve == PlanarTuning().improve
