"""``python -m benchmarks.improvement_stages [--worlds NAME|PATH ...] [--seeds N] [--improve-time S]``: where the
anytime improvement's time goes, and whether its work counting keeps it within its budget.

For each world (names and files as :mod:`benchmarks.improvement` takes them) and seed, the plan is made with
the improvement on, and each stage of :class:`clew_ros.planar.improve._Improver` (rebuilding, routing, the
lattice's regrasps, fewer transfers, greedy and random shortcuts, the lattice's first grasps) records its wall
time and the work it was charged. Prints a Markdown row per world and stage, summed over the seeds: wall time
(s), the seconds its work stands for (``work / ImproveSettings.work_per_second``) and their ratio. Routing runs inside
rebuilding and is counted in both (the lattice's first grasps route their transits themselves). A stage
whose ratio is far above the others' is charged too little for its Python.
"""

from __future__ import annotations

import time
from collections import defaultdict
from collections.abc import Callable
from typing import Any
from unittest import mock

from benchmarks.improvement import arguments
from benchmarks.reference import load_worlds
from clew_ros.core.settings import PlannerSettings
from clew_ros.planar.improve import ImproveSettings, _Improver
from clew_ros.planar.kernel import warm_up
from clew_ros.planar.space import plan

STAGES = (
    "rebuild",
    "connect",
    "lattice_regrasps",
    "fewer_transfers",
    "greedy_shortcuts",
    "random_shortcuts",
    "lattice_first_grasps",
)


def _recording(totals: dict[str, list[float]]) -> None:
    """Make each stage of every improver add ``[wall s, work units]`` to ``totals[stage]``."""

    def timed(stage: str, method: Callable[..., Any]) -> Callable[..., Any]:
        def run(improver: _Improver, *args: Any, **kwargs: Any) -> Any:
            started, spent = time.perf_counter(), improver.budget.spent
            try:
                return method(improver, *args, **kwargs)
            finally:
                totals[stage][0] += time.perf_counter() - started
                totals[stage][1] += improver.budget.spent - spent

        return run

    for stage in STAGES:
        mock.patch.object(_Improver, stage, timed(stage, getattr(_Improver, stage))).start()


def main(argv: list[str] | None = None) -> int:
    args, names = arguments(argv, __doc__, seeds=5)
    warm_up()
    print("| world | stage | wall s | work s | wall / work |\n|---|---|--:|--:|--:|")
    for world, parameters in load_worlds(names):
        totals: dict[str, list[float]] = defaultdict(lambda: [0.0, 0.0])
        _recording(totals)
        improving = {} if args.improve_time is None else {"improve_time": args.improve_time}
        for seed in range(args.seeds):
            plan(world, PlannerSettings.from_parameters(parameters, seed=seed, time_limit=120, **improving))
        mock.patch.stopall()
        for stage in STAGES:
            wall, work = totals[stage]
            nominal = work / ImproveSettings().work_per_second
            ratio = f"{wall / nominal:.2f}" if nominal > 0 else "-"
            print(f"| {world.name} | {stage} | {wall:.3f} | {nominal:.3f} | {ratio} |", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
