"""The saved plans of ``test/data/saved_plans``: what they are and how they are made.

Each file is ``clew_plan WORLD.yaml --seed S --improve-time 0`` (the
first plan, before the anytime improvement) with ``stats.time_s`` removed (a
wall-clock figure), for the worlds of :data:`WORLDS`: the planar config worlds and
five spatial ones (a shipped Panda world, and worlds of ``clew_world``'s spatial families
kept in ``test/data/saved_plans/worlds``: a UR5 table to table, two narrow shelf to shelf
ones, a bin-to-cubby regrasp). ``test/core/test_plans_unchanged.py`` plans them again
and compares every key: same seed, same plan, across refactors.

When the algorithm changes on purpose, the plans change: regenerate them with
``python test/helpers/saved_plans.py [WORLD ...]`` (all of them without a name) and say so
in the commit message. ``python test/helpers/saved_plans.py --check [WORLD ...]`` plans them
again and compares the files byte for byte (the test allows 1e-9).

``clew_plan`` runs in a process of its own with numpy's AVX-512 kernels turned off
(``NPY_DISABLE_CPU_FEATURES``): on a CPU that has them, numpy's vectorised sin, cos and
arctan2 round differently in the last bit, and the planner's choices turn that into another
plan (single_transfer seed 1: 3 landmarks instead of 4). The saved plans are those of
numpy's AVX2 kernels, the same on every x86-64 machine with or without AVX-512.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
DIRECTORY = ROOT / "test" / "data" / "saved_plans"
WORLD_FILES = ROOT / "test" / "data" / "saved_plans" / "worlds"

#: The saved worlds: name -> (parameter file, seeds planned, time limit in s). The spatial worlds each plan
#: in a few seconds, one seed each (the spatial files' plans are made by ``clew_world FAMILY --robot R --seed 0``;
#: see each file's first line).
WORLDS: dict[str, tuple[Path, tuple[int, ...], float]] = {
    "figure1": (ROOT / "config" / "figure1.yaml", (0, 1), 60.0),
    "single_transfer": (ROOT / "config" / "single_transfer.yaml", (0, 1), 60.0),
    "arm3_regrasp": (ROOT / "config" / "arm3_regrasp.yaml", (0, 1), 60.0),
    "arm5_regrasp": (ROOT / "config" / "arm5_regrasp.yaml", (0, 1), 60.0),
    "spatial_panda_table_to_table": (ROOT / "config" / "spatial" / "panda_table_to_table.yaml", (0,), 30.0),
    "spatial_table_ur5": (WORLD_FILES / "spatial_table_ur5.yaml", (0,), 30.0),
    "spatial_narrow_panda": (WORLD_FILES / "spatial_narrow_panda.yaml", (0,), 30.0),
    "spatial_narrow_ur5": (WORLD_FILES / "spatial_narrow_ur5.yaml", (0,), 30.0),
    "spatial_bin_cubby_panda": (WORLD_FILES / "spatial_bin_cubby_panda.yaml", (0,), 30.0),
}


def without_avx512() -> dict[str, str]:
    """This environment with numpy's AVX-512 kernels (those this numpy dispatches and this CPU has) turned off."""
    from numpy._core._multiarray_umath import __cpu_dispatch__, __cpu_features__

    wide = [f for f in __cpu_dispatch__ if ("AVX512" in f or f == "X86_V4") and __cpu_features__.get(f)]
    return dict(os.environ, NPY_DISABLE_CPU_FEATURES=" ".join(wide))


def plan_file(world: str, seed: int, output: Path) -> tuple[int, dict]:
    """``clew_plan``'s exit code and its plan document, ``stats.time_s`` removed (module docstring: its own
    process, without numpy's AVX-512 kernels)."""
    path, _seeds, time_limit = WORLDS[world]
    arguments = ["-o", str(output), "--seed", str(seed), "--time-limit", str(time_limit), "--improve-time", "0", "-q"]
    command = [sys.executable, "-m", "clew_ros.cli.plan", str(path), *arguments]
    code = subprocess.run(command, env=without_avx512(), cwd=ROOT, check=False).returncode
    document = json.loads(output.read_text())
    document["stats"].pop("time_s", None)
    return code, document


def main(arguments: list[str]) -> int:
    """Plan and save the worlds named (all of :data:`WORLDS` when none is); with ``--check``, compare each
    plan with its saved file byte for byte instead (exit 1 if one differs)."""
    check = "--check" in arguments
    names = [a for a in arguments if a != "--check"]
    unknown = sorted(set(names) - set(WORLDS))
    if unknown:
        print(f"saved_plans: unknown world(s) {unknown}; expected some of {sorted(WORLDS)}", file=sys.stderr)
        return 2
    DIRECTORY.mkdir(parents=True, exist_ok=True)
    different = 0
    with tempfile.TemporaryDirectory() as tmp:
        for world in names or list(WORLDS):
            for seed in WORLDS[world][1]:
                _, document = plan_file(world, seed, Path(tmp) / "plan.json")
                path = DIRECTORY / f"{world}_seed{seed}.json"
                text = json.dumps(document, indent=1) + "\n"
                if check:
                    same = path.exists() and path.read_text() == text
                    different += not same
                    print(f"{path.relative_to(ROOT)}: {'byte-identical' if same else 'DIFFERENT'}")
                    continue
                path.write_text(text)
                print(f"{path.relative_to(ROOT)}: {document['message'].splitlines()[0]}")
    return 1 if different else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
