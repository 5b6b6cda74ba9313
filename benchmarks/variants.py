"""Settings of the planner's modules compared on the same worlds, in one run: ``python -m benchmarks.variants
--variant NAME=stage.FIELD:VALUE[,...] [--variant ...] [--families A,B] [--config-worlds figure1,...]
[--worlds 4] [--seeds 6] [--time-limit 10] [--jobs 2] [--out DIR]``.

A variant replaces fields of the planner's tuning, :class:`clew_ros.planar.space.PlanarTuning` (``stage.FIELD``:
``search`` :class:`~clew_ros.core.settings.SearchSettings`, ``many`` :class:`~clew_ros.core.settings.ManyJoints`,
``reach`` :class:`~clew_ros.planar.reach.ReachSettings`, ``improve`` :class:`~clew_ros.planar.improve.ImproveSettings`;
for example ``search.join_radius:0`` or ``improve.work_per_second:0``): the workers plan with that copy, nothing
else changes. ``NAME=`` alone is the code as it is. Every variant plans every (world, seed): the
generated families' worlds (:mod:`benchmarks.generated`) and the benchmark worlds named, in worker processes of
their own (``--jobs`` at a time, one kernel thread each). The figure compared is the time to the first plan
(``PlanResult.first_plan_s``: what a change of SEARCH or EXPLORE moves; a failed run counts at the limit). Per
family and in all: success, median first-plan time, median landmarks, and the geometric mean over (world, seed) of
each run's time over the first variant's (below 1: faster). A change of the random stream makes single runs diverge:
read the ratios over many runs, not one.
``DIR/variants.json`` keeps every run.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import multiprocessing
import os
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

from benchmarks.generated import GeneratedBenchWorld, build_world, solvable_families
from benchmarks.report import command_line, header, write_report
from benchmarks.worlds import all_worlds, select, write_world

#: Benchmark worlds (``config/`` and :mod:`benchmarks.worlds`) planned by default next to the generated
#: families, with their own time limit (``--config-limit``).
CONFIG_WORLDS = "figure1,obstacles_8,obstacles_32,joints_10,arm5_regrasp"


def bench_world(name: str, directory: str) -> GeneratedBenchWorld:
    """The benchmark world ``name`` written into ``directory``, as a family of one world."""
    from clew_ros.planar.world import load_world

    matches = select(all_worlds(), name)
    if len(matches) != 1:
        raise ValueError(f"--config-worlds: expected one benchmark world named {name!r}, found {len(matches)}")
    path = write_world(matches[0], Path(directory))
    world = load_world(path)
    return GeneratedBenchWorld(name, 0, str(path), True, world.robot.dof, len(world.obstacles), None, None)


def _stages() -> dict[str, type]:
    """The tuning's stages by name: the dataclasses of :class:`~clew_ros.planar.space.PlanarTuning`'s fields."""
    from clew_ros.planar.space import PlanarTuning

    return {f.name: type(getattr(PlanarTuning(), f.name)) for f in dataclasses.fields(PlanarTuning)}


def parse_variant(text: str) -> tuple[str, dict[str, Any]]:
    """``NAME=stage.FIELD:VALUE,...`` → (name, {"stage.FIELD": value}); values are JSON literals."""
    name, _, body = text.partition("=")
    if not name:
        raise ValueError(f"--variant {text!r}: expected NAME=stage.FIELD:VALUE[,...]")
    stages = _stages()
    settings: dict[str, Any] = {}
    for item in filter(None, body.split(",")):
        key, sep, value = item.partition(":")
        stage, dot, name_ = key.partition(".")
        if not sep or not dot or not name_:
            raise ValueError(f"--variant {text!r}: {item!r} is not stage.FIELD:VALUE")
        if stage not in stages:
            raise ValueError(f"--variant {text!r}: no stage {stage!r} (expected one of {', '.join(stages)})")
        if name_ not in {f.name for f in dataclasses.fields(stages[stage])}:
            raise ValueError(f"--variant {text!r}: {stages[stage].__name__} has no {name_}")
        settings[key] = json.loads(value)
    return name, settings


def tuning_of(settings: dict[str, Any]) -> Any:
    """The :class:`~clew_ros.planar.space.PlanarTuning` with the variant's fields replaced."""
    from clew_ros.planar.space import PlanarTuning

    tuning = PlanarTuning()
    by_stage: dict[str, dict[str, Any]] = {}
    for key, value in settings.items():
        stage, field = key.split(".")
        by_stage.setdefault(stage, {})[field] = value
    changed = {stage: dataclasses.replace(getattr(tuning, stage), **fields) for stage, fields in by_stage.items()}
    return dataclasses.replace(tuning, **changed)


#: The tuning a worker process plans with (set by its initializer, :func:`_apply`).
_TUNING: list[Any] = []


def _apply(settings: dict[str, Any]) -> None:
    """A worker process's initializer: the variant's tuning kept for its plans, then the compiled kernel loaded."""
    from clew_ros.planar.kernel import warm_up

    _TUNING[:] = [tuning_of(settings)]
    warm_up()


