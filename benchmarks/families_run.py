"""The planner on the generated families: ``python -m benchmarks.families_run [--quick] [--families A,B]
[--worlds 10] [--first-world 0] [--seeds 5] [--time-limit 10] [--jobs 2] [--out DIR]``.

Run from the repository root. For each family of :mod:`clew_ros.worlds` (default: every one, the
``unsolvable`` family included) it generates worlds K..K+W-1 (``--first-world K``, default 0; worlds from
70 on are held out, no tuning has looked at them; 40-43, 50-52 and 60-62 were measured and fixed for in session 24;
:mod:`benchmarks.generated`), into a
temporary directory or ``--keep-worlds DIR``, plans each with planner seeds 0..S-1 as ``clew_plan
WORLD --seed S --time-limit T`` would (the world's own ``planner.*`` defaults, ``planner.threads``
1 so that the ``--jobs`` worker processes do not compete for the cores), and does the same on
figure1 (``config/figure1.yaml``, W = 1) as the reference. Then it prints a table per family and
writes ``DIR/families.json`` (every run) and ``DIR/families.md`` (the table in Markdown):

* success: successful runs over the runs on known-solvable worlds (every world of a solvable family
  has a witness; for ``unsolvable`` the column says how many runs answered ``NO_PATH_AT_RESOLUTION``);
* median and p90 wall time of all runs (a failed run counts at its limit), median CPU time of the run's
  process (steadier than wall time on a shared machine);
* medians of landmarks, and over successful runs of transfers and joint travel (rad, the plan returned);
* the witnesses' median transfers and joint travel: a plan that solves the world, for scale; and the
  median over successful runs of the plan's joint travel over its world's witness's.

``--quick``: one world per family, two seeds, a 3 s limit (about a minute on 2 cores).
"""

from __future__ import annotations

import argparse
import concurrent.futures
import json
import multiprocessing
import os
import sys
import tempfile
import time
from collections import Counter
from pathlib import Path

import numpy as np

from benchmarks.generated import GeneratedBenchWorld, add_first_world, build_world, reference_world, world_seeds
from clew_ros.worlds import FAMILIES

#: Default sizes (the issue's: at least 6 solvable families x 10 worlds x 5 seeds) and their --quick values.
DEFAULTS = {"worlds": 10, "seeds": 5, "time_limit": 10.0}
QUICK = {"worlds": 1, "seeds": 2, "time_limit": 3.0}


def _warm_up() -> None:
    """Each worker process loads (or compiles) the kernel once, before its first timed run."""
    from clew_ros.planar.kernel import warm_up

    warm_up()


def run_one(path: str, seed: int, time_limit_s: float, threads: int) -> dict:
    """Plan the world file ``path`` once, as ``clew_plan`` does; the run's figures."""
    from clew_ros.core.settings import PlannerSettings
    from clew_ros.planar.collision import check_start_and_goal
    from clew_ros.planar.plan import checked_plan
    from clew_ros.planar.space import plan
    from clew_ros.planar.world import read_parameter_file, world_from_parameters

    parameters = read_parameter_file(path)
    world = check_start_and_goal(world_from_parameters(parameters))
    settings = PlannerSettings.from_parameters(parameters, seed=seed, time_limit=time_limit_s, threads=threads)
    started, cpu_started = time.perf_counter(), time.process_time()
    result = plan(world, settings)
    wall, cpu = time.perf_counter() - started, time.process_time() - cpu_started
    planned = checked_plan(world, result)
    return {
        "world": world.name,
        "seed": seed,
        "outcome": planned.code,
        "success": planned.success,
        "wall_s": wall,
        "cpu_s": cpu,
        "landmarks": result.stats.get("landmarks"),
        "transfers": planned.grasp_count if planned.success else None,
        "travel_rad": result.stats.get("joint_travel_rad") if planned.success else None,
    }


def _median(values: list) -> float | None:
    values = [v for v in values if v is not None]
    return float(np.median(values)) if values else None


def _p90(values: list) -> float | None:
    return float(np.percentile(values, 90)) if values else None


