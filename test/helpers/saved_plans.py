"""The saved plans of ``test/data/saved_plans``: what they are and how they are made.

Each file is ``clew_plan config/WORLD.yaml --seed S --improve-time 0`` (the
first plan, before the anytime improvement) with ``stats.time_s`` removed (a
wall-clock figure). ``test/core/test_plans_unchanged.py`` plans them again
and compares every key: same seed, same plan, across refactors.

When the algorithm changes on purpose, the plans change: regenerate them with
``python test/helpers/saved_plans.py`` and say so in the commit message.
"""

from __future__ import annotations

import json
import sys
import tempfile
from pathlib import Path

from clew_ros.cli.plan import main as clew_plan

ROOT = Path(__file__).resolve().parents[2]
DIRECTORY = ROOT / "test" / "data" / "saved_plans"
WORLDS = ("figure1", "single_transfer", "arm3_regrasp", "arm5_regrasp")
SEEDS = (0, 1)


def plan_file(world: str, seed: int, output: Path) -> tuple[int, dict]:
    """``clew_plan``'s exit code and its plan document, ``stats.time_s`` removed."""
    arguments = ["-o", str(output), "--seed", str(seed), "--time-limit", "60", "--improve-time", "0", "-q"]
    code = clew_plan([str(ROOT / "config" / f"{world}.yaml"), *arguments])
    document = json.loads(output.read_text())
    document["stats"].pop("time_s", None)
    return code, document


def main() -> int:
    DIRECTORY.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() as tmp:
        for world in WORLDS:
            for seed in SEEDS:
                _, document = plan_file(world, seed, Path(tmp) / "plan.json")
                path = DIRECTORY / f"{world}_seed{seed}.json"
                path.write_text(json.dumps(document, indent=1) + "\n")
                print(f"{path.relative_to(ROOT)}: {document['message'].splitlines()[0]}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
