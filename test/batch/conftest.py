"""Shared fixtures of the clew_batch tests: cheap worlds."""

from __future__ import annotations

from pathlib import Path

import pytest
from helpers.batch_cli import CONFIG


@pytest.fixture
def unreachable_fast(tmp_path: Path) -> Path:
    """config/unreachable.yaml with planner.time_limit 0.5 s: a quick failure (TIME_LIMIT)."""
    text = (CONFIG / "unreachable.yaml").read_text().replace("time_limit: 5.0", "time_limit: 0.5")
    assert "time_limit: 0.5" in text
    path = tmp_path / "worlds" / "unreachable_fast.yaml"
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text)
    return path
