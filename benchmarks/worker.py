"""One world's planner runs, in a process of its own: ``python -m benchmarks.worker NAME ...``.

Prints one JSON object on stdout: per-seed results (wall time and this
process's CPU time: on a shared machine the CPU time is the steadier figure,
the planner's time limit is wall time), and the process's peak resident
memory (``ru_maxrss``) before and after planning, so memory figures
belong to this world alone. :mod:`benchmarks.run` starts one per world.
"""

from __future__ import annotations

import argparse
import json
import resource
import sys
import time

from benchmarks.worlds import all_worlds, select
from clew_ros.core.settings import PlannerSettings
from clew_ros.planar.collision import check_start_and_goal
from clew_ros.planar.kernel import warm_up
from clew_ros.planar.plan import checked_plan
from clew_ros.planar.space import plan
from clew_ros.planar.world import world_from_parameters


def _maxrss_mb() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0  # Linux: KiB


def run_world(name: str, seeds: list[int], time_limit_s: float, validate: bool = True) -> dict:
    """Plan ``name`` once per seed; returns the per-run records and memory figures."""
    matches = select(all_worlds(), name)
    if len(matches) != 1:
        raise SystemExit(f"worker: expected one world named {name!r}, found {len(matches)}")
    bench = matches[0]
    world = check_start_and_goal(world_from_parameters(bench.parameters))
    warm_up_s = warm_up()  # compile or load the kernel first, as clew_plan and the node do
    base_rss = _maxrss_mb()
    runs = []
    for seed in seeds:
        settings = PlannerSettings.from_parameters(bench.parameters, seed=seed, time_limit=time_limit_s)
        started, cpu_started = time.perf_counter(), time.process_time()
        result = plan(world, settings)
        wall, cpu = time.perf_counter() - started, time.process_time() - cpu_started
        record = {
            "seed": seed,
            "outcome": result.outcome.name,
            "success": result.success,
            "wall_s": wall,
            "cpu_s": cpu,
            "first_plan_s": result.first_plan_s,  # before planner.improve_time's improvement
            "landmarks": result.stats["landmarks"],
            "evaluations": result.stats["evaluations"],
            "collision_checks": result.stats["collision_checks"],
            "grasps": sum(s.kind == "transfer" for s in result.segments),
            # plan quality (issue 14): joint travel of the plan returned and of the first plan found
            "travel_rad": result.stats.get("joint_travel_rad"),
            "first_travel_rad": result.stats.get("first_joint_travel_rad"),
            "valid": None,
        }
        if validate and result.success:
            record["valid"] = checked_plan(world, result).success
        runs.append(record)
    return {
        "world": bench.name,
        "time_limit_s": time_limit_s,
        "runs": runs,
        "warm_up_s": warm_up_s,
        "rss_before_mb": base_rss,
        "peak_rss_mb": _maxrss_mb(),
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m benchmarks.worker", description=__doc__.split("\n\n")[0])
    parser.add_argument("world")
    parser.add_argument("--seeds", type=int, default=20)
    parser.add_argument("--first-seed", type=int, default=0)
    parser.add_argument("--time-limit", type=float, required=True, help="per run (s)")
    parser.add_argument("--no-validate", action="store_true", help="skip validate_plan on successful plans")
    args = parser.parse_args(argv)
    seeds = list(range(args.first_seed, args.first_seed + args.seeds))
    json.dump(run_world(args.world, seeds, args.time_limit, not args.no_validate), sys.stdout)
    print()
    return 0


if __name__ == "__main__":
    sys.exit(main())