def _plan(job: tuple[str, str, int, float]) -> dict[str, Any]:
    from clew_ros.core.settings import PlannerSettings
    from clew_ros.planar.space import plan
    from clew_ros.planar.world import load_world

    family, path, seed, limit = job
    tuning = _TUNING[0] if _TUNING else None
    result = plan(load_world(path), PlannerSettings(seed=seed, time_limit=limit, threads=1), tuning=tuning)
    first = result.first_plan_s if result.success and result.first_plan_s is not None else limit
    return {
        "family": family,
        "world": Path(path).stem,
        "seed": seed,
        "outcome": result.outcome.name,
        "success": result.success,
        "first_plan_s": first,
        "landmarks": result.stats["landmarks"],
        "travel_rad": result.stats.get("joint_travel_rad"),
        "first_travel_rad": result.stats.get("first_joint_travel_rad"),
    }


def run_variant(settings: dict[str, Any], jobs: list[tuple[str, str, int, float]], workers: int) -> list[dict]:
    """Every job planned by worker processes with ``settings`` applied, in the jobs' order."""
    context = multiprocessing.get_context("spawn")  # a fresh interpreter: constants set before any plan
    with context.Pool(workers, initializer=_apply, initargs=(settings,)) as pool:
        return pool.map(_plan, jobs, chunksize=1)


def _median(values: list[float]) -> float:
    ordered = sorted(values)
    middle = len(ordered) // 2
    return ordered[middle] if len(ordered) % 2 else 0.5 * (ordered[middle - 1] + ordered[middle])


def table(names: list[str], runs: dict[str, list[dict]]) -> str:
    """Markdown: one row per family and variant, then all runs."""
    families = list(dict.fromkeys(r["family"] for r in runs[names[0]]))
    lines = [
        "| family | variant | success | median first plan s | landmarks | time / first variant |",
        "|---|---|--:|--:|--:|--:|",
    ]
    for family in [*families, "all"]:
        for name in names:
            pairs = [(r, b) for r, b in zip(runs[name], runs[names[0]], strict=True) if family in ("all", r["family"])]
            mine = [r for r, _ in pairs]
            ratio = math.exp(sum(math.log(r["first_plan_s"] / b["first_plan_s"]) for r, b in pairs) / len(pairs))
            lines.append(
                f"| {family} | {name} | {sum(r['success'] for r in mine)}/{len(mine)} "
                f"| {_median([r['first_plan_s'] for r in mine]):.2f} | {_median([r['landmarks'] for r in mine]):.0f} "
                f"| {ratio:.2f} |"
            )
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m benchmarks.variants", description=__doc__.split("\n\n")[0])
    parser.add_argument("--variant", action="append", required=True, help="NAME=module.CONSTANT:VALUE[,...]")
    parser.add_argument("--families", default=",".join(solvable_families()), help="comma-separated")
    parser.add_argument("--config-worlds", default=CONFIG_WORLDS, help="worlds of config/, comma-separated")
    parser.add_argument("--worlds", type=int, default=4, help="worlds per family, seeds 0..W-1")
    parser.add_argument("--seeds", type=int, default=6, help="planner seeds per world, 0..S-1")
    parser.add_argument("--time-limit", type=float, default=10.0, help="per run on the families, s")
    parser.add_argument("--config-limit", type=float, default=5.0, help="per run on the config/ worlds, s")
    parser.add_argument("--jobs", type=int, default=2, help="worker processes")
    parser.add_argument("--out", type=Path, default=Path("bench_out"), help="where variants.json/.md go")
    args = parser.parse_args(argv)
    try:
        variants = [parse_variant(text) for text in args.variant]
    except ValueError as error:
        parser.error(str(error))
    started, load = time.monotonic(), os.getloadavg()[0]
    runs: dict[str, list[dict]] = {}
    with tempfile.TemporaryDirectory(prefix="clew_variants_") as scratch:
        generated = [build_world(f, s, scratch) for f in args.families.split(",") if f for s in range(args.worlds)]
        try:
            configs = [bench_world(name, scratch) for name in args.config_worlds.split(",") if name]
        except ValueError as error:
            parser.error(str(error))
        jobs = [(w.family, w.path, seed, args.time_limit) for w in generated for seed in range(args.seeds)]
        jobs += [(w.family, w.path, seed, args.config_limit) for w in configs for seed in range(args.seeds)]
        for name, settings in variants:
            begun = time.monotonic()
            runs[name] = run_variant(settings, jobs, args.jobs)
            print(f"  {name}: {len(jobs)} runs, {time.monotonic() - begun:.0f} s", file=sys.stderr)
    names = [name for name, _ in variants]
    command = command_line("benchmarks.variants", argv)
    what = f"{args.worlds} worlds x {args.seeds} seeds per family, {args.seeds} seeds per config world"
    text = f"{header(command, started, load, what)}\n\n{table(names, runs)}\n"
    write_report(args.out, "variants", text, {"command": command, "runs": runs})
    return 0


if __name__ == "__main__":
    sys.exit(main())
