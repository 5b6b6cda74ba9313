"""``python -m benchmarks.one_transfer_bound [--worlds NAME|PATH ...] [--seeds N] [--step RAD] [--approaches N]
[--goal-angles N]``: the shortest one-transfer plan of a 3-joint world found on a fine lattice with no budget, and
what it bounds the improvement's gain to (issue 14).

**The bound** (:func:`one_transfer_bound`): every grasp configuration at the object's start
(:func:`clew_ros.planar.lattice.grasp_configurations`, ``--approaches`` tip angles a grasp point, both elbows)
that is valid with the object resting and held; from each, every configuration holding the object on the goal
position at ``--goal-angles`` angles evenly spaced within the goal's angle tolerance (both elbows). The transit
from the start and the transfer to the goal are each the shortest path on a lattice of step ``--step``
(:func:`clew_ros.planar.lattice.lattice_route`, with the improver's margin, unlimited work), candidates in the
order of their straight joint distance, any that cannot beat the best found skipped. The plan is validated at
0.002 rad (:func:`clew_ros.planar.plan.validate_plan`). It is a plan, so an upper bound on the shortest
one-transfer plan: the goal position's tolerance, other approaches and paths off the lattice could shorten it.

**The report**: per world, the bound's travel, the time it took and the work units its routings spent (the
improver's budget is ``improve_time * ImproveSettings.work_per_second`` of them), the planner's first and improved plans
(median over seeds ``0..N-1``, as ``clew_plan WORLD --seed S`` plans them, transfers in brackets), and the
first plan's median over the bound: the gain a plan of one transfer could give at most about that.
"""

from __future__ import annotations

import argparse
import math
import statistics
import sys
import time
from dataclasses import dataclass

import numpy as np

from benchmarks.reference import load_worlds, plan_segment, planner_runs, succeeded_plan
from clew_ros.core.plan import Plan
from clew_ros.core.settings import PlannerSettings
from clew_ros.planar.continuous import ContinuousSettings, straight_moves_clear
from clew_ros.planar.improve import ImproveSettings, check_work, joint_travel
from clew_ros.planar.kinematics import compose, relative
from clew_ros.planar.lattice import KnownNodes, LatticeWork, grasp_configurations, lattice_route, pose_configurations
from clew_ros.planar.plan import validate_plan
from clew_ros.planar.world import World


class _Unlimited:
    """A :class:`clew_ros.planar.lattice.LatticeBudget` that never stops and counts as the improver's does."""

    def __init__(self, world: World) -> None:
        self.check_work = check_work(world)
        self.spent = 0

    def spend(self, units: int) -> None:
        self.spent += units

    def spend_move_checks(self, configurations: int) -> None:
        self.spent += math.ceil(configurations * self.check_work) + ImproveSettings().move_call_work

    def spend_checks(self, configurations: int, calls: int = 1) -> None:
        self.spent += math.ceil(configurations * self.check_work) + calls * ImproveSettings().call_work

    def stop(self) -> bool:
        return False


@dataclass
class Bound:
    """The shortest one-transfer plan found (``None``: none) and its validation."""

    plan: Plan | None
    travel: float  # rad; inf without a plan
    problems: list[str]
    time_s: float
    work: int  # the work units its routings spent, as the improver's budget counts them


