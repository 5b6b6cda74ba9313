"""Same seed, same plan file: plans saved before the architecture refactor (issue 12) still come out.

``test/data/plans_before_refactor/`` holds plan files written by ``clew_plan``
at commit 5771ed5 (``stats.time_s`` removed, it is a wall-clock figure). The
test plans the same worlds with the same seeds and compares every key; the
numbers must agree to 1e-9 (the plans are equal bit for bit on the machine
that saved them, the tolerance only absorbs a different libm). The plans
were saved before the anytime improvement (issue 14), so they are planned
with ``--improve-time 0`` (the first plan), and the quality stats added since
(:data:`NEW_STATS`) are left out of the comparison.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest

from clew_ros.cli.plan import main as clew_plan

ROOT = Path(__file__).resolve().parents[2]
#: Stats keys added after the plans were saved (issue 14: the plan's quality).
NEW_STATS = ("joint_travel_rad", "transfers", "first_joint_travel_rad", "first_transfers", "improve_work")
SAVED = sorted((ROOT / "test" / "data" / "plans_before_refactor").glob("*.json"))


def _differences(saved, fresh, where="plan") -> list[str]:
    if isinstance(saved, dict) and isinstance(fresh, dict):
        if saved.keys() != fresh.keys():
            return [f"{where}: keys {sorted(saved)} != {sorted(fresh)}"]
        return [d for key in saved for d in _differences(saved[key], fresh[key], f"{where}.{key}")]
    if isinstance(saved, list) and isinstance(fresh, list):
        if len(saved) != len(fresh):
            return [f"{where}: {len(saved)} items != {len(fresh)}"]
        return [
            d for i, (a, b) in enumerate(zip(saved, fresh, strict=True)) for d in _differences(a, b, f"{where}[{i}]")
        ]
    if isinstance(saved, float) and isinstance(fresh, float):
        return [] if math.isclose(saved, fresh, rel_tol=0, abs_tol=1e-9) else [f"{where}: {saved} != {fresh}"]
    return [] if saved == fresh and type(saved) is type(fresh) else [f"{where}: {saved!r} != {fresh!r}"]


def test_saved_plans_exist() -> None:
    assert len(SAVED) >= 8


@pytest.mark.parametrize("saved_path", SAVED, ids=[p.stem for p in SAVED])
def test_same_seed_same_plan_as_before_the_refactor(saved_path: Path, tmp_path: Path) -> None:
    world, seed = saved_path.stem.rsplit("_seed", 1)
    out = tmp_path / "plan.json"
    code = clew_plan(
        [
            str(ROOT / "config" / f"{world}.yaml"),
            "-o",
            str(out),
            "--seed",
            seed,
            "--time-limit",
            "60",
            "--improve-time",
            "0",
            "-q",
        ]
    )
    fresh = json.loads(out.read_text())
    saved = json.loads(saved_path.read_text())
    assert code == (0 if saved["success"] else 1)
    fresh["stats"].pop("time_s", None)
    if fresh["success"]:
        assert fresh["stats"]["joint_travel_rad"] == fresh["stats"]["first_joint_travel_rad"]
    for key in NEW_STATS:
        fresh["stats"].pop(key, None)
    assert _differences(saved, fresh) == []
