"""clew_ros.batch.jobs: world files from files, folders and lists; seeds; where plans go."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from helpers.batch_cli import CONFIG

from clew_ros.batch.errors import BatchInputError
from clew_ros.batch.jobs import collect_world_paths, derived_seeds, load_worlds, make_jobs


def test_files_folders_and_list_files_each_world_once(tmp_path: Path) -> None:
    folder = tmp_path / "worlds"
    folder.mkdir()
    for name in ("b.yaml", "a.yaml", "notes.txt"):
        (folder / name).write_text("x")
    listing = tmp_path / "lists" / "list.txt"
    listing.parent.mkdir()
    listing.write_text("# worlds\n\n../worlds/b.yaml  # again\n" + str(CONFIG / "figure1.yaml") + "\n")
    paths = collect_world_paths([str(folder), f"@{listing}", str(folder / "a.yaml")])
    assert paths == [(folder / "a.yaml").resolve(), (folder / "b.yaml").resolve(), (CONFIG / "figure1.yaml").resolve()]


@pytest.mark.parametrize(
    ("source", "argument", "expected"),
    [
        ("missing.yaml", "missing.yaml", "does not exist"),
        ("@missing.txt", "@missing.txt", "readable list file"),
        ("empty_folder", "empty_folder", "holding .yaml world files"),
    ],
)
def test_a_bad_source_is_named(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, source: str, argument: str, expected: str
) -> None:
    monkeypatch.chdir(tmp_path)
    (tmp_path / "empty_folder").mkdir()
    with pytest.raises(BatchInputError) as caught:
        collect_world_paths([source])
    assert caught.value.argument == argument
    assert expected in caught.value.expected


def test_a_bad_line_of_a_list_file_is_named(tmp_path: Path) -> None:
    listing = tmp_path / "list.txt"
    listing.write_text(str(CONFIG / "figure1.yaml") + "\nnowhere.yaml\n")
    with pytest.raises(BatchInputError, match=r"list.txt:2: expected a world file"):
        collect_world_paths([f"@{listing}"])


def test_an_invalid_world_is_named_with_its_parameter(tmp_path: Path) -> None:
    bad = tmp_path / "bad.yaml"
    bad.write_text(
        (CONFIG / "figure1.yaml").read_text().replace("link_lengths: [1.0, 0.7]", "link_lengths: [1.0, -0.7]")
    )
    with pytest.raises(BatchInputError) as caught:
        load_worlds([bad])
    assert caught.value.argument == str(bad)
    assert "world.robot.link_lengths" in caught.value.expected


def test_two_world_files_of_one_name_are_refused(tmp_path: Path) -> None:
    (tmp_path / "other").mkdir()
    twin = tmp_path / "other" / "figure1.yaml"
    twin.write_text((CONFIG / "figure1.yaml").read_text())
    with pytest.raises(BatchInputError, match="same file name"):
        load_worlds([CONFIG / "figure1.yaml", twin])


def test_derived_seeds_are_seed_sequence_children() -> None:
    seeds = derived_seeds(2024, 50)
    children = np.random.SeedSequence(2024).spawn(50)
    assert seeds == [int(c.generate_state(1, dtype=np.uint32)[0]) >> 1 for c in children]  # no repeat among 50
    assert len(set(seeds)) == 50
    assert all(0 <= s < 2**31 for s in seeds)
    assert derived_seeds(2024, 10) == seeds[:10]
    assert derived_seeds(2025, 10) != seeds[:10]


def test_jobs_keys_plan_paths_and_fingerprints() -> None:
    (world,) = load_worlds([(CONFIG / "single_transfer.yaml").resolve()])
    jobs = make_jobs([world], [0, 7, 123456])
    assert [job.key for job in jobs] == [
        "single_transfer/seed_0000",
        "single_transfer/seed_0007",
        "single_transfer/seed_123456",
    ]
    assert jobs[1].plan_path == Path("plans/single_transfer/seed_0007.json")
    assert jobs[1].settings.seed == 7
    assert jobs[1].settings.time_limit == 20.0  # the world file's
    (limited,) = make_jobs([world], [7], time_limit_s=3.0)
    assert limited.settings.time_limit == 3.0
    assert len({job.fingerprint for job in [*jobs, limited]}) == 4
    assert make_jobs([world], [7])[0].fingerprint == jobs[1].fingerprint


@pytest.mark.parametrize(("option", "value"), [("--time-limit", -1.0), ("--improve-time", float("nan"))])
def test_overrides_out_of_range_are_named(option: str, value: float) -> None:
    (world,) = load_worlds([(CONFIG / "single_transfer.yaml").resolve()])
    keyword = "time_limit_s" if option == "--time-limit" else "improve_time_s"
    with pytest.raises(BatchInputError) as caught:
        make_jobs([world], [0], **{keyword: value})
    assert caught.value.argument == option