def summarise(family: str, worlds: list[GeneratedBenchWorld], runs: list[dict], limit_s: float) -> dict:
    """One table row: the family's worlds and runs. On solvable worlds a failed run counts at the limit
    (an early NO_PATH_AT_RESOLUTION there is no faster answer); on unsolvable ones the time is the answer's."""
    solvable = all(w.solvable for w in worlds)
    walls = [r["wall_s"] if r["success"] or not solvable else max(r["wall_s"], limit_s) for r in runs]
    successes = [r for r in runs if r["success"]]
    joints = sorted({w.joints for w in worlds})
    witness = {Path(w.path).stem: w.witness_travel_rad for w in worlds}
    return {
        "family": family,
        "solvable": solvable,
        "joints": f"{joints[0]}" if len(joints) == 1 else f"{joints[0]}-{joints[-1]}",
        "obstacles_median": _median([w.obstacles for w in worlds]),
        "worlds": len(worlds),
        "runs": len(runs),
        "successes": len(successes),
        "no_path": sum(r["outcome"] == "NO_PATH_AT_RESOLUTION" for r in runs),
        "success_rate": len(successes) / len(runs) if runs and solvable else None,
        "median_s": _median(walls),
        "p90_s": _p90(walls),
        "median_success_s": _median([r["wall_s"] for r in successes]),
        "median_cpu_s": _median([r["cpu_s"] for r in runs]),
        "landmarks_median": _median([r["landmarks"] for r in runs]),
        "transfers_median": _median([r["transfers"] for r in successes]),
        "travel_median": _median([r["travel_rad"] for r in successes]),
        "travel_ratio_median": _median(
            [r["travel_rad"] / witness[r["world"]] for r in successes if witness.get(r["world"]) and r["travel_rad"]]
        ),
        "witness_transfers_median": _median([w.witness_transfers for w in worlds]),
        "witness_travel_median": _median([w.witness_travel_rad for w in worlds]),
        "worlds_solved": sum(any(r["success"] for r in runs if r["world"] == Path(w.path).stem) for w in worlds),
        "outcomes": dict(Counter(r["outcome"] for r in runs)),
    }


def _fmt(value: float | None, digits: int = 2) -> str:
    return "-" if value is None else f"{value:.{digits}f}"


HEADER = [
    "family",
    "n",
    "obs",
    "worlds x seeds",
    "success",
    "worlds solved",
    "median s",
    "p90 s",
    "median CPU s",
    "landmarks",
    "transfers",
    "travel rad",
    "witness transfers",
    "witness travel rad",
    "travel / witness",
    "failures",
]


def cells(row: dict) -> list[str]:
    """The table's cells of one row."""
    if row["solvable"]:
        success = f"{100 * row['success_rate']:.0f}% ({row['successes']}/{row['runs']})"
    else:
        success = f"unsolvable: {row['no_path']}/{row['runs']} NO_PATH"
    failures = ", ".join(f"{count} {name}" for name, count in sorted(row["outcomes"].items()) if name != "SUCCEEDED")
    return [
        row["family"],
        row["joints"],
        _fmt(row["obstacles_median"], 0),
        f"{row['worlds']} x {row['runs'] // max(1, row['worlds'])}",
        success,
        f"{row['worlds_solved']}/{row['worlds']}" if row["solvable"] else "-",
        _fmt(row["median_s"]),
        _fmt(row["p90_s"]),
        _fmt(row["median_cpu_s"]),
        _fmt(row["landmarks_median"], 0),
        _fmt(row["transfers_median"], 0),
        _fmt(row["travel_median"], 1),
        _fmt(row["witness_transfers_median"], 0),
        _fmt(row["witness_travel_median"], 1),
        _fmt(row.get("travel_ratio_median")),
        failures or "-",
    ]


def markdown(rows: list[dict]) -> str:
    """The table in Markdown (first column left-aligned, the others right-aligned)."""
    align = ["---"] + ["--:"] * (len(HEADER) - 2) + ["---"]
    return "\n".join("| " + " | ".join(line) + " |" for line in [HEADER, align, *(cells(r) for r in rows)])


def print_table(rows: list[dict]) -> None:
    lines = [HEADER, *(cells(r) for r in rows)]
    widths = [max(len(line[i]) for line in lines) for i in range(len(HEADER))]
    for index, line in enumerate(lines):
        print(
            "  ".join(
                c.ljust(w) if i in (0, len(line) - 1) else c.rjust(w)
                for i, (c, w) in enumerate(zip(line, widths, strict=True))
            )
        )
        if index == 0:
            print("  ".join("-" * w for w in widths))


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="python -m benchmarks.families_run", description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="1 world per family, 2 seeds, 3 s limit")
    parser.add_argument("--families", default=None, help=f"comma-separated (default all: {','.join(FAMILIES)})")
    parser.add_argument("--worlds", type=int, default=None, help="worlds per family, seeds K..K+W-1 (default 10)")
    add_first_world(parser)
    parser.add_argument("--seeds", type=int, default=None, help="planner seeds per world, 0..S-1 (default 5)")
    parser.add_argument("--time-limit", type=float, default=None, help="per run, s (default 10)")
    parser.add_argument("--jobs", type=int, default=2, help="worker processes (default 2)")
    parser.add_argument("--threads", type=int, default=1, help="planner.threads of every run (default 1)")
    parser.add_argument(
        "--min-joints", type=int, default=0, metavar="N", help="leave out generated worlds of fewer joints (default 0)"
    )
    parser.add_argument("--no-figure1", action="store_true", help="leave out the figure1 reference row")
    parser.add_argument("--out", type=Path, default=Path("bench_out"), help="where families.json/.md go")
    parser.add_argument("--keep-worlds", type=Path, default=None, help="write the worlds here (default: a temp dir)")
    parser.add_argument(
        "--render", type=Path, default=None, metavar="JSON", help="re-summarise a saved families.json, no planning"
    )
    return parser


