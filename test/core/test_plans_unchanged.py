"""Same seed, same plan file: the plans saved in ``test/data/saved_plans`` still come out.

What they are and how to regenerate them when the algorithm changes on
purpose: :mod:`helpers.saved_plans`. The numbers must agree to 1e-9 (the
plans are equal bit for bit on the machine that saved them, the tolerance
only absorbs a different libm).
"""

from __future__ import annotations

import math
from pathlib import Path

import pytest
from helpers.saved_plans import DIRECTORY, WORLDS, plan_file

SAVED = sorted(DIRECTORY.glob("*.json"))


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
    """A saved plan for every world and seed of :data:`helpers.saved_plans.WORLDS`, and none other."""
    expected = {f"{world}_seed{seed}" for world, (_, seeds, _) in WORLDS.items() for seed in seeds}
    assert {p.stem for p in SAVED} == expected
    assert sum(world.startswith("spatial_") for world in WORLDS) >= 4


@pytest.mark.parametrize("saved_path", SAVED, ids=[p.stem for p in SAVED])
def test_same_seed_same_plan_as_saved(saved_path: Path, tmp_path: Path) -> None:
    import json

    world, seed = saved_path.stem.rsplit("_seed", 1)
    code, fresh = plan_file(world, int(seed), tmp_path / "plan.json")
    saved = json.loads(saved_path.read_text())
    assert code == (0 if saved["success"] else 1)
    if fresh["success"] and not world.startswith("spatial_"):
        # (a spatial plan's dragging transfers are mended even without improvement time: spatial.lift)
        assert fresh["stats"]["joint_travel_rad"] == fresh["stats"]["first_joint_travel_rad"]
    assert _differences(saved, fresh) == []
