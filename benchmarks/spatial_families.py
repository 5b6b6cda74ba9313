"""``python -m benchmarks spatial_families [--families ...] [--robots panda ur5 random] [--worlds 2] [--seeds 2]
[--time-limit 10] [--exact]``: the Ariadne's Clew planner on ``clew_world``'s generated spatial families.

For each family (:data:`clew_ros.worlds.spatial.SPATIAL_FAMILIES`), robot (the shipped Panda and UR5, random
serial arms of 4-8 joints) and world seed (``--first-world`` .. + ``--worlds`` - 1), the world is generated
(:func:`~clew_ros.worlds.spatial.generate_spatial`, not timed) and loaded as a user's file is
(:meth:`~clew_ros.worlds.spatial.SpatialGenerated.world`, its sphere model built, not timed), its kernels
warmed (:func:`clew_ros.spatial.offline.warm_up`, not timed), then planned by
:func:`clew_ros.spatial.space.plan` with planner seeds 0 .. ``--seeds`` - 1 (default ``planner.*`` but the
seed and ``--time-limit``; the improvement runs within its default ``planner.improve_time``). The wall time
of each run is measured around that call alone.

Every successful plan is checked as ``clew_plan`` checks it: its ``clew-plan/1`` plan validated by
:func:`clew_ros.spatial.plan.validate_plan` (every configuration of every straight piece at 0.002 rad, the
grasps held, the object resting stably, the goal reached). Its transfers are compared with the witness's
(the generator's plan, solvable by construction): "no needless regrasp" counts the runs with transfers at
most the witness's + 1.

Per family and robot, and per family over the robots: runs, success (a valid plan within the time limit,
what ``clew_plan`` gives: a plan the validator refuses is an ``INTERNAL_ERROR``), median and p90 time (a
failure counts at the limit), median transfers against the witness's, the share with transfers <= the
witness's + 1, the plans the validator passed over those the planner returned, and with ``--exact`` the plans
that also pass the exact geometry (:func:`clew_ros.spatial.exact.exact_problems`: pinocchio + coal on the
URDF's collision meshes, the obstacles and the object, resting or held, at the same 0.002 rad; the checker is
built once per world, not timed) over those the planner returned. On the unsolvable
family (no witness plan: the goal boxed in or out of reach) the outcomes and their median time instead: a
quick answer is one well inside the limit.
"""

from __future__ import annotations

import argparse
import statistics
import time
from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from clew_ros.core.plan import Plan
from clew_ros.core.settings import PlannerSettings
from clew_ros.spatial.exact import ExactChecker, exact_available
from clew_ros.spatial.offline import checked_plan, warm_up
from clew_ros.spatial.space import plan
from clew_ros.worlds.errors import GenerationError
from clew_ros.worlds.spatial import SPATIAL_FAMILIES, SPATIAL_ROBOTS, generate_spatial

__all__ = ["FamilyRun", "main", "rows", "run_world"]


@dataclass(frozen=True)
class FamilyRun:
    """One planner run on one generated world."""

    family: str
    robot: str
    world_seed: int
    seed: int
    dof: int
    solvable: bool
    outcome: str
    success: bool
    time_s: float
    transfers: int | None  # the plan's (None: no plan)
    witness_transfers: int | None  # the witness's (None: unsolvable)
    valid: bool | None  # the plan passed validate_plan (None: no plan)
    message: str
    exact_valid: bool | None = None  # no collision on the exact geometry (None: no plan, or not checked)
    exact_message: str = ""  # the first collision found on the exact geometry