def _settings(args: argparse.Namespace) -> tuple[list[str], int, int, float]:
    chosen = QUICK if args.quick else DEFAULTS
    families = [f.strip() for f in (args.families or ",".join(FAMILIES)).split(",") if f.strip()]
    unknown = [f for f in families if f not in FAMILIES]
    if unknown:
        raise SystemExit(f"benchmarks.families_run: --families: unknown {unknown}; expected some of {list(FAMILIES)}")
    worlds = args.worlds if args.worlds is not None else chosen["worlds"]
    seeds = args.seeds if args.seeds is not None else chosen["seeds"]
    limit = args.time_limit if args.time_limit is not None else chosen["time_limit"]
    return families, int(worlds), int(seeds), float(limit)


def run(args: argparse.Namespace, directory: Path) -> dict:
    """Generate the worlds and plan them; the report (rows and every run)."""
    families, world_count, seed_count, limit = _settings(args)
    context = multiprocessing.get_context("spawn")
    loadavg_start = os.getloadavg()
    started = time.monotonic()
    with concurrent.futures.ProcessPoolExecutor(
        max_workers=args.jobs, mp_context=context, initializer=_warm_up
    ) as pool:
        jobs = [(f, s) for s in world_seeds(args, world_count) for f in families]
        built = list(pool.map(build_world, *zip(*jobs, strict=True), [str(directory)] * len(jobs)))
        built = [w for w in built if w.joints >= getattr(args, "min_joints", 0)]
        generation_s = time.monotonic() - started
        print(f"generated {len(built)} worlds in {generation_s:.0f} s", file=sys.stderr)
        worlds = ([] if args.no_figure1 else [reference_world()]) + built
        tasks = [(w, seed) for seed in range(seed_count) for w in worlds]
        futures = [pool.submit(run_one, w.path, seed, limit, args.threads) for w, seed in tasks]
        runs = []
        for index, future in enumerate(futures):
            runs.append({**future.result(), "family": tasks[index][0].family})
            if (index + 1) % 20 == 0:
                print(f"  {index + 1}/{len(futures)} runs, {time.monotonic() - started:.0f} s", file=sys.stderr)
    order = ([] if args.no_figure1 else ["figure1"]) + families
    rows = [
        summarise(f, [w for w in worlds if w.family == f], [r for r in runs if r["family"] == f], limit) for f in order
    ]
    command = " ".join(["python -m benchmarks.families_run", *sys.argv[1:]]) if args.command is None else args.command
    return {
        "command": command,
        "started": time.strftime("%Y-%m-%d %H:%M:%S"),
        "nproc": os.cpu_count(),
        "loadavg_start": loadavg_start,
        "loadavg_end": os.getloadavg(),
        "worlds_per_family": world_count,
        "first_world": args.first_world,
        "seeds": seed_count,
        "time_limit_s": limit,
        "jobs": args.jobs,
        "threads": args.threads,
        "generation_s": generation_s,
        "total_s": time.monotonic() - started,
        "rows": rows,
        "worlds": [w.__dict__ for w in worlds],
        "runs": runs,
    }


def rerender(path: Path) -> dict:
    """A saved report with its rows summarised again from its worlds and runs (after a change of the table)."""
    report = json.loads(path.read_text())
    worlds = [GeneratedBenchWorld(**w) for w in report["worlds"]]
    order = list(dict.fromkeys(w.family for w in worlds))
    report["rows"] = [
        summarise(
            family,
            [w for w in worlds if w.family == family],
            [r for r in report["runs"] if r["family"] == family],
            report["time_limit_s"],
        )
        for family in order
    ]
    return report


def main(argv: list[str] | None = None) -> int:
    args = _parser().parse_args(argv)
    args.command = None if argv is None else " ".join(["python -m benchmarks.families_run", *argv])
    if args.render:
        report = rerender(args.render)
    elif args.keep_worlds:
        args.keep_worlds.mkdir(parents=True, exist_ok=True)
        report = run(args, args.keep_worlds)
    else:
        with tempfile.TemporaryDirectory(prefix="clew_families_") as directory:
            report = run(args, Path(directory))
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "families.json").write_text(json.dumps(report, indent=1) + "\n")
    text = (
        f"`{report['command']}` ({report['started']}, {report['total_s'] / 60:.1f} min on {report['nproc']} cores, "
        f"{report['jobs']} worker processes, planner.threads {report['threads']}, load average "
        f"{report['loadavg_start'][0]:.1f} at the start and {report['loadavg_end'][0]:.1f} at the end; per-run limit "
        f"{report['time_limit_s']:g} s):\n\n{markdown(report['rows'])}\n"
    )
    (args.out / "families.md").write_text(text)
    print_table(report["rows"])
    print(f"wrote {args.out / 'families.json'} and families.md ({report['total_s']:.0f} s)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
