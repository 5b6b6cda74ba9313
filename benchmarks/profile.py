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
from pathlib import Path

from benchmarks.worlds import all_worlds, select
from clew_ros.core.settings import PlannerSettings
from clew_ros.planar.collision import check_start_and_goal
from clew_ros.planar.kernel import warm_up
from clew_ros.planar.space import plan
from clew_ros.planar.world import world_from_parameters


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
    world = check_start_and_goal(world_from_parameters(bench.parameters))
    settings = PlannerSettings.from_parameters(bench.parameters, seed=seed, time_limit=time_limit_s)
    warm_up()  # as clew_plan and the node do: loading the compiled kernel is not part of a plan
    profile = cProfile.Profile()
    profile.enable()
    result = plan(world, settings)
    profile.disable()
    root = str(Path(sys.modules["numpy"].__file__ or "").absolute().parents[1]) + os.sep
    here = str(Path(__file__).absolute().parents[1]) + os.sep
    raw = pstats.Stats(profile).stats  # type: ignore[attr-defined]  # (undocumented, not in typeshed)
    total = sum(row[2] for row in raw.values())  # sum of tottime (s)
    by_file: dict[str, float] = {}
    for (filename, _line, function), row in raw.items():
        if filename == "~":  # built-ins and C functions: grouped by library
            key = next((f"{lib} (C)" for lib in ("numpy", "shapely") if lib in function), "other built-ins (C)")
        else:
            key = filename.replace(root, "").replace(here, "")
            parts = Path(key).parts
            if parts[0] in ("numpy", "shapely"):
                key = f"{parts[0]} (Python)"
            elif "python3" in key:
                key = "Python standard library"
        by_file[key] = by_file.get(key, 0.0) + row[2]
    ranked = sorted(by_file.items(), key=lambda item: -item[1])[:top]
    return {
        "world": bench.name,
        "seed": seed,
        "time_limit_s": time_limit_s,
        "outcome": result.outcome.name,
        "stats": result.stats,
        "profiled_s": total,
        "by_file": [(name, seconds, seconds / total if total else 0.0) for name, seconds in ranked],
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