def run_world(
    family: str, robot: str, world_seed: int, seeds: Sequence[int], time_limit_s: float, *, exact: bool = False
) -> list[FamilyRun]:
    """Generate one world and plan it with every planner seed of ``seeds``; ``exact``: check each plan
    returned on the exact geometry too."""
    generated = generate_spatial(family, world_seed, robot)
    world = generated.world()
    warm_up(world)
    reference = ExactChecker(world) if exact else None
    witness = generated.witness.grasp_count if generated.solvable else None
    out = []
    for seed in seeds:
        started = time.perf_counter()
        result = plan(world, PlannerSettings(seed=seed, time_limit=time_limit_s))
        elapsed = time.perf_counter() - started
        checked = checked_plan(world, result) if result.success else None
        found = (
            None
            if reference is None or not result.success
            else reference.plan_problems(Plan.from_result(world, result))
        )
        out.append(
            FamilyRun(
                family=family,
                robot=robot,
                world_seed=world_seed,
                seed=seed,
                dof=world.robot.dof,
                solvable=generated.solvable,
                outcome=result.outcome.name,
                success=result.success and elapsed <= time_limit_s,
                time_s=elapsed,
                transfers=None if checked is None else sum(s.kind == "transfer" for s in result.segments),
                witness_transfers=witness,
                valid=None if checked is None else checked.success,
                message=result.message if checked is None or checked.success else checked.message,
                exact_valid=None if found is None else not found,
                exact_message="" if not found else f"{len(found)} colliding pieces; first: {found[0]}",
            )
        )
    return out


def _figures(runs: Sequence[FamilyRun], time_limit_s: float, exact: bool = False) -> str:
    """One table row's cells after its label (``exact``: and the plans valid on the exact geometry)."""
    times = [r.time_s if (r.success and r.valid) or not r.solvable else time_limit_s for r in runs]
    median, p90 = statistics.median(times), float(np.percentile(times, 90))
    if not runs[0].solvable:
        outcomes = Counter(r.outcome for r in runs)
        said = ", ".join(f"{name} {count}" for name, count in outcomes.most_common())
        return f"{len(runs)} | {said} | {median:.3f} | {p90:.3f} | - | - | - |{' - |' * exact}"
    returned = [r for r in runs if r.success]
    good = [r for r in returned if r.valid]  # what clew_plan gives: a plan the validator refuses is an error
    transfers = [r.transfers for r in good if r.transfers is not None]
    witness = [r.witness_transfers for r in runs if r.witness_transfers is not None]
    needless = [
        r for r in good if r.transfers is not None and r.witness_transfers is not None
        and r.transfers <= r.witness_transfers + 1
    ]  # fmt: skip
    plan_transfers = f"{statistics.median(transfers):g}" if transfers else "-"
    lean = f"{len(needless)}/{len(good)}" if good else "-"
    exact_cell = f" {sum(bool(r.exact_valid) for r in returned)}/{len(returned)} |" if exact else ""
    return (
        f"{len(runs)} | {len(good) / len(runs):.0%} | {median:.3f} | {p90:.3f} | "
        f"{plan_transfers} / {statistics.median(witness):g} | {lean} | {len(good)}/{len(returned)} |{exact_cell}"
    )


def rows(runs: Sequence[FamilyRun], time_limit_s: float) -> list[str]:
    """The markdown table: each family on each robot, then the family over all robots (with a column of the
    plans valid on the exact geometry when the runs were checked on it)."""
    exact = any(r.exact_valid is not None for r in runs)
    lines = [
        (
            "| family | robot | runs | success (unsolvable: outcomes) | median s | p90 s | transfers (plan / "
            "witness, median) | transfers <= witness + 1 | valid |" + (" valid (exact) |" if exact else "")
        ),
        "|---|---|--:|--:|--:|--:|--:|--:|--:|" + ("--:|" if exact else ""),
    ]
    robots = [robot for robot in SPATIAL_ROBOTS if any(r.robot == robot for r in runs)]
    for family in SPATIAL_FAMILIES:
        chosen = [r for r in runs if r.family == family]
        if not chosen:
            continue
        for robot in robots:
            mine = [r for r in chosen if r.robot == robot]
            if mine:
                lines.append(f"| {family} | {robot} | {_figures(mine, time_limit_s, exact)}")
        if len(robots) > 1:
            lines.append(f"| {family} | all | {_figures(chosen, time_limit_s, exact)}")
    solvable = [r for r in runs if r.solvable]
    if solvable:
        lines.append(f"| solvable | all | {_figures(solvable, time_limit_s, exact)}")
    return lines


