"""``python -m benchmarks.improvement [--worlds NAME|PATH ...] [--seeds N] [--improve-time S] [--shortest]``: what the
anytime improvement gains.

For each world (default figure1, arm3_regrasp and arm5_regrasp; any benchmark
world name of :mod:`benchmarks.worlds` such as obstacles_32, a generated
family's world such as shapes2_60 (as ``clew_world shapes2 --seed 60`` writes
it), or a parameter file), seeds ``0..N-1``: each seed planned with
``planner.improve_time: 0`` (the first plan) and with the given budget
(the file's other ``planner.*`` parameters apply);
prints a Markdown table row per world: plans found, median joint travel of
the first and the improved plan (rad), the gain, median transfers, the
wall time the improvement added (median / max, s), and that time over the
seconds its work stands for (``improve_work / ImproveSettings.work_per_second``, median / max:
under 1, the work counted keeps the improvement within its budget); with
``--shortest``, also the shortest improved plan over the seeds (rad). A run whose improved plan the final checks
refused (``stats.improve_refused``, a fault) is named on standard error.
docs/algorithm.md quotes it.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path
from typing import Any
from unittest import mock

from benchmarks.reference import load_worlds
from clew_ros.core.settings import PlannerSettings
from clew_ros.planar import space as planar_space
from clew_ros.planar.improve import ImproveSettings, improve
from clew_ros.planar.kernel import warm_up
from clew_ros.planar.space import plan

ROOT = Path(__file__).resolve().parents[1]
WORLDS = ("figure1", "arm3_regrasp", "arm5_regrasp")


def _timing_improvement() -> list[float]:
    """Make the planner's calls of :func:`clew_ros.planar.improve.improve` record their wall time (s) in the list
    returned: the time the improvement adds to a run, measured alone (the difference of two whole runs is noisy
    on a shared machine)."""
    times: list[float] = []
    improved = improve

    def timed(*args: Any, **kwargs: Any) -> Any:
        started = time.monotonic()
        try:
            return improved(*args, **kwargs)
        finally:
            times.append(time.monotonic() - started)

    mock.patch.object(planar_space, "improve", timed).start()  # PlanarSpace.improve calls it by its name
    return times


def arguments(
    argv: list[str] | None, doc: str, seeds: int, *, shortest: bool = False
) -> tuple[argparse.Namespace, list[str]]:
    """The options the improvement's benchmarks share (``--worlds``, ``--seeds``, ``--improve-time``; ``doc``'s
    first paragraph as the description; ``--shortest`` if ``shortest``), and the world files or names to run."""
    parser = argparse.ArgumentParser(description=doc.split("\n\n", maxsplit=1)[0])
    parser.add_argument(
        "--worlds", nargs="+", default=None, help=f"benchmark world names or YAML files (default {' '.join(WORLDS)})"
    )
    parser.add_argument("--seeds", type=int, default=seeds)
    parser.add_argument("--improve-time", type=float, default=None, help="default: planner.improve_time's default")
    if shortest:
        parser.add_argument(
            "--shortest", action="store_true", help="one more column: the shortest improved plan over the seeds (rad)"
        )
    args = parser.parse_args(argv)
    return args, args.worlds or [str(ROOT / "config" / f"{name}.yaml") for name in WORLDS]


def main(argv: list[str] | None = None) -> int:
    args, names = arguments(argv, __doc__, seeds=10, shortest=True)
    warm_up()
    times = _timing_improvement()
    for world, parameters in load_worlds(names):
        name = world.name
        rows: list[tuple[float, ...]] = []
        for seed in range(args.seeds):
            first = plan(
                world, PlannerSettings.from_parameters(parameters, seed=seed, time_limit=120, improve_time=0.0)
            )
            improving = {} if args.improve_time is None else {"improve_time": args.improve_time}
            times.clear()
            better = plan(world, PlannerSettings.from_parameters(parameters, seed=seed, time_limit=120, **improving))
            added = sum(times)
            if "improve_refused" in better.stats:  # a fault of the improvement: said apart from the table
                print(f"{name} seed {seed}: improved plan refused ({better.stats['improve_refused']})", file=sys.stderr)
            if first.success and better.success:
                s = better.stats
                nominal = s["improve_work"] / ImproveSettings().work_per_second  # the seconds the work spent stands for
                rows.append(
                    (
                        s["first_joint_travel_rad"],
                        s["joint_travel_rad"],
                        s["first_transfers"],
                        s["transfers"],
                        added,
                        added / nominal if nominal > 0 else 0.0,
                    )
                )

        def median(i: int, rows: list[tuple[float, ...]] = rows) -> float:
            return statistics.median(r[i] for r in rows)

        if not rows:
            print(f"| {name} | 0/{args.seeds} | | | | | | |")
            continue
        print(
            f"| {name} | {len(rows)}/{args.seeds} | {median(0):.1f} | {median(1):.1f} | {median(0) / median(1):.2f}x "
            f"| {median(2):g} / {median(3):g} | {median(4):.2f} / {max(r[4] for r in rows):.2f} "
            f"| {median(5):.2f} / {max(r[5] for r in rows):.2f} |"
            + (f" {min(r[1] for r in rows):.2f} |" if args.shortest else ""),
            flush=True,
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
