"""families_ab's "same plan file": equal but for the clock, and nothing else."""

import json
from pathlib import Path

from benchmarks.families_ab import same_plan


def _write(path: Path, time_s: float, travel: float) -> Path:
    plan = {"format": "clew-plan/1", "segments": [[0.0, 1.0]], "stats": {"time_s": time_s, "joint_travel_rad": travel}}
    path.write_text(json.dumps(plan))
    return path


def test_same_plan_ignores_only_the_clock(tmp_path: Path) -> None:
    a = _write(tmp_path / "a.json", 0.5, 3.0)
    assert same_plan(a, _write(tmp_path / "b.json", 1.7, 3.0))
    assert not same_plan(a, _write(tmp_path / "c.json", 0.5, 3.1))
