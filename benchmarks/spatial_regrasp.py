"""The planner on spatial worlds where a regrasp is necessary (:mod:`clew_ros.worlds.spatial_regrasp`).

For each family (``spatial_bin_cubby``, ``spatial_cubby_bin``, ``spatial_shelf_bin``, ``spatial_bin_shelf``, and
those that turn the object, :mod:`clew_ros.worlds.spatial_flips`: ``spatial_flip``, ``spatial_laid_down``), arm
(Panda, UR5, random arms of 6-7 joints ending in a wrist) and world seed, the world is generated (not timed; its
witness has two transfers and no grasp is valid at both the start and the goal) and planned once within
``--time-limit``. Printed per family and arm: success, median time, transfers against the witness's, false "no path"
answers (NO_PATH_AT_RESOLUTION on a world with a witness: must be 0), plans valid on the exact geometry
(:func:`clew_ros.spatial.plan.validate_plan`, coal) and plans that drag the object
(:func:`clew_ros.spatial.handling.drag_problems`).

    python -m benchmarks spatial_regrasp --seeds 4 --first-seed 100 --time-limit 10
"""

from __future__ import annotations

import argparse
import statistics
import time
from collections import defaultdict
from typing import Any

from clew_ros.core.settings import Outcome, PlannerSettings
from clew_ros.spatial.exact import exact_available, exact_problems
from clew_ros.spatial.handling import drag_problems
from clew_ros.spatial.plan import make_plan, validate_plan
from clew_ros.spatial.space import plan
from clew_ros.worlds.errors import GenerationError
from clew_ros.worlds.spatial import SPATIAL_FAMILIES, generate_spatial

__all__ = ["main", "run_one"]

FAMILIES = [name for name, family in SPATIAL_FAMILIES.items() if family.regrasp]


def run_one(family: str, robot: str, seed: int, time_limit: float, *, exact: bool = False) -> dict[str, Any] | None:
    """One generated world planned once: its figures, or ``None`` when no world was generated; ``exact``: its
    plan checked on the exact geometry by pinocchio and coal too (:func:`clew_ros.spatial.exact.exact_problems`)."""
    try:
        generated = generate_spatial(family, seed, robot)
    except GenerationError:
        return None
    world = generated.world()
    began, cpu = time.perf_counter(), time.process_time()
    result = plan(world, PlannerSettings(time_limit=time_limit, seed=0))
    elapsed, cpu = time.perf_counter() - began, time.process_time() - cpu
    row: dict[str, Any] = {
        "outcome": result.outcome.name,
        "time_s": elapsed,
        "cpu_s": cpu,
        "witness_transfers": generated.witness.grasp_count,
        "no_path": result.outcome is Outcome.NO_PATH_AT_RESOLUTION,
    }
    if result.success:
        built = make_plan(world, [(s.kind, s.grasp, s.waypoints) for s in result.segments])
        row["transfers"] = built.grasp_count
        row["valid"] = not validate_plan(world, built)
        row["drags"] = bool(drag_problems(world, built))
        if exact:
            row["exact"] = not exact_problems(world, built)
    return row


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m benchmarks spatial_regrasp", description=__doc__.split("\n")[0])
    parser.add_argument("--families", nargs="+", default=FAMILIES, choices=FAMILIES)
    parser.add_argument("--robots", nargs="+", default=["panda", "ur5", "random"], choices=["panda", "ur5", "random"])
    parser.add_argument("--seeds", type=int, default=4)
    parser.add_argument("--first-seed", type=int, default=100)
    parser.add_argument("--time-limit", type=float, default=10.0)
    parser.add_argument(
        "--exact", action="store_true", help="check every plan with pinocchio + coal too (the spatial-ref extra)"
    )
    args = parser.parse_args(argv)
    if args.exact and not exact_available():
        parser.error("--exact: needs pinocchio and coal (pip install -e '.[spatial-ref]')")
    rows: dict[tuple[str, str], list[dict[str, Any]]] = defaultdict(list)
    run_one(args.families[0], args.robots[0], args.first_seed, 1.0)  # warm-up: compiled kernels and caches, not kept
    for family in args.families:
        for robot in args.robots:
            for seed in range(args.first_seed, args.first_seed + args.seeds):
                row = run_one(family, robot, seed, args.time_limit, exact=args.exact)
                if row is None:
                    print(f"{family} {robot} {seed}: no world generated", flush=True)
                    continue
                rows[family, robot].append(row)
                print(f"{family} {robot} {seed}: {row}", flush=True)
    header = "| family | arm | solved | median s (CPU s) | transfers <= witness + 1 | false no path | valid | drags |"
    header += " valid (pinocchio) |" if args.exact else ""
    print("\n" + header + "\n|" + "---|" * (9 if args.exact else 8))
    every: list[dict[str, Any]] = []
    for (family, robot), found in rows.items():
        every += found
        print(_line(family.removeprefix("spatial_"), robot, found))
    print(_line("all", "all", every))
    return 0


def _line(family: str, robot: str, rows: list[dict[str, Any]]) -> str:
    solved = [r for r in rows if r["outcome"] == "SUCCEEDED"]
    median = statistics.median(r["time_s"] for r in rows) if rows else float("nan")
    cpu = statistics.median(r["cpu_s"] for r in rows) if rows else float("nan")
    few = sum(r["transfers"] <= r["witness_transfers"] + 1 for r in solved)
    return (
        f"| {family} | {robot} | {len(solved)}/{len(rows)} | {median:.2f} ({cpu:.2f}) | {few}/{len(solved)} | "
        f"{sum(r['no_path'] for r in rows)} | {sum(r['valid'] for r in solved)}/{len(solved)} | "
        f"{sum(r['drags'] for r in solved)}/{len(solved)} |"
        + (f" {sum(r['exact'] for r in solved)}/{len(solved)} |" if any("exact" in r for r in solved) else "")
    )


if __name__ == "__main__":
    raise SystemExit(main())
