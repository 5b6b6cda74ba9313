"""clew_ros.batch.summary: success by world, median and p90 time, median transfers and travel."""

from __future__ import annotations

from clew_ros.batch.summary import summary_rows, summary_table


def _record(job: str, success: bool, time_s: float, transfers: int | None, travel: float | None) -> dict[str, object]:
    return {"job": job, "success": success, "plan_time_s": time_s, "transfers": transfers, "joint_travel_rad": travel}


def test_rows_per_world_then_all() -> None:
    records = [
        _record("a/seed_0000", True, 1.0, 2, 10.0),
        _record("a/seed_0001", True, 3.0, 4, 20.0),
        _record("a/seed_0002", False, 5.0, None, None),
        _record("b/seed_0000", False, 0.5, None, None),
    ]
    rows = summary_rows(records)
    assert rows[0] == ("a", "3", "2", "67 %", "3.00", "4.60", "3.0", "15.00")
    assert rows[1] == ("b", "1", "0", "0 %", "0.50", "0.50", "-", "-")
    assert rows[2][:4] == ("all", "4", "2", "50 %")
    table = summary_table(records).splitlines()
    assert table[0].split()[:3] == ["world", "jobs", "ok"]
    assert len(table) == 4
