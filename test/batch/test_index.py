"""clew_ros.batch.index: complete lines only; a torn last line is cut off; the last line of a job wins."""

from __future__ import annotations

import json
from pathlib import Path

from clew_ros.batch.index import INDEX_NAME, Index


def _record(job: str, code: str = "SUCCEEDED") -> dict[str, object]:
    return {"job": job, "code": code, "success": code == "SUCCEEDED"}


def test_appended_lines_are_read_back(tmp_path: Path) -> None:
    with Index.open(tmp_path / "out") as index:
        index.append(_record("w/seed_0000"))
        index.append(_record("w/seed_0001", "TIME_LIMIT"))
    text = (tmp_path / "out" / INDEX_NAME).read_text()
    assert text.endswith("\n")
    assert [json.loads(line)["job"] for line in text.splitlines()] == ["w/seed_0000", "w/seed_0001"]
    with Index.open(tmp_path / "out") as index:
        assert index.records["w/seed_0001"]["code"] == "TIME_LIMIT"
        assert index.repaired_bytes == 0
        assert index.skipped_lines == 0


def test_a_torn_last_line_is_cut_off_and_appending_goes_on(tmp_path: Path) -> None:
    with Index.open(tmp_path) as index:
        index.append(_record("w/seed_0000"))
    path = tmp_path / INDEX_NAME
    whole = path.read_bytes()
    torn = b'{"job": "w/seed_0001", "co'
    path.write_bytes(whole + torn)
    with Index.open(tmp_path) as index:
        assert index.repaired_bytes == len(torn)
        assert list(index.records) == ["w/seed_0000"]
        assert path.read_bytes() == whole
        index.append(_record("w/seed_0001"))
    assert [json.loads(line)["job"] for line in path.read_text().splitlines()] == ["w/seed_0000", "w/seed_0001"]


def test_lines_that_are_not_records_are_skipped_and_the_last_line_of_a_job_wins(tmp_path: Path) -> None:
    lines = [
        json.dumps(_record("w/seed_0000", "INTERNAL_ERROR")),
        "not json",
        json.dumps([1, 2]),
        json.dumps({"no": "job"}),
        json.dumps(_record("w/seed_0000")),
    ]
    (tmp_path / INDEX_NAME).write_text("\n".join(lines) + "\n")
    with Index.open(tmp_path) as index:
        assert index.skipped_lines == 3
        assert index.records["w/seed_0000"]["code"] == "SUCCEEDED"
