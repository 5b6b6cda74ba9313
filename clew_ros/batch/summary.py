"""The summary table printed at the end of a batch: per world file, the share of plans found, the planning
time (median and 90th percentile over every job) and, over the plans found, the median transfers and
joint travel."""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from typing import Any

import numpy as np

__all__ = ["summary_rows", "summary_table"]

HEADER = ("world", "jobs", "ok", "success", "time med s", "time p90 s", "transfers med", "travel med rad")


def _numbers(records: Iterable[Mapping[str, Any]], column: str) -> list[float]:
    values = (record.get(column) for record in records)
    return [float(v) for v in values if isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)]


def _statistic(values: Sequence[float], percentile: float, digits: int) -> str:
    return f"{np.percentile(values, percentile):.{digits}f}" if values else "-"


def _row(name: str, records: Sequence[Mapping[str, Any]]) -> tuple[str, ...]:
    found = [r for r in records if r.get("success") is True]
    times = _numbers(records, "plan_time_s")
    share = f"{100.0 * len(found) / len(records):.0f} %" if records else "-"
    return (
        name,
        str(len(records)),
        str(len(found)),
        share,
        _statistic(times, 50, 2),
        _statistic(times, 90, 2),
        _statistic(_numbers(found, "transfers"), 50, 1),
        _statistic(_numbers(found, "joint_travel_rad"), 50, 2),
    )


def summary_rows(records: Iterable[Mapping[str, Any]]) -> list[tuple[str, ...]]:
    """One row per world file (named by its plan folder, in order of first appearance), then ``all``."""
    by_world: dict[str, list[Mapping[str, Any]]] = {}
    for record in records:
        by_world.setdefault(str(record.get("job", "?")).rpartition("/")[0], []).append(record)
    rows = [_row(name, group) for name, group in by_world.items()]
    if len(by_world) > 1:
        rows.append(_row("all", [record for group in by_world.values() for record in group]))
    return rows


def summary_table(records: Iterable[Mapping[str, Any]]) -> str:
    """:func:`summary_rows` as an aligned text table (header first)."""
    rows = [HEADER, *summary_rows(records)]
    widths = [max(len(row[i]) for row in rows) for i in range(len(HEADER))]
    lines = []
    for row in rows:
        cells = [row[0].ljust(widths[0])] + [cell.rjust(width) for cell, width in zip(row[1:], widths[1:], strict=True)]
        lines.append("  ".join(cells).rstrip())
    return "\n".join(lines)
