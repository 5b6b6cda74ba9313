"""cProfile of one planner run: ``python -m benchmarks.profile WORLD [--seed N] [--time-limit S] [--top K]``.

Prints one JSON object: the run's outcome and stats, and the top ``K``
functions by cumulative and by own (``tottime``) time as text tables.
"""

from __future__ import annotations

import argparse
import cProfile
import io
import json
import os
import pstats
import sys

from benchmarks.families import all_worlds, select
from clew_ros.core.clew import plan
from clew_ros.core.settings import PlannerSettings
from clew_ros.core.world import world_from_parameters


def _table(profile: cProfile.Profile, key: str, top: int, root: str) -> str:
    stream = io.StringIO()
    stats = pstats.Stats(profile, stream=stream)
    stats.sort_stats(key).print_stats(top)
    lines = [line.replace(root, "") for line in stream.getvalue().splitlines()]
    start = next(i for i, line in enumerate(lines) if line.strip().startswith("ncalls"))
    return "\n".join(line.rstrip() for line in lines[start:] if line.strip())


def profile_run(name: str, seed: int, time_limit_s: float, top: int = 15) -> dict:
    matches = select(all_worlds(), name)
    if len(matches) != 1:
        raise SystemExit(f"profile: expected one world named {name!r}, found {len(matches)}")
    bench = matches[0]
    world = world_from_parameters(bench.parameters)
    settings = PlannerSettings.from_parameters(bench.parameters, seed=seed, time_limit=time_limit_s)
    profile = cProfile.Profile()
    profile.enable()
    result = plan(world, settings)
    profile.disable()
    root = os.path.dirname(os.path.dirname(os.path.abspath(sys.modules["numpy"].__file__))) + os.sep
    here = os.path.dirname(os.path.dirname(os.path.abspath(__file__))) + os.sep
    total = sum(row[2] for row in pstats.Stats(profile).stats.values())  # sum of tottime (s)
    return {
        "world": bench.name,
        "seed": seed,
        "outcome": result.outcome.name,
        "stats": result.stats,
        "profiled_s": total,
        "cumulative": _table(profile, "cumulative", top, root).replace(here, ""),
        "tottime": _table(profile, "tottime", top, root).replace(here, ""),
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m benchmarks.profile", description=__doc__.split("\n\n")[0])
    parser.add_argument("world", nargs="?", default="figure1")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--time-limit", type=float, default=60.0)
    parser.add_argument("--top", type=int, default=15)
    args = parser.parse_args(argv)
    json.dump(profile_run(args.world, args.seed, args.time_limit, args.top), sys.stdout)
    print()
    return 0


if __name__ == "__main__":
    sys.exit(main())