def one_transfer_bound(world: World, *, step: float, approaches: int, goal_angles: int, margin: float) -> Bound:
    """The shortest one-transfer plan of a 3-joint ``world`` on the lattice of ``step`` (module docstring)."""
    started = time.perf_counter()
    budget = _Unlimited(world)
    work = LatticeWork(budget, math.inf, ImproveSettings().expansion_work)
    start, rest, goal = np.asarray(world.robot.initial, float), world.object.initial, world.object.goal
    q, which, rels = grasp_configurations(world, rest, start, approaches)
    valid = straight_moves_clear(world, q, q, object_pose=rest, min_margin=margin) & np.array(
        [
            straight_moves_clear(world, q[k][None], q[k][None], grasp_rel=rels[k], min_margin=margin)[0]
            for k in range(len(q))
        ],
        dtype=bool,
    )
    spread = min(math.pi, world.goal_angle_tolerance)
    angles = np.linspace(-spread, spread, goal_angles, endpoint=spread < math.pi)
    goals = np.c_[np.broadcast_to(goal[:2], (len(angles), 2)), goal[2] + angles]
    candidates = []  # (straight distance, grasp configuration, goal configurations)
    for k in np.flatnonzero(valid).tolist():
        tips = compose(goals, relative(rels[k], np.zeros(3)))
        solved, ok = pose_configurations(world.robot, tips, np.broadcast_to(q[k], (len(tips), 3)))
        ends = solved[ok]
        if len(ends):
            ends = ends[straight_moves_clear(world, ends, ends, grasp_rel=rels[k], min_margin=margin)]
        if len(ends):
            ends = ends[np.argsort(np.abs(ends - q[k]).sum(axis=1), kind="stable")]
            candidates.append((float(np.abs(q[k] - start).sum() + np.abs(ends[0] - q[k]).sum()), int(k), ends))
    candidates.sort(key=lambda c: c[0])
    best: tuple[float, np.ndarray, np.ndarray, int] | None = None
    transit_known = KnownNodes()
    held_known: dict[bytes, KnownNodes] = {}
    for straight, k, ends in candidates:
        limit = math.inf if best is None else best[0]
        if straight >= limit:
            break
        transit = lattice_route(
            world, start, q[k], object_pose=rest, grasp_rel=None, shorter_than=limit - np.abs(ends[0] - q[k]).sum(),
            min_margin=margin, work=work, nodes_known=transit_known, step=step,
        )  # fmt: skip
        if transit is None:
            continue
        known = held_known.setdefault(rels[k].tobytes(), KnownNodes())
        for end in ends:
            limit = (math.inf if best is None else best[0]) - joint_travel([transit])
            if np.abs(end - q[k]).sum() >= limit:
                break
            carried = lattice_route(
                world, q[k], end, object_pose=rest, grasp_rel=rels[k], shorter_than=limit, nodes_known=known,
                min_margin=margin, work=work, step=step,
            )  # fmt: skip
            if carried is not None:
                best = (joint_travel([transit]) + joint_travel([carried]), transit, carried, int(which[k]))
    elapsed = time.perf_counter() - started
    if best is None:
        return Bound(None, math.inf, [], elapsed, budget.spent)
    segments = (plan_segment("transit", None, best[1]), plan_segment("transfer", best[3], best[2]))
    plan = succeeded_plan(world, segments, f"one-transfer bound: joint travel {best[0]:.3f} rad, step {step} rad")
    return Bound(plan, best[0], validate_plan(world, plan), elapsed, budget.spent)


HEADER = (
    "| world | one-transfer bound rad | bound s | bound work units | found | first plan rad (transfers) "
    "| improved rad (transfers) | improved / bound | first / bound |\n|---|---|---|---|---|---|---|---|---|"
)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m benchmarks.one_transfer_bound", description=__doc__.split("\n\n")[0]
    )
    parser.add_argument("--worlds", nargs="+", default=["obstacles_14"], help="benchmark world names or YAML files")
    parser.add_argument("--seeds", type=int, default=10, help="planner seeds 0..N-1 per world (default 10)")
    parser.add_argument("--step", type=float, default=0.14, help="lattice step (rad, default 0.14)")
    parser.add_argument("--approaches", type=int, default=48, help="tip angles a grasp point (default 48)")
    parser.add_argument("--goal-angles", type=int, default=72, help="goal angles tried (default 72)")
    args = parser.parse_args(argv)
    if args.step <= 0 or args.approaches < 1 or args.goal_angles < 1 or args.seeds < 1:
        print("benchmarks.one_transfer_bound: --step > 0, --approaches, --goal-angles, --seeds >= 1", file=sys.stderr)
        return 2
    from clew_ros.planar.kernel import warm_up

    warm_up()
    print(HEADER, flush=True)
    for world, parameters in load_worlds(args.worlds):
        if world.robot.dof != 3:
            print(f"| {world.name} | not a 3-joint world | | | | | | | |", flush=True)
            continue
        margin = ContinuousSettings().min_margin_factor * PlannerSettings.from_parameters(parameters).clearance
        bound = one_transfer_bound(
            world, step=args.step, approaches=args.approaches, goal_angles=args.goal_angles, margin=margin
        )
        runs = planner_runs(world, parameters, args.seeds)
        text = "none" if bound.plan is None else f"{bound.travel:.2f}" + (" INVALID" if bound.problems else "")
        if not runs.travel:
            print(f"| {world.name} | {text} | {bound.time_s:.1f} | {bound.work} | 0/{args.seeds} | | | | |", flush=True)
            continue
        first, improved = statistics.median(runs.first_travel), statistics.median(runs.travel)
        ratios = f"{improved / bound.travel:.2f}x | {first / bound.travel:.2f}x" if bound.plan is not None else " | "
        print(
            f"| {world.name} | {text} | {bound.time_s:.1f} | {bound.work} | {len(runs.travel)}/{args.seeds} "
            f"| {first:.2f} ({statistics.median(runs.first_transfers):g}) "
            f"| {improved:.2f} ({statistics.median(runs.transfers):g}) | {ratios} |",
            flush=True,
        )
        for problem in bound.problems[:3]:
            print(f"  bound plan of {world.name}: {problem}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