def _plan_all(args: argparse.Namespace) -> tuple[list[FamilyRun], list[str]]:
    """Every (family, robot, world, seed) of ``args`` planned, a line printed for each; the worlds the generator
    could not make are skipped and named."""
    runs: list[FamilyRun] = []
    skipped: list[str] = []
    for family in args.families:
        for robot in [r for r in args.robots if r in SPATIAL_FAMILIES[family].robots]:
            for world_seed in range(args.first_world, args.first_world + args.worlds):
                try:
                    world_runs = run_world(
                        family, robot, world_seed, range(args.seeds), args.time_limit, exact=args.exact
                    )
                except GenerationError as error:  # the generator found no such world: nothing to plan
                    skipped.append(f"{family} {robot} world {world_seed}")
                    print(f"{family} {robot} world {world_seed}: not generated ({error})", flush=True)
                    continue
                for r in world_runs:
                    runs.append(r)
                    said = "" if r.transfers is None else f" transfers {r.transfers} (witness {r.witness_transfers})"
                    invalid = (" INVALID" if r.valid is False else "") + (
                        " EXACT-COLLIDES" if r.exact_valid is False else ""
                    )
                    print(
                        f"{family} {robot} world {world_seed} ({r.dof} joints) seed {r.seed}: {r.outcome} "
                        f"{r.time_s:.3f} s{said}{invalid}  {r.message[:100]}",
                        flush=True,
                    )
    return runs, skipped


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m benchmarks spatial_families", description=__doc__.split("\n\n")[0])
    one_transfer = [name for name, family in SPATIAL_FAMILIES.items() if not family.regrasp]  # regrasps: their own
    parser.add_argument("--families", nargs="+", default=one_transfer, choices=list(SPATIAL_FAMILIES))
    parser.add_argument("--robots", nargs="+", default=list(SPATIAL_ROBOTS), choices=list(SPATIAL_ROBOTS))
    parser.add_argument("--worlds", type=int, default=2, help="worlds per family and robot (default 2)")
    parser.add_argument("--first-world", type=int, default=0, help="the first world's seed (default 0)")
    parser.add_argument("--seeds", type=int, default=2, help="planner seeds per world (default 2)")
    parser.add_argument("--time-limit", type=float, default=10.0, help="per run (s; default 10)")
    parser.add_argument(
        "--exact", action="store_true", help="check every plan on the exact geometry too (pinocchio + coal)"
    )
    args = parser.parse_args(argv)
    if args.exact and not exact_available():
        parser.error("--exact: needs pinocchio and coal (pip install -e '.[spatial-ref]')")
    if args.worlds < 1 or args.seeds < 1 or args.first_world < 0 or not args.time_limit > 0:
        parser.error(
            "--worlds and --seeds: expected at least 1; --first-world: expected >= 0; "
            "--time-limit: expected a positive number"
        )
    started = time.perf_counter()
    runs, skipped = _plan_all(args)
    print()
    print(f"time limit {args.time_limit:g} s a run; whole run {time.perf_counter() - started:.0f} s")
    if skipped:
        print(f"not generated (no such world in the generator's attempts): {', '.join(skipped)}")
    print("\n".join(rows(runs, args.time_limit)))
    for r in runs:
        if r.valid is False:
            print(f"invalid: {r.family} {r.robot} world {r.world_seed} seed {r.seed}: {r.message[:400]}")
        if r.exact_valid is False:
            print(f"exact: {r.family} {r.robot} world {r.world_seed} seed {r.seed}: {r.exact_message[:400]}")
        if r.solvable and not r.success and r.valid is not False:
            print(f"failed: {r.family} {r.robot} world {r.world_seed} seed {r.seed}: {r.outcome} {r.message[:160]}")
    return 1 if any(r.valid is False for r in runs) else 0  # a plan the validator refuses is a bug


if __name__ == "__main__":
    raise SystemExit(main())
